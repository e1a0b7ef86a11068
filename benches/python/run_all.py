"""Times every stage of the Python reference path on the paper's data set, in one run.

Prints a Markdown table `| stage | python seconds (median of N) | what |` and one JSON line
(prefixed `JSON `) with the same numbers, for combining with the Rust figures. Needs numpy and
scipy; without them it says so and exits 0 (these benches are optional).

    python3 run_all.py [--repeats N] [--simulate-repeats N] [--skip-simulate]
"""

import argparse
import json
import os
import platform
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5,
                        help="timed runs of each fast stage, after one warm-up (default 5)")
    parser.add_argument("--simulate-repeats", type=int, default=1,
                        help="timed runs of the simulation, no warm-up (default 1: it takes seconds)")
    parser.add_argument("--skip-simulate", action="store_true", help="leave the simulation out")
    args = parser.parse_args()
    if args.repeats < 1 or args.simulate_repeats < 1:
        parser.error("repeats must be at least 1")

    try:
        import numpy
        import scipy
    except ImportError as missing:
        print(f"Python benches skipped: {missing.name} is not installed (pip install numpy scipy).")
        return 0

    import ami
    import close_returns
    import common
    import fnn
    import identify_upo
    import identify_windowed
    import simulate

    t, x = common.load_paper_dataset()
    n = args.repeats
    results = []  # (stage, seconds, repeats, what, check)

    if not args.skip_simulate:
        seconds, (_, sim) = simulate.bench(repeats=args.simulate_repeats)
        results.append(("simulate", seconds, args.simulate_repeats,
                        "solve_ivp DOP853 rtol 1e-10, 30000 samples after 200 transient periods",
                        {"samples": int(sim.size)}))

    seconds, curve = ami.bench(x, repeats=n)
    results.append(("ami", seconds, n, "average mutual information, histogram2d 16 boxes, lags 0..40",
                    {"first_minimum": ami.first_minimum(curve)}))

    seconds, fractions = fnn.bench(x, repeats=n)
    results.append(("fnn", seconds, n, "false nearest neighbours, cKDTree, Td 5, d 1..6",
                    {"fractions": [round(float(f), 4) for f in fractions]}))

    seconds, segments = close_returns.bench(x, repeats=n)
    results.append(("close_returns", seconds, n, "close returns, d 2, Td 5, e 3 % of 2 pi, periods 1..16",
                    {"segments": int(segments.shape[0])}))

    seconds, (coefficients, count) = identify_upo.bench(t, x, repeats=n)
    results.append(("identify_upo", seconds, n,
                    f"close returns + eq. 15 rows (rfft, K 1, M 12) over {count} segments + lstsq",
                    {"coefficients": coefficients.tolist(),
                     "max_error": float(numpy.max(numpy.abs(coefficients - common.TRUTH)))}))

    seconds, (coefficients, count) = identify_windowed.bench(t, x, repeats=n)
    results.append(("identify_windowed", seconds, n,
                    f"weak form, {count} windows of 2 periods, 33 test functions, trapezoid + lstsq",
                    {"coefficients": coefficients.tolist(),
                     "max_error": float(numpy.max(numpy.abs(coefficients - common.TRUTH)))}))

    print("| stage | python seconds (median of N) | what |")
    print("| --- | ---: | --- |")
    for stage, seconds, repeats, what, _ in results:
        print(f"| `{stage}` | {seconds:.4g} (N = {repeats}) | {what} |")

    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    record = {
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "load_average_1min_after": load[0] if load else None,
        "stages": {stage: {"seconds": seconds, "repeats": repeats, "check": check}
                   for stage, seconds, repeats, _, check in results},
    }
    print("JSON " + json.dumps(record))
    return 0


if __name__ == "__main__":
    sys.exit(main())
