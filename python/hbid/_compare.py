"""A saved model against a record it was not fitted to, as ``hbid compare`` and ``hbid simulate
--model --input`` run it: the model driven by the record's measured input, run freely from the
state its first samples give, and its output scored against the measured one."""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass, field
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _hbid
from ._common import ArrayLike, ColumnsLike, HbidWarning, PathLike, column, columns, emit, flag, numbers, options_json, signals, step
from ._model import Model
from ._record import Record, _columns_by_name, source
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
    """``(x, v, rms of the fit)`` of each piece run (of a system, this coordinate's position and
    velocity, and the rms of the state's fit to every coordinate)."""
    skipped_pieces: int
    """Pieces between gaps too short to run."""
    stopped: Optional[str]
    """Where and why the model's run stopped, if it did."""
    coordinate: Optional[str] = None
    """The coordinate scored, for a system of several (each range has one score per
    coordinate); None for a model of one."""
    bridged: int = 0
    """Samples after each piece's ``init`` that were bridged into gaps (``bridge_gaps``): run
    through, not scored (they were not measured)."""


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
    """The measured output (NaN at the samples bridged into gaps, which were not measured)."""
    x: np.ndarray
    """The simulated position (on the turn of the measured angle, on the circle)."""
    v: np.ndarray
    """The simulated velocity."""


@dataclass(frozen=True, eq=False)
class Comparison:
    """What :func:`compare` gives: one :class:`RangeScore` per range (``ranges``; of a system one
    per range and coordinate, each range's coordinates in order), the runs themselves (``runs``,
    a list of :class:`RunPiece` per entry of ``ranges``, for plots), the notes, and the report as
    ``hbid compare --json`` prints it (``report``)."""

    ranges: List[RangeScore]
    runs: List[List[RunPiece]] = field(repr=False)
    measured_drive: bool
    """Whether the model was driven by the record's measured drive."""
    notes: List[str]
    report: Dict[str, Any] = field(repr=False)
    json_text: str = field(repr=False)
    coordinates: List[str] = field(default_factory=list)
    """The coordinates of a system, in order; empty for a model of one."""

    @property
    def rmse(self) -> List[Optional[float]]:
        """The RMSE of each range (of a system, of each range and coordinate)."""
        return [r.rmse for r in self.ranges]

    @property
    def fit_percent(self) -> List[Optional[float]]:
        """The fit percentage of each range (of a system, of each range and coordinate)."""
        return [r.fit_percent for r in self.ranges]

    @property
    def by_coordinate(self) -> Dict[str, List[RangeScore]]:
        """A system's scores by coordinate, each coordinate's ranges in order (``{"x": ranges}``
        for a model of one)."""
        if not self.coordinates:
            return {"x": list(self.ranges)}
        return {q: [r for r in self.ranges if r.coordinate == q] for q in self.coordinates}

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


def _model(model: Union[Model, PathLike]) -> Model:
    if isinstance(model, Model):
        return model
    if isinstance(model, (str, os.PathLike)):
        return Model.load(model)
    raise OptionsError(f"model: a hbid.Model or the path of a saved model, not {type(model).__name__}")


def _in_order(x: Any, model: Model) -> Any:
    """A dict of arrays by coordinate in the order of the model's coordinates, whose names it
    must be (compare reads the record's coordinates in the model's order)."""
    if not isinstance(x, Mapping) or len(x) < 2:
        return x
    names = model.coordinates
    if set(x) != set(names):
        raise OptionsError(
            f"x: the arrays are named {', '.join(map(str, x))}; the model's coordinates are {', '.join(names)}"
        )
    return {name: x[name] for name in names}


def compare(
    model: Union[Model, PathLike],
    x: Union[PathLike, ArrayLike, Mapping[str, ArrayLike], Any],
    *,
    t: Optional[ArrayLike] = None,
    dt: Optional[float] = None,
    drive: Union[ArrayLike, Mapping[str, ArrayLike], None] = None,
    time_col: Union[str, int, None] = None,
    angle_col: Union[str, int, None] = None,
    coords: ColumnsLike = None,
    drive_col: ColumnsLike = None,
    velocity_col: ColumnsLike = None,
    repair: bool = False,
    no_repair: bool = False,
    bridge_gaps: int = 0,
    skip_missing: bool = False,
    signal: Union[str, Sequence[str], None] = None,
    measured: str = "displacement",
    angle_unit: str = "rad",
    range: Union[str, Tuple[int, Optional[int]], Sequence[Any], None] = None,
    init: Optional[int] = None,
    x0: Union[float, Sequence[float], None] = None,
    v0: Union[float, Sequence[float], None] = None,
    rtol: float = _hbid.DEFAULT_RTOL,
    skip_unsettled: bool = False,
) -> Comparison:
    """Runs a saved model freely under a record's measured input and scores it against the
    record's measured output, as ``hbid compare`` does.

    Each range (and each piece of it between gaps) starts from the state whose free run best
    matches its first ``init`` samples (or from the measured state of ``velocity_col``); the
    model is driven by the record's drive (a model with terms in ``p``: give ``drive_col=`` or
    ``drive=``) or by its own drive on the record's clock; the scores count the samples after
    them. A system of several coordinates is run on all of them at once and scored on each
    (:attr:`Comparison.by_coordinate`); its record's columns are the system's own names unless
    ``coords`` and ``drive_col`` say otherwise.

    Args:
        model: a :class:`Model`, or the path of a saved model.
        x: the record: a path (text or ``.npy``), a :class:`Record`, or the measured output's
            samples (with ``t`` or ``dt``, and ``drive``): an array, or a dict of arrays by
            coordinate for a system.
        t: the samples' times (with arrays).
        dt: the sampling step, for samples or a file without times.
        drive: the measured drive's samples (with arrays), or a dict of them by drive name.
        time_col: a file's time column (name or 1-based position).
        angle_col: a file's output column (angle or displacement).
        coords: a system's coordinates' columns in a file (``"q2=3,q1=2"``: by the model's
            names, in any order; columns alone: in the order of its coordinates), or the names
            of an array's columns (default: the columns it was identified from). A record's
            columns are paired with the model's by name wherever they have its names.
        drive_col: a file's measured drive column (several: a list, by the system's drive
            names in any order or, columns alone, in the order of its drives).
        velocity_col: a file's columns of the coordinates' measured velocities: each piece then
            runs from its first sample's measured state, every sample scored (unless ``init``
            says otherwise).
        repair: replace isolated time-stamp glitches and every spike.
        no_repair: keep every spike instead of replacing the few large ones.
        bridge_gaps: bridge every gap of at most this many missing samples by the cubic through
            its neighbours, in every column, as for :func:`identify`: a run then goes on through
            it (driven by the bridged drives), and the bridged samples, not measured, are counted
            apart (``bridged`` of each range) and not scored.
        skip_missing: leave out every row with a missing value in a column read, as a
            logger's dropped row, as for :func:`identify`.
        signal: ``"circle"`` or ``"line"`` (default: the model's).
        measured: ``"displacement"``, ``"velocity"`` or ``"acceleration"`` (one coordinate on
            the line: integrated piece by piece with the constants the model's equation holds
            best with, given in a note; a logger's unsettled first rows left out).
        angle_unit: the unit of the angles on the circle (and of their measured velocities):
            ``"rad"``, ``"deg"`` or ``"counts:N"`` (an encoder's N counts per turn); converted
            to radians as they are read.
        range: the samples compared: ``"A..B"`` (``"A.."`` to the end), ``(A, B)``, or a list
            of them, each scored on its own (default: the whole record). A file's first rows
            that its logger stamped before it settled to its rate are run through at their own
            stamps and counted as its first samples (a note says so), so that the samples are the
            file's rows for a record without gaps (the samples bridged into gaps, with
            ``bridge_gaps``, count among them).
        init: samples that set the initial state of each piece (default: one period of the
            model's drive, at most a tenth of the range, at least 8).
        x0: the initial position instead of fitting it (with ``v0``): one per coordinate of a
            system.
        v0: the initial velocity, in the record's time unit (with ``x0``).
        rtol: the integrator's relative tolerance.
        skip_unsettled: leave out those unsettled first rows, as ``identify`` does, and start
            at the first row on the record's grid (the ranges then count from there).

    Returns:
        A :class:`Comparison`.

    Raises:
        InputError: the record cannot be read.
        OptionsError: a bad option, or one that does not fit the model or the record.
        ModelError: the model cannot be read.
    """
    saved = _model(model)
    options: Dict[str, Any] = dict(
        time_col=column(time_col, "time_col"),
        angle_col=column(angle_col, "angle_col"),
        coords=columns(coords, "coords"),
        dt=step(dt),
        drive_col=columns(drive_col, "drive_col"),
        velocity_col=columns(velocity_col, "velocity_col"),
        repair=flag(repair, "repair"),
        no_repair=flag(no_repair, "no_repair"),
        bridge_gaps=bridge_gaps,
        skip_missing=flag(skip_missing, "skip_missing"),
        signal=signals(signal),
        measured=measured,
        angle_unit=angle_unit,
        range=_ranges(range),
        init=init,
        x0=numbers(x0, "x0"),
        v0=numbers(v0, "v0"),
        rtol=rtol,
        skip_unsettled=flag(skip_unsettled, "skip_unsettled"),
    )
    if isinstance(drive, Mapping):
        # By the model's names, checked as Model.simulate checks them (a name the model does not
        # have is not taken for another by its place).
        drive = dict(zip(saved.drives, saved._drives(drive)))
    if saved.is_system and not isinstance(x, (Record, str, os.PathLike)):
        # An array of shape (samples, coordinates) named by coords: by its names, as a dict.
        x = _columns_by_name(x, options.get("coords"), "x", "coords")
        if isinstance(x, Mapping):
            options.pop("coords", None)
    if isinstance(x, Record) and x.lead_rows > 0 and not skip_unsettled:
        warnings.warn(
            f"the Record leaves out its file's first {x.lead_rows} rows (stamped before the logger settled to its "
            "rate): the ranges count from its grid's first sample; compare the file itself to run from row 0 "
            "through them, as the command line does",
            HbidWarning,
            stacklevel=2,
        )
    samples = source(_in_order(x, saved), t, drive, options, COMPARE_DEFAULTS)
    if saved.is_system:
        if isinstance(x, Record):
            # A system's coordinates keep their own domains: the record's come with its grid.
            options.pop("signal", None)
        if not isinstance(x, (Record, str, os.PathLike)):
            # Arrays: the dict's names are the coordinates'; the system names its own drives.
            options.pop("coords", None)
            if isinstance(drive, Mapping):
                options["drive_col"] = [n for n in saved.drives if n in drive] + [n for n in drive if n not in saved.drives]
                samples["drive"] = [np.ascontiguousarray(drive[n], dtype=np.float64) for n in options["drive_col"]]
            elif drive is not None and len(saved.drives) == 1:
                options["drive_col"] = saved.drives
    d = _hbid.compare(saved.to_bytes(), options_json(options), **samples)
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
            coordinate=r.get("coordinate"),
            bridged=r["bridged"],
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
        coordinates=list(report.get("coordinates", [])),
    )


@dataclass(frozen=True, eq=False)
class ModelRun:
    """A saved model's free run: ``t, x, v = ...`` unpacks it; ``stopped`` says where and why the
    run stopped, if it did (its later samples are NaN). A system's run has every column by name
    in ``named`` (``t``, the coordinates, their velocities ``q1'``, as ``columns`` lists them);
    ``x`` and ``v`` are then its first coordinate and that one's velocity."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    stopped: Optional[str]
    columns: Tuple[str, ...] = ("t", "x", "v")
    """The columns of the file ``out`` holds."""
    named: Dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    """Every column by its name."""

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
    coords: ColumnsLike,
    dt: Optional[float],
    drive_col: ColumnsLike,
    init: Optional[int],
    skip_missing: bool,
    repair: bool,
    x0: Union[float, Sequence[float]],
    v0: Union[float, Sequence[float]],
    rtol: float,
    out: Optional[PathLike],
) -> ModelRun:
    """``simulate(model=..., input=...)``: the model over the input record's grid."""
    given = init == 0
    options: Dict[str, Any] = dict(
        time_col=column(time_col, "time_col"),
        angle_col=column(angle_col, "angle_col"),
        coords=columns(coords, "coords"),
        dt=step(dt),
        drive_col=columns(drive_col, "drive_col"),
        init=None if given else init,
        skip_missing=flag(skip_missing, "skip_missing"),
        repair=flag(repair, "repair"),
        x0=numbers(x0, "x0") if given else None,
        v0=numbers(v0, "v0") if given else None,
        rtol=rtol,
    )
    samples = source(input, None, None, options, COMPARE_DEFAULTS)
    d = _hbid.model_run(
        _model(model).to_bytes(),
        options_json(options),
        rig,
        out=None if out is None else os.fspath(out),
        **samples,
    )
    emit(d["notes"], stacklevel=4)
    named = dict(zip(d["columns"], d["values"]))
    n = (len(d["columns"]) - 1) // 2
    values = d["values"]
    return ModelRun(
        t=values[0], x=values[1], v=values[1 + n], stopped=d["stopped"], columns=tuple(d["columns"]), named=named
    )
