"""False nearest neighbours (Kennel, Brown & Abarbanel 1992) with scipy.spatial.cKDTree.

For d = 1..6 and delay Td = 5: the points y_n = (x_n, x_{n+Td}, ..., x_{n+(d-1)Td}) for every n
whose next coordinate x_{n+d Td} exists (N - d Td points); the nearest neighbour y_m of each
(Euclidean norm, values on the line, no Theiler window); the pair is false when
|x_{n+d Td} - x_{m+d Td}| / |y_n - y_m| > 10 (Kennel's first test). Printed: the false fraction
per d (timed), and for comparison the same test with the max norm. Pairs at distance 0
(duplicate points) cannot be tested and are left out of the fraction.
"""

import numpy as np
from scipy.spatial import cKDTree

import common

THRESHOLD = 10.0
MAX_DIM = 6


def false_nearest_fractions(x, delay=common.DELAY, max_dim=MAX_DIM, threshold=THRESHOLD, p=2):
    """The false fraction for d = 1..max_dim; `p` is the Minkowski norm (2 Euclidean, inf max)."""
    fractions = []
    for d in range(1, max_dim + 1):
        count = x.size - d * delay
        points = np.column_stack([x[c * delay : c * delay + count] for c in range(d)])
        dist, idx = cKDTree(points).query(points, k=2, p=p)
        # Column 0 is normally the point itself; with a duplicate it may be the twin instead.
        own = idx[:, 0] == np.arange(count)
        neighbour = np.where(own, idx[:, 1], idx[:, 0])
        distance = dist[:, 1]
        usable = distance > 0
        next_gap = np.abs(x[np.arange(count) + d * delay] - x[neighbour + d * delay])
        false = next_gap[usable] > threshold * distance[usable]
        fractions.append(np.count_nonzero(false) / np.count_nonzero(usable))
    return np.array(fractions)


def bench(x, repeats=3):
    """Median seconds of the fractions for d = 1..6 and the fractions."""
    return common.median_time(lambda: false_nearest_fractions(x), repeats)


# A classic tool (max norm) on the same data, for comparison.
CLASSIC = np.array([1.000, 0.776, 0.196, 0.033, 0.014, 0.008])


def main():
    _, x = common.load_paper_dataset()
    seconds, fractions = bench(x)
    max_norm = false_nearest_fractions(x, p=np.inf)
    print("  d  Euclidean  classic tool  difference  (this code, max norm)")
    for d, (f, c, m) in enumerate(zip(fractions, CLASSIC, max_norm), start=1):
        print(f"{d:3d}  {f:9.3f}  {c:12.3f}  {f - c:+10.3f}  ({m:.3f})")
    print(f"time: {seconds:.3f} s (median of 3)")


if __name__ == "__main__":
    main()
