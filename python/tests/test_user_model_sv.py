"""implicit.ssm on a stochastic volatility model, whose F is convex (so both implicit maps
apply, spec §1.3), against a fine-grid reference filter (numpy quadrature):

    x_t = PHI x_{t-1} + SIGMA v_t,   x_0 ~ N(0, SIGMA^2 / (1 - PHI^2))
    y_t = BETA exp(x_t / 2) w_t,     v_t, w_t ~ N(0, 1)

F(x) = (x - PHI x')^2 / (2 SIGMA^2) + x / 2 + y^2 exp(-x) / (2 BETA^2) + const. The mean over
R = 20 independent runs of the filtering means and of the likelihood Z-hat (unbiased) is
compared with the grid in units of its standard error estimated from the same runs: a t
statistic with 19 degrees of freedom. Z_SIGMA is its quantile for a probability of 1e-3 that a
correct filter fails any of the 124 checks (4 variants x 31; Bonferroni):
scipy.stats.t.isf(1e-3 / (2 * 124), 19) = 6.05, rounded up.
"""
import math

import numpy as np
import pytest

from implicit import ssm

Z_SIGMA = 6.1  # see the module docstring: 124 checks
PHI, SIGMA, BETA = 0.95, 0.4, 0.7
STEPS = 30
P0 = SIGMA ** 2 / (1 - PHI ** 2)


def gauss_logpdf(e, var):
    return -0.5 * (e * e / var + np.log(2 * math.pi * var))


def obs_logpdf(y, x):
    return gauss_logpdf(y, BETA ** 2 * np.exp(x))


def model(**extra):
    return ssm.Model(
        dim=1,
        initial=lambda z: math.sqrt(P0) * z,
        transition=lambda t, xp, z: PHI * xp + SIGMA * z,
        transition_logpdf=lambda t, x, xp: gauss_logpdf(x[:, 0] - PHI * xp[:, 0], SIGMA ** 2),
        observation_logpdf=lambda t, x, y: obs_logpdf(y, x[:, 0]),
        **extra)


def derivatives():
    def gradient(t, x, xp, y):
        return (x - PHI * xp) / SIGMA ** 2 + 0.5 - y * y * np.exp(-x) / (2 * BETA ** 2)

    def hessian(t, x, xp, y):
        return (1 / SIGMA ** 2 + y * y * np.exp(-x[:, 0]) / (2 * BETA ** 2))[:, None, None]

    return {"gradient": gradient, "hessian": hessian}


def simulate(seed=5):
    rng = np.random.default_rng(seed)
    x, ys = math.sqrt(P0) * rng.normal(), []
    for _ in range(STEPS):
        x = PHI * x + SIGMA * rng.normal()
        ys.append(BETA * math.exp(x / 2) * rng.normal())
    return np.array(ys)


def grid_filter(ys, n=4001):
    x = np.linspace(-8.0, 8.0, n)  # the stationary sd is 1.28: 6 sd either side
    dx = x[1] - x[0]
    p = np.exp(gauss_logpdf(x, P0))
    k = np.exp(gauss_logpdf(x[:, None] - PHI * x[None, :], SIGMA ** 2))
    means, ll = [], 0.0
    for y in ys:
        p = k @ p * dx
        p *= np.exp(obs_logpdf(y, x))
        z = p.sum() * dx
        ll += math.log(z)
        p /= z
        means.append((x * p).sum() * dx)
    return np.array(means), ll


@pytest.fixture(scope="module")
def reference():
    ys = simulate()
    means, ll = grid_filter(ys)
    fine_means, fine_ll = grid_filter(ys, n=8001)
    assert np.max(np.abs(fine_means - means)) < 1e-8 and abs(fine_ll - ll) < 1e-8
    return ys, means, ll


@pytest.mark.parametrize("proposal,extra,implicit_map", [
    ("bootstrap", {}, "linear"),
    ("implicit", {}, "linear"),
    ("implicit", {}, "random"),
    ("implicit", derivatives(), "random"),
])
def test_stochastic_volatility(reference, proposal, extra, implicit_map):
    ys, means, ll = reference
    runs = [ssm.particle_filter(model(**extra), ys, particles=500, proposal=proposal, seed=s,
                                map=implicit_map) for s in range(1, 21)]
    for what, values, exact in [
            ("filtering mean", np.array([r.mean[:, 0] for r in runs]), means),
            ("likelihood", np.array([math.exp(r.log_likelihood - ll) for r in runs]), 1.0)]:
        se = values.std(axis=0, ddof=1) / math.sqrt(len(runs))
        z = np.abs(values.mean(axis=0) - exact) / se
        assert np.all(z < Z_SIGMA), f"{what}: max |mean - grid| / SE = {z.max():.2f}"
    assert sum(r.map_failures.sum() + r.newton_failures.sum() for r in runs) == 0
