"""Average mutual information (paper eq. 18) with NumPy histograms.

I(lag) = sum_ab p_ab ln(p_ab / (p_a p_b)) over the joint histogram of (x_n, x_{n+lag}), 16 equal
boxes per axis over the range [min x, max x] of the whole record, in nats. The delay is the first
local minimum of I over lags 1..40 (the paper finds 5).
"""

import numpy as np

import common

BINS = 16
MAX_LAG = 40


def average_mutual_information(x, bins=BINS, max_lag=MAX_LAG):
    """I(lag) for lag = 0..max_lag, natural log."""
    edges = (x.min(), x.max())
    values = np.empty(max_lag + 1)
    for lag in range(max_lag + 1):
        a = x[: x.size - lag]
        b = x[lag:]
        joint, _, _ = np.histogram2d(a, b, bins=bins, range=[edges, edges])
        p_ab = joint / a.size
        p_a = p_ab.sum(axis=1)
        p_b = p_ab.sum(axis=0)
        outer = np.outer(p_a, p_b)
        nz = p_ab > 0
        values[lag] = np.sum(p_ab[nz] * np.log(p_ab[nz] / outer[nz]))
    return values


def first_minimum(values):
    """The first lag l >= 1 with I(l - 1) > I(l) <= I(l + 1), or None."""
    for lag in range(1, values.size - 1):
        if values[lag - 1] > values[lag] <= values[lag + 1]:
            return lag
    return None


def bench(x, repeats=5):
    """Median seconds of the AMI curve (lags 0..40) and the curve."""
    return common.median_time(lambda: average_mutual_information(x), repeats)


def main():
    _, x = common.load_paper_dataset()
    seconds, values = bench(x)
    lag = first_minimum(values)
    print("lag  AMI (nats)")
    for l in range(min(values.size, 12)):
        print(f"{l:3d}  {values[l]:.4f}")
    print(f"first minimum: lag {lag} (I({lag}) = {values[lag]:.4f}, I({lag + 1}) = {values[lag + 1]:.4f})")
    print(f"time: {seconds * 1e3:.2f} ms (median of 5)")


if __name__ == "__main__":
    main()
