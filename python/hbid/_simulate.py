"""Simulated rigs, as ``hbid simulate`` makes them."""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from typing import Any, Dict, Iterator, Optional, Sequence, Tuple, Union

import numpy as np

from . import _hbid
from ._common import ColumnsLike, PathLike, options_json, renamed
from ._equation import flattened
from .errors import OptionsError


@dataclass(frozen=True, eq=False)
class Simulation:
    """A simulated record: ``t, x, v = hbid.simulate()`` unpacks it.

    ``x`` is the angle as the encoder reports it (wrapped unless ``unwrapped=True``; counts with
    ``raw_counts=True``) or the Duffing displacement; ``v`` the clean velocity; ``drive`` the
    drive ``p(t)`` as it enters the equation (with ``write_drive=True``, else None). The rows are
    those ``hbid simulate`` writes (the gaps left out, the numbers as printed with ``decimals``).
    ``truth`` holds the coefficients of the equation the record satisfies, ``x'' + sum c_i g_i =
    0``, in the identification's term names and the record's time unit (as ``hbid simulate
    --truth``); ``truth_file`` the whole truth file.
    """

    t: np.ndarray
    """The time stamps."""
    x: np.ndarray
    """The angle (or displacement, or counts) as recorded."""
    v: np.ndarray
    """The velocity, in the record's time unit."""
    drive: Optional[np.ndarray]
    """The drive p(t), with ``write_drive=True``."""
    columns: Tuple[str, ...]
    """The columns ``hbid simulate`` writes (``t,theta,omega``, ``t,count,omega``, ``t,x,v``, and
    ``p``; a system's ``t``, its coordinates, their velocities and its drives:
    ``t,theta1,theta2,omega1,omega2``)."""
    truth_file: Dict[str, Any]
    """The truth file ``hbid simulate --truth`` writes."""
    named: Dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    """Every column by its name (``sim.named["theta2"]``)."""

    @property
    def truth(self) -> Dict[str, float]:
        """The true coefficients, keyed by the identification's term names (of a system every
        equation's, ``"theta1: sin(theta1)"``, as :attr:`Identification.coefficients` keys
        them)."""
        if "equations" in self.truth_file:
            return flattened({q: e["coefficients"] for q, e in self.truth_equations.items()})
        return dict(self.truth_file["coefficients"])

    @property
    def truth_equations(self) -> Dict[str, Dict[str, Any]]:
        """A system's true equations by coordinate, each with its ``coefficients`` by term name;
        of a system of one coordinate, ``{"x": {"coefficients": truth}}``."""
        if "equations" in self.truth_file:
            return {q: dict(e) for q, e in self.truth_file["equations"].items()}
        return {"x": {"coefficients": dict(self.truth_file["coefficients"])}}

    @property
    def identify_options(self) -> Dict[str, Any]:
        """The keywords of :func:`identify` that identify the truth's equations from this record
        (the truth file's hint: a system's ``coords``, ``signal``, ``terms`` and drives; for a
        record of one coordinate its ``signal``, the truth's ``terms`` and, in seconds, its
        ``drive_frequency``), if it has them."""
        hint = dict(self.truth_file.get("identify") or {})
        hint.pop("args", None)
        if not hint or "equations" in self.truth_file:
            return hint
        # A record of one coordinate: the truth's terms, on its drive (the hint's other keys say
        # how the CLI's defaults read the record's columns).
        terms = list(self.truth_file["coefficients"])
        options: Dict[str, Any] = {"signal": hint["signal"]}
        if self.truth_file.get("forcing") == "none":
            # A free oscillation: no drive's phase to balance (its drive terms are all 0).
            terms = [t for t in terms if not re.search(r"\b(cos|sin)\(\d*t\)", t)]
            options["forcing"] = "none"
        elif self.truth_file.get("time_unit") == "s" and self.truth_file.get("drive_frequency"):
            options["drive_frequency"] = self.truth_file["drive_frequency"]
        encoder = self.truth_file.get("encoder") or {}
        if encoder.get("raw_counts") and encoder.get("counts"):
            options["angle_unit"] = f"counts:{encoder['counts']}"
        options["terms"] = ", ".join(terms)
        return options

    @property
    def drive_period(self) -> float:
        """The drive's period in the record's time unit."""
        return float(self.truth_file["forcing_period"])

    @property
    def forcing_period(self) -> float:
        """The drive's period (the old name of :attr:`drive_period`)."""
        return self.drive_period

    @property
    def sample_step(self) -> float:
        """The sampling step."""
        return float(self.truth_file["sample_step"])

    def __iter__(self) -> Iterator[np.ndarray]:
        return iter((self.t, self.x, self.v))

    def __len__(self) -> int:
        return len(self.t)


#: Old keyword names of ``simulate``, and their names now (the command line's aliases).
SIMULATE_RENAMED = {"forcing": "drive", "theta0": "x0", "omega0": "v0"}


def _gaps(gaps: Union[str, Sequence[int], None]) -> Optional[str]:
    if gaps is None or isinstance(gaps, str):
        return gaps
    k, length = gaps
    return f"{int(k)}:{int(length)}"


def _harmonics(harmonics: Union[str, Sequence[Any], None]) -> list:
    """Repeatable ``K:RATIO[:PHASE]`` (or ``A:OMEGA[:PHASE]``) options: a text, a tuple of
    numbers, or a list of either."""
    if harmonics is None:
        return []
    if isinstance(harmonics, str):
        return [harmonics]
    items = list(harmonics)
    if items and all(isinstance(v, (int, float, np.integer, np.floating)) for v in items):
        items = [tuple(items)]
    out = []
    for h in items:
        out.append(h if isinstance(h, str) else ":".join(str(v) for v in h))
    return out


def simulate(
    *,
    system: str = "pendulum",
    f: Optional[float] = None,
    c: Optional[float] = None,
    r: Optional[float] = None,
    a: Optional[float] = None,
    b: Optional[float] = None,
    friction: Optional[float] = None,
    drag: Optional[float] = None,
    cubic_damping: Optional[float] = None,
    drive_harmonic: Union[str, Sequence[Any], None] = None,
    drive: str = "drive",
    c2: Optional[float] = None,
    mu: Optional[float] = None,
    length_ratio: Optional[float] = None,
    torque1: Union[str, Sequence[Any], None] = None,
    torque2: Union[str, Sequence[Any], None] = None,
    joint_damping: Union[str, Sequence[float], None] = None,
    joint_friction: Union[str, Sequence[float], None] = None,
    a2: Optional[float] = None,
    b2: Optional[float] = None,
    coupling: Optional[float] = None,
    coupling_cubic: Optional[float] = None,
    mass_ratio: Optional[float] = None,
    drive_seed: Optional[int] = None,
    q0: Union[str, Sequence[float], None] = None,
    dq0: Union[str, Sequence[float], None] = None,
    x0: float = 0.1,
    v0: float = 0.0,
    rtol: float = _hbid.DEFAULT_RTOL,
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
    gaps: Union[str, Tuple[int, int], None] = None,
    jitter: Optional[float] = None,
    time_decimals: Optional[int] = None,
    decimals: Optional[int] = None,
    truth: Optional[PathLike] = None,
    write_drive: bool = False,
    out: Optional[PathLike] = None,
    model: Any = None,
    input: Any = None,
    time_col: Union[str, int, None] = None,
    angle_col: Union[str, int, None] = None,
    coords: ColumnsLike = None,
    dt: Optional[float] = None,
    drive_col: ColumnsLike = None,
    init: Optional[int] = None,
    skip_missing: bool = False,
    repair: bool = False,
    **old: Any,
) -> Any:
    """Simulates a rig's record, as ``hbid simulate`` does (defaults: the paper's data set).

    The base-excited pendulum ``x'' + c x' + (1/r^2) sin x - f sin(t) cos x = 0`` or the
    two-well Duffing oscillator ``x'' + c x' + a x + b x^3 = f cos(t)``, with a rig's losses and
    drive harmonics, sampled as a rig records it; or a system of two coordinates: the double
    pendulum on a shaken pivot, whirling (``"double-pendulum"``), a robot arm driven by a torque
    at each joint (``"arm"``), or two coupled two-well Duffing oscillators on a shaken base
    (``"coupled-duffing"``); :attr:`Simulation.named` has every column by name. Without options: 30000 samples, 25 per drive
    period 2 pi, after 200 periods, the angle wrapped into ``[-pi, pi)``. Every option is that of
    ``hbid simulate``, spelled with ``_`` for ``-`` (``hbid simulate --help`` says more of each).

    Args:
        system: ``"pendulum"``, ``"duffing"``, ``"double-pendulum"``, ``"arm"`` or
            ``"coupled-duffing"``.
        f: drive amplitude (default 1.52 for the pendulum, 0.3 for Duffing).
        c: damping (default 0.03, or 0.25).
        r: pendulum: frequency ratio, stiffness 1/r^2 (default 0.8333).
        a: Duffing: linear stiffness (default -1).
        b: Duffing: cubic stiffness (default 1).
        friction: dry friction ``mu sign(x')`` in the model's time.
        drag: quadratic drag ``d x'|x'|`` in the model's time.
        cubic_damping: cubic damping ``c3 x'^3`` in the model's time.
        drive_harmonic: harmonics of the drive, ``"K:RATIO[:PHASE]"`` or ``(K, RATIO[, PHASE])``
            each (a list for several).
        drive: ``"drive"``, or ``"none"`` for a free decay (f = 0, no transient by default).
        c2: double pendulum and coupled oscillators: the damping of link 2 or oscillator 2
            (default 0.05, or 0.2).
        mu: double pendulum: the mass ratio m2/(m1+m2), in [0, 1) (default 0.5).
        length_ratio: double pendulum: the length ratio l2/l1 (default 1).
        torque1: arm: the shoulder's torque, sinusoids ``"A:OMEGA[:PHASE]"`` (N m, rad/s, rad)
            or ``(A, OMEGA[, PHASE])``, a list for several (added), or ``"none"`` (default
            ``"0.4:10"``).
        torque2: arm: the elbow's torque, as ``torque1`` (default ``0.8 cos 10t``).
        joint_damping: arm: the joints' viscous friction ``(b1, b2)`` in N m s/rad (default the
            published 0.001, 0.001).
        joint_friction: arm: the joints' dry friction ``(cf1, cf2)`` in N m (default the
            published 0.093, 0.078; ``(0, 0)`` for none).
        a2: coupled oscillators: linear stiffness of oscillator 2 (default -0.8).
        b2: coupled oscillators: cubic stiffness of oscillator 2 (default 1.2).
        coupling: coupled oscillators: the coupling spring's stiffness k (default 0.3).
        coupling_cubic: coupled oscillators: the coupling spring's cubic part k3 (default 0.05).
        mass_ratio: coupled oscillators: the mass ratio m2/m1 (default 1).
        drive_seed: coupled oscillators: the seed of the base's synthetic acceleration (default
            1).
        q0: a system's initial coordinates ``(q1, q2)`` at the start of the integration (default
            (2, 0) for the double pendulum, (0, 0) for the arm, (1, -0.9) for the coupled
            oscillators).
        dq0: a system's initial velocities ``(v1, v2)`` (default at rest).
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
        gaps: ``"K:LEN"`` or ``(K, LEN)``: drop K runs of LEN samples at seeded places.
        jitter: Gaussian jitter of the written time stamps, its standard deviation in the
            record's time unit (seeded by ``seed``).
        time_decimals: time stamps printed with this many decimals.
        decimals: angle (or displacement) and velocity printed with this many decimals.
        truth: also write the truth file here (JSON).
        write_drive: also give (and write) the drive p(t) as a column ``p``.
        out: also write the record here: ``.npy`` or CSV.
        model: a saved model (a :class:`Model` or its path) to run instead of a built-in system,
            over the grid of the record ``input`` and driven by its measured drive; takes no
            option of a built-in system (only ``x0``, ``v0``, ``rtol``, ``out`` and the input's).
        input: the record that drives ``model``: a path or a :class:`Record`.
        time_col: the input's time column.
        angle_col: the input's output column (its first samples set the initial state).
        coords: a saved system's coordinates' columns in the input file, as :func:`compare`
            takes them (default: the columns it was identified from).
        dt: the input's sampling step, for a record without times.
        drive_col: the input's measured drive column, for a model with terms in ``p`` (several
            as a list, for a system's drives).
        init: samples of the input that set the initial state of each piece (default: one period
            of the model's drive, at most a tenth of the record, at least 8); 0 starts from
            ``x0``, ``v0``.
        skip_missing: leave out every row of the input with a missing value in a column read, as
            a logger's dropped row (a gap, where the run starts again).
        repair: replace the input's isolated time-stamp glitches and every spike, as
            :func:`compare` does.

    Returns:
        A :class:`Simulation` (``t, x, v = ...`` unpacks the arrays); with ``model``, a
        :class:`~hbid.ModelRun`.

    Raises:
        OptionsError: a bad value or combination of options.
        SimulationError: the integration failed.
        OutputError: a file could not be written.
    """
    options: Dict[str, Any] = dict(
        system=system,
        f=f,
        c=c,
        r=r,
        a=a,
        b=b,
        friction=friction,
        drag=drag,
        cubic_damping=cubic_damping,
        drive_harmonic=_harmonics(drive_harmonic),
        drive=drive,
        c2=c2,
        mu=mu,
        length_ratio=length_ratio,
        torque1=_harmonics(torque1),
        torque2=_harmonics(torque2),
        joint_damping=joint_damping,
        joint_friction=joint_friction,
        a2=a2,
        b2=b2,
        coupling=coupling,
        coupling_cubic=coupling_cubic,
        mass_ratio=mass_ratio,
        drive_seed=drive_seed,
        q0=q0,
        dq0=dq0,
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
        gaps=_gaps(gaps),
        jitter=jitter,
        time_decimals=time_decimals,
        decimals=decimals,
        write_drive=write_drive,
    )
    renamed("simulate", old, SIMULATE_RENAMED, options)
    import os

    if model is not None or input is not None:
        if model is None or input is None:
            raise OptionsError("model= runs under the record input=: give both")
        from ._compare import run_model

        if truth is not None:
            raise OptionsError("truth is the equation of a built-in system: a saved model= has none to write")
        # A system's state: q0, dq0, or x0, v0 given one value per coordinate.
        rig = dict(options)
        state = {}
        for one, several, default in (("x0", "q0", 0.1), ("v0", "dq0", 0.0)):
            value = rig[one]
            if rig.get(several) is not None:
                state[one] = rig[several]
            elif value is not None and not np.isscalar(value):
                state[one] = value
                rig[several], rig[one] = value, default
            else:
                state[one] = value
        return run_model(
            model,
            input,
            rig=options_json(rig),
            time_col=time_col,
            angle_col=angle_col,
            coords=coords,
            dt=dt,
            drive_col=drive_col,
            init=init,
            skip_missing=skip_missing,
            repair=repair,
            x0=state["x0"],
            v0=state["v0"],
            rtol=options["rtol"],
            out=out,
        )
    for name, value in (
        ("time_col", time_col),
        ("angle_col", angle_col),
        ("coords", coords),
        ("dt", dt),
        ("drive_col", drive_col),
        ("init", init),
        ("skip_missing", True if skip_missing else None),
        ("repair", True if repair else None),
    ):
        if value is not None:
            raise OptionsError(f"{name} reads the record of input=, for a saved model=")

    d = _hbid.simulate(
        options_json(options),
        out=None if out is None else os.fspath(out),
        truth=None if truth is None else os.fspath(truth),
    )
    return Simulation(
        t=d["t"],
        x=d["x"],
        v=d["v"],
        drive=d["drive"],
        columns=tuple(d["columns"]),
        truth_file=json.loads(d["truth"]),
        named=dict(d["named"]),
    )
