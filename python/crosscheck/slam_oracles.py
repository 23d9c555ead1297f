#!/usr/bin/python3
"""The numpy SLAM model against the closed-form oracles of the specification.

Usage: /usr/bin/python3 python/crosscheck/slam_oracles.py

Checks slam_common.predict against the Ute model oracle of spec §3.1, the implicit-SLAM
objective, its gradient, Hessian and minimiser (slam_filters.objective, minimise) against Case A
of spec §3.7, and the new-landmark proposal of implicit (A) against Case C, to a relative 1e-8
(the spec's values carry 10-11 digits; one gradient also needs the rounding of the printed
measurement, see there). Exits 1 on a mismatch.
"""
import sys

import numpy as np

from slam_common import H, L, SIGMA2, jacobians, place, predict, residual
from slam_filters import minimise, objective

CHECKS = []


def check(name, got, want, rel=1e-8, atol=0.0):
    got, want = np.asarray(got, float), np.asarray(want, float)
    scale = np.maximum(np.abs(want), 1e-3 * np.abs(want).max())
    ok = bool(np.all(np.abs(got - want) <= rel * scale + atol))
    CHECKS.append(ok)
    print(f"{name}: {'ok' if ok else 'MISMATCH'} (largest relative difference "
          f"{float(np.max(np.abs(got - want) / scale)):.1e})")


def main():
    # Spec §3.1: X = (10, 5, 0.3), v_l = 3, alpha = 0.1.
    x0 = np.array([[10.0, 5.0, 0.3]])
    alpha = 0.1
    vc = 3 / (1 - np.tan(alpha) * H / L)
    check("v_c", vc, 3.083073413995238)
    f, sigma1 = predict(x0, vc, alpha)
    check("f (spec §3.1)", f[0], [10.0692764169, 5.0322421519, 0.3027326781])
    check("Sigma1 (spec §3.1)", sigma1[0],
          [[0.0245454899, -0.0394493293, -0.0118696275],
           [-0.0394493293, 0.0921222704, 0.0263034408],
           [-0.0118696275, 0.0263034408, 0.0075758305]])
    check("det Sigma1", np.linalg.det(sigma1[0]), 1.23520096419e-8)
    # Spec §3.7 Case A: one landmark m = (20, 12), S = Sigma2, F without constants.
    m = np.array([[20.0, 12.0]])
    z = np.array([12.1682955572, 1.8806599794])
    s1inv = np.linalg.inv(sigma1)
    sinv = np.linalg.inv(SIGMA2)[None]
    val, grad, hess, _ = objective(f, f, s1inv, m, z, sinv)
    check("Case A, F(f)", val[0], 0.014014336680)
    # At f the gradient is H^T Sigma2^-1 e alone, and z is printed to 1e-10: a bearing off by
    # 5e-11 moves the heading component by 5e-11 / sigma_b^2 = 5.7e-8, hence the absolute term.
    check("Case A, grad F(f)", grad[0], [0.5634353514, 0.4845133583, 0.8856871421], atol=1e-7)
    check("Case A, Hessian at f", hess[0],
          [[504.2632900481, -1075.0720121249, 4463.5484653852],
           [-1075.0720121249, 3660.1271445824, -14283.2532646218],
           [4463.5484653852, -14283.2532646218, 58216.5213328328]])
    xt = f + np.array([0.2, -0.1, 0.01])
    val, grad, hess, _ = objective(xt, f, s1inv, m, z, sinv)
    check("Case A, F(f + d)", val[0], 76.093242330183)
    check("Case A, grad F(f + d)", grad[0], [253.5311514905, -723.3752344939, 2903.9233431589])
    check("Case A, Hessian at f + d", hess[0],
          [[504.1078441596, -1075.0042387521, 4461.8076973143],
           [-1075.0042387521, 3660.244117105, -14283.4859080862],
           [4461.8076973143, -14283.4859080862, 58216.5213328328]])
    mu, hmu = minimise(f, s1inv, m, z, sinv)
    check("Case A, minimiser", mu[0], [10.0667353158, 5.028063506, 0.3018870747])
    check("Case A, phi", objective(mu, f, s1inv, m, z, sinv, order=0)[0], 0.011911716008)
    check("Case A, log det L", np.log(np.diag(np.linalg.cholesky(hmu[0]))).sum(),
          10.545986532115)
    # Case C: (A)'s new landmark. slam_filters.implicit_a_new draws theta given the pose with
    # mean g - J_th^-1 J_x (X - f) and covariance J_th^-1 Sigma2 J_th^-T, X ~ N(f, Sigma1); its
    # theta-marginal must be that of the 5-D Gaussian N(mu, H^-1) the spec gives.
    g, _, _ = place(f, z)
    check("Case C, g(f, z)", g[0], [20.0248635998, 12.0289342712])
    _, dx, dy, r = residual(f, g, z)
    jx, jth = jacobians(dx, dy, r)
    b = np.linalg.solve(jth[0], jx[0])
    c = np.linalg.inv(jth[0])
    cov_theta = c @ SIGMA2 @ c.T + b @ sigma1[0] @ b.T
    check("Case C, theta-marginal of H^-1", cov_theta,
          [[0.6376959687, -0.9066236254], [-0.9066236254, 1.4697472995]])
    bad = CHECKS.count(False)
    print(f"spec §3.1 and §3.7 oracles: {len(CHECKS) - bad} of {len(CHECKS)} checks agree")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
