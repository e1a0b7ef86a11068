"""SINDy (pysindy) on the DFKI double pendulum, as a peer of `cargo xtask benchmarks`.

Fits pysindy's SINDy with control on the protocol's training records and free-runs it on the test
records as the protocol scores a model:

- State x = (q1, q2, q1', q2') from `pos_meas1/2`, `vel_meas1/2`; control u = (tau1, tau2) from
  `tau_meas1/2`. The derivative handed to SINDy is (q1', q2', q1'', q2''): the measured velocities,
  and their derivative by pysindy's smoothed finite differences (Savitzky-Golay). The equations of
  q1 and q2 are those of a mechanical system, q_i' = v_i; SINDy's sparse regression fits q1'' and
  q2'' (STLSQ) on the library below.
- Library (55 functions, pysindy's GeneralizedLibrary): the angles' functions sin q1, cos q1,
  sin q2, cos q2, sin(q1+q2), cos(q1+q2); the velocities' monomials of degree 1 and 2 (q1', q2',
  q1'^2, q1' q2', q2'^2); the torques tau1, tau2; and the products of the angles' functions with
  each of the other two. That holds the double pendulum's gravity, Coriolis and viscous terms and
  the torques times the first harmonics of the inverse mass matrix in cos q2; no Coulomb term
  (a discontinuity the free run's integrator would have to step through).
- The fit takes each training record's rows after its logger settled to its 2 ms rate (the
  smoothed derivative wants even steps); the free runs start at row 0.
- STLSQ's threshold is chosen by leave-one-training-record-out cross-validation on the 1 s free
  run from row 0 (the mean RMSE over folds and joints), from THRESHOLDS, as the window of the
  other model.
- Free run: from each test record's state at --test's start row (the protocol's is 0), driven by
  the measured torques through a cubic spline (not-a-knot), DOP853 at rtol = atol = 1e-10,
  sampled at the record's time stamps; the error is wrap(q_sim - q_meas) into [-pi, pi); the
  score is its RMSE over each horizon (the rows with t - t0 <= the horizon). A run that fails or
  leaves the finite numbers counts pi for each remaining sample, as the protocol says, and is
  reported as failed.

With --published YML the published model (the README's equations, friction cf atan(100 q')) is
also run by the protocol itself, from row 0.

Usage:
    python dfki_sindy.py --train trajectory_00.csv ... --test 04,0,trajectory_04.csv ...
        [--horizons 1,2] [--published model_2.0_parameters.yml] --out OUT.json
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pysindy as ps
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

THRESHOLDS: list[float] = [0.1, 0.3, 1.0, 3.0]
CV_HORIZON = 1.0  # s


def read(path: Path) -> dict[str, np.ndarray]:
    with open(path) as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return {name: data[:, i] for i, name in enumerate(header)}


def settled_row(t: np.ndarray) -> int:
    """The first row after the logger's unsettled first steps (longer than the median's 1.25)."""
    step = np.median(np.diff(t))
    k = 0
    while k + 1 < len(t) and t[k + 1] - t[k] > 1.25 * step:
        k += 1
    return k


def states(rec: dict[str, np.ndarray], start: int):
    t = rec["time"][start:]
    x = np.column_stack(
        [rec["pos_meas1"], rec["pos_meas2"], rec["vel_meas1"], rec["vel_meas2"]]
    )[start:]
    u = np.column_stack([rec["tau_meas1"], rec["tau_meas2"]])[start:]
    return t, x, u


def library() -> ps.GeneralizedLibrary:
    angles = ps.CustomLibrary(
        library_functions=[
            lambda a: np.sin(a),
            lambda a: np.cos(a),
            lambda a, b: np.sin(a + b),
            lambda a, b: np.cos(a + b),
        ],
        function_names=[
            lambda a: f"sin({a})",
            lambda a: f"cos({a})",
            lambda a, b: f"sin({a}+{b})",
            lambda a, b: f"cos({a}+{b})",
        ],
    )
    velocities = ps.PolynomialLibrary(degree=2, include_bias=False)
    torques = ps.IdentityLibrary()
    return ps.GeneralizedLibrary(
        [angles, velocities, torques],
        tensor_array=[[1, 1, 0], [1, 0, 1]],
        inputs_per_library=[[0, 1], [2, 3], [4, 5]],
    )


def derivative(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(q1', q2', q1'', q2''): the measured velocities and their smoothed finite differences."""
    acc = ps.SmoothedFiniteDifference()._differentiate(x[:, 2:], t)
    return np.column_stack([x[:, 2], x[:, 3], acc])


def fit(records: list[tuple[np.ndarray, ...]], threshold: float) -> ps.SINDy:
    xs = [r[1] for r in records]
    us = [r[2] for r in records]
    ts = [r[0] for r in records]
    dxs = [derivative(r[0], r[1]) for r in records]
    model = ps.SINDy(
        feature_library=library(),
        optimizer=ps.STLSQ(threshold=threshold, alpha=1e-6),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(xs, t=ts, x_dot=dxs, u=us, feature_names=["q1", "q2", "q1'", "q2'", "tau1", "tau2"])
    return model


def features(x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The library's functions at one state and torque, in the library's order (checked against
    pysindy's own transform in `accelerations_of`): its own evaluation costs tens of milliseconds
    a call, too slow for an adaptive integrator's thousands of calls."""
    q1, q2, v1, v2 = x
    angles = np.array(
        [math.sin(q1), math.sin(q2), math.cos(q1), math.cos(q2), math.sin(q1 + q2), math.cos(q1 + q2)]
    )
    velocities = np.array([v1, v2, v1 * v1, v1 * v2, v2 * v2])
    return np.concatenate(
        [angles, velocities, u, np.outer(angles, velocities).ravel(), np.outer(angles, u).ravel()]
    )


def accelerations_of(model: ps.SINDy, check: tuple[np.ndarray, np.ndarray]):
    """The model's q1'', q2'' at one state and torque."""
    coef = model.coefficients()[2:]
    x, u = check
    theta = np.asarray(model.feature_library.transform(np.column_stack([x, u])))
    mine = np.array([features(a, b) for a, b in zip(x, u)])
    if theta.shape != mine.shape or not np.allclose(theta, mine, rtol=1e-12, atol=1e-12):
        raise SystemExit("the library's order is not the one features() assumes")

    def acc(x: np.ndarray, u: np.ndarray) -> np.ndarray:
        return coef @ features(x, u)

    return acc


def free_run(acc, t: np.ndarray, x: np.ndarray, u: np.ndarray, n: int) -> dict[str, Any]:
    """The free run over the first n samples: per joint the wrapped error, and how it ended."""
    t = t[:n]
    spline = CubicSpline(t, u[:n], bc_type="not-a-knot")

    def rhs(s: float, y: np.ndarray) -> np.ndarray:
        a = acc(y, spline(s))
        return np.array([y[2], y[3], a[0], a[1]])

    failed = None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            sol = solve_ivp(rhs, (t[0], t[-1]), x[0], method="DOP853", t_eval=t, rtol=1e-10, atol=1e-10)
            if not sol.success:
                failed = sol.message
            q = sol.y[:2].T
        except (FloatingPointError, ValueError, OverflowError) as e:
            failed = str(e)
            q = np.zeros((0, 2))
    done = len(q)
    finite = np.all(np.isfinite(q), axis=1)
    if not np.all(finite):
        done = int(np.argmin(finite))
        failed = failed or "left the finite numbers"
    err = np.full((n, 2), math.pi)
    e = q[:done] - x[:done, :2]
    err[:done] = (e + math.pi) % (2 * math.pi) - math.pi
    return {"error": err, "failed": failed, "failed_at_s": None if failed is None else float(t[done - 1] - t[0]) if done else 0.0}


def rmse(err: np.ndarray, n: int) -> dict[str, float]:
    return {q: float(np.sqrt(np.mean(err[:n, i] ** 2))) for i, q in enumerate(["q1", "q2"])}


def published_acc(path: Path):
    p = {}
    for line in path.read_text().splitlines():
        if ":" in line:
            k, v = line.split(":", 1)
            p[k.strip()] = float(v)
    l1, g, gr, ir, i2 = p["l1"], p["g"], p["gr"], p["Ir"], p["I2"]
    ia = p["I1"] + p["m2"] * l1**2
    mr1 = p["m1"] * p["r1"] + p["m2"] * l1
    mr2 = p["m2"] * p["r2"]

    def acc(y: np.ndarray, tau: np.ndarray) -> np.ndarray:
        q1, q2, v1, v2 = y
        c, s = math.cos(q2), math.sin(q2)
        m11 = ia + i2 + 2 * l1 * mr2 * c + (gr**2 + 1) * ir
        m12 = i2 + l1 * mr2 * c - gr * ir
        m22 = i2 + gr**2 * ir
        h1 = (
            -l1 * mr2 * s * (2 * v1 * v2 + v2**2)
            + g * mr1 * math.sin(q1)
            + g * mr2 * math.sin(q1 + q2)
            + p["b1"] * v1
            + p["cf1"] * math.atan(100 * v1)
        )
        h2 = l1 * mr2 * s * v1**2 + g * mr2 * math.sin(q1 + q2) + p["b2"] * v2 + p["cf2"] * math.atan(100 * v2)
        r1, r2 = tau[0] - h1, tau[1] - h2
        det = m11 * m22 - m12 * m12
        return np.array([(m22 * r1 - m12 * r2) / det, (m11 * r2 - m12 * r1) / det])

    return acc


def rows_within(t: np.ndarray, horizon: float) -> int:
    """The rows with t - t0 <= horizon (a stamp's rounding is not a row past it)."""
    return int(np.count_nonzero(t - t[0] <= horizon + 1e-9))


def scores(acc, t, x, u, horizons: list[float]) -> dict[str, Any]:
    rows = [rows_within(t, h) for h in horizons]
    run = free_run(acc, t, x, u, max(rows))
    out: dict[str, Any] = {f"{h:g}s": rmse(run["error"], n) for h, n in zip(horizons, rows)}
    out["failed"] = run["failed"]
    out["failed_at_s"] = run["failed_at_s"]
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--train", type=Path, action="append", required=True, help="a training record")
    ap.add_argument("--test", action="append", required=True, help="NAME,START_ROW,PATH of a test record")
    ap.add_argument("--horizons", default="1,2", help="scored horizons from the start row, s")
    ap.add_argument("--published", type=Path, help="the published parameters (model_2.0_parameters.yml)")
    ap.add_argument("--out", type=Path, required=True, help="output JSON file")
    args = ap.parse_args(argv)
    horizons = [float(h) for h in args.horizons.split(",")]

    records = [read(p) for p in args.train]
    train = [states(r, settled_row(r["time"])) for r in records]
    whole = [states(r, 0) for r in records]
    names = [p.stem.removeprefix("trajectory_") for p in args.train]
    cv = []
    for threshold in THRESHOLDS:
        folds = {}
        for k, name in enumerate(names):
            model = fit(train[:k] + train[k + 1 :], threshold)
            t, x, u = whole[k]
            folds[name] = scores(accelerations_of(model, (x[:50], u[:50])), t, x, u, [CV_HORIZON])["1s"]
        mean = {q: float(np.mean([f[q] for f in folds.values()])) for q in ["q1", "q2"]}
        cv.append({"threshold": threshold, "folds": folds, **mean, "mean": (mean["q1"] + mean["q2"]) / 2})
        print(f"sindy cv threshold {threshold}: {mean}", file=sys.stderr)
    threshold = min(cv, key=lambda c: c["mean"])["threshold"]

    started = time.perf_counter()
    model = fit(train, threshold)
    seconds = time.perf_counter() - started
    coef = model.coefficients()
    features = model.get_feature_names()
    equations = {
        q: {f: float(c) for f, c in zip(features, coef[row]) if c != 0.0} for q, row in [("q1''", 2), ("q2''", 3)]
    }
    acc = accelerations_of(model, (train[0][1][:50], train[0][2][:50]))
    tests = {}
    published: dict[str, Any] = {}
    pub = published_acc(args.published) if args.published else None
    for spec in args.test:
        name, start, path = spec.split(",", 2)
        rec = read(Path(path))
        t, x, u = states(rec, int(start))
        tests[name] = scores(acc, t, x, u, horizons)
        if pub is not None:
            t0, x0, u0 = states(rec, 0)
            published[name] = {"row_0": scores(pub, t0, x0, u0, horizons)}
        print(f"sindy {name}: {tests[name]}", file=sys.stderr)

    result = {
        "tool": "pysindy",
        "version": ps.__version__,
        "library": features,
        "threshold": threshold,
        "cv": cv,
        "equations": equations,
        "terms": int(np.count_nonzero(coef[2:])),
        "fit_seconds": seconds,
        "rmse_rad": tests,
        "published_model_by_protocol": published or None,
    }
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
