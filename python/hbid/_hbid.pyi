"""Type stubs of the extension module ``hbid._hbid`` (Rust, PyO3). Use the documented wrappers
of :mod:`hbid` instead: these take the options as a JSON object of the command line's option
names (``_`` for ``-``) and return plain dicts, lists, arrays and ``bytes``. Samples come as
lists of arrays: one per coordinate (``x``), per measured drive (``drive``) and per coordinate's
measured velocity (``velocity``, a record's grid only)."""

from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str
DEFAULT_RTOL: float

Array = npt.NDArray[np.float64]
Grid = Tuple[float, float, List[Tuple[int, int]], str]

def condition(
    options: str,
    *,
    path: Optional[str] = None,
    x: Optional[List[Array]] = None,
    t: Optional[Array] = None,
    drive: Optional[List[Array]] = None,
) -> Dict[str, Any]: ...
def identify(
    options: str,
    *,
    path: Optional[List[str]] = None,
    x: Optional[List[Array]] = None,
    t: Optional[Array] = None,
    drive: Optional[List[Array]] = None,
    velocity: Optional[List[Array]] = None,
    grid: Optional[Grid] = None,
) -> Dict[str, Any]: ...
def embed(
    options: str,
    *,
    path: Optional[str] = None,
    x: Optional[List[Array]] = None,
    t: Optional[Array] = None,
    drive: Optional[List[Array]] = None,
    velocity: Optional[List[Array]] = None,
    grid: Optional[Grid] = None,
) -> Dict[str, Any]: ...
def upos(
    options: str,
    *,
    path: Optional[str] = None,
    x: Optional[List[Array]] = None,
    t: Optional[Array] = None,
    drive: Optional[List[Array]] = None,
    velocity: Optional[List[Array]] = None,
    grid: Optional[Grid] = None,
) -> Dict[str, Any]: ...
def simulate(options: str, *, out: Optional[str] = None, truth: Optional[str] = None) -> Dict[str, Any]: ...
def compare(
    model: bytes,
    options: str,
    *,
    path: Optional[str] = None,
    x: Optional[List[Array]] = None,
    t: Optional[Array] = None,
    drive: Optional[List[Array]] = None,
    velocity: Optional[List[Array]] = None,
    grid: Optional[Grid] = None,
) -> Dict[str, Any]: ...
def model_run(
    model: bytes,
    options: str,
    rig: str,
    *,
    path: Optional[str] = None,
    x: Optional[List[Array]] = None,
    t: Optional[Array] = None,
    drive: Optional[List[Array]] = None,
    velocity: Optional[List[Array]] = None,
    grid: Optional[Grid] = None,
    out: Optional[str] = None,
) -> Dict[str, Any]: ...
def model_run_on(
    model: bytes,
    t: Array,
    *,
    x0: List[float],
    v0: List[float],
    drive: Optional[List[Array]] = None,
    rtol: Optional[float] = None,
) -> Dict[str, Any]: ...
def model_info(model: bytes) -> Dict[str, Any]: ...
def model_json(model: bytes) -> str: ...
def model_from_json(text: str) -> bytes: ...
def model_save(model: bytes, path: str) -> None: ...
def check_output(path: str) -> None: ...
def model_load(path: str) -> bytes: ...
def model_simulate(
    model: bytes,
    *,
    samples: int,
    x0: float = 0.1,
    v0: float = 0.0,
    samples_per_period: Optional[int] = None,
    transient_periods: int = 0,
    rtol: Optional[float] = None,
    wrapped: bool = True,
) -> Tuple[Array, Array, Array]: ...
def rayon_sweep(cases: List[Tuple[float, int]], *, samples: int, bootstrap: int, threads: int) -> List[str]: ...
