"""The sampling core: implicit.sample, resample, ess and log_sum_exp (spec §1)."""
import numbers
import warnings
from dataclasses import dataclass

import numpy as np

from . import _implicit


class SamplerWarning(UserWarning):
    """implicit.sample may have sampled one minimum of several: its samples and log Z can then be
    wrong while the ESS looks healthy. Issued when x0 is a point where F is not locally convex
    (single start), when another start found a lower minimum than x0's (with `starts`), or
    when a sample has a lower F than every minimum found."""


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
        minima: (K, d) the distinct minima found from x0 and `starts`, lowest F first (K = 1
            for a single start; mode is minima[0]).
        minima_phi: (K,) F at each minimum.
        mixture_weights: (K,) the proposal's weight pi_k of each minimum (Laplace mass), sum 1.
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
    minima: np.ndarray
    minima_phi: np.ndarray
    mixture_weights: np.ndarray

    def mean(self):
        """Self-normalised posterior mean (d,)."""
        return self.weights @ self.samples

    def covariance(self):
        """Self-normalised posterior covariance (d, d)."""
        d = self.samples - self.mean()
        return (d * self.weights[:, None]).T @ d


def sample(F, x0, n=1000, grad=None, hess=None, map="linear", seed=1, vectorized=False,
           starts=None):
    """Implicit sampling of the density proportional to exp(-F(x)) (spec §1).

    Minimises F from x0 (Newton), then maps n Gaussian reference samples onto the target with
    the linear map (x = mu + L^-T xi) or the random map (a root of F(x) - phi = |xi|^2 / 2 along
    a random direction), and weights them.

    One start finds one minimum: when F has several, the samples and log Z miss the others
    while the ESS can look healthy. With `starts`, Newton runs from x0 and from every row; the
    distinct minima (closer than 0.01 standard deviations of either's Laplace approximation:
    one) make the mixture q = sum_k pi_k N(mu_k, H_k^-1), pi_k proportional to
    exp(-phi_k) / sqrt(det H_k), and every sample is weighted by exp(-F(x)) / q(x), so the mean
    weight estimates Z without bias whatever the minima found (spec §1.2). Starts whose
    minimisation fails are left out; the mixture uses the linear map.

    Warns (SamplerWarning) when F is not locally convex at x0 without `starts` (Newton from
    there may find any of several minima), when another start finds a lower minimum than x0's
    (a single start from x0 would have missed it), and when a sample has a lower F than every
    minimum found (F has a lower minimum that no start reached).

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
        starts: optional (K, d) further start points for the minimisation (multi-start).

    Returns:
        SampleResult with samples (n, d), log_weights, weights, ess, log_Z, status, and the
        minima found with their mixture weights.

    Raises:
        implicit.InvalidArgument (a ValueError): bad shapes, non-finite x0 or starts, unknown
        map, a minimisation that does not converge from any start (the message names the
        status), or map="random" with more than one minimum.

    Warns:
        SamplerWarning: x0 where F is not locally convex (no `starts`), a start that found a
        lower minimum than x0's, or a sample below every minimum found.

    Example:
        >>> import numpy as np, implicit
        >>> r = implicit.sample(lambda x: 0.5 * x @ x, np.zeros(2), n=100, seed=1)
        >>> r.samples.shape, round(float(r.weights.sum()), 12)
        ((100, 2), 1.0)
    """
    d = _implicit._sample(F, x0, _count(n, "sample: n", 1), grad, hess, map, _seed(seed),
                          bool(vectorized), starts)
    _warn_about_minima(d, starts is None)
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
        minima=d["minima"],
        minima_phi=d["minima_phi"],
        mixture_weights=d["mixture_weights"],
    )


def _warn_about_minima(d, single_start):
    # stacklevel 3: the warning points at the caller of implicit.sample.
    if single_start and not d["x0_convex"]:
        warnings.warn(
            "implicit.sample: F is not locally convex at x0 (its Hessian there is not positive "
            f"definite); Newton went to the minimum at {d['mode'].tolist()} (F = {d['phi']:.6g}), "
            "possibly one of several, and the samples and log Z would miss the others: pass "
            "starts=... to start from several points and sample the mixture over all minima",
            SamplerWarning, stacklevel=3)
    # A sample below the lowest minimum found: F has a lower minimum no start reached. The
    # margin is far above the minimiser's error in F at a minimum (its gradient is ~1e-8).
    phi = d["minima_phi"][0]
    if d["lowest_sample_F"] < phi - 1e-6 * (1.0 + abs(phi)):
        warnings.warn(
            f"implicit.sample: a sample has F = {d['lowest_sample_F']:.6g} at "
            f"{d['lowest_sample'].tolist()}, below the lowest minimum found (F = {phi:.6g} at "
            f"{d['mode'].tolist()}): F has a lower minimum that no start reached, so the samples "
            "and log Z miss its mass; pass starts=... including a point near that sample",
            SamplerWarning, stacklevel=3)
    first = d["found_by"][0]
    if first > 0:  # x0 converged, but not to the lowest minimum (index 0)
        phi = d["minima_phi"]
        warnings.warn(
            f"implicit.sample: the minimum found from x0 (F = {phi[first]:.6g} at "
            f"{d['minima'][first].tolist()}) is not the lowest: another start found F = "
            f"{phi[0]:.6g} at {d['minima'][0].tolist()}; a single start from x0 would have missed "
            f"it. The mixture over all {len(phi)} minima was sampled.",
            SamplerWarning, stacklevel=3)


def _count(value, name, lo):
    """An integer count >= lo: a float (even 3.0) or bool is refused, never truncated."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise _implicit.InvalidArgument(
            f"{name}: expected an integer, got {type(value).__name__} {value!r}")
    if value < lo:
        raise _implicit.InvalidArgument(f"{name}: expected an integer >= {lo}, got {value}")
    return int(value)


def _seed(value, name="seed"):
    """A seed: an integer in [0, 2^64 - 1], the range of the tool's --seed."""
    seed = _count(value, name, 0)
    if seed >= 2**64:
        raise _implicit.InvalidArgument(f"{name}: expected an integer below 2^64, got {seed}")
    return seed


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
    count = m if n is None else _count(n, "resample: n", 0)
    return _implicit._resample(scheme, w, count, _seed(seed), uniforms)


def uniforms_needed(scheme, n):
    """Number of uniforms `resample(..., scheme=scheme, n=n, uniforms=...)` consumes."""
    return _implicit._uniforms_needed(scheme, _count(n, "uniforms_needed: n", 0))


def ess(weights):
    """Effective sample size 1 / sum(w**2) of normalised weights (m,)."""
    return _implicit._ess(weights)


def log_sum_exp(a):
    """log(sum(exp(a))) of an (m,) array without overflow; -inf for all -inf."""
    return _implicit._log_sum_exp(a)
