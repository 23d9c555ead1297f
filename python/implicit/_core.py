"""The sampling core: implicit.sample, resample, ess and log_sum_exp (spec §1)."""
from dataclasses import dataclass

import numpy as np

from . import _implicit


@dataclass(frozen=True)
class SampleResult:
    """Weighted samples of the density proportional to exp(-F), from implicit.sample.

    Attributes:
        samples: (n, d) the samples x_j.
        log_weights: (n,) log w_j with every constant, so that the mean weight estimates
            Z = integral of exp(-F) (spec §1.2); -inf for a sample of weight zero.
        weights: (n,) normalised weights (sum 1).
        ess: effective sample size 1 / sum(weights**2), between 1 and n.
        log_Z: log of the mean weight, an estimate of log Z.
        status: the minimisation status ("converged"; other statuses raise).
        iterations: Newton iterations of the minimisation.
        mode: (d,) the minimiser mu of F.
        phi: F(mu).
        log_det_L: log det of the Cholesky factor of the Hessian at mu.
        zero_weight: samples with weight zero.
        map_failures: samples the map could not place (weight zero).
    """

    samples: np.ndarray
    log_weights: np.ndarray
    weights: np.ndarray
    ess: float
    log_Z: float
    status: str
    iterations: int
    mode: np.ndarray
    phi: float
    log_det_L: float
    zero_weight: int
    map_failures: int

    def mean(self):
        """Self-normalised posterior mean (d,)."""
        return self.weights @ self.samples

    def covariance(self):
        """Self-normalised posterior covariance (d, d)."""
        d = self.samples - self.mean()
        return (d * self.weights[:, None]).T @ d


def sample(F, x0, n=1000, grad=None, hess=None, map="linear", seed=1, vectorized=False):
    """Implicit sampling of the density proportional to exp(-F(x)) (spec §1).

    Minimises F from x0 (Newton), then maps n Gaussian reference samples onto the target with
    the linear map (x = mu + L^-T xi) or the random map (a root of F(x) - phi = |xi|^2 / 2 along
    a random direction), and weights them.

    Args:
        F: the negative log density, a function of x of shape (d,) returning a float; with
            vectorized=True a function of an (k, d) array returning (k,) values (the linear map
            then calls it once with all n samples).
        x0: (d,) start point of the minimisation.
        n: number of samples.
        grad: optional gradient of F, (d,) -> (d,); default: central finite differences.
        hess: optional Hessian of F, (d,) -> (d, d); default: finite differences.
        map: "linear" or "random".
        seed: sample j uses the random stream (seed, 0, j); results do not depend on threads.
        vectorized: whether F takes a batch (k, d).

    Returns:
        SampleResult with samples (n, d), log_weights, weights, ess, log_Z, status.

    Raises:
        implicit.InvalidArgument (a ValueError): bad shapes, non-finite x0, unknown map, or a
        minimisation that does not converge (the message names the status).

    Example:
        >>> import numpy as np, implicit
        >>> r = implicit.sample(lambda x: 0.5 * x @ x, np.zeros(2), n=100, seed=1)
        >>> r.samples.shape, round(float(r.weights.sum()), 12)
        ((100, 2), 1.0)
    """
    d = _implicit._sample(F, x0, int(n), grad, hess, map, int(seed), bool(vectorized))
    return SampleResult(
        samples=d["x"],
        log_weights=d["log_weights"],
        weights=d["weights"],
        ess=d["ess"],
        log_Z=d["log_Z"],
        status=d["status"],
        iterations=d["iterations"],
        mode=d["mode"],
        phi=d["phi"],
        log_det_L=d["log_det_L"],
        zero_weight=d["zero_weight"],
        map_failures=d["map_failures"],
    )


SCHEMES = ("multinomial", "systematic", "stratified", "residual")


def resample(weights, n=None, scheme="systematic", seed=1, uniforms=None):
    """Ancestor indices drawn from normalised weights.

    Args:
        weights: (m,) non-negative weights summing to 1 (within 1e-8).
        n: number of indices (default m).
        scheme: "multinomial", "systematic", "stratified" or "residual".
        seed: seed of the uniforms when `uniforms` is not given.
        uniforms: optional uniforms in (0, 1), as many as the scheme needs
            (see uniforms_needed); with them the result is a pure function of the input.

    Returns:
        (n,) int64 ancestor indices in ascending order.

    Example:
        >>> implicit.resample([0.1, 0.2, 0.7], n=10, scheme="systematic", seed=3)
    """
    w = np.asarray(weights, dtype=float)
    m = w.shape[0] if w.ndim == 1 else 0
    return _implicit._resample(scheme, w, int(m if n is None else n), int(seed), uniforms)


def uniforms_needed(scheme, n):
    """Number of uniforms `resample(..., scheme=scheme, n=n, uniforms=...)` consumes."""
    return _implicit._uniforms_needed(scheme, int(n))


def ess(weights):
    """Effective sample size 1 / sum(w**2) of normalised weights (m,)."""
    return _implicit._ess(weights)


def log_sum_exp(a):
    """log(sum(exp(a))) of an (m,) array without overflow; -inf for all -inf."""
    return _implicit._log_sum_exp(a)
