"""Identification: the equation of motion of a record, as ``hbid identify`` finds it."""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _hbid
from ._common import (
    RECORD_RENAMED,
    ArrayLike,
    ColumnsLike,
    PathLike,
    column,
    columns,
    flag,
    step,
    drive_value,
    emit,
    options_json,
    renamed,
    signals,
)
from ._equation import DroppedTerm, Equation, Selection, SelectionStep, equation_text, flattened
from ._record import Record, source
from ._model import Model
from .errors import OptionsError

__all__ = ["DroppedTerm", "Selection", "SelectionStep", "Identification", "identify"]

#: The record's options with the command line's defaults (a Record fixes its own).
RECORD_DEFAULTS: Dict[str, Any] = dict(
    time_col=None,
    angle_col=None,
    coords=None,
    dt=None,
    drive_col=None,
    velocity_col=None,
    repair=False,
    no_repair=False,
    bridge_gaps=0,
    skip_missing=False,
    signal="circle",
    measured="displacement",
    angle_unit="rad",
)


@dataclass(frozen=True)
class Identification:
    """An identified equation of motion ``x'' + sum c_i g_i = 0`` with its uncertainties, or a
    system of them, one per coordinate (``identify(..., coords=...)``).

    ``coefficients``, ``std_errors`` and ``intervals`` are keyed by the command line's term names
    (``x'``, ``sin(x)``, ``cos(t)*cos(x)``, ``hat3``, ...), in the model's order. A system's
    equations are in :attr:`equations`, by coordinate (``result.equations["theta1"]``, an
    :class:`Equation` with its own coefficients, intervals and fit); its ``coefficients``,
    ``std_errors`` and ``intervals`` hold every equation's, keyed ``"theta1: sin(theta1)"``.
    :meth:`to_json` is exactly what ``hbid identify --json`` prints. Results of the same record,
    settings and seed are identical, whatever the machine's threads.
    """

    coefficients: Dict[str, float]
    """The coefficient of each term (of a system: of each equation's, ``"q1: term"``)."""
    std_errors: Dict[str, float]
    """The standard error of each coefficient (least squares)."""
    intervals: Optional[Dict[str, Tuple[float, float]]]
    """The bootstrap interval of each coefficient at ``interval_level``; None with ``bootstrap=0``
    (or when the record gave none: :attr:`no_intervals` says why)."""
    interval_level: Optional[float]
    """The confidence level of the intervals."""
    resamples: int
    """Bootstrap resamples."""
    model: Model
    """The model: simulate, save and load it."""
    method: str
    """``"windowed"`` or ``"upo"``."""
    basis: str
    """The basis as named on the command line (``harmonic:1``, ``hat:8``, ``poly:3``); of a
    system, its first coordinate's (each one's in :attr:`equations`)."""
    signal: str
    """``"circle"`` or ``"line"`` (of a system, its first coordinate's)."""
    segments: int
    """Orbit segments (``upo``) or windows (``windowed``) used."""
    delay: Optional[int]
    """The delay of the close-return search (``upo``), in samples."""
    drive_period: float
    """The period of the analysis in the record's time unit: the drive's, or the free
    oscillation's."""
    drive_period_uncertainty: Optional[float]
    """Its standard uncertainty when it was estimated from the record."""
    drive: str
    """``"given"``, ``"estimated"`` or ``"free"`` (no drive: the free oscillation's period)."""
    samples_per_period: int
    """Samples per period after any resampling."""
    resampled_from: Optional[float]
    """Samples per period as read, when the record was resampled."""
    summary: str
    """One line on the record as analysed."""
    notes: List[str]
    """What was done to the record or found on the way, as the command line prints it."""
    report: Dict[str, Any] = field(repr=False)
    """The JSON of ``hbid identify --json``, read."""
    json_text: str = field(repr=False)
    """The JSON of ``hbid identify --json``."""
    equations: Dict[str, Equation] = field(default_factory=dict, repr=False)
    """Each coordinate's equation, in order: ``{"x": ...}`` for a record of one coordinate, a
    system's by its coordinates' names."""
    parameters: Optional[Dict[str, Dict[str, float]]] = None
    """With ``tie``: the tied physical parameters by name, in the spec's order, each
    ``{"value": ..., "std_error": ..., "interval": [lower, upper], "interval_level": ...}`` (the
    interval with ``bootstrap > 0`` when the record gives one); None otherwise."""

    @property
    def coordinates(self) -> List[str]:
        """The coordinates, one equation each (``["x"]`` for a record of one)."""
        return list(self.equations)

    @property
    def is_system(self) -> bool:
        """Whether the record has several coordinates (``coords``)."""
        return len(self.equations) > 1

    def matrix(self) -> Tuple[List[str], List[str], np.ndarray]:
        """The coefficients as a matrix, equations by terms: ``(coordinates, terms, C)`` with
        ``C[i, k]`` the coefficient of ``terms[k]`` in the equation of ``coordinates[i]``, 0 where
        that equation has no such term; the terms are every equation's, in the order they first
        appear. A record of one coordinate gives one row."""
        terms: List[str] = []
        for e in self.equations.values():
            terms.extend(name for name in e.coefficients if name not in terms)
        column = {name: k for k, name in enumerate(terms)}
        c = np.zeros((len(self.equations), len(terms)))
        for i, e in enumerate(self.equations.values()):
            for name, value in e.coefficients.items():
                c[i, column[name]] = value
        return self.coordinates, terms, c

    @property
    def refinement(self) -> Optional[Dict[str, Any]]:
        """What the output-error refinement did (``refine=True``): ``rmse_before``,
        ``rmse_after``, ``scored``, ``init``, ``iterations``, ``simulations``, ``converged`` and
        the ``start`` coefficients (the weak form's); None without it."""
        return self.report.get("refinement")

    @property
    def equation(self) -> str:
        """The equation, ``x'' + c_1*g_1 + ... = 0``, coefficients to 6 significant digits; a
        system's equations one per line."""
        if self.is_system:
            return "\n".join(e.equation for e in self.equations.values())
        return equation_text(self.coefficients)

    @property
    def terms(self) -> List[str]:
        """The model's terms, in its order (with ``select``, the kept ones); of a system every
        equation's, as ``"q1: term"``."""
        return list(self.coefficients)

    @property
    def selection(self) -> Optional[Selection]:
        """With ``select``: the library, the kept terms and why the others were dropped; else None
        (of a system, each equation's :attr:`Equation.selection`)."""
        d = self.report.get("selection")
        return None if d is None else Selection._from_json(d)

    def _worst(self, name: str, pick: Any) -> Any:
        """A fit measure: the report's, or over a system's equations the one ``pick`` chooses."""
        if not self.is_system:
            return self.report[name]
        values = [getattr(e, name) for e in self.equations.values()]
        values = [v for v in values if v is not None]
        return pick(values) if values else None

    @property
    def explained(self) -> float:
        """The fraction of the balanced acceleration the model explains, in [0, 1] (of a
        system, the least of its equations')."""
        return self._worst("explained", min)

    @property
    def warning(self) -> Optional[str]:
        """The command line's warning when the model explains too little, else None (of a
        system, each equation's that has one, named by its coordinate)."""
        if not self.is_system:
            return self.report["warning"]
        warnings_ = [f"the equation of {q}: {e.warning}" for q, e in self.equations.items() if e.warning]
        return "; ".join(warnings_) or None

    @property
    def held_out_explained(self) -> Optional[float]:
        """The fraction explained on stretches of the record the model was not fitted on (fit on
        all folds of segments but one, scored on that one), beside :attr:`explained`; None when it
        cannot be had (of a system, the least of its equations')."""
        return self._worst("held_out_explained", min)

    @property
    def no_intervals(self) -> Optional[str]:
        """Why there are no bootstrap intervals although they were asked for, else None."""
        if not self.is_system:
            return self.report.get("no_intervals")
        whys = [f"the equation of {q}: {e.no_intervals}" for q, e in self.equations.items() if e.no_intervals]
        return "; ".join(whys) or None

    @property
    def condition_number(self) -> float:
        """The condition number of the column-scaled system (of a system, the largest of its
        equations')."""
        return self._worst("condition_number", max)

    @property
    def residual_rms(self) -> float:
        """The residual root mean square of the equations (of a system, the largest of its
        equations')."""
        return self._worst("residual_rms", max)

    @property
    def rows(self) -> int:
        """Equations of the stacked system (of a system, of all its equations)."""
        return self._worst("rows", sum)

    @property
    def forcing_period(self) -> float:
        """The period of the analysis (the old name of :attr:`drive_period`)."""
        return self.drive_period

    @property
    def forcing_period_uncertainty(self) -> Optional[float]:
        """The old name of :attr:`drive_period_uncertainty`."""
        return self.drive_period_uncertainty

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

    @classmethod
    def _from(cls, d: Mapping[str, Any], notes: List[str]) -> "Identification":
        report = json.loads(d["json"])
        record = report["record"]
        if "equations" in report:
            equations = {q: Equation._from_json(q, e) for q, e in report["equations"].items()}
            first = next(iter(report["equations"].values()))
            intervals: Optional[Dict[str, Tuple[float, float]]] = None
            if all(e.intervals is not None for e in equations.values()):
                intervals = flattened({q: e.intervals for q, e in equations.items()})
            return cls(
                coefficients=flattened({q: e.coefficients for q, e in equations.items()}),
                std_errors=flattened({q: e.std_errors for q, e in equations.items()}),
                intervals=intervals,
                interval_level=first["interval_level"],
                resamples=first["resamples"] or 0,
                model=Model(d["model"]),
                method=report["method"],
                basis=first["basis"],
                signal=record["signal"],
                segments=report["segments"],
                delay=report["delay"],
                drive_period=record["period"],
                drive_period_uncertainty=record["period_uncertainty"],
                drive=record["drive"],
                samples_per_period=record["samples_per_period"],
                resampled_from=record["resampled_from"],
                summary=record["summary"],
                notes=notes,
                report=report,
                json_text=d["json"],
                equations=equations,
                parameters=report.get("parameters"),
            )
        intervals = report["intervals"]
        return cls(
            coefficients=dict(report["coefficients"]),
            std_errors=dict(report["std_errors"]),
            intervals=None if intervals is None else {k: (v[0], v[1]) for k, v in intervals.items()},
            interval_level=report["interval_level"],
            resamples=report["resamples"] or 0,
            model=Model(d["model"]),
            method=report["method"],
            basis=report["basis"],
            signal=record["signal"],
            segments=report["segments"],
            delay=report["delay"],
            drive_period=record["period"],
            drive_period_uncertainty=record["period_uncertainty"],
            drive=record["drive"],
            samples_per_period=record["samples_per_period"],
            resampled_from=record["resampled_from"],
            summary=record["summary"],
            notes=notes,
            report=report,
            json_text=d["json"],
            equations={"x": Equation._from_json("x", report)},
        )


TermsLike = Union[str, Sequence[str], Mapping[str, Union[str, Sequence[str]]], None]


def _tie(tie: Union[Mapping[str, Any], PathLike, None]) -> Union[Dict[str, Any], str, None]:
    """``tie=`` as the option's JSON value: the spec as an object, or its file's path."""
    if tie is None:
        return None
    if isinstance(tie, Mapping):
        return dict(tie)
    try:
        return os.fspath(tie)
    except TypeError:
        raise OptionsError(f"tie={tie!r}: the spec as a dict, or the path of its JSON file") from None


def _terms(terms: TermsLike) -> Optional[str]:
    """``terms=`` as the list's text: one list for every equation, or (a dict) one per
    coordinate by its name, as ``--terms "q1: ...; q2: ..."`` writes them."""
    if terms is None or isinstance(terms, str):
        return terms
    if isinstance(terms, Mapping):
        parts = []
        for name, items in terms.items():
            if not isinstance(name, str) or not name.strip():
                raise OptionsError(f"terms: the keys name coordinates (texts), not {name!r}")
            parts.append(f"{name}: {_terms(items)}")
        if not parts:
            raise OptionsError("terms: an empty dict; give each coordinate's terms by its name")
        return "; ".join(parts)
    try:
        items = list(terms)
    except TypeError:
        raise OptionsError(f"terms={terms!r}: a list of terms as text, or a sequence of such texts") from None
    if not all(isinstance(t, str) for t in items):
        raise OptionsError(f"terms={terms!r}: every item must be a text such as 'sin(t)*cos(x)'")
    return ", ".join(items)


def _select(select: Union[bool, Mapping[str, Any]], options: Dict[str, Any]) -> None:
    """``select=``: a flag, or (as before) a mapping with ``folds`` and ``tolerance``."""
    if isinstance(select, bool):
        options["select"] = select
        return
    if not isinstance(select, Mapping):
        raise OptionsError(f"select={select!r}: True, False or a mapping with 'folds' and 'tolerance'")
    unknown = sorted(set(select) - {"folds", "tolerance"})
    if unknown:
        raise OptionsError(f"select: unknown option(s) {unknown}; expected 'folds' and 'tolerance'")
    options["select"] = True
    if "folds" in select:
        options["select_folds"] = select["folds"]
    if "tolerance" in select:
        options["select_tolerance"] = select["tolerance"]


def identify(
    x: Union[PathLike, Sequence[PathLike], ArrayLike, Mapping[str, ArrayLike], Any],
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
    drive_period: Union[float, str, None] = None,
    drive_frequency: Union[float, str, None] = None,
    method: str = "windowed",
    basis: Optional[str] = None,
    harmonics: Optional[int] = None,
    window_periods: int = 3,
    window: Optional[float] = None,
    window_samples: Optional[int] = None,
    window_order: int = 4,
    bootstrap: int = 1000,
    level: float = 0.95,
    seed: int = 0,
    noise_sigma: Union[float, str, None] = None,
    solver: str = "qr",
    tolerance: float = 0.03,
    max_period: int = 16,
    dim: int = 2,
    delay: Optional[int] = None,
    forcing: Optional[str] = None,
    no_parametric: bool = False,
    drive_harmonics: Optional[int] = None,
    terms: TermsLike = None,
    select: Union[bool, Mapping[str, Any]] = False,
    select_folds: int = 10,
    select_tolerance: float = 1e-6,
    refine: bool = False,
    refine_init: Optional[int] = None,
    tie: Union[Mapping[str, Any], PathLike, None] = None,
    stream: bool = False,
    no_stream: bool = False,
    save_model: Optional[PathLike] = None,
    **old: Any,
) -> Identification:
    """Identifies the equation of motion of a record, as ``hbid identify`` does.

    The record is fitted to its time grid, wrapped (an angle), resampled onto a whole number of
    samples per drive period when needed, cut into windows (``method="windowed"``, the weak
    form, the default) or searched for unstable periodic orbits (``method="upo"``, the
    paper's), and the coefficients are found by least squares, with bootstrap intervals. Every
    keyword is the option of ``hbid identify`` of the same name (``_`` for ``-``), with the same
    default; ``hbid identify --help`` says more of each.

    A record of several coordinates (``coords``, or a dict of arrays) gets one equation per
    coordinate, ``q_i'' + sum c_ik g_ik = 0``, whose terms name the coordinates and drives
    (``sin(theta1)``, ``theta2''*cos(theta1-theta2)``, ``tau1``): :attr:`Identification.equations`
    holds each, and the model is the system of them.

    Args:
        x: a file (text or ``.npy``), several files of the same columns (a list of paths: each
            conditioned on its own, joined with a gap between each two, one fit), a
            :class:`Record` from :func:`read`, or the samples: a 1-D array, or a dict of arrays
            by coordinate name for several coordinates (with ``t`` or ``dt``).
        t: the time stamps of the samples.
        dt: or their sampling step (sample 0 at t = 0).
        drive: the measured drive p(t), one sample per sample of ``x`` (the array form of
            ``drive_col``), or a dict of such arrays by the names terms call them.
        time_col, angle_col: a file's time and angle (or displacement) columns.
        coords: the columns of a file that each get an equation: a system of several
            coordinates, its terms naming them (``["theta1", "theta2"]``, ``"q1=pos1,q2=pos2"``
            or ``{"q1": "pos1", "q2": "pos2"}`` to name the columns otherwise).
        drive_col: a file's column of the measured drive p(t): terms in ``p`` (``p``,
            ``p*cos(x)``, ``p*x'``) are balanced by the weak form as measured; several drives as
            a list (or a dict of names to columns), named in terms by their names.
        velocity_col: refused, as the command line refuses it: the fit reads no velocities
            (they start :func:`compare`'s runs; a :class:`Record` read with them is identified
            without them).
        repair: replace isolated time-stamp glitches and every spike.
        no_repair: keep every spike (a warning) instead of replacing those larger than the
            record's own steps when they are few (at most one in 1000 samples, the default).
        bridge_gaps: bridge every gap of at most this many missing samples (at most 4) by the
            cubic through its neighbours, in every column, as :func:`read` describes; 0 bridges
            none.
        skip_missing: leave out every row with a missing value in a column read, as a
            logger's dropped row, as :func:`read` describes.
        signal: ``"circle"`` (an angle) or ``"line"`` (a displacement), for every coordinate or
            one per coordinate (``["circle", "line"]``); a Record's own.
        measured: ``"displacement"``, or (on the line) ``"velocity"`` or ``"acceleration"``,
            integrated to the displacement (its drift fitted with the model); a Record's own.
        angle_unit: the unit of the angles on the circle (and of their measured velocities):
            ``"rad"``, ``"deg"`` or ``"counts:N"`` (an encoder's N counts per turn); converted
            to radians as they are read.
        drive_period: the drive's period in the record's time unit (default 2 pi, the paper's
            time), ``"auto"`` or ``"auto:A..B"`` to estimate it, ``"none"`` for no drive (a free
            oscillation).
        drive_frequency: or the drive's frequency in cycles per time unit (Hz for seconds).
        method: ``"windowed"`` (the weak form on plain windows) or ``"upo"`` (the paper's).
        basis: ``"harmonic:K"``, ``"hat:N"`` or ``"poly:D"`` (default ``harmonic:1`` on the
            circle, ``poly:3`` on the line).
        harmonics: harmonics per segment (default: the method's band).
        window_periods: the weak form's window length in drive periods.
        window: for a record without a periodic drive (``drive_period="none"``, or a measured
            drive alone), the window length in the record's time unit; its unit is
            ``window / window_periods``, rounded to whole samples.
        window_samples: the window length in samples, instead of ``window``.
        window_order: order p of the window ``sin^p``.
        bootstrap: bootstrap resamples for the intervals (0: none).
        level: confidence level of the intervals.
        seed: seed of the bootstrap: the same seed gives the same result on any machine.
        noise_sigma: correct the bias of Gaussian noise on the angle: sigma in radians, or
            ``"auto"`` to estimate it (harmonic basis).
        solver: ``"qr"`` or ``"svd"``.
        tolerance: ``upo``: close-return tolerance, a fraction of the data's span.
        max_period: ``upo``: longest orbit period searched, in drive periods.
        dim: ``upo``: dimension of the delay vectors compared.
        delay: ``upo``: delay in samples (default: first minimum of the mutual information).
        forcing: external forcing terms cos(t), sin(t) of the default model: ``"none"`` (the
            default on the circle) or ``"identified"`` (the default on the line). ``"none"``
            with no drive given is a free oscillation.
        no_parametric: leave out the parametric terms ``cos(t)*B``, ``sin(t)*B``.
        drive_harmonics: drive harmonics 1..H of the default model's drive terms.
        terms: the model's terms instead of the default, as ``hbid identify --terms`` reads
            them: a string such as ``"x', sign(x'), {1,cos(t),sin(t)}*{cos(x),sin(x)}"``, or a
            sequence of such strings; for a system one list for every equation, or a dict of
            lists by coordinate (``{"q1": "...", "q2": "..."}``, the command line's
            ``"q1: ...; q2: ..."``), a coordinate without one taking the default library.
        select: model selection: the model's terms are a library of candidates, those that
            predict held-out stretches of the record are kept and fitted alone
            (:attr:`Identification.selection` says which and why).
        select_folds: contiguous folds of segments of the selection (at least 2).
        select_tolerance: the smallest held-out unexplained fraction a term must remove to be
            kept, in [0, 1).
        refine: after the fit, refine the coefficients by the free run's error on the record
            (output error; :attr:`Identification.refinement` says what it did): the model then
            follows the record as :func:`compare` scores it.
        refine_init: samples at the start of each piece that set the refinement's free-run
            state and are not scored (default: one drive period, at most a tenth of the longest
            piece, at least 8).
        tie: physical parameters shared by a system's equations (a tied fit, ``hbid identify
            --tie``): the spec as a dict, ``{"parameters": ["Ia", ...], "equations": {"q1":
            {"q1''": {"Ia": 1, "I2": 1}, "q1''*cos(q2)": {"mr2": 0.6}, ..., "tau1": -1}, "q2":
            {...}}}`` (per equation, each term's coefficient as a fixed number or a dict of
            parameter weights, the own acceleration's included), or the path of its JSON file.
            Its keys are the terms, so it replaces ``terms``; :attr:`Identification.parameters`
            holds the parameters with their standard errors and bootstrap intervals.
        stream: read the record's file in chunks, never holding the whole record (the weak form;
            the default for a file of 256 MiB or more; ``drive_frequency="auto"`` is then
            estimated on the first chunk).
        no_stream: read the record's file whole, however large.
        save_model: also save the model here (JSON for a ``.json`` name, compact binary
            otherwise).

    Returns:
        The :class:`Identification`.

    Raises:
        InputError: the record.
        OptionsError: a bad argument (a term naming a coordinate the record does not have, ...).
        IdentificationError: too few segments, a rank-deficient system, a drive that cannot be
            estimated.
        OutputError: ``save_model`` in a folder that does not exist, or a folder (checked before
            any work).
    """
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
        drive_period=drive_value(drive_period, "drive_period"),
        drive_frequency=drive_value(drive_frequency, "drive_frequency"),
        method=method,
        basis=basis,
        harmonics=harmonics,
        window_periods=window_periods,
        window=window,
        window_samples=window_samples,
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
        forcing=forcing,
        no_parametric=flag(no_parametric, "no_parametric"),
        drive_harmonics=drive_harmonics,
        terms=_terms(terms),
        select_folds=select_folds,
        select_tolerance=select_tolerance,
        refine=flag(refine, "refine"),
        refine_init=refine_init,
        tie=_tie(tie),
        stream=True if flag(stream, "stream") else (False if flag(no_stream, "no_stream") else None),
    )
    if stream and no_stream:
        raise OptionsError("stream: give «stream» or «no_stream», not both")
    _select(select, options)
    if "parametric" in old:
        warnings.warn("identify(parametric=...) is now identify(no_parametric=...)", DeprecationWarning, stacklevel=2)
        options["no_parametric"] = not old.pop("parametric")
    renamed("identify", old, RECORD_RENAMED, options)
    for name in ("drive_period", "drive_frequency"):
        options[name] = drive_value(options[name], name)
    samples = source(x, t, drive, options, RECORD_DEFAULTS, several_files=True)
    if isinstance(x, Record):
        # A Record read with its velocities (for a comparison's start) is identified without
        # them: the fit reads none.
        options.pop("velocity_col", None)
        samples.pop("velocity", None)
    if save_model is not None:
        # Before the work, as the command line checks it.
        _hbid.check_output(os.fspath(save_model))
    d = _hbid.identify(options_json(options), **samples)
    result = Identification._from(d, emit(d["notes"]))
    if save_model is not None:
        result.model.save(os.fspath(save_model))
    return result
