"""Your own state-space model, filtered by the library's engine (spec §1.2, §1.3, §1.5).

A model is a handful of numpy callbacks that work on all particles at once: arrays of shape
(k, d), one row per particle (k is the number of particles, a subset of them, or the stacked
points of a finite difference: never assume k = N). The filter calls each callback a fixed
number of times per step, never once per particle.

    x_0 ~ initial,  x_t ~ p(x_t | x_{t-1}),  y_t ~ p(y_t | x_t),  t = 1, ..., T

Callbacks (t is the step, 1 for the first observation; y is observations[t - 1] as given):

    initial(z) -> (k, d)                    x_0 from standard normals z (k, d)
    transition(t, x_prev, z) -> (k, d)      a draw of x_t given x_prev, from normals z (k, d)
    transition_logpdf(t, x, x_prev) -> (k,) log p(x | x_prev)      (implicit and guided)
    observation_logpdf(t, x, y) -> (k,)     log p(y | x)
    gradient(t, x, x_prev, y) -> (k, d)     optional: grad F, F = -log p(y|x) - log p(x|x_prev)
    hessian(t, x, x_prev, y) -> (k, d, d)   optional: the Hessian of F
    proposal(t, x_prev, y, z) -> ((k, d), (k,))   optional: your proposal's draws and log q

Every random number comes from the library's streams (the z arguments): a seed gives the same
run for any thread count, whatever numpy's own random state is. Log densities may be -inf
(density zero); NaN, +inf, non-finite draws and wrong shapes raise implicit.InvalidArgument
(a ValueError) naming the callback and the step.
"""
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from . import _implicit


@dataclass(frozen=True)
class Model:
    """A state-space model given by vectorised callbacks (see the module docstring).

    Attributes:
        dim: the dimension d of the state.
        initial, transition, observation_logpdf: needed by every proposal.
        transition_logpdf: needed by the implicit and guided proposals.
        gradient, hessian: optional derivatives of F = -log p(y | x) - log p(x | x_prev) for
            the implicit proposal; missing ones are central finite differences, evaluated in
            one stacked call (values only: 1 + 2d^2 points per particle; with the gradient
            alone: F and the gradient at 2d points per particle).
        proposal: optional, for proposal="guided".
    """

    dim: int
    initial: Callable
    transition: Callable
    observation_logpdf: Callable
    transition_logpdf: Optional[Callable] = None
    gradient: Optional[Callable] = None
    hessian: Optional[Callable] = None
    proposal: Optional[Callable] = None


@dataclass(frozen=True)
class FilterResult:
    """What implicit.ssm.particle_filter collected, one row per step t = 1..T.

    Attributes:
        mean: (T, d) filtering means E[x_t | y_1..t] (weights before resampling).
        variance: (T, d) filtering variances, per coordinate.
        ess: (T,) effective sample size after reweighting.
        log_likelihood_increments: (T,) log p-hat(y_t | y_1..t-1).
        log_likelihood: their sum, the estimate of log p(y_1..T).
        resampled: (T,) whether the step resampled (ESS below threshold * N).
        newton_iterations: (T,) mean Newton iterations per particle (implicit; else 0).
        newton_failures: (T,) particles without a minimiser (weight zero; implicit).
        map_failures: (T,) particles whose random-map ray had no root (weight zero).
        objective_calls: (T,) batched calls of F per step (implicit; else 0).
        particles: (N, d) the final population; weights: (N,) its normalised weights.
    """

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


def particle_filter(model, observations, particles=1000, proposal="bootstrap",
                    resampling="systematic", threshold=0.5, seed=1, threads=0,
                    max_newton_iterations=50, map="linear"):
    """Filters `observations` (a sequence, one entry per step) with the model's callbacks.

    Args:
        model: an implicit.ssm.Model.
        observations: y_1..y_T; entry t - 1 is passed to the callbacks as y at step t.
        particles: N, an integer in [1, 10^7].
        proposal: "bootstrap" (the transition; weight p(y | x)), "implicit" (per particle,
            minimise F(x) = -log p(y | x) - log p(x | x_prev) by Newton, all particles in
            lockstep, from the transition's draw with z = 0; sample x = mu + L^-T xi; exact
            weight, spec §1.2) or "guided" (model.proposal; weight p(y|x) p(x|x_prev) / q).
        resampling: "multinomial", "systematic", "stratified" or "residual".
        threshold: resample when ESS < threshold * N (0: never, 1: every step).
        seed: an integer in [0, 2^64 - 1]; the run depends on it alone.
        threads: worker threads of the C++ parts (0: all); results do not depend on it.
        max_newton_iterations: Newton's iteration limit (implicit).
        map: the implicit proposal's map, "linear" (x = mu + L^-T xi) or "random" (x on the ray
            mu + lambda L^-T xi / |xi| where F(x) - F(mu) = |xi|^2 / 2; spec §1.3).

    Returns:
        FilterResult. A step at which every particle has weight zero raises InvalidArgument.
    """
    if not isinstance(model, Model):
        raise _implicit.InvalidArgument(
            f"model: expected an implicit.ssm.Model, got {type(model).__name__}")
    r = _implicit._user_model_filter({
        "dim": model.dim, "initial": model.initial, "transition": model.transition,
        "transition_logpdf": model.transition_logpdf,
        "observation_logpdf": model.observation_logpdf, "gradient": model.gradient,
        "hessian": model.hessian, "proposal_fn": model.proposal, "observations": observations,
        "particles": particles, "proposal": proposal, "resampling": resampling,
        "threshold": threshold, "seed": seed, "threads": threads,
        "max_newton_iterations": max_newton_iterations, "map": map})
    return FilterResult(**r)
