#!/usr/bin/python3
"""The Himmelblau closed loop of Table 4 written again from spec §2.6 in numpy.

Usage: /usr/bin/python3 python/crosscheck/himmelblau_numpy.py [--runs R] [--samples M]
           [--seed S] [--compare RESULTS.json]

Each of the K = 20 receding-horizon steps minimises the reduced 2-D function G(z) (damped Newton
with a positive-definite Hessian), builds the path-space Hessian, draws M implicit samples
Y = mu + L^-T xi with weights exp(-F(Y) + |xi|^2/2), and takes the control from the score form
u = sum_j w_j (Y_j1 - x)/dt (spec §2.3; valid here since the drift is zero, and a different
estimator from the C++ finite differences, so agreement is not shared code). Random numbers:
numpy's Generator.

Prints mean ± SE over runs of the cost f(x_20) + sum_k R|u_k|^2 dt/2, f(x_19) and f(x_20), and
the fraction of runs ending with f(x_20) < 10. With --compare, reads the closed-form expectations
("expected" of the himmelblau run) and the reference cost from a results.json written by
`implicit reproduce`, and exits 1 when |numpy - reference| > 4.5 sqrt(SE_numpy^2 + SE_ref^2).
"""
import argparse
import json
import math
import sys

import numpy as np

R, SIGMA, DT, K = 0.01, 0.01, 1.0, 20
GAMMA = SIGMA * R  # spec E20
X0 = np.array([-1.0, -4.0])


def f(z):
    z = np.asarray(z)
    return (z[..., 0] ** 2 + z[..., 1] - 11) ** 2 + (z[..., 0] + z[..., 1] ** 2 - 7) ** 2


def grad_f(z):
    a, b = z[0] ** 2 + z[1] - 11, z[0] + z[1] ** 2 - 7
    return np.array([4 * z[0] * a + 2 * b, 2 * a + 4 * z[1] * b])


def hess_f(z):
    return np.array([[12 * z[0] ** 2 + 4 * z[1] - 42, 4 * (z[0] + z[1])],
                     [4 * (z[0] + z[1]), 12 * z[1] ** 2 + 4 * z[0] - 26]])


def minimise_reduced(x, n, z):
    """argmin of G(z) = |z - x|^2/(2 sigma n dt) + f(z)/gamma by damped, convexified Newton."""
    scale = 1.0 / (SIGMA * n * DT)

    def g_val(z):
        return 0.5 * scale * np.sum((z - x) ** 2) + f(z) / GAMMA

    for _ in range(200):
        g = scale * (z - x) + grad_f(z) / GAMMA
        h = scale * np.eye(2) + hess_f(z) / GAMMA
        low = np.linalg.eigvalsh(h)[0]
        if low <= 1e-8 * abs(h).max():
            h = h + (1e-8 * abs(h).max() - low) * np.eye(2)
        step = -np.linalg.solve(h, g)
        step_len, g0 = 1.0, g_val(z)
        while g_val(z + step_len * step) > g0 + 1e-4 * step_len * g @ step and step_len > 1e-12:
            step_len *= 0.5
        z = z + step_len * step
        if np.linalg.norm(step_len * step) < 1e-12 * (1 + np.linalg.norm(z)):
            break
    return z


def control(x, n, z_star, samples, rng):
    """Score-form control from M implicit samples of the n-step path (variables y_1..y_n)."""
    mu = x + np.outer(np.arange(1, n + 1) / n, z_star - x)
    tri = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    tri[-1, -1] = 1
    hess = np.kron(tri, np.eye(2)) / (SIGMA * DT)
    hess[-2:, -2:] += hess_f(z_star) / GAMMA
    chol = np.linalg.cholesky(hess)
    xi = rng.standard_normal((samples, 2 * n))
    y = mu.reshape(-1) + np.linalg.solve(chol.T, xi.T).T
    paths = y.reshape(samples, n, 2)
    steps = np.diff(np.concatenate([np.broadcast_to(x, (samples, 1, 2)), paths], 1), axis=1)
    cost = (steps**2).sum((1, 2)) / (2 * SIGMA * DT) + f(paths[:, -1]) / GAMMA
    log_w = -cost + 0.5 * (xi**2).sum(1)
    w = np.exp(log_w - log_w.max())
    w /= w.sum()
    return (w[:, None] * (paths[:, 0] - x)).sum(0) / DT


def run(samples, rng):
    x, z, cost, f19 = X0.copy(), X0.copy(), 0.0, None
    for k in range(K):
        n = K - k
        z = minimise_reduced(x, n, z)
        u = control(x, n, z, samples, rng)
        cost += 0.5 * R * (u @ u) * DT
        if k == K - 1:
            f19 = float(f(x))
        x = x + u * DT + math.sqrt(SIGMA * DT) * rng.standard_normal(2)
    final = float(f(x))
    return cost + final, f19, final


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--runs", type=int, default=400)
    p.add_argument("--samples", type=int, default=50)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--compare", metavar="RESULTS_JSON")
    a = p.parse_args()
    if a.runs < 2 or a.samples < 1:
        p.error("--runs must be at least 2 and --samples at least 1")
    refs, ref = {}, None
    if a.compare:
        try:
            with open(a.compare) as fh:
                res = json.load(fh)
            ref = res["reference"]["himmelblau"]
            runs = res["experiments"]["himmelblau"]["runs"]
            expected = next(r["result"]["expected"] for r in runs if r["status"] == "ok")
        except (OSError, ValueError, KeyError, StopIteration) as e:
            print(f"{a.compare}: cannot read the himmelblau reference: {e}", file=sys.stderr)
            return 1
        refs = {"cost": [("closed form", expected["cost"], 0.0),
                         ("reference", ref["mean_cost"], ref["mean_cost_sd"])],
                "f(x_19)": [("closed form", expected["f_before_last_step"], 0.0)],
                "f(x_20)": [("closed form", expected["final_f"], 0.0)]}
    rng = np.random.default_rng(a.seed)
    out = np.array([run(a.samples, rng) for _ in range(a.runs)])
    bad = 0
    print(f"{'quantity':<10} {'numpy':>18}  {'against':<12} {'value':>16}  check")
    for i, name in enumerate(("cost", "f(x_19)", "f(x_20)")):
        mean, se = out[:, i].mean(), out[:, i].std(ddof=1) / math.sqrt(a.runs)
        print(f"{name:<10} {mean:>9.4f} ± {se:<6.4f}")
        for label, value, ref_se in refs.get(name, []):
            ok = abs(mean - value) <= 4.5 * math.hypot(se, ref_se)
            bad += not ok
            print(f"{'':<10} {'':>18}  {label:<12} {value:>8.4f} ± {ref_se:<5.3f}  "
                  f"{'ok' if ok else 'DISAGREES'}")
    below = float((out[:, 2] < 10).mean())
    print(f"fraction of runs with f(x_20) < 10: {below:.3f}")
    if a.compare and below < ref["min_fraction_below_10"]:
        print(f"fewer than {ref['min_fraction_below_10']} of the runs end near a minimum")
        bad += 1
    print(f"{a.runs} runs, M = {a.samples}, seed {a.seed}")
    if bad:
        print(f"{bad} quantities disagree with the reference", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
