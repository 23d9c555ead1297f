# Type stubs of the compiled core (implicit._implicit); the public names are re-exported by the
# package modules, whose docstrings describe them.
from typing import Any, Callable, Optional, Sequence

import numpy as np
import numpy.typing as npt

from . import data as data, eval as eval, laser as laser, models as models, slam as slam

ArrayLike = npt.ArrayLike
__version__: str

class InvalidArgument(ValueError): ...
class ParseError(ValueError): ...

class ParticleFilter:
    """Monte Carlo localization with a known landmark map, stepped from Python.

    Detections name landmarks by id, as in slam.Filter and Log.scans: column 0 of each (k, 3)
    detections row is a landmark id (or -1: unlabelled, associated by the filter). The ids are
    `landmark_ids` (e.g. log.landmark_ids, or the ids of slam.Filter.map()), or 0 to K-1 (the
    rows of `landmarks`) when it is None, as in Steps.detections. An id that is not in the map
    raises ValueError naming the row and the id, never a silently wrong landmark.
    """
    def __init__(
        self,
        model: "models.Ute | models.Unicycle",
        sensor: "models.RangeBearing",
        landmarks: ArrayLike,
        proposal: str = "implicit",
        particles: int = 100,
        seed: int = 1,
        map: str = "linear",
        resample_threshold: float = 0.5,
        resampling: str = "systematic",
        clutter: bool = True,
        landmark_ids: Optional[ArrayLike] = None,
    ) -> None: ...
    def initialize(self, mean: ArrayLike, covariance: ArrayLike) -> None: ...
    def step(
        self, control: ArrayLike, dt: float = 0.0, detections: Optional[ArrayLike] = None
    ) -> None:
        """One motion step, then the update with detections (k, 3) [landmark id or -1, range m,
        bearing rad]; an id outside [0, 2^31 - 1] or not in the map raises ValueError."""
    @property
    def particles(self) -> np.ndarray: ...
    @property
    def weights(self) -> np.ndarray: ...
    def mean(self) -> np.ndarray: ...
    def covariance(self) -> np.ndarray: ...
    @property
    def ess(self) -> float: ...
    @property
    def last(self) -> dict[str, Any]: ...

def _sample(F: Callable[..., Any], x0: ArrayLike, n: int, grad: Any, hess: Any, map: str,
            seed: int, vectorized: bool, starts: Optional[ArrayLike]) -> dict[str, Any]: ...
def _resample(scheme: str, weights: ArrayLike, n: int, seed: int,
              uniforms: Optional[ArrayLike]) -> np.ndarray: ...
def _uniforms_needed(scheme: str, n: int) -> int: ...
def _ess(weights: ArrayLike) -> float: ...
def _log_sum_exp(a: ArrayLike) -> float: ...
def _user_model_filter(arguments: dict[str, Any]) -> dict[str, Any]: ...
def _run_mcl(settings: dict[str, Any], seed: int, out: Optional[str], threads: int,
             verbose: bool = False,
             progress: Optional[Callable[[int, int], Any]] = None) -> str: ...
def _run_slam(settings: dict[str, Any], seed: int, out: Optional[str], threads: int,
              verbose: bool = False,
              progress: Optional[Callable[[int, int], Any]] = None) -> str: ...
def _run_setting_ranges(command: str) -> list[dict[str, Any]]: ...
def _run_slit(samples: int, runs: int, mode: str, estimator: str, seed: int,
              out: Optional[str], threads: int) -> str: ...
def _run_himmelblau(runs: int, samples: int, seed: int, out: Optional[str],
                    threads: int) -> str: ...
def _run_arm(estimator: str, seed: int, out: Optional[str], threads: int) -> str: ...
