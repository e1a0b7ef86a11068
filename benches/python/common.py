"""Shared pieces of the Python reference benches: the data, the constants, a timer.

The record is `shared/fixtures/paper_dataset.csv` (columns `t,theta`, lines starting with `#` are
comments): 30000 samples of the wrapped angle theta in [-pi, pi) at P = 25 samples per forcing
period 2 pi, after 200 periods of transient.
"""

import math
import os
import statistics
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
# benches/python -> repository root -> the checkout's parent, which holds shared/.
FIXTURES = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared", "fixtures"))
PAPER_DATASET = os.path.join(FIXTURES, "paper_dataset.csv")
REFERENCE_TRAJECTORY = os.path.join(FIXTURES, "reference_trajectory.csv")

# The system x'' + c x' + (1/r^2) sin x - f sin(t) cos x = 0 (method notes, section 1).
F = 1.52
C = 0.03
R = 0.8333
SAMPLES_PER_PERIOD = 25  # P
STEP = 2.0 * math.pi / SAMPLES_PER_PERIOD  # h
DELAY = 5  # Td, the first minimum of the AMI on the paper's data
TOLERANCE = 0.03  # e, as a fraction of the span 2 pi
MAX_PERIOD = 16

# Unknowns in the order c_r, then per basis function (cos x, sin x): n, p, q.
NAMES = ["c_r", "n_cos", "p_cos", "q_cos", "n_sin", "p_sin", "q_sin"]
TRUTH = np.array([C, 0.0, -F, 0.0, 0.0, 0.0, 1.0 / R**2])


def load_csv(path):
    """The columns of a fixture (comment lines `#` skipped, header row read) as a dict of arrays."""
    with open(path, encoding="utf-8") as f:
        lines = [line for line in f if line.strip() and not line.lstrip().startswith("#")]
    header = [name.strip() for name in lines[0].split(",")]
    table = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    if table.shape[1] != len(header):
        raise ValueError(f"{path}: {table.shape[1]} columns of data, header names {len(header)}")
    return {name: np.ascontiguousarray(table[:, i]) for i, name in enumerate(header)}


def load_paper_dataset(path=PAPER_DATASET):
    """(t, theta) of the paper's data set."""
    cols = load_csv(path)
    return cols["t"], cols["theta"]


def wrap(x):
    """((x + pi) mod 2 pi) - pi, in [-pi, pi)."""
    return np.mod(x + math.pi, 2.0 * math.pi) - math.pi


def circle_distance(a, b):
    """|a - b|_c = |wrap(a - b)| (paper eq. 19), elementwise, in [0, pi]."""
    return np.abs(wrap(a - b))


def median_time(fn, repeats, warmup=True):
    """Runs `fn()` once untimed (if `warmup`), then `repeats` timed times.

    Returns (median seconds, the result of the last call).
    """
    if warmup:
        fn()
    times = []
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def format_errors(coefficients):
    """Lines `name  value  error` against the truth."""
    lines = []
    for name, value, truth in zip(NAMES, coefficients, TRUTH):
        lines.append(f"  {name:<6} {value:+.10f}   truth {truth:+.7f}   error {value - truth:+.3e}")
    worst = np.max(np.abs(np.asarray(coefficients) - TRUTH))
    lines.append(f"  largest |error|: {worst:.3e}")
    return "\n".join(lines)
