from os import PathLike
from typing import Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

from .models import RangeBearing, Unicycle, Ute

class Filter:
    def __init__(self, method: str = "implicit-rb", particles: int = 100, seed: int = 1,
                 model: Optional[Union[Ute, Unicycle]] = None,
                 sensor: RangeBearing = ..., association: str = "known",
                 initial_pose: npt.ArrayLike = ...) -> None: ...
    def step(self, control: npt.ArrayLike, dt: float = 0.0,
             detections: Optional[npt.ArrayLike] = None) -> None:
        """One motion step, then detections (k, 3) [landmark id, range m, bearing rad]: column
        0 is the landmark's id (an integer in [0, 2^31 - 1]), as in ParticleFilter; with
        association="ml" the filter associates instead (-1 marks an unlabelled row). Other
        values raise ValueError naming the row and the id."""
    def mean(self) -> np.ndarray: ...
    def covariance(self) -> np.ndarray: ...
    def map(self) -> tuple[np.ndarray, np.ndarray]: ...
    @property
    def ess(self) -> float: ...

def run(method: str = "implicit", particles: int = 100, datasets: int = 50, seed: int = 1,
        data: Optional[str] = None, association: str = "known", truth: str = "paper",
        laser_every: int = 1, control_noise: float = 0.5, min_range: float = 0.0,
        range_sd: float = 0.0, bearing_sd_deg: float = 0.0, gate_chi2: float = 0.0,
        new_landmark_density: float = 0.0, model: Optional[str] = None,
        control_sd: Optional[list[float]] = None, state_sd: Optional[list[float]] = None,
        out: Optional[str] = None, threads: int = 0, verbose: bool = False,
        bearing_sd: Optional[float] = None,
        progress: Optional[Callable[[int, int], Any]] = None) -> dict[str, Any]: ...

def grid(data: Union[str, "PathLike[str]", dict[str, Any]], method: str = "implicit",
         particles: int = 30, seed: int = 1,
         alphas: npt.ArrayLike = (0.002, 0.002, 0.002, 0.002), max_scans: int = 0,
         threads: int = 0,
         progress: Optional[Callable[[int, int], Any]] = None,
         map_min_echoes: int = 1) -> dict[str, Any]:
    """Grid SLAM on a CARMEN laser log, one run of `implicit slam --sensor laser`: trajectory
    and reference (n, 3), times (n,), map int8 (height, width) (-1 unknown, 0..100; row 0 the
    lowest y), resolution, origin, grid (an implicit.laser.OccupancyGrid or None), the relation
    errors of the estimate and of the odometry, ate_m and odometry_ate_m (float or None),
    cpu_seconds, resamplings, ess_fraction,
    evaluations_per_particle_and_scan, fallbacks, failures, the map score (map_agreement,
    map_occupied_precision, map_occupied_recall, map_f1, their odometry_ twins, each a float or
    None; map_tolerance_m, reference_map_cpu_s, map_score_cpu_s), scans_processed and the
    settings."""
def _grid(settings: dict[str, Any],
          progress: Optional[Callable[[int, int], Any]] = None) -> dict[str, Any]: ...
