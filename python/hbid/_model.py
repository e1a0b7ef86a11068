"""Identified models: their coefficients, simulation, saving and loading."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Union

import numpy as np

from . import _hbid
from ._common import HbidWarning, PathLike, array, flag
from ._equation import Equation, equation_text, flattened
from .errors import OptionsError


@dataclass(frozen=True, eq=False)
class SystemRun:
    """A system's free run, as :meth:`Model.simulate` gives it for several coordinates: the
    times, each coordinate's position and velocity by name. ``t, q1, q2, v1, v2 = run`` unpacks
    its columns in order (:attr:`columns`: ``t``, the coordinates, then their velocities, named
    ``q1'``); ``run["q1'"]`` is one by name. ``stopped`` says where and why the run stopped, if
    it did (its later samples are NaN)."""

    t: np.ndarray
    """The times."""
    positions: Dict[str, np.ndarray]
    """Each coordinate's position, by name (angles wrapped into [-pi, pi) unless
    ``wrapped=False``)."""
    velocities: Dict[str, np.ndarray]
    """Each coordinate's velocity, by the coordinate's name."""
    stopped: Optional[str] = None
    """Where and why the run stopped, if it did."""

    @property
    def columns(self) -> List[str]:
        """``t``, the coordinates, then their velocities (``q1'``): the columns of ``hbid
        simulate --model``'s file."""
        return ["t", *self.positions, *(f"{q}'" for q in self.velocities)]

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "t":
            return self.t
        if name in self.positions:
            return self.positions[name]
        if name.endswith("'") and name[:-1] in self.velocities:
            return self.velocities[name[:-1]]
        raise KeyError(f"{name!r}: the columns are {', '.join(self.columns)}")

    def __iter__(self) -> Iterator[np.ndarray]:
        return iter([self.t, *self.positions.values(), *self.velocities.values()])

    def __len__(self) -> int:
        return len(self.t)


def _state(values: Any, name: str) -> List[float]:
    """``x0=``, ``v0=``: one number, or one per coordinate."""
    items = list(values) if isinstance(values, (list, tuple, np.ndarray)) else [values]
    out = []
    for v in items:
        if isinstance(v, (bool, np.bool_)):
            raise OptionsError(f"{name}={values!r}: numbers, one per coordinate")
        try:
            out.append(float(v))
        except (TypeError, ValueError):
            raise OptionsError(f"{name}={values!r}: numbers, one per coordinate") from None
    return out


def _one_state(value: Any, default: float, name: str) -> List[float]:
    """``x0=``, ``v0=`` of one coordinate: one number (or a list of one)."""
    values = _state(default if value is None else value, name)
    if len(values) != 1:
        raise OptionsError(f"{name}={value!r}: the model has one coordinate: give one number")
    return values


def _count(value: Any, name: str, least: int) -> int:
    """A whole number of at least ``least``, or an ``OptionsError`` naming ``name``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < least:
        raise OptionsError(f"{name}={value!r}: a whole number of at least {least}")
    return int(value)


class Model:
    """An identified equation of motion ``x'' + sum c_i g_i(t, x, x') = 0``, or a system of them,
    one per coordinate (``q_i'' + sum c_ik g_ik = 0``, its terms reading the other coordinates,
    their velocities and accelerations, and measured drives).

    Simulate it (:meth:`simulate`), save it (:meth:`save`: JSON for a name ending in ``.json``,
    compact binary otherwise, the files ``hbid identify --save-model`` writes) and load it
    (:meth:`load`). It pickles as its compact bytes; two models are equal when their bytes are.
    A system's equations are in :attr:`equations`, by coordinate.
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
    def coordinates(self) -> List[str]:
        """The coordinates, one equation each: ``["x"]`` for a model of one, a system's names
        (``["theta1", "theta2"]``) otherwise."""
        return list(self._info["coordinates"])

    @property
    def drives(self) -> List[str]:
        """The measured drives the terms read, by name (``["p"]``, ``["tau1", "tau2"]``); empty
        for a model on its own periodic drive."""
        return list(self._info["drives"])

    @property
    def signals(self) -> List[str]:
        """The domain of each coordinate: ``"circle"`` or ``"line"``."""
        return list(self._info["signals"])

    @property
    def is_system(self) -> bool:
        """Whether the model has several coordinates."""
        return len(self._info["coordinates"]) > 1

    @property
    def equations(self) -> Dict[str, Equation]:
        """Each coordinate's equation (its terms, coefficients and standard errors), in order."""
        return {
            e["coordinate"]: Equation(
                coordinate=e["coordinate"],
                coefficients={name: value for name, value, _ in e["coefficients"]},
                std_errors={name: se for name, _, se in e["coefficients"]},
                basis=e["basis"],
                condition_number=None if e["summary"] is None else e["summary"]["condition_number"],
                residual_rms=None if e["summary"] is None else e["summary"]["residual_rms"],
                rows=None if e["summary"] is None else e["summary"]["rows"],
            )
            for e in self._info["equations"]
        }

    @property
    def coefficients(self) -> Dict[str, float]:
        """The coefficient of each term, in the model's order, keyed by the command line's names;
        for a system every equation's, keyed ``"q1: term"`` (each one's alone in
        :attr:`equations`)."""
        if self.is_system:
            return flattened({q: e.coefficients for q, e in self.equations.items()})
        return {name: value for name, value, _ in self._info["coefficients"]}

    @property
    def std_errors(self) -> Dict[str, float]:
        """The standard error of each coefficient (0 for a model built from given values), keyed
        as :attr:`coefficients`."""
        if self.is_system:
            return flattened({q: e.std_errors for q, e in self.equations.items()})
        return {name: se for name, _, se in self._info["coefficients"]}

    @property
    def basis(self) -> str:
        """The basis of the unknown functions (e.g. ``harmonic (K = 1)``); of a system, its first
        equation's (each one's in :attr:`equations`)."""
        return self._info["basis"]

    @property
    def signal(self) -> str:
        """``"circle"`` (an angle) or ``"line"`` (a displacement); of a system whose coordinates
        differ, one per coordinate (``"circle,line"``)."""
        signals = self._info["signals"]
        return signals[0] if len(set(signals)) == 1 else ",".join(signals)
    @property
    def drive_angular_frequency(self) -> float:
        """The drive's angular frequency ``W`` in the record's time unit (radians per unit)."""
        return self._info["forcing_frequency"]

    @property
    def drive_frequency(self) -> float:
        """The drive's frequency ``W / 2 pi`` in cycles per time unit (Hz for seconds), as
        ``drive_frequency=`` takes it."""
        return self.drive_angular_frequency / (2.0 * np.pi)

    @property
    def drive_period(self) -> float:
        """The drive's period ``2 pi / W`` in the record's time unit."""
        return 2.0 * np.pi / self.drive_angular_frequency

    @property
    def forcing_period(self) -> float:
        """The drive's period (the old name of :attr:`drive_period`)."""
        return self.drive_period

    @property
    def forcing_frequency(self) -> float:
        """Deprecated: the drive's *angular* frequency (radians per unit); use
        :attr:`drive_frequency` (cycles per unit) or :attr:`drive_angular_frequency`."""
        warnings.warn(
            "Model.forcing_frequency is the angular frequency; use Model.drive_frequency (cycles per unit) "
            "or Model.drive_angular_frequency",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.drive_angular_frequency

    @property
    def summary(self) -> Optional[Dict[str, Any]]:
        """How the model was fitted (solver, rows, unknowns, segments, condition number,
        residual RMS, the record's forcing period and sample step), or None; of a system, its
        first equation's (the record's period and step are every equation's)."""
        s = self._info["summary"]
        return None if s is None else dict(s)

    @property
    def equation(self) -> str:
        """The equation, ``x'' + c_1*g_1 + ... = 0``, coefficients to 6 significant digits; a
        system's equations one per line."""
        if self.is_system:
            return "\n".join(e.equation for e in self.equations.values())
        return equation_text(self.coefficients)

    def simulate(
        self,
        samples: Optional[int] = None,
        *,
        t: Optional[Any] = None,
        drive: Optional[Any] = None,
        x0: Union[float, Sequence[float], None] = None,
        v0: Union[float, Sequence[float], None] = None,
        samples_per_period: Optional[int] = None,
        transient_periods: int = 0,
        rtol: float = _hbid.DEFAULT_RTOL,
        wrapped: bool = True,
    ) -> Any:
        """Simulates the model from ``(x0, v0)`` in the record's time.

        Either ``samples`` samples on the record's grid (``samples_per_period`` per drive period,
        after ``transient_periods``), or the times ``t`` (an even grid, in the record's time unit;
        the model's own drive at those times), driven by ``drive`` (one sample per time, for a
        model with terms in a measured drive; read between samples from the C1 cubic spline
        through them). With ``t`` the run starts at ``t[0]`` with no transient; a run that blows
        up stops with a :class:`HbidWarning` and NaN from there on.

        A system of several coordinates runs over times ``t`` only, from one position and one
        velocity per coordinate, driven by one series per drive of :attr:`drives`.

        Args:
            samples: samples kept (without ``t``).
            t: the times to run over, instead of ``samples``.
            drive: the measured drive at the times ``t``: an array (a model of one drive), a
                dict of arrays by drive name, or a sequence of arrays in the order of
                :attr:`drives`.
            x0: initial position (default 0.1), or of a system one per coordinate (required).
            v0: initial velocity (default 0), or of a system one per coordinate (default: at
                rest).
            samples_per_period: samples per drive period (default: the record's, from the fit).
            transient_periods: drive periods integrated and dropped first.
            rtol: relative tolerance of the integrator.
            wrapped: angles (on the circle) wrapped into ``[-pi, pi)``.

        Returns:
            ``(t, x, v)`` arrays; of a system, a :class:`SystemRun` (``t, q1, q2, v1, v2 = ...``).

        Raises:
            OptionsError: a state or drives that are not one per coordinate or drive, times off
                an even grid.
            SimulationError: the integration cannot start.
        """
        n = len(self._info["coordinates"])
        if t is None:
            if n > 1:
                raise OptionsError("t: a system runs over given times: give t= (an even grid)")
            if drive is not None:
                raise OptionsError("drive: a measured drive is given at times: give t= with it")
            if samples is None:
                raise OptionsError("give samples= (on the record's grid) or the times t=")
            if self._info["drives"]:
                raise OptionsError(
                    f"drive: the model has terms in the measured drive {', '.join(self._info['drives'])}: "
                    "give its samples at the times t= (drive=...)"
                )
            (start,) = _one_state(x0, 0.1, "x0")
            (speed,) = _one_state(v0, 0.0, "v0")
            return _hbid.model_simulate(
                self._bytes,
                samples=_count(samples, "samples", 1),
                x0=start,
                v0=speed,
                samples_per_period=None if samples_per_period is None else _count(samples_per_period, "samples_per_period", 2),
                transient_periods=_count(transient_periods, "transient_periods", 0),
                rtol=rtol,
                wrapped=flag(wrapped, "wrapped"),
            )
        if samples is not None or samples_per_period is not None or transient_periods != 0:
            raise OptionsError("t: the times say where to run; give no samples, samples_per_period or transient_periods")
        if x0 is None and n > 1:
            raise OptionsError(
                f"x0: give the initial position of each coordinate ({', '.join(self._info['coordinates'])})"
            )
        positions = _state(0.1 if x0 is None else x0, "x0")
        velocities = _state([0.0] * n if v0 is None else v0, "v0")
        d = _hbid.model_run_on(
            self._bytes,
            array(t, "t"),
            x0=positions,
            v0=velocities,
            drive=self._drives(drive),
            rtol=rtol,
        )
        if d["stopped"] is not None:
            warnings.warn(d["stopped"], HbidWarning, stacklevel=2)
        values = list(d["values"])
        for i, signal in enumerate(self._info["signals"]):
            x = values[1 + i]
            if flag(wrapped, "wrapped") and signal == "circle":
                values[1 + i] = np.where(np.isfinite(x), (x + np.pi) % (2.0 * np.pi) - np.pi, x)
        if n == 1:
            return values[0], values[1], values[2]
        names = self._info["coordinates"]
        return SystemRun(
            t=values[0],
            positions=dict(zip(names, values[1 : 1 + n])),
            velocities=dict(zip(names, values[1 + n :])),
            stopped=d["stopped"],
        )

    def _drives(self, drive: Any) -> Optional[List[np.ndarray]]:
        """``drive=`` as one array per drive of the model, in the order of its names."""
        if drive is None:
            return None
        names = self._info["drives"]
        if isinstance(drive, Mapping):
            unknown = sorted(set(drive) - set(names))
            if unknown:
                raise OptionsError(
                    f"drive: {unknown} {'is' if len(unknown) == 1 else 'are'} not a drive of the model "
                    f"(its drives: {', '.join(names) or 'none'})"
                )
            missing = [name for name in names if name not in drive]
            if missing:
                raise OptionsError(f"drive: give the drive(s) {', '.join(missing)} too")
            return [array(drive[name], f"drive[{name!r}]") for name in names]
        if isinstance(drive, (list, tuple)) and drive and not np.isscalar(drive[0]):
            return [array(p, f"drive[{i}]") for i, p in enumerate(drive)]
        return [array(drive, "drive")]

    def save(self, path: PathLike) -> None:
        """Saves the model: JSON if the name ends in ``.json``, compact binary otherwise (written
        to a temporary file and renamed into place; ``OutputError`` if it cannot be)."""
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

