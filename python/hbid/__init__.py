"""hbid: identify the equation of motion of a forced (chaotic, whirling) oscillator from a
measured record, by harmonic balance.

The work is done in Rust (the library behind the command line ``hbid``), without the
interpreter's lock, so threads and Dask workers run side by side; results and messages are the
command line's. Every result is a plain, picklable object.

Example: the paper's pendulum, simulated and identified in three lines::

    import hbid
    t, x, v = hbid.simulate(samples=6000)
    result = hbid.identify(x, t=t, bootstrap=200)
    print(result.equation)
    result.coefficients["sin(t)*cos(x)"]     # about -1.52
    result.intervals["sin(t)*cos(x)"]        # 95 % bootstrap interval

A record from a file (text or ``.npy``), its drive frequency in Hz::

    record = hbid.read("rig.csv", repair=True)
    result = hbid.identify(record, forcing_frequency=1.02)
    result.model.save("rig-model.json")

The functions:

- :func:`read` a record from a file; :func:`simulate` a rig's record;
- :func:`identify` the equation of motion (:class:`Identification`, with its :class:`Model`);
- :func:`embed`: the delay and the embedding dimension (:class:`Embedding`);
- :func:`upos`: unstable periodic orbits by close returns (:class:`Orbits`).

Errors are the exceptions of :mod:`hbid.errors`, all :class:`HbidError`.
"""

from __future__ import annotations

import json as _json
import os
import warnings
from dataclasses import dataclass, field
from typing import Any, Dict, Iterator, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _hbid
from .errors import (
    HbidError,
    IdentificationError,
    InputError,
    ModelError,
    NotSupportedError,
    OptionsError,
    SimulationError,
)

__version__: str = _hbid.__version__

__all__ = [
    "read",
    "simulate",
    "identify",
    "embed",
    "upos",
    "Record",
    "Simulation",
    "Identification",
    "Selection",
    "DroppedTerm",
    "SelectionStep",
    "Model",
    "Embedding",
    "Orbits",
    "Orbit",
    "HbidWarning",
    "HbidError",
    "InputError",
    "OptionsError",
    "IdentificationError",
    "SimulationError",
    "ModelError",
    "NotSupportedError",
]

PathLike = Union[str, "os.PathLike[str]"]
Drive = Union[float, str, None]
ArrayLike = Any


class HbidWarning(UserWarning):
    """Something found in a record that the analysis does not fix by itself (isolated encoder
    spikes left in place: read with ``repair=True`` to replace them)."""


# --------------------------------------------------------------------------------------------
# Records


@dataclass(frozen=True, eq=False)
class Record:
    """A record on its time grid ``t0 + n * dt``, as :func:`read` gives it.

    The time stamps were fitted to a uniform grid; gaps split the record into ``pieces``
    (``(start, stop)`` sample ranges; ``x`` is NaN between them); an angle (``signal="circle"``)
    was wrapped into ``[-pi, pi)``. ``notes`` lists what was done or found, as the command line
    prints it; ``time_repairs`` the stamps replaced by their grid time (``(where, was, now)``)
    and ``spikes`` the isolated encoder spikes found (``(index, size, replaced)``), both only
    repaired with ``repair=True``.

    Pass it to :func:`identify`, :func:`embed` or :func:`upos` in place of an array: its grid
    and signal come with it.
    """

    x: np.ndarray
    t0: float
    dt: float
    pieces: List[Tuple[int, int]]
    signal: str
    repaired: bool = False
    notes: List[str] = field(default_factory=list)
    time_repairs: List[Tuple[str, float, float]] = field(default_factory=list)
    spikes: List[Tuple[int, float, bool]] = field(default_factory=list)
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

    def _grid(self) -> Tuple[float, float, List[Tuple[int, int]]]:
        return (float(self.t0), float(self.dt), [(int(a), int(b)) for a, b in self.pieces])


def _record(d: Mapping[str, Any], path: Optional[str] = None) -> Record:
    notes = [text for text, _ in d["notes"]]
    for text, warning in d["notes"]:
        if warning:
            warnings.warn(text, HbidWarning, stacklevel=3)
    return Record(
        x=d["x"],
        t0=d["t0"],
        dt=d["dt"],
        pieces=[tuple(p) for p in d["pieces"]],
        signal=d["signal"],
        repaired=d["repaired"],
        notes=notes,
        time_repairs=[tuple(r) for r in d["time_repairs"]],
        spikes=[tuple(s) for s in d["spikes"]],
        path=path,
    )


def _column(col: Union[str, int, None], name: str) -> Optional[str]:
    if col is None:
        return None
    if isinstance(col, bool) or not isinstance(col, (str, int)):
        raise OptionsError(f"{name}: a column name or a 1-based position, not {col!r}")
    return str(col)


def read(
    path: PathLike,
    *,
    time_col: Union[str, int, None] = None,
    angle_col: Union[str, int, None] = None,
    dt: Optional[float] = None,
    repair: bool = False,
    signal: str = "circle",
) -> Record:
    """Reads a record from a file, as ``hbid`` reads one.

    Text (cells separated by commas, semicolons, spaces or tabs; a header with columns ``t``
    and ``theta`` (or ``x``, ``angle``), or headerless time and angle in either order) or
    ``.npy`` (a 1-D array of samples with ``dt``, or samples x channels). The time stamps are
    fitted to a uniform grid: gaps split the record into pieces, and an isolated glitch is an
    error unless ``repair=True`` replaces it by its grid time. Isolated encoder spikes (bit
    errors) are reported, and replaced with ``repair=True``.

    Args:
        path: the file.
        time_col: the time column, by header name or 1-based position.
        angle_col: the angle (or displacement) column, by name or 1-based position.
        dt: the sampling step, for a record without a time column (sample 0 at t = 0).
        repair: replace isolated time-stamp glitches and encoder spikes (listed in the notes).
        signal: ``"circle"`` for an angle (wrapped into ``[-pi, pi)``) or ``"line"`` for a
            displacement.

    Returns:
        The :class:`Record` on its grid, with what was repaired.

    Raises:
        InputError: the file, its columns, its values or its time stamps.
        OptionsError: a bad argument.
    """
    path = os.fspath(path)
    d = _hbid.read(
        path,
        time_col=_column(time_col, "time_col"),
        angle_col=_column(angle_col, "angle_col"),
        dt=None if dt is None else float(dt),
        repair=bool(repair),
        signal=signal,
    )
    return _record(d, path)


def _array(values: ArrayLike, name: str) -> np.ndarray:
    try:
        a = np.ascontiguousarray(values, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise OptionsError(f"{name}: not an array of numbers ({e})") from None
    if a.ndim != 1:
        raise OptionsError(f"{name}: a one-dimensional array is needed, not shape {a.shape}")
    return a


def _source(
    x: Union[Record, ArrayLike], t: Optional[ArrayLike], dt: Optional[float], signal: Optional[str]
) -> Dict[str, Any]:
    """The keyword arguments that say where the samples come from."""
    if isinstance(x, Record):
        if signal is not None and signal != x.signal:
            raise OptionsError(
                f"signal={signal!r}: the record was read as {x.signal!r}; read it again with signal={signal!r}"
            )
        if t is not None or dt is not None:
            raise OptionsError("a Record carries its own time: give no t or dt with it")
        return dict(x=_array(x.x, "x"), grid=x._grid(), signal=x.signal, repair=x.repaired)
    return dict(
        x=_array(x, "x"),
        t=None if t is None else _array(t, "t"),
        dt=None if dt is None else float(dt),
        signal="circle" if signal is None else signal,
    )


def _drive(value: Drive, name: str) -> Union[float, str, None]:
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, bool):
        raise OptionsError(f"{name}={value!r}: a number, 'auto' or 'auto:A..B'")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise OptionsError(f"{name}={value!r}: a number, 'auto' or 'auto:A..B'") from None


# --------------------------------------------------------------------------------------------
# Simulation


@dataclass(frozen=True, eq=False)
class Simulation:
    """A simulated record: ``t, x, v = hbid.simulate()`` unpacks it.

    ``x`` is the angle as the encoder reports it (wrapped unless ``unwrapped=True``; counts with
    ``raw_counts=True``) or the Duffing displacement; ``v`` the clean velocity. ``truth`` holds
    the coefficients of the equation the record satisfies, ``x'' + sum c_i g_i = 0``, in the
    identification's term names and the record's time unit (as ``hbid simulate --truth``).
    """

    t: np.ndarray
    """The time stamps."""
    x: np.ndarray
    """The angle (or displacement, or counts) as recorded."""
    v: np.ndarray
    """The velocity, in the record's time unit."""
    columns: Tuple[str, str, str]
    """The columns ``hbid simulate`` would write (``t,theta,omega``, ``t,count,omega``, ``t,x,v``)."""
    truth: Dict[str, float]
    """The true coefficients, keyed by the identification's term names."""
    forcing_period: float
    """The drive's period in the record's time unit."""
    sample_step: float
    """The sampling step."""

    def __iter__(self) -> Iterator[np.ndarray]:
        return iter((self.t, self.x, self.v))

    def __len__(self) -> int:
        return len(self.t)


def simulate(
    *,
    system: str = "pendulum",
    f: Optional[float] = None,
    c: Optional[float] = None,
    r: Optional[float] = None,
    a: Optional[float] = None,
    b: Optional[float] = None,
    forcing: str = "drive",
    x0: float = 0.1,
    v0: float = 0.0,
    rtol: float = 1e-10,
    drive_frequency: Optional[float] = None,
    sample_rate: Optional[float] = None,
    samples_per_period: Optional[int] = None,
    samples: Optional[int] = None,
    duration: Optional[float] = None,
    transient_periods: Optional[int] = None,
    phase: float = 0.0,
    time_origin: str = "drive",
    counts: Optional[int] = None,
    raw_counts: bool = False,
    zero_offset: Optional[float] = None,
    bit_errors: Optional[float] = None,
    angle_range: Optional[str] = None,
    noise: Optional[float] = None,
    seed: int = 0,
    unwrapped: bool = False,
    gaps: Optional[Tuple[int, int]] = None,
) -> Simulation:
    """Simulates a rig's record, as ``hbid simulate`` does (defaults: the paper's data set).

    The base-excited pendulum ``x'' + c x' + (1/r^2) sin x - f sin(t) cos x = 0`` or the
    two-well Duffing oscillator ``x'' + c x' + a x + b x^3 = f cos(t)``, sampled as a rig records
    it. Without options: 30000 samples, 25 per drive period 2 pi, after 200 periods, the angle
    wrapped into ``[-pi, pi)``.

    Args:
        system: ``"pendulum"`` or ``"duffing"``.
        f: drive amplitude (default 1.52 for the pendulum, 0.3 for Duffing).
        c: damping (default 0.03, or 0.25).
        r: pendulum: frequency ratio, stiffness 1/r^2 (default 0.8333).
        a: Duffing: linear stiffness (default -1).
        b: Duffing: cubic stiffness (default 1).
        forcing: ``"drive"``, or ``"none"`` for a free decay (f = 0, no transient by default).
        x0: initial angle (or displacement) at the start of the integration.
        v0: initial velocity, in the record's time unit.
        rtol: relative tolerance of the integrator (absolute: rtol/10).
        drive_frequency: drive frequency in Hz: time in seconds. Without it, the model's own
            time (drive period 2 pi).
        sample_rate: samples per second, any ratio to the drive (needs drive_frequency).
        samples_per_period: samples per drive period, a whole number (default 25).
        samples: samples kept, before gaps remove any (default 30000).
        duration: the record's length in its time unit, instead of samples.
        transient_periods: drive periods integrated and dropped first (default 200).
        phase: drive phase (radians) of the first sample.
        time_origin: ``"drive"`` (stamps are the integration's time) or ``"first-sample"``
            (stamps ``n h`` from 0, as a data acquisition's clock).
        counts: encoder counts per revolution (the angle to the nearest count).
        raw_counts: give the integer counts in ``[0, N)`` instead of radians (needs counts).
        zero_offset: the encoder's zero this far (radians) from the bottom.
        bit_errors: probability per sample of a bit error of the count (needs counts >= 1024).
        angle_range: ``"signed"`` ``[-pi, pi)`` or ``"positive"`` ``[0, 2 pi)``.
        noise: standard deviation of Gaussian noise on the angle or displacement.
        seed: seed of the noise, the bit errors and the gaps.
        unwrapped: the continuous angle instead of the wrapped one.
        gaps: ``(K, LEN)``: drop K runs of LEN samples at seeded places.

    Returns:
        A :class:`Simulation` (``t, x, v = ...`` unpacks the arrays).

    Raises:
        OptionsError: a bad value or combination of options.
        SimulationError: the integration failed.
    """
    d = _hbid.simulate(
        system=system,
        f=f,
        c=c,
        r=r,
        a=a,
        b=b,
        forcing=forcing,
        x0=x0,
        v0=v0,
        rtol=rtol,
        drive_frequency=drive_frequency,
        sample_rate=sample_rate,
        samples_per_period=samples_per_period,
        samples=samples,
        duration=duration,
        transient_periods=transient_periods,
        phase=phase,
        time_origin=time_origin,
        counts=counts,
        raw_counts=raw_counts,
        zero_offset=zero_offset,
        bit_errors=bit_errors,
        angle_range=angle_range,
        noise=noise,
        seed=seed,
        unwrapped=unwrapped,
        gaps=None if gaps is None else tuple(gaps),
    )
    return Simulation(
        t=d["t"],
        x=d["x"],
        v=d["v"],
        columns=tuple(d["columns"]),
        truth=dict(d["truth"]),
        forcing_period=d["forcing_period"],
        sample_step=d["sample_step"],
    )


# --------------------------------------------------------------------------------------------
# Models


class Model:
    """An identified equation of motion ``x'' + sum c_i g_i(t, x, x') = 0``.

    Simulate it (:meth:`simulate`), save it (:meth:`save`: JSON for a name ending in ``.json``,
    compact binary otherwise, the files ``hbid identify --save-model`` writes) and load it
    (:meth:`load`). It pickles as its compact bytes; two models are equal when their bytes are.
    """

    __slots__ = ("_bytes", "_info")

    def __init__(self, data: bytes):
        """A model from its compact bytes (:meth:`to_bytes`)."""
        info = _hbid.model_info(bytes(data))
        self._bytes = bytes(data)
        self._info = info

    def __getstate__(self) -> bytes:
        return self._bytes

    def __setstate__(self, state: bytes) -> None:
        self._bytes = state
        self._info = _hbid.model_info(state)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Model) and other._bytes == self._bytes

    def __hash__(self) -> int:
        return hash(self._bytes)

    def __repr__(self) -> str:
        return f"Model({self.equation!r})"

    @property
    def coefficients(self) -> Dict[str, float]:
        """The coefficient of each term, in the model's order, keyed by the command line's names."""
        return {name: value for name, value, _ in self._info["coefficients"]}

    @property
    def std_errors(self) -> Dict[str, float]:
        """The standard error of each coefficient (0 for a model built from given values)."""
        return {name: se for name, _, se in self._info["coefficients"]}

    @property
    def basis(self) -> str:
        """The basis of the unknown functions (e.g. ``harmonic (K = 1)``)."""
        return self._info["basis"]

    @property
    def signal(self) -> str:
        """``"circle"`` (an angle) or ``"line"`` (a displacement)."""
        return self._info["signal"]

    @property
    def forcing_frequency(self) -> float:
        """The drive's angular frequency ``W`` in the record's time unit (radians per unit)."""
        return self._info["forcing_frequency"]

    @property
    def forcing_period(self) -> float:
        """The forcing period ``2 pi / W`` in the record's time unit."""
        return 2.0 * np.pi / self.forcing_frequency

    @property
    def summary(self) -> Optional[Dict[str, Any]]:
        """How the model was fitted (solver, rows, unknowns, segments, condition number,
        residual RMS, the record's forcing period and sample step), or None."""
        s = self._info["summary"]
        return None if s is None else dict(s)

    @property
    def equation(self) -> str:
        """The equation, ``x'' + c_1*g_1 + ... = 0``, coefficients to 6 significant digits."""
        return _equation(self.coefficients)

    def simulate(
        self,
        samples: int,
        *,
        x0: float = 0.1,
        v0: float = 0.0,
        samples_per_period: Optional[int] = None,
        transient_periods: int = 0,
        rtol: float = 1e-10,
        wrapped: bool = True,
    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Simulates the model from ``(x0, v0)`` in the record's time.

        Args:
            samples: samples kept.
            x0: initial position.
            v0: initial velocity.
            samples_per_period: samples per forcing period (default: the record's, from the fit).
            transient_periods: forcing periods integrated and dropped first.
            rtol: relative tolerance of the integrator.
            wrapped: on the circle, the angle wrapped into ``[-pi, pi)``.

        Returns:
            ``(t, x, v)`` arrays.
        """
        return _hbid.model_simulate(
            self._bytes,
            samples=samples,
            x0=x0,
            v0=v0,
            samples_per_period=samples_per_period,
            transient_periods=transient_periods,
            rtol=rtol,
            wrapped=wrapped,
        )

    def save(self, path: PathLike) -> None:
        """Saves the model: JSON if the name ends in ``.json``, compact binary otherwise (written
        to a temporary file and renamed into place)."""
        _hbid.model_save(self._bytes, os.fspath(path))

    @classmethod
    def load(cls, path: PathLike) -> "Model":
        """Loads a model saved by :meth:`save` or ``hbid identify --save-model``."""
        return cls(_hbid.model_load(os.fspath(path)))

    def to_json(self) -> str:
        """The model as JSON (the file :meth:`save` writes for a ``.json`` name)."""
        return _hbid.model_json(self._bytes)

    @classmethod
    def from_json(cls, text: str) -> "Model":
        """A model from its JSON (:meth:`to_json`)."""
        return cls(_hbid.model_from_json(text))

    def to_bytes(self) -> bytes:
        """The model's compact binary form (what :meth:`save` writes for other names)."""
        return self._bytes


def _equation(coefficients: Mapping[str, float]) -> str:
    parts = ["x''"]
    for name, value in coefficients.items():
        sign = "-" if value < 0 else "+"
        parts.append(f"{sign} {abs(value):.6g}*{name}")
    return " ".join(parts) + " = 0"


# --------------------------------------------------------------------------------------------
# Identification


class DroppedTerm(NamedTuple):
    """A candidate term the selection dropped, and why: the cross-validated fraction of the
    held-out equations' right-hand side left unexplained by the model just without it and just
    with it (the term removes less than the allowance)."""

    term: str
    unexplained_without: float
    unexplained_with: float


class SelectionStep(NamedTuple):
    """One model of the backward elimination: the term removed to reach it (None for the whole
    library), its number of terms, its cross-validated unexplained fraction and that score's
    standard error over the folds."""

    removed: Optional[str]
    terms: int
    unexplained: float
    std_error: float


@dataclass(frozen=True)
class Selection:
    """Which terms of a library of candidates the data support, as ``hbid identify --select``
    chooses them: backward elimination scored by cross-validation over contiguous folds of
    segments; the smallest model on the path within ``allowance`` of the best one is kept
    (``allowance`` is the larger of the best score's standard error and the tolerance).

    ``kept`` are the model's terms (in the library's order); ``dropped`` the others, in the
    order they were removed.
    """

    library: List[str]
    kept: List[str]
    dropped: List[DroppedTerm]
    folds: int
    allowance: float
    path: List[SelectionStep]

    @classmethod
    def _from_json(cls, d: Mapping[str, Any]) -> "Selection":
        return cls(
            library=list(d["library"]),
            kept=list(d["kept"]),
            dropped=[
                DroppedTerm(x["term"], x["unexplained_without"], x["unexplained_with"]) for x in d["dropped"]
            ],
            folds=d["folds"],
            allowance=d["allowance"],
            path=[SelectionStep(p["removed"], p["terms"], p["unexplained"], p["std_error"]) for p in d["path"]],
        )


@dataclass(frozen=True)
class Identification:
    """An identified equation of motion ``x'' + sum c_i g_i = 0`` with its uncertainties.

    ``coefficients``, ``std_errors`` and ``intervals`` are keyed by the command line's term names
    (``x'``, ``sin(x)``, ``cos(t)*cos(x)``, ``hat3``, ...), in the model's order. :meth:`to_json`
    is exactly what ``hbid identify --json`` prints. Results of the same record, settings and
    seed are identical, whatever the machine's threads.
    """

    coefficients: Dict[str, float]
    """The coefficient of each term."""
    std_errors: Dict[str, float]
    """The standard error of each coefficient (least squares)."""
    intervals: Optional[Dict[str, Tuple[float, float]]]
    """The bootstrap interval of each coefficient at ``interval_level``; None with ``bootstrap=0``."""
    interval_level: Optional[float]
    """The confidence level of the intervals."""
    resamples: int
    """Bootstrap resamples."""
    model: Model
    """The model: simulate, save and load it."""
    method: str
    """``"windowed"`` or ``"upo"``."""
    basis: str
    """The basis as named on the command line (``harmonic:1``, ``hat:8``, ``poly:3``)."""
    signal: str
    """``"circle"`` or ``"line"``."""
    segments: int
    """Orbit segments (``upo``) or windows (``windowed``) used."""
    delay: Optional[int]
    """The delay of the close-return search (``upo``), in samples."""
    forcing_period: float
    """The forcing period of the analysis, in the record's time unit."""
    forcing_period_uncertainty: Optional[float]
    """Its standard uncertainty when it was estimated from the record."""
    drive: str
    """``"given"``, ``"estimated"`` or ``"free"`` (no drive: the free oscillation's period)."""
    samples_per_period: int
    """Samples per forcing period after any resampling."""
    resampled_from: Optional[float]
    """Samples per forcing period as read, when the record was resampled."""
    summary: str
    """One line on the record as analysed."""
    json_text: str = field(repr=False)
    """The JSON of ``hbid identify --json``."""

    @property
    def equation(self) -> str:
        """The equation, ``x'' + c_1*g_1 + ... = 0``, coefficients to 6 significant digits."""
        return _equation(self.coefficients)

    @property
    def terms(self) -> List[str]:
        """The model's terms, in its order (with ``select``, the kept ones)."""
        return list(self.coefficients)

    @property
    def selection(self) -> Optional[Selection]:
        """With ``select``: the library, the kept terms and why the others were dropped; else None."""
        d = _json.loads(self.json_text)["selection"]
        return None if d is None else Selection._from_json(d)

    @property
    def explained(self) -> float:
        """The fraction of the balanced acceleration the model explains, in [0, 1]."""
        return _json.loads(self.json_text)["explained"]

    @property
    def warning(self) -> Optional[str]:
        """The command line's warning when the model explains too little, else None."""
        return _json.loads(self.json_text)["warning"]

    @property
    def condition_number(self) -> float:
        """The condition number of the column-scaled system."""
        return _json.loads(self.json_text)["condition_number"]

    @property
    def residual_rms(self) -> float:
        """The residual root mean square of the equations."""
        return _json.loads(self.json_text)["residual_rms"]

    @property
    def rows(self) -> int:
        """Equations of the stacked system."""
        return _json.loads(self.json_text)["rows"]

    def to_json(self) -> str:
        """The JSON ``hbid identify --json`` prints for the same record and options."""
        return self.json_text

    def __str__(self) -> str:
        lines = [f"{self.equation}", f"method {self.method}, basis {self.basis}, {self.segments} segments"]
        for name, value in self.coefficients.items():
            se = self.std_errors[name]
            line = f"  {name:<18} {value:>14.6f} {se:>12.2e}"
            if self.intervals is not None:
                lo, hi = self.intervals[name]
                line += f"   [{lo:.6f}, {hi:.6f}]"
            lines.append(line)
        return "\n".join(lines)


def _terms(terms: Union[str, Sequence[str], None]) -> Optional[str]:
    """``terms=`` as the list's text."""
    if terms is None or isinstance(terms, str):
        return terms
    try:
        items = list(terms)
    except TypeError:
        raise OptionsError(f"terms={terms!r}: a list of terms as text, or a sequence of such texts") from None
    if not all(isinstance(t, str) for t in items):
        raise OptionsError(f"terms={terms!r}: every item must be a text such as 'sin(t)*cos(x)'")
    return ", ".join(items)


def _select(select: Union[bool, Mapping[str, Any]]) -> Dict[str, Any]:
    """``select=`` as the extension's arguments."""
    if isinstance(select, bool):
        return {"select": select}
    if not isinstance(select, Mapping):
        raise OptionsError(f"select={select!r}: True, False or a mapping with 'folds' and 'tolerance'")
    unknown = sorted(set(select) - {"folds", "tolerance"})
    if unknown:
        raise OptionsError(f"select: unknown option(s) {unknown}; expected 'folds' and 'tolerance'")
    out: Dict[str, Any] = {"select": True}
    if "folds" in select:
        folds = select["folds"]
        if isinstance(folds, bool) or not isinstance(folds, int) or folds < 0:
            raise OptionsError(f"select: folds={folds!r} must be a whole number, at least 2")
        out["select_folds"] = folds
    if "tolerance" in select:
        try:
            out["select_tolerance"] = float(select["tolerance"])
        except (TypeError, ValueError):
            raise OptionsError(f"select: tolerance={select['tolerance']!r} must be a number in [0, 1)") from None
    return out


def identify(
    x: Union[Record, ArrayLike],
    *,
    t: Optional[ArrayLike] = None,
    dt: Optional[float] = None,
    forcing_period: Drive = None,
    forcing_frequency: Drive = None,
    signal: Optional[str] = None,
    method: str = "windowed",
    terms: Union[str, Sequence[str], None] = None,
    select: Union[bool, Mapping[str, Any]] = False,
    bootstrap: int = 1000,
    seed: int = 0,
    level: Optional[float] = None,
    basis: Optional[str] = None,
    forcing: Optional[str] = None,
    parametric: bool = True,
    harmonics: Optional[int] = None,
    window_periods: Optional[int] = None,
    window_order: Optional[int] = None,
    noise_sigma: Union[float, str, None] = None,
    solver: str = "qr",
    repair: bool = False,
    tolerance: Optional[float] = None,
    max_period: Optional[int] = None,
    dim: Optional[int] = None,
    delay: Optional[int] = None,
) -> Identification:
    """Identifies the equation of motion of a record, as ``hbid identify`` does.

    The record is fitted to its time grid, wrapped (an angle), resampled onto a whole number of
    samples per forcing period when needed, cut into windows (``method="windowed"``, the weak
    form) or searched for unstable periodic orbits (``method="upo"``, the paper's), and the
    coefficients are found by least squares, with bootstrap intervals.

    Args:
        x: the samples (a 1-D array) or a :class:`Record` from :func:`read`.
        t: the time stamps of the samples.
        dt: or their sampling step (sample 0 at t = 0).
        forcing_period: the forcing period in the record's time unit (default 2 pi, the paper's
            time), ``"auto"`` or ``"auto:A..B"`` to estimate it (within periods A to B).
        forcing_frequency: or the forcing frequency (Hz for time in seconds), ``"auto"`` or
            ``"auto:A..B"``.
        signal: ``"circle"`` (an angle, the default) or ``"line"`` (a displacement); a Record's own.
        method: ``"windowed"`` (weak form on plain windows) or ``"upo"`` (orbits by close returns).
        terms: the model's terms instead of the default, as ``hbid identify --terms`` reads
            them: a string such as ``"x', sign(x'), {1,cos(t),sin(t)}*{cos(x),sin(x)}"`` (braces
            multiply out), or a sequence of such strings (joined by commas). Without ``basis``
            the smallest basis that holds every function of x named is used. Not with
            ``forcing="identified"`` or ``parametric=False`` (the list says its terms).
        select: model selection, as ``hbid identify --select``: the model's terms (``terms``, or
            the default's) are a library of candidates, those that predict held-out stretches of
            the record are kept and fitted alone (:attr:`Identification.selection` says which
            and why). ``True`` for the defaults, or a mapping with ``"folds"`` (contiguous folds
            of segments, at least 2; default 10) and ``"tolerance"`` (the smallest held-out
            unexplained fraction a term must remove, in [0, 1); default 1e-6).
        bootstrap: bootstrap resamples for the intervals (0: none).
        seed: seed of the bootstrap: the same seed gives the same result on any machine.
        level: confidence level of the intervals (default 0.95).
        basis: ``"harmonic:K"``, ``"hat:N"`` or ``"poly:D"`` (default ``harmonic:1`` on the
            circle, ``poly:3`` on the line).
        forcing: external forcing terms cos(t), sin(t): ``"none"`` (the default on the circle)
            or ``"identified"`` (the default on the line). ``"none"`` with no forcing period or
            frequency is a free oscillation: no drive at all (windowed method).
        parametric: keep the parametric terms ``cos(t)*B``, ``sin(t)*B``.
        harmonics: harmonics per segment (default: the method's).
        window_periods: windowed method: window length in forcing periods.
        window_order: windowed method: order p of the window ``sin^p``.
        noise_sigma: correct the bias of Gaussian noise on the angle: sigma in radians, or
            ``"auto"`` to estimate it (harmonic basis).
        solver: ``"qr"`` or ``"svd"``.
        repair: replace isolated time-stamp glitches and encoder spikes.
        tolerance: ``upo``: close-return tolerance, a fraction of the data's span.
        max_period: ``upo``: longest orbit period searched, in forcing periods.
        dim: ``upo``: dimension of the delay vectors compared.
        delay: ``upo``: delay in samples (default: first minimum of the mutual information).

    Returns:
        The :class:`Identification`.

    Raises:
        InputError: the record.
        OptionsError: a bad argument.
        IdentificationError: too few segments, a rank-deficient system, a drive that cannot be
            estimated.
    """
    d = _hbid.identify(
        **_source(x, t, dt, signal),
        **({} if isinstance(x, Record) else {"repair": bool(repair)}),
        forcing_period=_drive(forcing_period, "forcing_period"),
        forcing_frequency=_drive(forcing_frequency, "forcing_frequency"),
        forcing=forcing,
        parametric=bool(parametric),
        method=method,
        basis=basis,
        harmonics=harmonics,
        window_periods=window_periods,
        window_order=window_order,
        bootstrap=bootstrap,
        level=level,
        seed=seed,
        noise_sigma=noise_sigma,
        solver=solver,
        tolerance=tolerance,
        max_period=max_period,
        dim=dim,
        delay=delay,
        terms=_terms(terms),
        **_select(select),
    )
    intervals = None
    if d["intervals"] is not None:
        intervals = {name: (lo, hi) for name, lo, hi in d["intervals"]}
    return Identification(
        coefficients={name: value for name, value, _ in d["coefficients"]},
        std_errors={name: se for name, _, se in d["coefficients"]},
        intervals=intervals,
        interval_level=d["interval_level"],
        resamples=d["resamples"],
        model=Model(d["model"]),
        method=d["method"],
        basis=d["basis"],
        signal=d["signal"],
        segments=d["segments"],
        delay=d["delay"],
        forcing_period=d["forcing_period"],
        forcing_period_uncertainty=d["forcing_period_uncertainty"],
        drive=d["drive"],
        samples_per_period=d["samples_per_period"],
        resampled_from=d["resampled_from"],
        summary=d["summary"],
        json_text=d["json"],
    )


# --------------------------------------------------------------------------------------------
# Embedding and orbits


@dataclass(frozen=True, eq=False)
class Embedding:
    """The delay and the embedding dimension of a record, as ``hbid embed`` finds them.

    ``ami`` is the average mutual information (nats) at lags 0, 1, ...; ``delay`` its first
    minimum; ``fnn`` the fraction of false nearest neighbours in dimensions 1, 2, ...;
    ``embedding_dimension`` the first below ``fraction_threshold`` (None if none is).
    """

    delay: int
    embedding_dimension: Optional[int]
    ami: np.ndarray
    fnn: np.ndarray
    fraction_threshold: float
    metric: str
    forcing_period: float
    samples_per_period: int
    summary: str
    json_text: str = field(repr=False)

    def to_json(self) -> str:
        """The JSON ``hbid embed --json`` prints."""
        return self.json_text


def embed(
    x: Union[Record, ArrayLike],
    *,
    t: Optional[ArrayLike] = None,
    dt: Optional[float] = None,
    forcing_period: Drive = None,
    forcing_frequency: Drive = None,
    signal: Optional[str] = None,
    repair: bool = False,
    max_lag: Optional[int] = None,
    bins: int = 16,
    max_dim: int = 8,
    metric: Optional[str] = None,
    theiler: int = 0,
) -> Embedding:
    """Chooses the delay (first minimum of the average mutual information) and checks the
    embedding dimension (false nearest neighbours), as ``hbid embed`` does.

    Args:
        x, t, dt, forcing_period, forcing_frequency, signal, repair: the record, as for
            :func:`identify`.
        max_lag: largest lag of the mutual information (default: two forcing periods, at least 40).
        bins: equal boxes of the mutual-information histogram.
        max_dim: largest embedding dimension tested.
        metric: ``"circle"`` or ``"linear"`` (plain differences) (default: the signal's).
        theiler: neighbours closer in time than this many samples are not counted.

    Raises:
        InputError, OptionsError, IdentificationError: as for :func:`identify`.
    """
    d = _hbid.embed(
        **_source(x, t, dt, signal),
        **({} if isinstance(x, Record) else {"repair": bool(repair)}),
        forcing_period=_drive(forcing_period, "forcing_period"),
        forcing_frequency=_drive(forcing_frequency, "forcing_frequency"),
        max_lag=max_lag,
        bins=bins,
        max_dim=max_dim,
        metric=metric,
        theiler=theiler,
    )
    return Embedding(
        delay=d["delay"],
        embedding_dimension=d["embedding_dimension"],
        ami=d["ami"],
        fnn=d["fnn"],
        fraction_threshold=d["fraction_threshold"],
        metric=d["metric"],
        forcing_period=d["forcing_period"],
        samples_per_period=d["samples_per_period"],
        summary=d["summary"],
        json_text=d["json"],
    )


class Orbit(NamedTuple):
    """A segment of the record that nearly repeats after ``period`` forcing periods."""

    period: int
    """The orbit's period, in forcing periods."""
    start: int
    """Its first sample."""
    error: float
    """The close-return distance (the largest over the compared delay vectors), in the
    signal's unit: at most the search's tolerance."""


@dataclass(frozen=True)
class Orbits:
    """Unstable periodic orbits found by close returns, as ``hbid upos`` finds them.

    ``segments`` are the passages found; ``orbit_of_segment[i]`` the distinct orbit segment
    ``i`` belongs to; ``tolerance`` the close-return distance allowed, in the signal's unit (the
    fraction asked for times the data's span, 2 pi for an angle).
    """

    segments: List[Orbit]
    orbit_of_segment: List[int]
    distinct_orbits: int
    delay: int
    tolerance: float
    forcing_period: float
    samples_per_period: int
    summary: str
    json_text: str = field(repr=False)

    @property
    def by_period(self) -> Dict[int, int]:
        """Segments found per period."""
        out: Dict[int, int] = {}
        for s in self.segments:
            out[s.period] = out.get(s.period, 0) + 1
        return dict(sorted(out.items()))

    def to_json(self) -> str:
        """The JSON ``hbid upos --json`` prints."""
        return self.json_text


def upos(
    x: Union[Record, ArrayLike],
    *,
    t: Optional[ArrayLike] = None,
    dt: Optional[float] = None,
    forcing_period: Drive = None,
    forcing_frequency: Drive = None,
    signal: Optional[str] = None,
    repair: bool = False,
    tolerance: Optional[float] = None,
    max_period: Optional[int] = None,
    dim: Optional[int] = None,
    delay: Optional[int] = None,
) -> Orbits:
    """Finds unstable periodic orbits by close returns, as ``hbid upos`` does.

    Args:
        x, t, dt, forcing_period, forcing_frequency, signal, repair: the record, as for
            :func:`identify`.
        tolerance: close-return tolerance, a fraction of the data's span (default 0.03).
        max_period: longest orbit period searched, in forcing periods (default 16).
        dim: dimension of the delay vectors compared (default 2).
        delay: delay in samples (default: first minimum of the mutual information).

    Raises:
        InputError, OptionsError, IdentificationError: as for :func:`identify`.
    """
    d = _hbid.upos(
        **_source(x, t, dt, signal),
        **({} if isinstance(x, Record) else {"repair": bool(repair)}),
        forcing_period=_drive(forcing_period, "forcing_period"),
        forcing_frequency=_drive(forcing_frequency, "forcing_frequency"),
        tolerance=tolerance,
        max_period=max_period,
        dim=dim,
        delay=delay,
    )
    return Orbits(
        segments=[Orbit(*s) for s in d["segments"]],
        orbit_of_segment=list(d["orbit_of_segment"]),
        distinct_orbits=d["distinct_orbits"],
        delay=d["delay"],
        tolerance=d["tolerance"],
        forcing_period=d["forcing_period"],
        samples_per_period=d["samples_per_period"],
        summary=d["summary"],
        json_text=d["json"],
    )
