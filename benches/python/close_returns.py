"""The close-return search of the paper (section 3.2; method notes section 5) in NumPy.

Delay vectors S(n) = (x_n, x_{n+Td}) (d = 2, Td = 5); per component the circle distance
|a - b|_c = |wrap(a - b)| (eq. 19), the max over the components. A period-k close return at n when
|S(n + kP) - S(n)| < e, e = 3 % of 2 pi, for every n with n + kP + (d-1) Td < N. A maximal run of
consecutive passing n gives one segment, at the n of least error (the earliest on a tie). The
segment is dropped when it already closes at a proper divisor j of k at the same n (a repeated
shorter orbit). Periods k = 1..16; the computation is vectorised per period.
"""

import math

import numpy as np

import common

DIMENSION = 2


def return_errors(x, lag, count, delay=common.DELAY, dimension=DIMENSION):
    """err[n] = max_c |x[n + c Td + lag] - x[n + c Td]|_c for n = 0..count-1."""
    err = common.circle_distance(x[lag : lag + count], x[:count])
    for c in range(1, dimension):
        o = c * delay
        np.maximum(err, common.circle_distance(x[o + lag : o + lag + count], x[o : o + count]), out=err)
    return err


def errors_at(x, starts, lag, delay=common.DELAY, dimension=DIMENSION):
    """max_c |x[n + c Td + lag] - x[n + c Td]|_c for the indices n in `starts`."""
    err = np.zeros(starts.size)
    for c in range(dimension):
        i = starts + c * delay
        np.maximum(err, common.circle_distance(x[i + lag], x[i]), out=err)
    return err


def close_returns(x, p=common.SAMPLES_PER_PERIOD, delay=common.DELAY, tolerance=common.TOLERANCE,
                  max_period=common.MAX_PERIOD, dimension=DIMENSION):
    """The segments as an array of rows (start, period, error), sorted by period then start."""
    eps = tolerance * 2.0 * math.pi
    reach = (dimension - 1) * delay
    found = []
    for k in range(1, max_period + 1):
        lag = k * p
        count = x.size - lag - reach
        err = return_errors(x, lag, count, delay, dimension)
        passing = np.flatnonzero(err < eps)
        if passing.size == 0:
            continue
        # Run ids of consecutive passing n; in each run the n of least error, earliest on a tie.
        run = np.concatenate(([0], np.cumsum(np.diff(passing) != 1)))
        order = np.lexsort((passing, err[passing], run))
        first = np.concatenate(([True], run[order][1:] != run[order][:-1]))
        starts = np.sort(passing[order][first])
        keep = np.ones(starts.size, dtype=bool)
        for j in range(1, k):
            if k % j == 0:
                # starts + j p + reach < starts + k p + reach < N: the indices exist.
                keep &= errors_at(x, starts, j * p, delay, dimension) >= eps
        starts = starts[keep]
        found.append(np.column_stack([starts, np.full(starts.size, k), err[starts]]))
    return np.concatenate(found) if found else np.empty((0, 3))


def bench(x, repeats=5):
    """Median seconds of the search and the segments."""
    return common.median_time(lambda: close_returns(x), repeats)


def main():
    _, x = common.load_paper_dataset()
    seconds, segments = bench(x)
    print(f"e = 3 % of 2 pi = {common.TOLERANCE * 2 * math.pi:.4f} rad, d = 2, Td = 5, periods 1..16")
    print("period  segments  least error (rad)")
    for k in range(1, common.MAX_PERIOD + 1):
        rows = segments[segments[:, 1] == k]
        least = f"{rows[:, 2].min():.4f}" if rows.size else "-"
        print(f"{k:6d}  {rows.shape[0]:8d}  {least:>17}")
    print(f" total  {segments.shape[0]:8d}")
    print(f"time: {seconds * 1e3:.2f} ms (median of 5)")


if __name__ == "__main__":
    main()
