"""The delay and the embedding dimension, and unstable periodic orbits, as ``hbid embed`` and
``hbid upos`` find them."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, NamedTuple, Optional, Sequence, Union

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
from ._record import source
from ._identify import RECORD_DEFAULTS


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
    drive_period: float
    samples_per_period: int
    summary: str
    notes: List[str]
    json_text: str = field(repr=False)

    @property
    def forcing_period(self) -> float:
        """The period of the analysis (the old name of :attr:`drive_period`)."""
        return self.drive_period

    def to_json(self) -> str:
        """The JSON ``hbid embed --json`` prints."""
        return self.json_text


def _record_options(
    time_col: Any,
    angle_col: Any,
    coords: ColumnsLike,
    dt: Optional[float],
    drive_col: ColumnsLike,
    velocity_col: ColumnsLike,
    repair: bool,
    no_repair: bool,
    bridge_gaps: int,
    skip_missing: bool,
    signal: Union[str, Sequence[str]],
    measured: str,
    angle_unit: str,
    drive_period: Any,
    drive_frequency: Any,
) -> Dict[str, Any]:
    return dict(
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
    )


def embed(
    x: Union[PathLike, ArrayLike, Any],
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
    max_lag: Optional[int] = None,
    bins: int = 16,
    max_dim: int = 8,
    metric: Optional[str] = None,
    theiler: int = 0,
    **old: Any,
) -> Embedding:
    """Chooses the delay (first minimum of the average mutual information) and checks the
    embedding dimension (false nearest neighbours), as ``hbid embed`` does.

    Args:
        x, t, dt, drive, time_col, angle_col, coords, drive_col, velocity_col, repair,
            no_repair, bridge_gaps, skip_missing, signal, measured, angle_unit, drive_period,
            drive_frequency:
            the record, as for
            :func:`identify` (one file, a Record or arrays).
        max_lag: largest lag of the mutual information (default: two drive periods, at least 40).
        bins: equal boxes of the mutual-information histogram.
        max_dim: largest embedding dimension tested.
        metric: ``"circle"`` or ``"linear"`` (plain differences) (default: the signal's).
        theiler: neighbours closer in time than this many samples are not counted.

    Raises:
        InputError, OptionsError, IdentificationError: as for :func:`identify`.
    """
    options = _record_options(
        time_col,
        angle_col,
        coords,
        dt,
        drive_col,
        velocity_col,
        repair,
        no_repair,
        bridge_gaps,
        skip_missing,
        signal,
        measured,
        angle_unit,
        drive_period,
        drive_frequency,
    )
    options.update(max_lag=max_lag, bins=bins, max_dim=max_dim, metric=metric, theiler=theiler)
    renamed("embed", old, RECORD_RENAMED, options)
    samples = source(x, t, drive, options, RECORD_DEFAULTS)
    d = _hbid.embed(options_json(options), **samples)
    report = json.loads(d["json"])
    record = report["record"]
    return Embedding(
        delay=report["delay"],
        embedding_dimension=report["embedding_dimension"],
        ami=d["ami"],
        fnn=d["fnn"],
        fraction_threshold=report["fraction_threshold"],
        metric=report["metric"],
        drive_period=record["period"],
        samples_per_period=record["samples_per_period"],
        summary=record["summary"],
        notes=emit(d["notes"]),
        json_text=d["json"],
    )


class Orbit(NamedTuple):
    """A segment of the record that nearly repeats after ``period`` drive periods."""

    period: int
    """The orbit's period, in drive periods."""
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
    drive_period: float
    samples_per_period: int
    summary: str
    notes: List[str]
    json_text: str = field(repr=False)

    @property
    def by_period(self) -> Dict[int, int]:
        """Segments found per period."""
        out: Dict[int, int] = {}
        for s in self.segments:
            out[s.period] = out.get(s.period, 0) + 1
        return dict(sorted(out.items()))

    @property
    def forcing_period(self) -> float:
        """The period of the analysis (the old name of :attr:`drive_period`)."""
        return self.drive_period

    def to_json(self) -> str:
        """The JSON ``hbid upos --json`` prints."""
        return self.json_text


def upos(
    x: Union[PathLike, ArrayLike, Any],
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
    tolerance: float = 0.03,
    max_period: int = 16,
    dim: int = 2,
    delay: Optional[int] = None,
    **old: Any,
) -> Orbits:
    """Finds unstable periodic orbits by close returns, as ``hbid upos`` does.

    Args:
        x, t, dt, drive, time_col, angle_col, coords, drive_col, velocity_col, repair,
            no_repair, bridge_gaps, skip_missing, signal, measured, angle_unit, drive_period,
            drive_frequency:
            the record, as for
            :func:`identify` (one file, a Record or arrays).
        tolerance: close-return tolerance, a fraction of the data's span.
        max_period: longest orbit period searched, in drive periods.
        dim: dimension of the delay vectors compared.
        delay: delay in samples (default: first minimum of the mutual information).

    Raises:
        InputError, OptionsError, IdentificationError: as for :func:`identify`.
    """
    options = _record_options(
        time_col,
        angle_col,
        coords,
        dt,
        drive_col,
        velocity_col,
        repair,
        no_repair,
        bridge_gaps,
        skip_missing,
        signal,
        measured,
        angle_unit,
        drive_period,
        drive_frequency,
    )
    options.update(tolerance=tolerance, max_period=max_period, dim=dim, delay=delay)
    renamed("upos", old, RECORD_RENAMED, options)
    samples = source(x, t, drive, options, RECORD_DEFAULTS)
    d = _hbid.upos(options_json(options), **samples)
    report = json.loads(d["json"])
    record = report["record"]
    return Orbits(
        segments=[Orbit(o["period"], o["start"], o["error"]) for o in report["orbits"]],
        orbit_of_segment=list(report["orbit_of_segment"]),
        distinct_orbits=report["distinct_orbits"],
        delay=report["delay"],
        tolerance=report["tolerance"],
        drive_period=record["period"],
        samples_per_period=record["samples_per_period"],
        summary=record["summary"],
        notes=emit(d["notes"]),
        json_text=d["json"],
    )
