"""Records: read from a file or taken from arrays, on their time grid, as ``hbid`` makes them
ready."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

import numpy as np

from . import _hbid
from ._common import ArrayLike, PathLike, array, column, emit, options_json
from .errors import OptionsError


@dataclass(frozen=True, eq=False)
class Record:
    """A record on its time grid ``t0 + n * dt``, as :func:`read` gives it.

    The time stamps were fitted to a uniform grid; gaps split the record into ``pieces``
    (``(start, stop)`` sample ranges; ``x`` is NaN between them); an angle (``signal="circle"``)
    was wrapped into ``[-pi, pi)``; a velocity or acceleration (``measured``) was integrated to
    the displacement. ``notes`` lists what was done or found, as the command line prints it;
    ``time_repairs`` the stamps replaced by their grid time (``(where, was, now)``) and ``spikes``
    the isolated spikes found (``(index, size, replaced)``), both only repaired with
    ``repair=True``. ``drive`` is the measured drive read with ``drive_col`` (on the same grid),
    or None.

    Pass it to :func:`identify`, :func:`embed` or :func:`upos` in place of a file or arrays: its
    grid, signal, measured quantity and drive come with it.
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

    @property
    def t(self) -> np.ndarray:
        """The grid time of every sample (those in the gaps too)."""
        return self.t0 + np.arange(len(self.x)) * self.dt

    @property
    def samples(self) -> int:
        """The samples that hold data (gaps not counted)."""
        return sum(b - a for a, b in self.pieces)

    def __len__(self) -> int:
        return len(self.x)

    def __repr__(self) -> str:
        where = f"{self.path!r}, " if self.path else ""
        gaps = f", {len(self.pieces)} pieces" if len(self.pieces) > 1 else ""
        return (
            f"Record({where}{self.samples} samples from t = {self.t0:g} every {self.dt:g}, "
            f"signal={self.signal!r}{gaps}, {len(self.notes)} notes)"
        )

    def _grid(self) -> Tuple[float, float, List[Tuple[int, int]], str]:
        return (float(self.t0), float(self.dt), [(int(a), int(b)) for a, b in self.pieces], self.signal)


def _record(d: Any, path: Optional[str] = None) -> Record:
    return Record(
        x=d["x"],
        t0=d["t0"],
        dt=d["dt"],
        pieces=[tuple(p) for p in d["pieces"]],
        signal=d["signal"],
        measured=d["measured"],
        repaired=d["repaired"],
        notes=emit(d["notes"], stacklevel=4),
        time_repairs=[tuple(r) for r in d["time_repairs"]],
        spikes=[tuple(s) for s in d["spikes"]],
        drive=d["drive"],
        path=path,
    )


def read(
    path: Union[PathLike, ArrayLike],
    *,
    t: Optional[ArrayLike] = None,
    dt: Optional[float] = None,
    drive: Optional[ArrayLike] = None,
    time_col: Union[str, int, None] = None,
    angle_col: Union[str, int, None] = None,
    drive_col: Union[str, int, None] = None,
    repair: bool = False,
    signal: str = "circle",
    measured: str = "displacement",
) -> Record:
    """Reads a record from a file (or takes it from arrays), as ``hbid`` reads one.

    Text (cells separated by commas, semicolons, spaces or tabs; a header with columns ``t``
    and ``theta`` (or ``x``, ``angle``), or headerless time and angle in either order) or
    ``.npy`` (a 1-D array of samples with ``dt``, or samples x channels). The time stamps are
    fitted to a uniform grid: gaps split the record into pieces, and an isolated glitch is an
    error unless ``repair=True`` replaces it by its grid time. Isolated spikes (an encoder's bit
    errors, a sensor's outliers) are reported, and replaced with ``repair=True``.

    Args:
        path: the file; or an array of samples, with ``t`` or ``dt`` (and ``drive``).
        t: the time stamps of the samples of an array.
        dt: the sampling step, for a record without time stamps (sample 0 at t = 0).
        drive: the measured drive sampled with an array.
        time_col: the time column of a file, by header name or 1-based position.
        angle_col: the angle (or displacement) column, by name or 1-based position.
        drive_col: the column of the measured drive p(t), by name or 1-based position.
        repair: replace isolated time-stamp glitches and spikes (listed in the notes).
        signal: ``"circle"`` for an angle (wrapped into ``[-pi, pi)``) or ``"line"`` for a
            displacement.
        measured: ``"displacement"``, or (on the line) ``"velocity"`` or ``"acceleration"``,
            integrated to the displacement.

    Returns:
        The :class:`Record` on its grid, with what was repaired.

    Raises:
        InputError: the file, its columns, its values or its time stamps.
        OptionsError: a bad argument.
    """
    options = dict(
        time_col=column(time_col, "time_col"),
        angle_col=column(angle_col, "angle_col"),
        drive_col=column(drive_col, "drive_col"),
        dt=None if dt is None else float(dt),
        repair=bool(repair),
        signal=signal,
        measured=measured,
    )
    if isinstance(path, (str, os.PathLike)):
        if t is not None or drive is not None:
            raise OptionsError("a file carries its own time and drive: give no t or drive with a path")
        name = os.fspath(path)
        return _record(_hbid.condition(options_json(options), path=name), name)
    d = _hbid.condition(
        options_json(options),
        x=array(path, "x"),
        t=None if t is None else array(t, "t"),
        drive=None if drive is None else array(drive, "drive"),
    )
    return _record(d)


#: The options of a record that a :class:`~hbid.Record` fixes when it is read.
RECORD_FIXED = ("time_col", "angle_col", "dt", "drive_col", "repair")


def source(
    x: Any,
    t: Optional[ArrayLike],
    drive: Optional[ArrayLike],
    options: Dict[str, Any],
    defaults: Mapping[str, Any],
) -> Dict[str, Any]:
    """The extension's keyword arguments that say where the samples come from: ``path`` for a
    file, ``x`` (with ``t`` and ``drive``) for arrays, ``x`` and ``grid`` for a Record, whose
    own signal and measured quantity then hold (``options`` is updated)."""
    if isinstance(x, Record):
        for name in ("signal", "measured"):
            own = getattr(x, name)
            if options.get(name, defaults[name]) not in (defaults[name], own):
                raise OptionsError(
                    f"{name}={options[name]!r}: the record was read as {own!r}; read it again with {name}={options[name]!r}"
                )
            options[name] = own
        for name in RECORD_FIXED:
            if options.get(name, defaults.get(name)) != defaults.get(name):
                raise OptionsError(f"{name}: the Record was read with its own; read it again to change it")
            options.pop(name, None)
        if t is not None or drive is not None:
            raise OptionsError("a Record carries its own time and drive: give no t or drive with it")
        args: Dict[str, Any] = dict(x=array(x.x, "x"), grid=x._grid())
        if x.drive is not None:
            args["drive"] = array(x.drive, "drive")
        return args
    if isinstance(x, (str, os.PathLike)):
        if t is not None or drive is not None:
            raise OptionsError("a file carries its own time and drive: give no t or drive with a path")
        return dict(path=os.fspath(x))
    args = dict(x=array(x, "x"))
    if t is not None:
        args["t"] = array(t, "t")
    if drive is not None:
        args["drive"] = array(drive, "drive")
    return args
