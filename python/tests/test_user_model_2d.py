"""implicit.ssm in two dimensions: a constant-velocity tracking model (position and velocity,
the position observed) against the Kalman filter, and the exact implicit weight of a Gaussian
step, with every way of getting F's derivatives (values only: the 1 + 2d^2-point stencil with
its off-diagonal terms; the gradient differenced; both given).

The mean over R = 20 independent runs (seeds 1..20) is compared with the exact value in units
of its standard error estimated from the same runs: a t statistic with 19 degrees of freedom.
Z_SIGMA is its quantile for a probability of 1e-3 that a correct filter fails any of the file's
484 checks (Bonferroni): scipy.stats.t.isf(1e-3 / (2 * 484), 19) = 6.71, rounded up.
"""
import math

import numpy as np
import pytest

from implicit import ssm

Z_SIGMA = 6.8
DT = 0.5
A = np.array([[1.0, DT], [0.0, 1.0]])
Q = 0.3 * np.array([[DT ** 3 / 3, DT ** 2 / 2], [DT ** 2 / 2, DT]])
H = np.array([[1.0, 0.0]])
R = np.array([[0.2]])
P0 = np.eye(2)
QI, RI = np.linalg.inv(Q), np.linalg.inv(R)
LQ, L0 = np.linalg.cholesky(Q), np.linalg.cholesky(P0)


def mvn_logpdf(e, cov):
    """log N(e; 0, cov) for the rows of e."""
    k = cov.shape[0]
    sol = np.linalg.solve(cov, e.T).T
    return -0.5 * (np.sum(e * sol, axis=1) + k * math.log(2 * math.pi)
                   + math.log(np.linalg.det(cov)))


def derivatives():
    def gradient(t, x, xp, y):
        return (x - xp @ A.T) @ QI - (np.atleast_1d(y) - x @ H.T) @ RI @ H

    def hessian(t, x, xp, y):
        return np.broadcast_to(QI + H.T @ RI @ H, (len(x), 2, 2)).copy()

    return gradient, hessian


def model(derivs="none", initial=None):
    gradient, hessian = derivatives()
    return ssm.Model(
        dim=2,
        initial=initial or (lambda z: z @ L0.T),
        transition=lambda t, xp, z: xp @ A.T + z @ LQ.T,
        transition_logpdf=lambda t, x, xp: mvn_logpdf(x - xp @ A.T, Q),
        observation_logpdf=lambda t, x, y: mvn_logpdf(np.atleast_1d(y) - x @ H.T, R),
        gradient=gradient if derivs in ("gradient", "both") else None,
        hessian=hessian if derivs == "both" else None)


def simulate(steps=30, seed=2):
    rng = np.random.default_rng(seed)
    x, ys = L0 @ rng.normal(size=2), []
    for _ in range(steps):
        x = A @ x + LQ @ rng.normal(size=2)
        ys.append(float(H @ x + math.sqrt(R[0, 0]) * rng.normal()))
    return ys


def kalman(ys):
    m, p, ll, means, variances = np.zeros(2), P0.copy(), 0.0, [], []
    for y in ys:
        m, p = A @ m, A @ p @ A.T + Q
        s = H @ p @ H.T + R
        e = y - H @ m
        ll += float(mvn_logpdf(e[None, :], s)[0])
        k = p @ H.T @ np.linalg.inv(s)
        m, p = m + k @ e, (np.eye(2) - k @ H) @ p
        means.append(m)
        variances.append(np.diag(p))
    return np.array(means), np.array(variances), ll


@pytest.mark.parametrize("proposal,derivs", [
    ("bootstrap", "none"), ("implicit", "none"), ("implicit", "gradient"),
    ("implicit", "both")])
def test_tracking_model_agrees_with_kalman(proposal, derivs):
    ys = simulate()
    means, variances, ll = kalman(ys)
    runs = [ssm.particle_filter(model(derivs), ys, particles=500, proposal=proposal, seed=s)
            for s in range(1, 21)]
    for what, values, exact in [
            ("mean", np.array([r.mean for r in runs]), means),
            ("variance", np.array([r.variance for r in runs]), variances),
            ("likelihood", np.array([math.exp(r.log_likelihood - ll) for r in runs]), 1.0)]:
        se = values.std(axis=0, ddof=1) / math.sqrt(len(runs))
        z = np.abs(values.mean(axis=0) - exact) / se
        assert np.all(z < Z_SIGMA), f"{what}: max |mean - Kalman| / SE = {z.max():.2f}"


@pytest.mark.parametrize("derivs,tolerance", [("none", 1e-7), ("gradient", 1e-9),
                                              ("both", 1e-12)])
@pytest.mark.parametrize("implicit_map", ["linear", "random"])
def test_implicit_weight_is_exact_for_a_gaussian_step(derivs, tolerance, implicit_map):
    # The implicit proposal of a linear-Gaussian step is the optimal one, so particle j's weight
    # is p(y_1 | x_0^j) = N(y_1; H A x_0^j, H Q H^T + R). With finite differences the Hessian,
    # hence L and the weights, carry round-off: eps |F| / h^2 with h = eps^(1/4) from values
    # (about 1.5e-8 |F|), eps |grad F| / h with h = eps^(1/3) from the gradient (about 4e-11);
    # F and its gradient are O(1) here, so 1e-7 and 1e-9 (the quadratic F has no truncation error).
    seen = {}

    def initial(z):
        seen["x0"] = z @ L0.T
        return seen["x0"]

    y1 = 0.8
    r = ssm.particle_filter(model(derivs, initial), [y1], particles=200, proposal="implicit",
                            seed=9, map=implicit_map)
    inc = mvn_logpdf(y1 - seen["x0"] @ A.T @ H.T, H @ Q @ H.T + R)
    assert r.log_likelihood == pytest.approx(np.log(np.mean(np.exp(inc))), abs=tolerance)
    assert r.newton_failures[0] == 0 and r.map_failures[0] == 0
