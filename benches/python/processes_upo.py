"""Whole processes side by side: `hbid identify paper_dataset.csv --method upo` against this
folder's NumPy reference `identify_upo.py`, alternating, wall time of each process.

    python3 benches/python/processes_upo.py [--hbid target/release/hbid] [--rounds 6]

Each round runs the NumPy script once and each `hbid` command (with and without the bootstrap)
three times. Prints the medians and ranges, and the ratios (process against process, and the
NumPy computation alone, as the script times it, against `hbid`'s whole process).
"""

import argparse
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
DATASET = HERE.parents[1] / ".." / "shared" / "fixtures" / "paper_dataset.csv"


def timed(args):
    start = time.perf_counter()
    out = subprocess.run(args, capture_output=True, text=True, check=True)
    return time.perf_counter() - start, out.stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hbid", default=str(HERE.parents[1] / "target" / "release" / "hbid"))
    parser.add_argument("--rounds", type=int, default=6)
    args = parser.parse_args()
    hb, hb0, py, inner = [], [], [], []
    for _ in range(args.rounds):
        seconds, out = timed([sys.executable, str(HERE / "identify_upo.py")])
        py.append(seconds)
        inner.append(float(re.search(r"time .*: ([0-9.]+) ms", out).group(1)) / 1e3)
        for _ in range(3):
            hb.append(timed([args.hbid, "identify", str(DATASET), "--method", "upo", "--quiet"])[0])
            hb0.append(timed([args.hbid, "identify", str(DATASET), "--method", "upo", "--quiet",
                              "--bootstrap", "0"])[0])
    m = statistics.median
    for name, v in [("hbid process", hb), ("hbid process, --bootstrap 0", hb0),
                    ("NumPy process", py), ("NumPy computation (its own timing)", inner)]:
        print(f"{name}: median {m(v) * 1e3:.1f} ms, range {min(v) * 1e3:.1f}-{max(v) * 1e3:.1f} ms")
    print(f"process / process: {m(py) / m(hb):.1f}x; NumPy computation / hbid process: "
          f"{m(inner) / m(hb):.2f}x ({m(inner) / m(hb0):.2f}x without the bootstrap)")


if __name__ == "__main__":
    main()
