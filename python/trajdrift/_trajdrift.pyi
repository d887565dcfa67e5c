"""Stubs of the compiled module ``trajdrift._trajdrift`` (the Rust library's API on NumPy arrays).
Use the package's functions (``trajdrift.read``, ``trajdrift.evaluate``, …): this layer's signatures
may change."""

from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

_Arrays = Tuple[npt.NDArray[np.int64], npt.NDArray[np.float64], Optional[npt.NDArray[np.float64]]]
_TrajIn = Tuple[
    str,
    str,
    str,
    npt.NDArray[np.int64],
    npt.NDArray[np.float64],
    Optional[npt.NDArray[np.float64]],
    Optional[Sequence[float]],
]

def read(
    sources: List[str],
    topic: Optional[str] = None,
    stamp: str = "header",
    origin: Optional[Sequence[float]] = None,
    text_format: Optional[str] = None,
    csv: Optional[str] = None,
    kitti_times: Optional[str] = None,
) -> Dict[str, Any]: ...
def evaluate(
    recordings: List[str],
    reference: Optional[Tuple[Optional[str], str, str]],
    estimates: List[Tuple[Optional[str], str, str]],
    preset: Optional[str] = None,
    parameters_: Optional[Dict[str, Any]] = None,
    text_format: Optional[str] = None,
    csv: Optional[str] = None,
    kitti_times: Optional[str] = None,
    reference_lever: Optional[str] = None,
    estimate_levers: List[Tuple[Optional[str], str]] = ...,
) -> Tuple[str, List[str]]: ...
def evaluate_arrays(
    reference: _TrajIn, estimates: List[_TrajIn], parameters_: Optional[Dict[str, Any]] = None
) -> str: ...
def time_offset(
    reference: _Arrays, estimate: _Arrays, parameters_: Optional[Dict[str, Any]] = None
) -> str: ...
def drift_error(
    reference: _Arrays, estimate: _Arrays, parameters_: Optional[Dict[str, Any]] = None
) -> str: ...
def ape(reference: Dict[str, Any], estimate: Dict[str, Any], options: Dict[str, Any]) -> Dict[str, Any]: ...
def rpe(
    reference: Dict[str, Any],
    estimate: Dict[str, Any],
    options: Dict[str, Any],
    delta: float,
    delta_unit: str,
    rel_delta_tol: float,
    all_pairs: bool,
    pairs_from_reference: bool,
) -> Dict[str, Any]: ...
def parameter_specs() -> List[Dict[str, Any]]: ...
def check_parameters(parameters_: Optional[Dict[str, Any]] = None) -> None: ...
def main(argv: List[str]) -> int: ...
