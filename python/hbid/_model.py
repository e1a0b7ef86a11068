"""Identified models: their coefficients, simulation, saving and loading."""

from __future__ import annotations

import os
import warnings
from typing import Any, Dict, Mapping, Optional, Tuple

import numpy as np

from . import _hbid
from ._common import HbidWarning, PathLike, array
from .errors import OptionsError


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
        residual RMS, the record's forcing period and sample step), or None."""
        s = self._info["summary"]
        return None if s is None else dict(s)

    @property
    def equation(self) -> str:
        """The equation, ``x'' + c_1*g_1 + ... = 0``, coefficients to 6 significant digits."""
        return equation_text(self.coefficients)

    def simulate(
        self,
        samples: Optional[int] = None,
        *,
        t: Optional[Any] = None,
        drive: Optional[Any] = None,
        x0: float = 0.1,
        v0: float = 0.0,
        samples_per_period: Optional[int] = None,
        transient_periods: int = 0,
        rtol: float = 1e-10,
        wrapped: bool = True,
    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Simulates the model from ``(x0, v0)`` in the record's time.

        Either ``samples`` samples on the record's grid (``samples_per_period`` per drive period,
        after ``transient_periods``), or the times ``t`` (an even grid, in the record's time unit;
        the model's own drive at those times), driven by ``drive`` (one sample per time, for a
        model with terms in the measured drive ``p``; read between samples from the C1 cubic
        spline through them). With ``t`` the run starts at ``t[0]`` with no transient; a run that
        blows up stops with a :class:`HbidWarning` and NaN from there on.

        Args:
            samples: samples kept (without ``t``).
            t: the times to run over, instead of ``samples``.
            drive: the measured drive at the times ``t``.
            x0: initial position.
            v0: initial velocity.
            samples_per_period: samples per drive period (default: the record's, from the fit).
            transient_periods: drive periods integrated and dropped first.
            rtol: relative tolerance of the integrator.
            wrapped: on the circle, the angle wrapped into ``[-pi, pi)``.

        Returns:
            ``(t, x, v)`` arrays.
        """
        if t is None:
            if drive is not None:
                raise OptionsError("drive: a measured drive is given at times: give t= with it")
            if samples is None:
                raise OptionsError("give samples= (on the record's grid) or the times t=")
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
        if samples is not None or samples_per_period is not None or transient_periods != 0:
            raise OptionsError("t: the times say where to run; give no samples, samples_per_period or transient_periods")
        d = _hbid.model_run_on(
            self._bytes,
            array(t, "t"),
            x0=float(x0),
            v0=float(v0),
            drive=None if drive is None else array(drive, "drive"),
            rtol=rtol,
        )
        if d["stopped"] is not None:
            warnings.warn(d["stopped"], HbidWarning, stacklevel=2)
        x = d["x"]
        if wrapped and self.signal == "circle":
            x = np.where(np.isfinite(x), (x + np.pi) % (2.0 * np.pi) - np.pi, x)
        return d["t"], x, d["v"]

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


def equation_text(coefficients: Mapping[str, float]) -> str:
    """``x'' + c_1*g_1 + ... = 0``, coefficients to 6 significant digits."""
    parts = ["x''"]
    for name, value in coefficients.items():
        sign = "-" if value < 0 else "+"
        parts.append(f"{sign} {abs(value):.6g}*{name}")
    return " ".join(parts) + " = 0"
