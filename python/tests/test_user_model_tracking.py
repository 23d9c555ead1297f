"""implicit.ssm on the user guide's 4-D tracking model (docs/user-guide.md, "Your own model in
Python"): a constant-velocity target (x, y, vx, vy), range and bearing from a sensor at the
origin. No closed form exists (the observation is nonlinear), and a linearising smoother is an
approximation, not an oracle; the reference is the bootstrap filter with many particles,
independent of the implicit proposal's code path.

Reference: K = 20 bootstrap runs of 25 000 particles (seeds 101..120); filters under test:
R = 20 runs of 1000 particles (seeds 1..20). Per step and coordinate the difference of the two
means over runs is divided by its standard error sqrt(se_R^2 + se_K^2), each estimated from the
spread of its own runs (the runs are independent: different seeds). Its distribution is
Welch's t, whose degrees of freedom are at least min(R, K) - 1 = 19. Z_SIGMA is the t quantile
with 19 degrees of freedom for a probability of 1e-3 that a correct filter fails any of the
file's 160 checks (2 proposals x 20 steps x 4 coordinates; Bonferroni):
scipy.stats.t.isf(1e-3 / (2 * 160), 19) = 6.17, rounded up. The filters' O(1/N) bias is far
below these standard errors (about sd / 80: ESS ~ 300 x 20 runs for the implicit proposal).
"""
import math

import numpy as np
import pytest

from implicit import ssm

Z_SIGMA = 6.2  # see the module docstring: 160 checks, 19 degrees of freedom
F = np.array([[1.0, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1]])
Q = 0.5 * np.kron([[1 / 3, 1 / 2], [1 / 2, 1]], np.eye(2))
LQ, QI, LOG_DET_Q = np.linalg.cholesky(Q), np.linalg.inv(Q), math.log(np.linalg.det(Q))
SD_RANGE_M, SD_BEARING_RAD = 0.3, 0.005
M0, SD0 = np.array([40.0, 10.0, -1.0, 1.0]), np.array([2.0, 2.0, 0.5, 0.5])
STEPS = 20


def bearing_error(x, y):
    return np.angle(np.exp(1j * (y[1] - np.arctan2(x[:, 1], x[:, 0]))))


def transition_logpdf(t, x, x_prev):
    e = x - x_prev @ F.T
    return -0.5 * (np.einsum("ki,ij,kj->k", e, QI, e) + LOG_DET_Q + 4 * math.log(2 * math.pi))


def observation_logpdf(t, x, y):
    e_range = y[0] - np.hypot(x[:, 0], x[:, 1])
    return (-0.5 * ((e_range / SD_RANGE_M) ** 2 + (bearing_error(x, y) / SD_BEARING_RAD) ** 2)
            - math.log(2 * math.pi * SD_RANGE_M * SD_BEARING_RAD))


def gradient(t, x, x_prev, y):
    r2 = x[:, 0] ** 2 + x[:, 1] ** 2
    c_range = -(y[0] - np.sqrt(r2)) / (SD_RANGE_M ** 2 * np.sqrt(r2))
    c_bearing = -bearing_error(x, y) / (SD_BEARING_RAD ** 2 * r2)
    g = (x - x_prev @ F.T) @ QI
    g[:, 0] += c_range * x[:, 0] - c_bearing * x[:, 1]
    g[:, 1] += c_range * x[:, 1] + c_bearing * x[:, 0]
    return g


def negative_log_posterior(t, x, x_prev, y):
    return -(transition_logpdf(t, x, x_prev) + observation_logpdf(t, x, y))


def tracking_model(with_gradient=True):
    return ssm.Model(dim=4, initial=lambda z: M0 + z * SD0,
                     transition=lambda t, x_prev, z: x_prev @ F.T + z @ LQ.T,
                     transition_logpdf=transition_logpdf, observation_logpdf=observation_logpdf,
                     gradient=gradient if with_gradient else None)


def simulate(seed=7):
    """The user guide's data (the same generator and seed)."""
    rng = np.random.default_rng(seed)
    x, ys = M0 + SD0 * rng.normal(size=4), []
    for _ in range(STEPS):
        x = F @ x + LQ @ rng.normal(size=4)
        ys.append([math.hypot(x[0], x[1]) + SD_RANGE_M * rng.normal(),
                   math.atan2(x[1], x[0]) + SD_BEARING_RAD * rng.normal()])
    return ys


def mean_and_se(runs):
    means = np.array([r.mean for r in runs])  # (runs, T, 4)
    return means.mean(axis=0), means.std(axis=0, ddof=1) / math.sqrt(len(runs))


@pytest.fixture(scope="module")
def reference():
    ys = simulate()
    runs = [ssm.particle_filter(tracking_model(), ys, particles=25_000, seed=s)
            for s in range(101, 121)]
    return ys, mean_and_se(runs)


def test_gradient_matches_finite_differences():
    # The example's analytic gradient of F against central differences (step 1e-6 relative:
    # the error is O(h^2) times the third derivative, far below the 1e-5 relative tolerance).
    rng = np.random.default_rng(1)
    x_prev = M0 + rng.normal(size=(5, 4))
    x = x_prev @ F.T + rng.normal(size=(5, 4)) * 0.5
    y = [42.0, 0.25]
    g = gradient(1, x, x_prev, y)
    for i in range(4):
        h = 1e-6 * max(1.0, float(np.abs(x[:, i]).max()))
        e = np.zeros(4)
        e[i] = h
        fd = (negative_log_posterior(1, x + e, x_prev, y)
              - negative_log_posterior(1, x - e, x_prev, y)) / (2 * h)
        np.testing.assert_allclose(g[:, i], fd, rtol=1e-5, atol=1e-4)


@pytest.mark.parametrize("proposal", ["bootstrap", "implicit"])
def test_tracking_filtering_means_match_the_reference(reference, proposal):
    ys, (ref_mean, ref_se) = reference
    runs = [ssm.particle_filter(tracking_model(), ys, particles=1000, proposal=proposal, seed=s)
            for s in range(1, 21)]
    mean, se = mean_and_se(runs)
    z = np.abs(mean - ref_mean) / np.sqrt(se ** 2 + ref_se ** 2)
    step, coordinate = np.unravel_index(z.argmax(), z.shape)
    assert np.all(z < Z_SIGMA), (f"max |mean - reference| / SE = {z.max():.2f} at step "
                                 f"{step + 1}, coordinate {coordinate}")
    assert all(r.newton_failures.sum() == 0 for r in runs)
