"""Records: read from a file or taken from arrays, on their time grid, as ``hbid`` makes them
ready."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _hbid
from ._common import ArrayLike, ColumnsLike, PathLike, array, column, columns, emit, flag, options_json, refuse_non_real, signals, step
from .errors import OptionsError


@dataclass(frozen=True, eq=False)
class Record:
    """A record on its time grid ``t0 + n * dt``, as :func:`read` gives it.

    The time stamps were fitted to a uniform grid; gaps split the record into ``pieces``
    (``(start, stop)`` sample ranges; ``x`` is NaN between them); an angle (``signal="circle"``)
    was wrapped into ``[-pi, pi)``; a velocity or acceleration (``measured``) was integrated to
    the displacement. ``notes`` lists what was done or found, as the command line prints it;
    ``time_repairs`` the stamps replaced by their grid time (``(where, was, now)``, only with
    ``repair=True``) and ``spikes`` the isolated spikes found (``(index, size, replaced)``: by
    default those larger than the record's own steps are replaced when they are few, every one
    with ``repair=True``, none with ``no_repair=True``). ``drive`` is the measured drive read
    with ``drive_col`` (on the same grid), or None.

    A record of several coordinates (``coords``) has each one's samples in ``positions`` by the
    names its terms call them (``x`` is the first's), its drives in ``drives`` and, read with
    ``velocity_col``, the coordinates' measured velocities in ``velocities``.

    Pass it to :func:`identify`, :func:`embed`, :func:`upos` or :func:`compare` in place of a
    file or arrays: its grid, signal, measured quantity, coordinates and drives come with it.
    """

    x: np.ndarray
    t0: float
    dt: float
    pieces: List[Tuple[int, int]]
    signal: str
    measured: str = "displacement"
    repaired: bool = False
    notes: List[str] = field(default_factory=list)
    time_repairs: List[Tuple[str, float, float]] = field(default_factory=list)
    spikes: List[Tuple[int, float, bool]] = field(default_factory=list)
    drive: Optional[np.ndarray] = None
    path: Optional[str] = None
    positions: Dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    """Every coordinate's samples on the grid, by the name terms call it (``{"x": x}`` for a
    record of one)."""
    drives: Dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    """The measured drives on the grid, by the names terms call them (``p`` for the one drive of
    a record of one coordinate)."""
    velocities: Dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    """The coordinates' measured velocities (``velocity_col``) on the grid, by coordinate."""
    spikes_by_coordinate: Dict[str, List[Tuple[int, float, bool]]] = field(default_factory=dict, repr=False)
    """The spikes found in each coordinate, ``(index, size, replaced)``."""
    bridged: List[Tuple[int, int]] = field(default_factory=list)
    """The samples filled by ``bridge_gaps`` (``(start, stop)`` ranges inside ``pieces``):
    interpolated in every column, not measured; :func:`compare` runs through them and scores
    none of them."""
    columns: Dict[str, Any] = field(default_factory=dict, repr=False)
    """The options that named its columns (``coords``, ``drive_col``, ``velocity_col``), as it
    was read: an identification of the record names them in its saved model."""
    lead_rows: int = 0
    """The file's first rows left out of the grid because a logger stamped them before it
    settled to its rate (a note says so). :func:`compare` of the file runs through them from row
    0; of this Record it starts at the grid's first sample, and warns."""

    @property
    def t(self) -> np.ndarray:
        """The grid time of every sample (those in the gaps too)."""
        return self.t0 + np.arange(len(self.x)) * self.dt

    @property
    def samples(self) -> int:
        """The samples that hold data (gaps not counted)."""
        return sum(b - a for a, b in self.pieces)

    @property
    def coordinates(self) -> List[str]:
        """The coordinates' names, in order (``["x"]`` for a record of one)."""
        return list(self.positions) or ["x"]

    @property
    def signals(self) -> List[str]:
        """The domain of each coordinate, ``"circle"`` or ``"line"``."""
        given = self.signal.split(",")
        return given if len(given) > 1 else given * len(self.coordinates)

    def __len__(self) -> int:
        return len(self.x)

    def __repr__(self) -> str:
        where = f"{self.path!r}, " if self.path else ""
        gaps = f", {len(self.pieces)} pieces" if len(self.pieces) > 1 else ""
        several = f", coordinates {self.coordinates}" if len(self.coordinates) > 1 else ""
        return (
            f"Record({where}{self.samples} samples from t = {self.t0:g} every {self.dt:g}, "
            f"signal={self.signal!r}{several}{gaps}, {len(self.notes)} notes)"
        )

    def _grid(self) -> Tuple[float, float, List[Tuple[int, int]], str, List[Tuple[int, int]]]:
        return (
            float(self.t0),
            float(self.dt),
            [(int(a), int(b)) for a, b in self.pieces],
            self.signal,
            [(int(a), int(b)) for a, b in self.bridged],
        )


def _record(d: Any, options: Mapping[str, Any], path: Optional[str] = None) -> Record:
    names = list(d["names"])
    coordinates = dict(zip(names, d["coords"]))
    spikes = [(int(i), float(size), bool(replaced)) for i, size, replaced, _ in d["spikes"]]
    by_coordinate: Dict[str, List[Tuple[int, float, bool]]] = {name: [] for name in names}
    for i, size, replaced, c in d["spikes"]:
        by_coordinate[names[c]].append((int(i), float(size), bool(replaced)))
    drives = dict(zip(d["drive_names"], d["drives"]))
    drive = d["drive"]
    # One array per series: the first coordinate's (and a lone drive's) under both names, so that
    # an edit of either is the record's.
    if names:
        x = coordinates[names[0]]
    else:
        x = d["x"]
    if drive is not None and len(drives) == 1:
        drive = next(iter(drives.values()))
    return Record(
        x=x,
        t0=d["t0"],
        dt=d["dt"],
        pieces=[tuple(p) for p in d["pieces"]],
        bridged=[tuple(b) for b in d["bridged"]],
        signal=d["signal"],
        measured=d["measured"],
        repaired=d["repaired"],
        notes=emit(d["notes"], stacklevel=4),
        time_repairs=[tuple(r) for r in d["time_repairs"]],
        spikes=spikes,
        drive=drive,
        path=path,
        positions=coordinates,
        drives=drives,
        velocities=dict(zip(names, d["velocities"])),
        spikes_by_coordinate=by_coordinate,
        columns={name: options[name] for name in ("coords", "drive_col", "velocity_col") if options.get(name) is not None},
        lead_rows=int(d.get("lead_rows", 0)),
    )


def read(
    path: Union[PathLike, ArrayLike, Mapping[str, ArrayLike]],
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
    signal: Union[str, Sequence[str]] = "circle",
    measured: str = "displacement",
    angle_unit: str = "rad",
) -> Record:
    """Reads a record from a file (or takes it from arrays), as ``hbid`` reads one.

    Text (cells separated by commas, semicolons, spaces or tabs; a header with columns ``t``
    and ``theta`` (or ``x``, ``angle``), a row of units under it passed, or headerless time and
    angle in either order) or
    ``.npy`` (a 1-D array of samples with ``dt``, or samples x channels). The time stamps are
    fitted to a uniform grid: gaps split the record into pieces, and an isolated glitch is an
    error unless ``repair=True`` replaces it by its grid time. Isolated spikes (an encoder's bit
    errors, a sensor's outliers) are found: those larger than the record's own steps (an
    encoder's upper bits) are replaced by default when they are few, the others reported with
    a warning; ``repair=True`` replaces every one, ``no_repair=True`` none.

    Args:
        path: the file; or an array of samples, with ``t`` or ``dt`` (and ``drive``); or, for
            several coordinates, a dict of arrays by the names terms call them.
        t: the time stamps of the samples of an array.
        dt: the sampling step, for a record without time stamps (sample 0 at t = 0).
        drive: the measured drive sampled with an array, or a dict of drives by name.
        time_col: the time column of a file, by header name or 1-based position.
        angle_col: the angle (or displacement) column, by name or 1-based position.
        coords: the columns of a file that each get an equation (several coordinates): a list
            of columns, ``"q1=pos1,q2=pos2"``, or a dict of names to columns.
        drive_col: the column of the measured drive p(t), by name or 1-based position; several
            drives as a list, or a dict of names to columns.
        velocity_col: the columns of the coordinates' measured velocities, one per coordinate.
        repair: replace isolated time-stamp glitches and every spike (listed in the notes).
        no_repair: keep every spike (a warning), even those replaced by default.
        bridge_gaps: bridge every gap of at most this many missing samples (at most 4), between
            pieces of at least 7 samples, by the cubic through the two samples on each side, in
            every column, so that the pieces are analysed as one (a logger's dropped rows; a note
            counts them). A bridged sample of a sine of amplitude ``A`` and angular frequency
            ``omega`` is off by at most ``A * (omega * dt)**4`` times 1/6, 1/2, 3/2 or 3 for gaps
            of 1, 2, 3 or 4 samples, and carries at most 1.61 times one sample's noise; an angle
            that moves too far across a gap to tell its turn leaves it a gap. 0 bridges none (a
            displacement record only).
        skip_missing: leave out every row with a missing value in a column read (an empty
            cell, ``NA``, ``null``, ``NaN``, ...; an array's NaN), as if the logger had not
            written it: its time is then a gap's (with ``dt`` the rows keep their places), which
            ``bridge_gaps`` may bridge; a note counts them and names the first. Without it such
            a value is an error naming its line.
        signal: ``"circle"`` for an angle (wrapped into ``[-pi, pi)``) or ``"line"`` for a
            displacement; for several coordinates one for all or a list, one per coordinate.
        measured: ``"displacement"``, or (on the line) ``"velocity"`` or ``"acceleration"``,
            integrated to the displacement.
        angle_unit: the unit of the angles on the circle (and of their measured velocities):
            ``"rad"``, ``"deg"`` or ``"counts:N"`` (an encoder's N counts per turn); converted
            to radians as they are read.

    Returns:
        The :class:`Record` on its grid, with what was repaired.

    Raises:
        InputError: the file, its columns, its values or its time stamps.
        OptionsError: a bad argument.
    """
    options: Dict[str, Any] = dict(
        time_col=column(time_col, "time_col"),
        angle_col=column(angle_col, "angle_col"),
        coords=columns(coords, "coords"),
        drive_col=columns(drive_col, "drive_col"),
        velocity_col=columns(velocity_col, "velocity_col"),
        dt=step(dt),
        repair=flag(repair, "repair"),
        no_repair=flag(no_repair, "no_repair"),
        bridge_gaps=bridge_gaps,
        skip_missing=flag(skip_missing, "skip_missing"),
        signal=signals(signal),
        measured=measured,
        angle_unit=angle_unit,
    )
    if isinstance(path, (str, os.PathLike)):
        if t is not None or drive is not None:
            raise OptionsError("a file carries its own time and drive: give no t or drive with a path")
        name = os.fspath(path)
        return _record(_hbid.condition(options_json(options), path=name), options, name)
    args = _arrays(path, t, drive, options)
    return _record(_hbid.condition(options_json(options), **args), options)


#: The options of a record that a :class:`~hbid.Record` fixes when it is read.
RECORD_FIXED = (
    "time_col",
    "angle_col",
    "coords",
    "dt",
    "drive_col",
    "velocity_col",
    "repair",
    "no_repair",
    "bridge_gaps",
    "skip_missing",
)


def _is_path(x: Any) -> bool:
    return isinstance(x, (str, os.PathLike))


def _columns_by_name(values: Any, names: Any, what: str, option: str) -> Any:
    """A two-dimensional array of shape (samples, columns) as a dict of its columns by the names
    ``option`` gives (a list, or the command line's ``"a,b"``), one per column; anything else as
    it is. A single column needs no name."""
    if isinstance(values, Mapping) or _is_path(values):
        return values
    refuse_non_real(values, what)
    try:
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        return values
    if a.ndim != 2:
        return values
    columns = a.shape[1]
    if names is None:
        if columns == 1:
            return a[:, 0]
        raise OptionsError(
            f"{what}: an array of {columns} columns (shape {a.shape}); name each with {option}=[...] "
            f"(one name per column, in order)"
        )
    items = [str(n).strip() for n in (names.split(",") if isinstance(names, str) else names)]
    if isinstance(names, Mapping) or any("=" in n for n in items):
        # A name with a column (a dict, or NAME=COLUMN) picks columns of a file; an array's
        # columns are named in their order, and a position given here would be dropped.
        raise OptionsError(
            f"{option}: name the columns of an array with a list of names, one per column in order "
            f"(NAME=COLUMN and dicts pick columns of a file)"
        )
    listed = items
    if len(listed) != columns:
        raise OptionsError(
            f"{option}: {len(listed)} name(s) for an array of {columns} columns (shape {a.shape}): give one per column"
        )
    if len(set(listed)) != len(listed):
        raise OptionsError(f"{option}: a name given twice ({', '.join(listed)})")
    return {name: np.ascontiguousarray(a[:, j]) for j, name in enumerate(listed)}


def _arrays(x: Any, t: Optional[ArrayLike], drive: Any, options: Dict[str, Any]) -> Dict[str, Any]:
    """The extension's arguments of samples given as arrays: ``x`` one array (a coordinate), a
    dict of arrays by coordinate name or an array of shape (samples, coordinates) named by
    ``coords``; ``drive`` one array (``p``), a dict by drive name or an array of shape (samples,
    drives) named by ``drive_col``; the names become the options that name the columns of a
    file (``coords``, ``drive_col``)."""
    if options.get("velocity_col") is not None:
        raise OptionsError(
            "velocity_col names columns of a file: read the file with it (hbid.read), or give the record's file"
        )
    x = _columns_by_name(x, options.get("coords"), "x", "coords")
    if drive is not None and not isinstance(drive, Mapping):
        drive = _columns_by_name(drive, options.get("drive_col"), "drive", "drive_col")
        if isinstance(drive, Mapping):
            options.pop("drive_col", None)
    if isinstance(x, Mapping):
        if not x:
            raise OptionsError("x: an empty dict; give each coordinate's samples by its name")
        names = [str(name) for name in x]
        given = options.get("coords")
        if given is not None:
            # coords may name the dict's coordinates, in the order of the equations.
            order = [item.split("=")[0].strip() for item in (given.split(",") if isinstance(given, str) else given)]
            if sorted(order) != sorted(names):
                raise OptionsError(
                    f"coords: names {', '.join(order)}, but the dict of arrays holds {', '.join(names)}"
                )
            names = order
            x = {name: x[name] for name in names}
        if len(names) > 1:
            options["coords"] = names
        samples = [array(v, f"x[{name!r}]") for name, v in x.items()]
    else:
        samples = [array(x, "x")]
    args: Dict[str, Any] = dict(x=samples)
    if t is not None:
        args["t"] = array(t, "t")
    if drive is not None:
        if isinstance(drive, Mapping):
            if options.get("drive_col") is not None:
                raise OptionsError("drive_col: the dict of drives names them; give no drive_col with it")
            options["drive_col"] = [str(name) for name in drive]
            args["drive"] = [array(v, f"drive[{name!r}]") for name, v in drive.items()]
        else:
            # One drive: p for a record of one coordinate, or the name drive_col gives it.
            if options.get("drive_col") is None:
                options["drive_col"] = "p"
            args["drive"] = [array(drive, "drive")]
    return args


def source(
    x: Any,
    t: Optional[ArrayLike],
    drive: Any,
    options: Dict[str, Any],
    defaults: Mapping[str, Any],
    several_files: bool = False,
) -> Dict[str, Any]:
    """The extension's keyword arguments that say where the samples come from: ``path`` for a
    file (a list of paths with ``several_files``), ``x`` (with ``t`` and ``drive``) for arrays,
    ``x`` and ``grid`` for a Record, whose own signal, measured quantity, coordinates and drives
    then hold (``options`` is updated)."""
    if isinstance(x, Record):
        for name in ("signal", "measured"):
            own = getattr(x, name)
            if options.get(name, defaults[name]) not in (defaults[name], own):
                raise OptionsError(
                    f"{name}={options[name]!r}: the record was read as {own!r}; read it again with {name}={options[name]!r}"
                )
            options[name] = own
        if options.get("angle_unit", "rad") != "rad":
            raise OptionsError("angle_unit: the Record was read in radians already; read it again to change it")
        options.pop("angle_unit", None)
        for name in RECORD_FIXED:
            if options.get(name) not in (None, False):
                raise OptionsError(f"{name}: the Record was read with its own; read it again to change it")
            options.pop(name, None)
        if t is not None or drive is not None:
            raise OptionsError("a Record carries its own time and drive: give no t or drive with it")
        options.update(x.columns)
        positions = list(x.positions.values()) or [x.x]
        # A Record made anew with another first coordinate (dataclasses.replace(record, x=...)).
        if positions[0] is not x.x:
            positions[0] = x.x
        args: Dict[str, Any] = dict(x=[array(p, "x") for p in positions], grid=x._grid())
        drives = list(x.drives.values()) or ([] if x.drive is None else [x.drive])
        if drives:
            args["drive"] = [array(p, "drive") for p in drives]
            if "drive_col" not in options:
                options["drive_col"] = list(x.drives) if len(x.drives) > 1 else "p"
        if x.velocities:
            args["velocity"] = [array(v, "velocity") for v in x.velocities.values()]
        return args
    if _is_path(x):
        if t is not None or drive is not None:
            raise OptionsError("a file carries its own time and drive: give no t or drive with a path")
        return dict(path=[os.fspath(x)] if several_files else os.fspath(x))
    if isinstance(x, (list, tuple)) and x and all(_is_path(p) for p in x):
        if not several_files:
            raise OptionsError("x: one record here; only identify joins several files")
        if t is not None or drive is not None:
            raise OptionsError("files carry their own time and drive: give no t or drive with paths")
        return dict(path=[os.fspath(p) for p in x])
    return _arrays(x, t, drive, options)
