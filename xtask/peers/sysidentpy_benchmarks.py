"""SysIdentPy's polynomial NARX (structure chosen by FROLS) on Silverbox and EMPS, as a peer.

Fits sysidentpy's `FROLS` with a `Polynomial` basis on the estimation record of each benchmark
and scores a free-run simulation of the test records by the benchmarks' official protocols:

- Silverbox (`SNLS80mV.csv`, the `nonlinear_benchmarks` split): train rows [40650, 105712);
  tests multisine [105712, 127400), arrow full [100, 40575), arrow no-extrapolation
  [100, 32100). The first 50 measured outputs of each test set are its initial state (the
  model's lagged outputs); the simulation runs from the test input alone; the score is the RMSE
  of y over the remaining samples, in mV, as `[multisine, arrow_full, arrow_no_extrapolation]`.
- EMPS (`emps_train_txp.csv` / `emps_test_txp.csv`, columns t, x, p): trained on the
  estimation record, simulated from the test record's force p alone with its first 20 measured
  positions as initial state; the score is the RMSE of x over the remaining samples, in mm.

Configurations (constants below) are fixed in advance; nothing is chosen on test data here.
Silverbox uses sysidentpy's own published benchmark configuration (its Silverbox tutorial /
book case study), which fits a *different* model for each test set; the three Silverbox result
fields `terms`, `fit_seconds` and `simulate_seconds` are therefore lists aligned with `rmse_mv`.
(The two arrow configurations differ only in their term cap; when the ERR tolerance stops both
searches earlier, as it does, they are the same model and it is fitted once.) Every distinct
fitted model is also scored on all three test sets (`rmse_mv_by_model`), as context only. The
degree-3, lag-14 fit builds a 65 062 x 4 495 regressor matrix: about 9 GB of memory, ~1.5 min.
sysidentpy publishes no EMPS configuration, so EMPS uses the README quick-start configuration
(FROLS, polynomial degree 2, ylag = xlag = 2, AIC order selection, least squares) with
`n_info_values` at FROLS's default of 15, which is the whole candidate set at these lags.

`--quick` fits only the Silverbox multisine model (degree 2, lag 7) and scores all three test
sets with it (a single model, seconds instead of minutes, < 0.5 GB); EMPS is unchanged.

Usage:
    python sysidentpy_benchmarks.py --silverbox SNLS80mV.csv --emps-train emps_train_txp.csv \
        --emps-test emps_test_txp.csv [--quick] --out OUT.json

Writes OUT.json:
    {"tool": "sysidentpy", "version": "...",
     "silverbox": {"config": {...}, "terms": [..], "fit_seconds": [..],
                   "simulate_seconds": [..], "rmse_mv": [multisine, arrow_full, arrow_no_extr],
                   "rmse_mv_by_model": {model: [..]}, "note": "..."},
     "emps": {"config": {...}, "terms": N, "fit_seconds": s, "simulate_seconds": s,
              "rmse_mm": x}}
`fit_seconds` is the wall time of `model.fit` alone (time.perf_counter); `simulate_seconds`
that of `model.predict` (the free run). A simulation that diverges (non-finite output) gives
a null RMSE and a "note" instead of failing. A one-line summary goes to stderr.
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
import sysidentpy
from sysidentpy.basis_function import Polynomial
from sysidentpy.model_structure_selection import FROLS
from sysidentpy.parameter_estimation import LeastSquares

# --- Silverbox protocol (nonlinear_benchmarks.Silverbox(), 0-based half-open row ranges) ----
SILVERBOX_TRAIN: tuple[int, int] = (40650, 105712)
SILVERBOX_TESTS: dict[str, tuple[int, int]] = {
    "multisine": (105712, 127400),
    "arrow_full": (100, 40575),
    "arrow_no_extrapolation": (100, 32100),
}
SILVERBOX_INIT_WINDOW = 50  # measured outputs usable as initial state
SILVERBOX_ROWS = 131072

# --- Silverbox configuration: sysidentpy's own, one model per test set -----------------------
SILVERBOX_SOURCE = (
    "sysidentpy docs, tutorial 'Silver Box System' (also book ch. 10 'Case Studies'): "
    "https://github.com/wilsonrljr/sysidentpy/blob/main/docs/en/user-guide/tutorials/"
    "silver-box-system.md (commit a4786ed, 'verified with SysIdentPy 0.9.0'); "
    "https://sysidentpy.org/book/10%20-%20Case%20Studies/"
)
SILVERBOX_PUBLISHED_RMSE_MV: list[float] = [7.727, 4.148, 2.229]
# Shared by all three models: FROLS with least squares, structure size by ERR tolerance /
# n_terms (no information criterion), FROLS's default model_type "NARMAX" (NARX terms only
# with a plain least-squares estimator).
SILVERBOX_COMMON: dict[str, Any] = {
    "algorithm": "FROLS",
    "basis_function": "Polynomial",
    "estimator": "LeastSquares",
    "order_selection": False,
}
SILVERBOX_MODELS: dict[str, dict[str, Any]] = {
    "multisine": {"degree": 2, "ylag": 7, "xlag": 7, "err_tol": 0.999, "n_terms": 40},
    "arrow_full": {"degree": 3, "ylag": 14, "xlag": 14, "err_tol": 0.9999, "n_terms": 80},
    "arrow_no_extrapolation": {
        "degree": 3, "ylag": 14, "xlag": 14, "err_tol": 0.9999, "n_terms": 40,
    },
}
SILVERBOX_QUICK_MODEL = "multisine"  # --quick: this one model for all three test sets

# --- EMPS protocol --------------------------------------------------------------------------
EMPS_INIT_WINDOW = 20

# --- EMPS configuration: sysidentpy documents none; its README quick-start one ---------------
EMPS_SOURCE = (
    "sysidentpy publishes no EMPS configuration; this is its README quick-start FROLS "
    "configuration (https://github.com/wilsonrljr/sysidentpy/blob/main/README.md: "
    "Polynomial(degree=2), LeastSquares, ylag=xlag=2, order_selection with AIC) with "
    "n_info_values at the FROLS default of 15 (= the whole candidate set at these lags), "
    "fixed before looking at any result"
)
EMPS_MODEL: dict[str, Any] = {
    "algorithm": "FROLS",
    "basis_function": "Polynomial",
    "estimator": "LeastSquares",
    "degree": 2,
    "ylag": 2,
    "xlag": 2,
    "order_selection": True,
    "info_criteria": "aic",
    "n_info_values": 15,
    "err_tol": None,
    "n_terms": None,
}


def read_silverbox(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Return (u, y) in volts from SNLS80mV.csv (header "V1","V2", trailing commas)."""
    u: list[float] = []
    y: list[float] = []
    with path.open() as f:
        header = f.readline().replace('"', "").strip().rstrip(",").split(",")
        if header[:2] != ["V1", "V2"]:
            raise ValueError(f"{path}: unexpected header {header}")
        for line in f:
            fields = line.strip().rstrip(",").split(",")
            if fields == [""]:
                continue
            u.append(float(fields[0]))
            y.append(float(fields[1]))
    if len(u) != SILVERBOX_ROWS:
        raise ValueError(f"{path}: {len(u)} data rows, expected {SILVERBOX_ROWS}")
    return np.asarray(u), np.asarray(y)


def read_txp(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Return (p, x) from an EMPS `t,x,p` CSV (lines starting with '#' are comments)."""
    rows: list[list[float]] = []
    columns: list[str] | None = None
    with path.open() as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            if columns is None:
                columns = [c.strip() for c in line.split(",")]
                continue
            rows.append([float(v) for v in line.split(",")])
    if columns is None or "x" not in columns or "p" not in columns:
        raise ValueError(f"{path}: no t,x,p header")
    data = np.asarray(rows)
    return data[:, columns.index("p")], data[:, columns.index("x")]


def make_frols(cfg: dict[str, Any]) -> FROLS:
    """A FROLS polynomial NARX model from one configuration dictionary."""
    kwargs: dict[str, Any] = {
        "ylag": cfg["ylag"],
        "xlag": cfg["xlag"],
        "basis_function": Polynomial(degree=cfg["degree"]),
        "estimator": LeastSquares(),
        "order_selection": cfg.get("order_selection", False),
        "err_tol": cfg.get("err_tol"),
        "n_terms": cfg.get("n_terms"),
    }
    if "info_criteria" in cfg:
        kwargs["info_criteria"] = cfg["info_criteria"]
    if "n_info_values" in cfg:
        kwargs["n_info_values"] = cfg["n_info_values"]
    return FROLS(**kwargs)


def fit(model: FROLS, u: np.ndarray, y: np.ndarray) -> float:
    """Fit on column vectors; return the wall time of `model.fit` alone."""
    x_col, y_col = u.reshape(-1, 1), y.reshape(-1, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        model.fit(X=x_col, y=y_col)
        return time.perf_counter() - t0


def free_run_rmse(
    model: FROLS, u: np.ndarray, y: np.ndarray, init: int
) -> tuple[float | None, float, str | None]:
    """Free-run RMSE of y[init:] from u, the initial lagged outputs taken from y[:init].

    The simulation starts `max_lag` samples before `init` with the measured outputs there as
    its initial state (as sysidentpy's tutorial does), so only the first `init` measured
    outputs are used. Returns (rmse or None if the simulation diverged, predict seconds, note).
    """
    lag = int(model.max_lag)
    if lag > init:
        return None, 0.0, f"max_lag {lag} exceeds the {init}-sample initialisation window"
    start = init - lag
    x_col = u[start:].reshape(-1, 1)
    y0 = y[start:init].reshape(-1, 1)
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.perf_counter()
            yhat = model.predict(X=x_col, y=y0)
            seconds = time.perf_counter() - t0
    except (FloatingPointError, OverflowError, ValueError) as exc:
        return None, 0.0, f"simulation failed: {type(exc).__name__}: {exc}"
    yhat = np.asarray(yhat, dtype=float).reshape(-1)[lag:]
    target = y[init:]
    if yhat.shape != target.shape:
        raise RuntimeError(f"prediction length {yhat.shape} != target {target.shape}")
    if not np.all(np.isfinite(yhat)):
        first_bad = int(np.argmax(~np.isfinite(yhat)))
        return None, seconds, f"free run diverged (non-finite from sample {init + first_bad})"
    rmse = float(np.sqrt(np.mean((target - yhat) ** 2)))
    if not math.isfinite(rmse):
        return None, seconds, "free run diverged (RMSE overflow)"
    return rmse, seconds, None


def same_model(fitted_cfg: dict[str, Any], cfg: dict[str, Any], fitted: FROLS) -> bool:
    """Whether fitting `cfg` would give exactly the model already fitted from `fitted_cfg`.

    FROLS is greedy and deterministic: two configurations that differ only in `n_terms` give
    the same model when the ERR tolerance stopped the search before either term cap.
    """
    others_equal = all(
        fitted_cfg.get(k) == cfg.get(k) for k in set(fitted_cfg) | set(cfg) if k != "n_terms"
    )
    caps = [c for c in (fitted_cfg.get("n_terms"), cfg.get("n_terms")) if c is not None]
    return (
        others_equal
        and fitted_cfg.get("err_tol") is not None
        and len(caps) == 2
        and len(fitted.final_model) < min(caps)
    )


def run_silverbox(path: Path, quick: bool) -> dict[str, Any]:
    u, y = read_silverbox(path)
    lo, hi = SILVERBOX_TRAIN
    u_train, y_train = u[lo:hi], y[lo:hi]
    names = list(SILVERBOX_TESTS)
    model_of = {n: (SILVERBOX_QUICK_MODEL if quick else n) for n in names}

    # Fit each configuration once (reusing an identical model, see same_model).
    fitted: dict[str, tuple[FROLS, float]] = {}
    fit_of: dict[str, str] = {}
    for name in names:
        key = model_of[name]
        cfg = SILVERBOX_MODELS[key]
        twin = next(
            (k for k, (m, _) in fitted.items() if same_model(SILVERBOX_MODELS[k], cfg, m)),
            None,
        )
        if twin is None:
            model = make_frols(cfg)
            fitted[key] = (model, fit(model, u_train, y_train))
            twin = key
        fit_of[name] = twin

    # Score every fitted model on every test set; the reported score of a test set is that
    # of its own (documented) model, the others are context (no selection is made on them).
    scores: dict[str, list[tuple[float | None, float, str | None]]] = {
        key: [
            free_run_rmse(model, u[a:b], y[a:b], SILVERBOX_INIT_WINDOW)
            for a, b in SILVERBOX_TESTS.values()
        ]
        for key, (model, _) in fitted.items()
    }
    terms: list[int] = []
    fit_s: list[float] = []
    sim_s: list[float] = []
    rmse_mv: list[float | None] = []
    notes: list[str] = []
    for i, name in enumerate(names):
        model, seconds = fitted[fit_of[name]]
        rmse, sim, note = scores[fit_of[name]][i]
        terms.append(len(model.final_model))
        fit_s.append(round(seconds, 4))
        sim_s.append(round(sim, 4))
        rmse_mv.append(None if rmse is None else 1000.0 * rmse)
        if note:
            notes.append(f"{name}: {note}")
        if fit_of[name] != model_of[name]:
            notes.append(
                f"{name}: its configuration gives the same model as {fit_of[name]}'s (ERR "
                f"tolerance reached at {len(model.final_model)} terms, below both n_terms "
                "caps), fitted once; fit_seconds repeats that fit"
            )

    config: dict[str, Any] = {
        "source": SILVERBOX_SOURCE,
        "protocol": (
            "train rows [40650,105712); free run from the test input; the first 50 measured "
            "outputs of each test set give the initial lagged outputs (the run starts max_lag "
            "samples before sample 50); RMSE of y over samples 50.. of each test set, mV"
        ),
        "per_test_set_models": not quick,
        "quick": quick,
        **SILVERBOX_COMMON,
        "models": {n: SILVERBOX_MODELS[model_of[n]] for n in names},
        "test_sets": names,
        "published_rmse_mv": SILVERBOX_PUBLISHED_RMSE_MV,
    }
    out: dict[str, Any] = {
        "config": config,
        "terms": terms,
        "fit_seconds": fit_s,
        "simulate_seconds": sim_s,
        "rmse_mv": rmse_mv,
        # Each distinct fitted model on all three test sets (single-model rows, for context).
        "rmse_mv_by_model": {
            key: [None if r is None else 1000.0 * r for r, _, _ in rows]
            for key, rows in scores.items()
        },
    }
    if not quick:
        notes.insert(
            0,
            "sysidentpy's published Silverbox configuration fits one model per test set "
            "(degree 2 / lag 7 for multisine, degree 3 / lag 14 with 80 resp. 40 terms for "
            "the arrows); terms, fit_seconds and simulate_seconds are lists aligned with "
            "rmse_mv",
        )
    if notes:
        out["note"] = "; ".join(notes)
    return out


def run_emps(train: Path, test: Path) -> dict[str, Any]:
    p_train, x_train = read_txp(train)
    p_test, x_test = read_txp(test)
    model = make_frols(EMPS_MODEL)
    fit_seconds = fit(model, p_train, x_train)
    rmse, sim, note = free_run_rmse(model, p_test, x_test, EMPS_INIT_WINDOW)
    out: dict[str, Any] = {
        "config": {
            "source": EMPS_SOURCE,
            "protocol": (
                "train on emps_train_txp (DATA_EMPS), input p [N], output x [m]; free run "
                "from the test force alone, the first 20 measured positions give the initial "
                "lagged outputs; RMSE of x over samples 20.. of the test record, mm"
            ),
            **EMPS_MODEL,
        },
        "terms": len(model.final_model),
        "fit_seconds": round(fit_seconds, 4),
        "simulate_seconds": round(sim, 4),
        "rmse_mm": None if rmse is None else 1000.0 * rmse,
    }
    if note:
        out["note"] = note
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--silverbox", type=Path, required=True, help="SNLS80mV.csv")
    ap.add_argument("--emps-train", type=Path, required=True, help="emps_train_txp.csv")
    ap.add_argument("--emps-test", type=Path, required=True, help="emps_test_txp.csv")
    ap.add_argument("--quick", action="store_true",
                    help="one Silverbox model (the multisine configuration) for all test sets")
    ap.add_argument("--out", type=Path, required=True, help="output JSON file")
    args = ap.parse_args(argv)

    result: dict[str, Any] = {
        "tool": "sysidentpy",
        "version": sysidentpy.__version__,
        "silverbox": run_silverbox(args.silverbox, args.quick),
        "emps": run_emps(args.emps_train, args.emps_test),
    }
    # Whole or not at all: written beside, then renamed over the output.
    partial = args.out.with_name(args.out.name + ".partial")
    partial.write_text(json.dumps(result, indent=2) + "\n")
    partial.replace(args.out)

    sb, em = result["silverbox"], result["emps"]
    fmt = lambda v: "null" if v is None else f"{v:.3f}"  # noqa: E731
    print(
        f"sysidentpy {result['version']}: silverbox rmse_mv "
        f"[{'; '.join(fmt(v) for v in sb['rmse_mv'])}] (published "
        f"[{'; '.join(str(v) for v in SILVERBOX_PUBLISHED_RMSE_MV)}]), fit s "
        f"{sb['fit_seconds']}; emps rmse_mm {fmt(em['rmse_mm'])} "
        f"({em['terms']} terms, fit {em['fit_seconds']:.2f} s)",
        file=sys.stderr,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
