"""A saved model against a record it was not fitted to, as ``hbid compare`` and ``hbid simulate
--model --input`` run it: the model driven by the record's measured input, run freely from the
state its first samples give, and its output scored against the measured one."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _hbid
from ._common import ArrayLike, PathLike, column, emit, options_json
from ._model import Model
from ._record import source
from .errors import OptionsError

#: The record's options of ``compare`` and their defaults (``signal``: the model's).
COMPARE_DEFAULTS = {"signal": None, "measured": "displacement"}


@dataclass(frozen=True)
class RangeScore:
    """The scores of one range of a :func:`compare`: the field's usual three, over the samples
    after the ``init`` samples of each piece that set the model's state."""

    range: Tuple[int, int]
    """The samples compared, ``[start, end)`` of the record's grid."""
    init: int
    """Samples at the start of each piece that set the initial state (not scored)."""
    scored: int
    """Samples scored."""
    rmse: Optional[float]
    """Root mean square of the measured output less the simulated one, in the record's unit
    (None when the model's run stopped before the range's end)."""
    nrmse: Optional[float]
    """The RMSE over the standard deviation of the measured output."""
    fit_percent: Optional[float]
    """``100 (1 - |y - y_sim| / |y - mean(y)|)``."""
    max_error: Optional[float]
    """The largest difference."""
    initial_states: List[Tuple[float, float, float]]
    """``(x, v, rms of the fit)`` of each piece run."""
    skipped_pieces: int
    """Pieces between gaps too short to run."""
    stopped: Optional[str]
    """Where and why the model's run stopped, if it did."""


@dataclass(frozen=True)
class RunPiece:
    """One piece of a range as run: the times, the measured output and the model's."""

    start: int
    """The grid's index of the first sample."""
    init: int
    """Samples at the start that set the initial state."""
    t: np.ndarray
    """The times."""
    measured: np.ndarray
    """The measured output."""
    x: np.ndarray
    """The simulated position (on the turn of the measured angle, on the circle)."""
    v: np.ndarray
    """The simulated velocity."""


@dataclass(frozen=True, eq=False)
class Comparison:
    """What :func:`compare` gives: one :class:`RangeScore` per range (``ranges``), the runs
    themselves (``runs``, a list of :class:`RunPiece` per range, for plots), the notes, and the
    report as ``hbid compare --json`` prints it (``report``)."""

    ranges: List[RangeScore]
    runs: List[List[RunPiece]]
    measured_drive: bool
    """Whether the model was driven by the record's measured drive."""
    notes: List[str]
    report: Dict[str, Any]
    json_text: str

    @property
    def rmse(self) -> List[Optional[float]]:
        """The RMSE of each range."""
        return [r.rmse for r in self.ranges]

    @property
    def fit_percent(self) -> List[Optional[float]]:
        """The fit percentage of each range."""
        return [r.fit_percent for r in self.ranges]

    def to_json(self) -> str:
        """The report as ``hbid compare --json`` prints it."""
        return self.json_text


def _ranges(range: Union[str, Tuple[int, Optional[int]], Sequence[Any], None]) -> List[str]:
    """``range=``: ``"A..B"``, ``(A, B)`` (B None: to the end), or a list of either."""
    if range is None:
        return []
    if isinstance(range, str):
        return [range]
    items = list(range)
    if len(items) == 2 and all(isinstance(v, (int, np.integer)) or v is None for v in items):
        items = [tuple(items)]
    out = []
    for item in items:
        if isinstance(item, str):
            out.append(item)
            continue
        try:
            a, b = item
        except (TypeError, ValueError):
            raise OptionsError(f"range={item!r}: 'A..B' or (A, B)") from None
        out.append(f"{int(a)}..{'' if b is None else int(b)}")
    return out


def _model_bytes(model: Union[Model, PathLike]) -> bytes:
    if isinstance(model, Model):
        return model.to_bytes()
    if isinstance(model, (str, os.PathLike)):
        return Model.load(model).to_bytes()
    raise OptionsError(f"model: a hbid.Model or the path of a saved model, not {type(model).__name__}")


def compare(
    model: Union[Model, PathLike],
    x: Union[PathLike, ArrayLike, Any],
    *,
    t: Optional[ArrayLike] = None,
    dt: Optional[float] = None,
    drive: Optional[ArrayLike] = None,
    time_col: Union[str, int, None] = None,
    angle_col: Union[str, int, None] = None,
    drive_col: Union[str, int, None] = None,
    repair: bool = False,
    signal: Optional[str] = None,
    measured: str = "displacement",
    range: Union[str, Tuple[int, Optional[int]], Sequence[Any], None] = None,
    init: Optional[int] = None,
    x0: Optional[float] = None,
    v0: Optional[float] = None,
    rtol: float = 1e-10,
) -> Comparison:
    """Runs a saved model freely under a record's measured input and scores it against the
    record's measured output, as ``hbid compare`` does.

    Each range (and each piece of it between gaps) starts from the state whose free run best
    matches its first ``init`` samples; the model is driven by the record's drive (a model with
    terms in ``p``: give ``drive_col=`` or ``drive=``) or by its own drive on the record's clock;
    the scores count the samples after them.

    Args:
        model: a :class:`Model`, or the path of a saved model.
        x: the record: a path (text or ``.npy``), a :class:`Record`, or the measured output's
            samples (with ``t`` or ``dt``, and ``drive``).
        t: the samples' times (with arrays).
        dt: the sampling step, for samples or a file without times.
        drive: the measured drive's samples (with arrays).
        time_col: a file's time column (name or 1-based position).
        angle_col: a file's output column (angle or displacement).
        drive_col: a file's measured drive column.
        repair: replace isolated time-stamp glitches and encoder spikes.
        signal: ``"circle"`` or ``"line"`` (default: the model's).
        measured: ``"displacement"``, ``"velocity"`` or ``"acceleration"`` (integrated).
        range: the samples compared: ``"A..B"`` (``"A.."`` to the end), ``(A, B)``, or a list
            of them, each scored on its own (default: the whole record).
        init: samples that set the initial state of each piece (default: one period of the
            model's drive, at most a tenth of the range, at least 8).
        x0: the initial position instead of fitting it (with ``v0``).
        v0: the initial velocity, in the record's time unit (with ``x0``).
        rtol: the integrator's relative tolerance.

    Returns:
        A :class:`Comparison`.

    Raises:
        InputError: the record cannot be read.
        OptionsError: a bad option, or one that does not fit the model or the record.
        ModelError: the model cannot be read.
    """
    options: Dict[str, Any] = dict(
        time_col=column(time_col, "time_col"),
        angle_col=column(angle_col, "angle_col"),
        dt=dt,
        drive_col=column(drive_col, "drive_col"),
        repair=bool(repair),
        signal=signal,
        measured=measured,
        range=_ranges(range),
        init=init,
        x0=x0,
        v0=v0,
        rtol=rtol,
    )
    samples = source(x, t, drive, options, COMPARE_DEFAULTS)
    d = _hbid.compare(_model_bytes(model), options_json(options), **samples)
    report = json.loads(d["json"])
    ranges = [
        RangeScore(
            range=tuple(r["range"]),
            init=r["init"],
            scored=r["scored"],
            rmse=r["rmse"],
            nrmse=r["nrmse"],
            fit_percent=r["fit_percent"],
            max_error=r["max_error"],
            initial_states=[tuple(s) for s in r["initial_states"]],
            skipped_pieces=r["skipped_pieces"],
            stopped=r["stopped"],
        )
        for r in report["ranges"]
    ]
    runs = [[RunPiece(*piece) for piece in pieces] for pieces in d["runs"]]
    return Comparison(
        ranges=ranges,
        runs=runs,
        measured_drive=report["measured_drive"],
        notes=emit(d["notes"]),
        report=report,
        json_text=d["json"],
    )


@dataclass(frozen=True, eq=False)
class ModelRun:
    """A saved model's free run: ``t, x, v = ...`` unpacks it; ``stopped`` says where and why the
    run stopped, if it did (its later samples are NaN)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    stopped: Optional[str]

    def __iter__(self) -> Iterator[np.ndarray]:
        return iter((self.t, self.x, self.v))

    def __len__(self) -> int:
        return len(self.t)


def run_model(
    model: Union[Model, PathLike],
    input: Any,
    *,
    rig: str,
    time_col: Union[str, int, None],
    angle_col: Union[str, int, None],
    dt: Optional[float],
    drive_col: Union[str, int, None],
    init: Optional[int],
    x0: float,
    v0: float,
    rtol: float,
    out: Optional[PathLike],
) -> ModelRun:
    """``simulate(model=..., input=...)``: the model over the input record's grid."""
    given = init == 0
    options: Dict[str, Any] = dict(
        time_col=column(time_col, "time_col"),
        angle_col=column(angle_col, "angle_col"),
        dt=dt,
        drive_col=column(drive_col, "drive_col"),
        init=None if given else init,
        x0=x0 if given else None,
        v0=v0 if given else None,
        rtol=rtol,
    )
    samples = source(input, None, None, options, COMPARE_DEFAULTS)
    d = _hbid.model_run(
        _model_bytes(model),
        options_json(options),
        rig,
        out=None if out is None else os.fspath(out),
        **samples,
    )
    emit(d["notes"], stacklevel=4)
    return ModelRun(t=d["t"], x=d["x"], v=d["v"], stopped=d["stopped"])
