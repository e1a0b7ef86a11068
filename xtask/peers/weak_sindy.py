"""Weak-form SINDy (pysindy's WeakPDELibrary) on a record of a forced oscillator, as a peer.

Reads a CSV record (time in the first column, the coordinate in the second), builds the candidate
library named with hbid's term names (`x'`, `sign(x')`, `x'*|x'|`, `x'^3`, `sin(x)`, `cos(2t)*sin(x)`,
`x^3`, `cos(t)`, ...), and fits the second-order equation as pysindy does for such systems: the
states are the velocity and the candidate columns (the velocity estimated from the samples by pysindy's
smoothed finite differences, since the library needs it as data), the drive is given as known
columns, and the velocity's equation `x'' = -Σ c_i g_i` is found by weak-form sparse regression
(STLSQ) over test functions on subdomains.

The candidate columns g_i are handed to pysindy as control inputs and its function library is the
identity on them, so that both tools choose among exactly the same candidates; the weak
formulation, the test functions, the integration and the sparse regression are pysindy's.

Writes a JSON object: `{"terms": {name: coefficient, ...}, "threshold": λ, "subdomains": K,
"half_width": H, "velocity": "...", "pysindy": version}` with every candidate's coefficient in
hbid's sign convention (`x'' + Σ c_i g_i = 0`; 0 for a dropped term).
"""

import argparse
import json
import re
import sys
import warnings

import numpy as np


def drive_factor(name, phase):
    """cos(kt) / sin(kt) of the drive phase `phase` (W t)."""
    m = re.fullmatch(r"(cos|sin)\((\d*)t\)", name)
    if not m:
        return None
    k = int(m.group(2)) if m.group(2) else 1
    return (np.cos if m.group(1) == "cos" else np.sin)(k * phase)


def position_factor(name, x):
    m = re.fullmatch(r"(cos|sin)\((\d*)x\)", name)
    if m:
        k = int(m.group(2)) if m.group(2) else 1
        return (np.cos if m.group(1) == "cos" else np.sin)(k * x)
    if name == "x":
        return x
    m = re.fullmatch(r"x\^(\d+)", name)
    if m:
        return x ** int(m.group(1))
    return None


def velocity_factor(name, v):
    return {
        "x'": lambda: v,
        "sign(x')": lambda: np.sign(v),
        "x'*|x'|": lambda: v * np.abs(v),
        "x'^3": lambda: v**3,
    }.get(name, lambda: None)()


def split_factors(term):
    """Split `cos(2t)*sin(x)*x'` at the top-level `*` (not the one inside `x'*|x'|`)."""
    parts, depth, cur = [], 0, ""
    i = 0
    while i < len(term):
        ch = term[i]
        if term.startswith("x'*|x'|", i):
            parts.append("x'*|x'|")
            i += len("x'*|x'|")
            if i < len(term) and term[i] == "*":
                i += 1
            continue
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        if ch == "*" and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
        i += 1
    if cur:
        parts.append(cur)
    return parts


def column(term, phase, x, v):
    value = np.ones_like(x)
    for f in split_factors(term):
        for make in (
            lambda: drive_factor(f, phase),
            lambda: position_factor(f, x),
            lambda: velocity_factor(f, v),
        ):
            got = make()
            if got is not None:
                value = value * got
                break
        else:
            raise SystemExit(f"weak_sindy.py: unknown factor {f!r} in term {term!r}")
    return value


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--record", required=True)
    ap.add_argument("--circle", action="store_true", help="the coordinate is a wrapped angle")
    ap.add_argument("--drive-frequency", type=float, required=True, help="W, rad per time unit")
    ap.add_argument("--terms", required=True, help="candidate terms, separated by ';'")
    ap.add_argument("--threshold", type=float, required=True, help="STLSQ threshold λ")
    ap.add_argument("--periods-per-subdomain", type=float, default=3.0)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()

    import pysindy as ps

    data = np.loadtxt(a.record, delimiter=",", skiprows=1, usecols=(0, 1))
    t, x = data[:, 0], data[:, 1]
    if a.circle:
        x = np.unwrap(x)
    dt = float(np.median(np.diff(t)))
    v = ps.SmoothedFiniteDifference()._differentiate(x, t)
    phase = a.drive_frequency * t
    terms = [s.strip() for s in a.terms.split(";") if s.strip()]
    damping = "x'" in terms
    inputs = [s for s in terms if s != "x'"]
    u = np.column_stack([column(s, phase, x, v) for s in inputs])

    period = 2 * np.pi / a.drive_frequency
    half = 0.5 * a.periods_per_subdomain * period
    k = max(10, int((t[-1] - t[0]) / period))
    # The inputs of the library are the velocity and the candidate columns; its functions are
    # the identity, so its features are exactly the candidates. Only the velocity's equation
    # (the first) is read; the others are fitted by pysindy and ignored.
    # The library draws its subdomains at random when it is built: seeded first, so that a run is
    # repeatable.
    np.random.seed(0)
    library = ps.WeakPDELibrary(
        function_library=ps.PolynomialLibrary(degree=1, include_bias=False),
        spatiotemporal_grid=t,
        K=k,
        H_xt=[half],
        p=4,
    )
    model = ps.SINDy(feature_library=library, optimizer=ps.STLSQ(threshold=a.threshold))
    np.random.seed(0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(np.column_stack([v, u]), t=t)
    coef = model.coefficients()[0]
    if not damping:
        coef = coef[1:]
    names = (["x'"] if damping else []) + inputs
    out = {
        "terms": {n: -float(c) for n, c in zip(names, coef)},
        "threshold": a.threshold,
        "subdomains": k,
        "half_width": half,
        "step": dt,
        "velocity": "pysindy SmoothedFiniteDifference (Savitzky-Golay, its defaults)",
        "pysindy": ps.__version__ if hasattr(ps, "__version__") else "unknown",
    }
    with open(a.out, "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
