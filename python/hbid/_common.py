"""What the public functions share: arrays, the options object the extension reads, the record a
function is given (a path, arrays or a :class:`~hbid.Record`), the old keyword names and the
warnings."""

from __future__ import annotations

import json
import os
import warnings
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from .errors import OptionsError

PathLike = Union[str, "os.PathLike[str]"]
ArrayLike = Any


class HbidWarning(UserWarning):
    """Something found in a record or a fit that the analysis does not fix by itself (isolated
    encoder spikes left in place, a model that does not describe the record): the text says what
    to do."""


def refuse_non_real(values: Any, name: str) -> None:
    """Refuses complex and boolean arrays, which a conversion to ``float64`` would take silently
    (the real part, with only NumPy's warning; 0 and 1)."""
    kind = getattr(getattr(values, "dtype", None), "kind", None)
    if kind is None and isinstance(values, (list, tuple)):
        try:
            kind = np.asarray(values).dtype.kind
        except (TypeError, ValueError):
            return
    if kind == "c":
        raise OptionsError(f"{name}: complex values: give real numbers (np.real(...) if the real part is meant)")
    if kind == "b":
        raise OptionsError(f"{name}: boolean values: give numbers")


def flag(value: Any, name: str) -> bool:
    """An option that is on or off: ``True`` or ``False`` (a numpy bool too), not a value that
    Python would call true (``"no"``)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise OptionsError(f"{name}: {value!r} is not True or False")


def step(value: Any, name: str = "dt") -> Optional[float]:
    """A sampling step or other number given as an argument: ``None`` or a real number (the
    library checks its range), never text or a complex value taken as one."""
    if value is None:
        return None
    if isinstance(value, (str, bytes, bool, np.bool_)) or np.iscomplexobj(value):
        raise OptionsError(f"{name}={value!r}: give a number")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise OptionsError(f"{name}={value!r}: give a number") from None


def array(values: ArrayLike, name: str) -> np.ndarray:
    """``values`` as a contiguous one-dimensional ``float64`` array (borrowed by the extension).
    A masked array's masked samples are NaN: missing values, which ``skip_missing`` leaves out
    as a logger's dropped rows (an error names the first otherwise)."""
    if values is None:
        raise OptionsError(f"{name}: no samples (None)")
    refuse_non_real(values, name)
    try:
        if np.ma.isMaskedArray(values):
            values = np.ma.filled(np.ma.asarray(values, dtype=np.float64), np.nan)
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise OptionsError(f"{name}: not an array of numbers ({e})") from None
    if a.ndim != 1:
        raise OptionsError(f"{name}: a one-dimensional array is needed, not shape {a.shape}")
    return np.ascontiguousarray(a)


def _plain(value: Any) -> Any:
    """A value as JSON holds it: NumPy scalars as numbers, paths as text, tuples as lists."""
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating,)):
        return float(value)
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def options_json(options: Mapping[str, Any]) -> str:
    """The options as the extension reads them: a JSON object of the command line's option names
    (``_`` for ``-``). The values are checked in Rust, with the messages of the command line."""
    plain = {name: _plain(value) for name, value in options.items()}
    for name, value in plain.items():
        if isinstance(value, float) and not np.isfinite(value):
            raise OptionsError(f"{name}={value!r}: must be finite")
    try:
        return json.dumps(plain, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise OptionsError(f"an option's value is not a number, a text or a list of them: {e}") from None


def renamed(
    function: str, given: Dict[str, Any], old: Mapping[str, str], options: Dict[str, Any]
) -> None:
    """Moves the keywords of old names in ``given`` to their new names in ``options`` (with a
    :class:`DeprecationWarning`); any other name is an error, as Python's own."""
    for name, value in given.items():
        if name not in old:
            raise TypeError(f"{function}() got an unexpected keyword argument {name!r}")
        new = old[name]
        warnings.warn(
            f"{function}({name}=...) is now {function}({new}=...)", DeprecationWarning, stacklevel=3
        )
        options[new] = value


#: Old keyword names of the record's options, and their names now.
RECORD_RENAMED = {
    "forcing_period": "drive_period",
    "forcing_frequency": "drive_frequency",
    "forcing_col": "drive_col",
}


def emit(notes: Any, stacklevel: int = 3) -> list:
    """The notices' texts; the warnings among them are issued as :class:`HbidWarning`."""
    texts = []
    for text, warning in notes:
        texts.append(text)
        if warning:
            warnings.warn(text, HbidWarning, stacklevel=stacklevel)
    return texts


def drive_value(value: Any, name: str) -> Any:
    """A drive's period or frequency: a number, ``"auto"``, ``"auto:A..B"`` or ``"none"``."""
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, bool):
        raise OptionsError(f"{name}={value!r}: a number, 'auto', 'auto:A..B' or 'none'")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise OptionsError(f"{name}={value!r}: a number, 'auto', 'auto:A..B' or 'none'") from None


def column(col: Union[str, int, None], name: str) -> Optional[str]:
    """A column by header name or 1-based position."""
    if col is None:
        return None
    if isinstance(col, bool) or not isinstance(col, (str, int, np.integer)):
        raise OptionsError(f"{name}: a column name or a 1-based position, not {col!r}")
    return str(col)


ColumnsLike = Union[str, int, Sequence[Union[str, int]], Mapping[str, Union[str, int]], None]


def columns(value: ColumnsLike, name: str) -> Union[str, List[str], None]:
    """Columns of a file as the command line's ``A,B`` lists read them: one column (a header name
    or a 1-based position), a sequence of them, or a mapping of the names terms call them to
    their columns (``{"q1": "pos_meas1"}``, the command line's ``q1=pos_meas1``)."""
    if value is None:
        return None
    if isinstance(value, Mapping):
        items = []
        for key, col in value.items():
            if not isinstance(key, str):
                raise OptionsError(f"{name}: the names must be texts, not {key!r}")
            items.append(f"{key}={column(col, name)}")
        return items
    if isinstance(value, (str, int, np.integer)) and not isinstance(value, bool):
        return str(value)
    if isinstance(value, (list, tuple)):
        return [column(v, name) for v in value]  # type: ignore[misc]
    raise OptionsError(f"{name}: a column, a list of columns or a dict of names to columns, not {value!r}")


def signals(value: Union[str, Sequence[str], None], name: str = "signal") -> Optional[str]:
    """``signal=``: one domain for every coordinate, or one per coordinate (a sequence, or the
    command line's ``circle,line``)."""
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
        return ",".join(value)
    raise OptionsError(f"{name}={value!r}: 'circle', 'line', or a list of them (one per coordinate)")


def numbers(value: Any, name: str) -> Optional[str]:
    """One number or a sequence of them (one per coordinate) as the command line's ``A,B``, each
    exactly (the shortest text that reads back as the same float)."""
    if value is None:
        return None
    items = list(value) if isinstance(value, (list, tuple, np.ndarray)) else [value]
    out = []
    for v in items:
        if isinstance(v, (bool, np.bool_)):
            raise OptionsError(f"{name}={value!r}: numbers, one per coordinate")
        try:
            f = float(v)
        except (TypeError, ValueError):
            raise OptionsError(f"{name}={value!r}: numbers, one per coordinate") from None
        if not np.isfinite(f):
            raise OptionsError(f"{name}={value!r}: must be finite")
        out.append(repr(f))
    if not out:
        raise OptionsError(f"{name}: no value given")
    return ",".join(out)


def without(options: Dict[str, Any], *names: str) -> Tuple[Dict[str, Any], Dict[str, Any]]:
    """``options`` split into those named and the rest."""
    picked = {n: options.pop(n) for n in names if n in options}
    return picked, options
