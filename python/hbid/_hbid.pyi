"""Type stubs of the extension module ``hbid._hbid`` (Rust, PyO3). Use the documented wrappers
of :mod:`hbid` instead: these return plain dicts, lists, arrays and ``bytes``."""

from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Grid = Tuple[float, float, List[Tuple[int, int]]]
Drive = Union[float, str, None]

def read(
    path: str,
    *,
    time_col: Optional[str] = None,
    angle_col: Optional[str] = None,
    dt: Optional[float] = None,
    repair: bool = False,
    signal: str = "circle",
) -> Dict[str, Any]: ...
def condition_arrays(
    x: npt.NDArray[np.float64],
    *,
    t: Optional[npt.NDArray[np.float64]] = None,
    dt: Optional[float] = None,
    repair: bool = False,
    signal: str = "circle",
) -> Dict[str, Any]: ...
def identify(
    x: npt.NDArray[np.float64],
    *,
    t: Optional[npt.NDArray[np.float64]] = None,
    dt: Optional[float] = None,
    grid: Optional[Grid] = None,
    repair: bool = False,
    signal: str = "circle",
    forcing_period: Drive = None,
    forcing_frequency: Drive = None,
    forcing: Optional[str] = None,
    parametric: bool = True,
    method: str = "windowed",
    basis: Optional[str] = None,
    harmonics: Optional[int] = None,
    window_periods: Optional[int] = None,
    window_order: Optional[int] = None,
    bootstrap: int = 1000,
    level: Optional[float] = None,
    seed: int = 0,
    noise_sigma: Union[float, str, None] = None,
    solver: str = "qr",
    tolerance: Optional[float] = None,
    max_period: Optional[int] = None,
    dim: Optional[int] = None,
    delay: Optional[int] = None,
    terms: Optional[str] = None,
    select: bool = False,
    select_folds: int = 10,
    select_tolerance: float = 1e-6,
) -> Dict[str, Any]: ...
def embed(
    x: npt.NDArray[np.float64],
    *,
    t: Optional[npt.NDArray[np.float64]] = None,
    dt: Optional[float] = None,
    grid: Optional[Grid] = None,
    repair: bool = False,
    signal: str = "circle",
    forcing_period: Drive = None,
    forcing_frequency: Drive = None,
    max_lag: Optional[int] = None,
    bins: int = 16,
    max_dim: int = 8,
    metric: Optional[str] = None,
    theiler: int = 0,
) -> Dict[str, Any]: ...
def upos(
    x: npt.NDArray[np.float64],
    *,
    t: Optional[npt.NDArray[np.float64]] = None,
    dt: Optional[float] = None,
    grid: Optional[Grid] = None,
    repair: bool = False,
    signal: str = "circle",
    forcing_period: Drive = None,
    forcing_frequency: Drive = None,
    tolerance: Optional[float] = None,
    max_period: Optional[int] = None,
    dim: Optional[int] = None,
    delay: Optional[int] = None,
) -> Dict[str, Any]: ...
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
) -> Dict[str, Any]: ...
def model_info(model: bytes) -> Dict[str, Any]: ...
def model_json(model: bytes) -> str: ...
def model_from_json(text: str) -> bytes: ...
def model_save(model: bytes, path: str) -> None: ...
def model_load(path: str) -> bytes: ...
def model_simulate(
    model: bytes,
    *,
    samples: int,
    x0: float = 0.1,
    v0: float = 0.0,
    samples_per_period: Optional[int] = None,
    transient_periods: int = 0,
    rtol: float = 1e-10,
    wrapped: bool = True,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
def rayon_sweep(cases: List[Tuple[float, int]], *, samples: int, bootstrap: int, threads: int) -> List[str]: ...
