"""Type hints of the extension module (the public API is breathing_torso's)."""

from typing import Any, Callable, Dict, List, Optional, Tuple

class TorsoError(Exception): ...

class Torso:
    def __init__(
        self,
        subject: Optional[Dict[str, Any]] = ...,
        posture: str = ...,
        lod: Optional[int] = ...,
        solver: str = ...,
        rtol: float = ...,
        scenario: str = ...,
        drive: Optional[Dict[str, float]] = ...,
        muscle_law: str = ...,
        gravity: float = ...,
        gravity_loads: str = ...,
        postural_tone: bool = ...,
    ) -> None: ...
    @property
    def time(self) -> float: ...
    @staticmethod
    def columns() -> List[str]: ...
    def simulate(
        self,
        duration: float,
        rate: float = ...,
        activations: Optional[List[Tuple[str, List[float]]]] = ...,
    ) -> bytes: ...
    def state(self) -> bytes: ...
    def set_state(self, time: float, state: bytes) -> None: ...
    def state_dim(self) -> int: ...

def read_recording(
    path: str, units: Optional[str] = ..., rate: Optional[float] = ...
) -> Tuple[bytes, List[str], bytes, str, str, List[Tuple[str, str]]]: ...
def write_recording(
    path: str,
    times: bytes,
    labels: List[str],
    positions: bytes,
    units: str = ...,
    provenance: List[Tuple[str, str]] = ...,
) -> None: ...
def fit(
    path: str,
    out: str,
    subject: Optional[Dict[str, Any]] = ...,
    posture: str = ...,
    lod: Optional[int] = ...,
    solver: str = ...,
    rtol: float = ...,
    grid: str = ...,
    units: Optional[str] = ...,
    rate: Optional[float] = ...,
    method: str = ...,
    max_evals: int = ...,
    seed: int = ...,
    threads: Optional[int] = ...,
    skin_fit: bool = ...,
    marker_offsets: bool = ...,
    fit_size: Optional[bool] = ...,
    drift: bool = ...,
    sway: bool = ...,
    reference: List[str] = ...,
    marker_radius: float = ...,
    anterior: List[str] = ...,
    ti_ttot: Optional[float] = ...,
    progress: Optional[Callable[[int, float], Any]] = ...,
    muscle_law: str = ...,
    gravity: float = ...,
    gravity_loads: str = ...,
    postural_tone: bool = ...,
) -> str: ...
def validate(
    sim_path: Optional[str],
    sim_arrays: Optional[Tuple[bytes, bytes]],
    spiro_path: Optional[str],
    spiro_arrays: Optional[Tuple[bytes, bytes, str]],
    out: Optional[str] = ...,
    sim_column: Optional[str] = ...,
    lung_ratio: Optional[float] = ...,
    max_lag: int = ...,
    harmonics: int = ...,
    bootstrap: int = ...,
    max_ar_order: int = ...,
    seed: int = ...,
    bars_iterations: int = ...,
    detrend: bool = ...,
) -> str: ...
def breathing_frequency(times: bytes, positions: bytes, points: int) -> Tuple[float, bytes, bytes, float]: ...
def register(
    model: bytes, recorded: bytes, with_scale: bool = ...
) -> Tuple[bytes, Tuple[float, float, float], float, float]: ...
def version() -> str: ...
