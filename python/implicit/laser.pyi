from typing import Any, Callable, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from os import PathLike

Path = Union[str, "PathLike[str]"]
Scan = dict[str, Any]

class OccupancyGrid:
    def __init__(self, cells: npt.ArrayLike, resolution: float,
                 origin: npt.ArrayLike = (0.0, 0.0)) -> None: ...
    @property
    def cells(self) -> np.ndarray: ...
    @property
    def resolution(self) -> float: ...
    @property
    def origin(self) -> tuple[float, float]: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...

def load_map(yaml_path: Path) -> OccupancyGrid: ...
def save_map(grid: OccupancyGrid, yaml_path: Path) -> None: ...
def read_carmen(path: Path) -> dict[str, Any]: ...
def bundled_log(name: str) -> str: ...
def scan_at(log: dict[str, Any], k: int) -> Scan: ...
def build_map(poses: npt.ArrayLike, scans: Union[dict[str, Any], Sequence[Scan]],
              mount: npt.ArrayLike = (0.0, 0.0, 0.0), resolution: float = 0.05,
              max_range: float = 40.0, min_echoes: int = 2) -> OccupancyGrid: ...
def simulate_scan(grid: OccupancyGrid, pose: npt.ArrayLike,
                  mount: npt.ArrayLike = (0.0, 0.0, 0.0), beams: int = 181,
                  field_of_view: float = ..., range_min: float = 0.05, range_max: float = 30.0,
                  range_std: float = 0.02, seed: int = 0) -> Scan: ...

class LikelihoodField:
    def __init__(self, grid: OccupancyGrid, z_hit: float = 0.5, z_rand: float = 0.5,
                 sigma_hit: float = 0.2, max_dist: float = 2.0, max_beams: int = 60,
                 interpolation: str = "bicubic", aggregation: str = "product",
                 mount: npt.ArrayLike = (0.0, 0.0, 0.0)) -> None: ...
    @property
    def differentiable(self) -> bool: ...
    def log_likelihood(self, poses: npt.ArrayLike, ranges: npt.ArrayLike, angle_min: float,
                       angle_increment: float, range_min: float,
                       range_max: float) -> np.ndarray: ...
    def negative_log_likelihood(
        self, pose: npt.ArrayLike, ranges: npt.ArrayLike, angle_min: float,
        angle_increment: float, range_min: float, range_max: float
    ) -> tuple[float, np.ndarray, np.ndarray]: ...

class BeamModel:
    def __init__(self, grid: OccupancyGrid, z_hit: float = 0.5, z_short: float = 0.05,
                 z_max: float = 0.05, z_rand: float = 0.5, sigma_hit: float = 0.2,
                 lambda_short: float = 0.1, max_beams: int = 60,
                 laser_max_range: Optional[float] = None,
                 laser_min_range: Optional[float] = None,
                 mount: npt.ArrayLike = (0.0, 0.0, 0.0)) -> None: ...
    @property
    def differentiable(self) -> bool: ...
    def log_likelihood(self, poses: npt.ArrayLike, ranges: npt.ArrayLike, angle_min: float,
                       angle_increment: float, range_min: float,
                       range_max: float) -> np.ndarray: ...

class OdometryModel:
    def __init__(self, alpha1: float = 0.2, alpha2: float = 0.2, alpha3: float = 0.2,
                 alpha4: float = 0.2) -> None: ...
    @property
    def alphas(self) -> tuple[float, float, float, float]: ...
    def predict(self, pose: npt.ArrayLike, u: npt.ArrayLike) -> np.ndarray: ...
    def covariance(self, pose: npt.ArrayLike, u: npt.ArrayLike) -> np.ndarray: ...
    def sample(self, pose: npt.ArrayLike, u: npt.ArrayLike, seed: int = 0,
               n: Optional[int] = None) -> np.ndarray: ...

class ParticleFilter:
    def __init__(self, grid: OccupancyGrid, proposal: str = "implicit", particles: int = 100,
                 seed: int = 0, alphas: npt.ArrayLike = (0.2, 0.2, 0.2, 0.2),
                 laser: Union[dict[str, Any], BeamModel, None] = None,
                 resample_threshold: float = 0.5,
                 starts: int = 2, start_probe: int = 0,
                 **laser_keywords: Any) -> None: ...
    def initialize(self, mean: npt.ArrayLike, covariance: npt.ArrayLike) -> None: ...
    def step(self, u: npt.ArrayLike, ranges: Optional[npt.ArrayLike] = None,
             angle_min: Optional[float] = None, angle_increment: Optional[float] = None,
             range_min: float = 0.0, range_max: Optional[float] = None) -> dict[str, Any]: ...
    @property
    def particles(self) -> np.ndarray: ...
    @property
    def weights(self) -> np.ndarray: ...
    @property
    def last(self) -> dict[str, Any]: ...

def run(data: Path, proposal: str = "implicit", particles: int = 100, runs: int = 10,
        seed: int = 1, alphas: Optional[npt.ArrayLike] = None,
        filter_alphas: Optional[npt.ArrayLike] = None, map: Optional[Path] = None,
        start: str = "known", max_updates: int = 0, implicit_map: str = "linear",
        starts: int = 2, start_probe: int = 0,
        z_hit: float = 0.5, z_rand: float = 0.5, sigma_hit: float = 0.2, max_dist: float = 2.0,
        max_beams: int = 60, laser_max_range: Optional[float] = None,
        interpolation: str = "bicubic", aggregation: str = "product",
        laser_model: str = "likelihood-field", z_short: float = 0.05, z_max: float = 0.05,
        lambda_short: float = 0.1,
        update_min_d: float = 0.25, update_min_a: float = 0.2, map_resolution: float = 0.05,
        map_min_echoes: int = 2,
        global_updates: int = 10, global_radius: float = 0.5, kld: bool = False,
        kld_err: float = 0.01, kld_z: float = 0.99, recovery: str = "none",
        recovery_alpha_slow: float = 0.001, recovery_alpha_fast: float = 0.1,
        kidnap_probability: float = 1e-3, tracks: bool = False, threads: int = 0,
        progress: Optional[Callable[[int, int], Any]] = None) -> dict[str, Any]: ...
def _run(settings: dict[str, Any],
         progress: Optional[Callable[[int, int], Any]] = None) -> str: ...
