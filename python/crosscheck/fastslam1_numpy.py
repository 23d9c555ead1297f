#!/usr/bin/python3
"""FastSLAM 1.0 written again from spec §3.5 in numpy, for cross-checking the C++ estimator.

Usage: /usr/bin/python3 python/crosscheck/fastslam1_numpy.py [--runs R] [--particles M]
           [--seed S] DATA.csv.gz [DATA.csv.gz ...]

DATA is a synthetic data set in the reference CSV format of data/slam-synthetic (columns n, t_s,
vc, alpha, x_true, y_true, beta_true, has_obs, z_r, z_b, landmark; true landmarks from
data/slam-synthetic/landmarks.csv). Known association, systematic resampling when ESS < M/2, map
estimate = weighted mean of the particles' landmarks with the weights before the last resampling.
It shares no code with the C++ library (its own model, Jacobians, alignment and random numbers),
so agreement in distribution is evidence that both follow the spec, not each other. The model
and data loading are in slam_common.py (shared with slam_numpy.py, the other SLAM methods).

Prints one line per run: data set, seed, map shape [m], mean ESS/M, resamplings; then the mean
map shape with its standard error. A run of R = 50 on the ten paper_le1 sets takes about a
minute per 100 runs at M = 100.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

# The Ute model, the laser, data loading and the map-shape metric (spec §3.1-3.2, §4.2) are
# shared with the other SLAM cross-checks; none of it comes from the C++ library.
from slam_common import SIGMA2, load, load_landmarks, map_shape, predict, wrap


def run(d, landmarks, m, seed):
    rng = np.random.default_rng(seed)
    x = np.tile([d["x_true"][0], d["y_true"][0], d["beta_true"][0]], (m, 1))
    k_all = len(landmarks)
    mu, cov = np.zeros((m, k_all, 2)), np.zeros((m, k_all, 2, 2))
    seen = np.zeros(k_all, bool)
    w = np.full(m, 1.0 / m)
    log_w = np.zeros(m)
    ess_sum, weighted, resamplings = 0.0, 0, 0
    w_map, mu_map = w, mu
    for n in range(1, len(d["n"])):
        f, sigma1 = predict(x, d["vc"][n], d["alpha"][n])
        x = f + np.einsum("mij,mj->mi", np.linalg.cholesky(sigma1), rng.standard_normal((m, 3)))
        if d["has_obs"][n] < 0.5:
            continue
        z = np.array([d["z_r"][n], d["z_b"][n]])
        k = int(d["landmark"][n])
        weighted += 1
        if not seen[k]:
            # New landmark: inverse observation; the weight factor is common to all particles.
            seen[k] = True
            ang = x[:, 2] + z[1] - np.pi / 2
            mu[:, k] = x[:, :2] + z[0] * np.stack([np.cos(ang), np.sin(ang)], 1)
            gz = np.empty((m, 2, 2))
            gz[:, 0, 0], gz[:, 0, 1] = np.cos(ang), -z[0] * np.sin(ang)
            gz[:, 1, 0], gz[:, 1, 1] = np.sin(ang), z[0] * np.cos(ang)
            cov[:, k] = gz @ SIGMA2 @ gz.transpose(0, 2, 1)
            ess_sum += 1.0 / (w**2).sum() / m
            continue
        delta = mu[:, k] - x[:, :2]
        q = (delta**2).sum(1)
        r = np.sqrt(q)
        bearing = np.arctan2(delta[:, 1], delta[:, 0]) - x[:, 2] + np.pi / 2
        hm = np.empty((m, 2, 2))
        hm[:, 0, 0], hm[:, 0, 1] = delta[:, 0] / r, delta[:, 1] / r
        hm[:, 1, 0], hm[:, 1, 1] = -delta[:, 1] / q, delta[:, 0] / q
        pk = cov[:, k]
        s = hm @ pk @ hm.transpose(0, 2, 1) + SIGMA2
        s_inv = np.linalg.inv(s)
        e = np.stack([z[0] - r, wrap(z[1] - bearing)], 1)
        log_w = log_w - 0.5 * np.einsum("mi,mij,mj->m", e, s_inv, e) \
            - 0.5 * np.log(np.linalg.det(2 * np.pi * s))
        gain = pk @ hm.transpose(0, 2, 1) @ s_inv
        mu[:, k] = mu[:, k] + np.einsum("mij,mj->mi", gain, e)
        cov[:, k] = (np.eye(2)[None] - gain @ hm) @ pk
        w = np.exp(log_w - log_w.max())
        w /= w.sum()
        with np.errstate(divide="ignore"):
            log_w = np.log(w)
        ess = 1.0 / (w**2).sum()
        ess_sum += ess / m
        w_map, mu_map = w, mu
        if ess < m / 2:
            u = (rng.random() + np.arange(m)) / m
            idx = np.minimum(np.searchsorted(np.cumsum(w), u), m - 1)
            x, mu, cov = x[idx], mu[idx], cov[idx]  # fancy indexing copies
            w, log_w = np.full(m, 1.0 / m), np.zeros(m)
            resamplings += 1
    est = np.einsum("m,mkj->kj", w_map, mu_map)
    return map_shape(est[seen], landmarks[seen]), ess_sum / max(weighted, 1), resamplings


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data", nargs="+", type=Path)
    ap.add_argument("--runs", type=int, default=10, help="filter runs per data set")
    ap.add_argument("--particles", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1, help="run r of data set i uses seed + 1000 i + r")
    a = ap.parse_args()
    if a.runs < 1 or a.particles < 1:
        ap.error("--runs and --particles must be at least 1")
    landmarks = load_landmarks()
    shapes = []
    for i, path in enumerate(a.data):
        try:
            d = load(path)
        except (OSError, ValueError) as err:
            sys.exit(f"{path}: cannot read a reference data set: {err}")
        for r in range(a.runs):
            seed = a.seed + 1000 * i + r
            shape, ess, res = run(d, landmarks, a.particles, seed)
            shapes.append(shape)
            print(f"{path.name} {seed} {shape:.6f} {ess:.4f} {res}", flush=True)
    v = np.array(shapes)
    if len(v) > 1:
        se = v.std(ddof=1) / np.sqrt(len(v))
        print(f"mean map shape {v.mean():.4f} m, SE {se:.4f} m over {len(v)} runs")
    else:
        print(f"mean map shape {v.mean():.4f} m over 1 run (no standard error)")


if __name__ == "__main__":
    main()
