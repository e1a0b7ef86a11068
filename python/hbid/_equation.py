"""One equation of motion, ``q'' + sum c_i g_i = 0``: its terms and coefficients, and what the
fit and the selection said of it. A record of one coordinate has one (of ``x``); a system one per
coordinate."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, NamedTuple, Optional, Tuple


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
            dropped=[DroppedTerm(x["term"], x["unexplained_without"], x["unexplained_with"]) for x in d["dropped"]],
            folds=d["folds"],
            allowance=d["allowance"],
            path=[SelectionStep(p["removed"], p["terms"], p["unexplained"], p["std_error"]) for p in d["path"]],
        )


@dataclass(frozen=True)
class Equation:
    """The equation of one coordinate, ``q'' + sum c_i g_i = 0``: what
    :attr:`Identification.equations` and :attr:`Model.equations` hold per coordinate.

    ``coefficients``, ``std_errors`` and ``intervals`` are keyed by the command line's term names
    in the equation's order (a system's terms name its coordinates and drives: ``sin(theta1)``,
    ``theta2''*cos(theta1-theta2)``, ``tau1``). The fit's measures are those of ``hbid identify``
    for this equation; a saved model's equation has none of them (None).
    """

    coordinate: str
    """The coordinate whose acceleration the equation gives (``x`` for a record of one)."""
    coefficients: Dict[str, float]
    """The coefficient of each term."""
    std_errors: Dict[str, float]
    """The standard error of each coefficient (least squares)."""
    basis: str
    """The basis of the coordinate's own functions (``harmonic:1``, ``poly:3``)."""
    intervals: Optional[Dict[str, Tuple[float, float]]] = None
    """The bootstrap interval of each coefficient, when there are any."""
    explained: Optional[float] = None
    """The fraction of the balanced acceleration the equation explains, in [0, 1]."""
    held_out_explained: Optional[float] = None
    """The fraction explained on stretches of the record it was not fitted on."""
    warning: Optional[str] = None
    """The command line's warning when the equation explains too little, else None."""
    no_intervals: Optional[str] = None
    """Why there are no bootstrap intervals although they were asked for, else None."""
    condition_number: Optional[float] = None
    """The condition number of the column-scaled system of the fit."""
    residual_rms: Optional[float] = None
    """The residual root mean square of the fit's equations."""
    rows: Optional[int] = None
    """Equations of the stacked system of the fit."""
    selection: Optional[Selection] = None
    """With ``select``: the library, the kept terms and why the others were dropped."""

    @property
    def terms(self) -> List[str]:
        """The equation's terms, in its order."""
        return list(self.coefficients)

    @property
    def equation(self) -> str:
        """The equation, ``q'' + c_1*g_1 + ... = 0``, coefficients to 6 significant digits."""
        return equation_text(self.coefficients, self.coordinate)

    @classmethod
    def _from_json(cls, coordinate: str, d: Mapping[str, Any]) -> "Equation":
        """An equation of ``hbid identify --json`` (the report of one coordinate, or an entry of
        a system's ``equations``)."""
        intervals = d.get("intervals")
        selection = d.get("selection")
        return cls(
            coordinate=coordinate,
            coefficients=dict(d["coefficients"]),
            std_errors=dict(d["std_errors"]),
            basis=d["basis"],
            intervals=None if intervals is None else {k: (v[0], v[1]) for k, v in intervals.items()},
            explained=d.get("explained"),
            held_out_explained=d.get("held_out_explained"),
            warning=d.get("warning"),
            no_intervals=d.get("no_intervals"),
            condition_number=d.get("condition_number"),
            residual_rms=d.get("residual_rms"),
            rows=d.get("rows"),
            selection=None if selection is None else Selection._from_json(selection),
        )


def flattened(equations: Mapping[str, Mapping[str, Any]]) -> Dict[str, Any]:
    """The values of a system's equations in one dict, keyed ``"q1: term"`` (the coordinate,
    then the term, as ``terms="q1: ...; q2: ..."`` writes them)."""
    return {f"{coordinate}: {term}": value for coordinate, values in equations.items() for term, value in values.items()}


def equation_text(coefficients: Mapping[str, float], coordinate: str = "x") -> str:
    """``q'' + c_1*g_1 + ... = 0``, coefficients to 6 significant digits."""
    parts = [f"{coordinate}''"]
    for name, value in coefficients.items():
        sign = "-" if value < 0 else "+"
        parts.append(f"{sign} {abs(value):.6g}*{name}")
    return " ".join(parts) + " = 0"
