from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence

import numpy as np

@dataclass(frozen=True)
class Model:
    dim: int
    initial: Callable[[np.ndarray], Any]
    transition: Callable[[int, np.ndarray, np.ndarray], Any]
    observation_logpdf: Callable[[int, np.ndarray, Any], Any]
    transition_logpdf: Optional[Callable[[int, np.ndarray, np.ndarray], Any]] = None
    gradient: Optional[Callable[[int, np.ndarray, np.ndarray, Any], Any]] = None
    hessian: Optional[Callable[[int, np.ndarray, np.ndarray, Any], Any]] = None
    proposal: Optional[Callable[[int, np.ndarray, Any, np.ndarray], tuple[Any, Any]]] = None

@dataclass(frozen=True)
class FilterResult:
    mean: np.ndarray
    variance: np.ndarray
    ess: np.ndarray
    log_likelihood_increments: np.ndarray
    log_likelihood: float
    resampled: np.ndarray
    newton_iterations: np.ndarray
    newton_failures: np.ndarray
    map_failures: np.ndarray
    objective_calls: np.ndarray
    particles: np.ndarray
    weights: np.ndarray

def particle_filter(model: Model, observations: Sequence[Any], particles: int = 1000,
                    proposal: str = "bootstrap", resampling: str = "systematic",
                    threshold: float = 0.5, seed: int = 1, threads: int = 0,
                    max_newton_iterations: int = 50, map: str = "linear") -> FilterResult: ...
