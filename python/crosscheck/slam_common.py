"""Model, data loading, metrics and reference comparison shared by the numpy SLAM cross-checks.

Written from docs/specification.md (spec §3.1-3.2 for the Ute model and the range-bearing laser,
§3.6 for the data, §4.1-4.2 for the metrics) without the C++ library's code. Every function works
on a batch of poses (rows), so the particle filters are vectorised over particles.
"""
import gzip
import json
import math
from pathlib import Path

import numpy as np

# Ute model and laser (spec §3.1-3.2).
L, H, A, B, DT = 2.83, 0.76, 3.78, 0.5, 0.025
P_CONTROL = 0.5
Q = np.array([0.1, 0.1, 0.1 * np.pi / 180])
SIGMA2 = np.diag([0.05, 0.05 * np.pi / 180])  # variances (spec E27)
LOG_DET_2PI_SIGMA2 = float(np.log(np.linalg.det(2 * np.pi * SIGMA2)))
DATA_DIR = Path(__file__).resolve().parents[2] / "data" / "slam-synthetic"
LANDMARKS = DATA_DIR / "landmarks.csv"


def wrap(a):
    return a - 2 * np.pi * np.floor((a + np.pi) / (2 * np.pi))


def load(path):
    """A reference data set as a dict of columns (n, t_s, vc, alpha, x_true, ..., landmark)."""
    with gzip.open(path, "rt") as f:
        cols = f.readline().strip().split(",")
        rows = [[float(v) for v in line.strip().split(",")] for line in f if line.strip()]
    d = np.array(rows)
    return {c: d[:, i] for i, c in enumerate(cols)}


def load_landmarks():
    return np.loadtxt(LANDMARKS, delimiter=",", skiprows=1)[:, 1:3]


def predict(x, vc, alpha):
    """Mean f and covariance Sigma1 of the next pose for every row of x (spec §3.1)."""
    be = x[:, 2]
    ta = np.tan(alpha) / L
    s, c = np.sin(be), np.cos(be)
    g = np.stack([c - ta * (A * s + B * c), s + ta * (A * c - B * s), np.full_like(be, ta)], 1)
    k = np.stack([-(A * s + B * c), A * c - B * s, np.ones_like(be)], 1)
    cc = vc / np.cos(alpha) ** 2 / L
    sigma1 = DT * (P_CONTROL**2 * g[:, :, None] * g[:, None, :]
                   + P_CONTROL**2 * cc**2 * k[:, :, None] * k[:, None, :] + np.diag(Q**2)[None])
    return x + DT * vc * g, sigma1


def predict_jacobian(x, vc, alpha):
    """d f / d x of the mean motion (3x3 per row): only the heading column is not the identity."""
    be = x[:, 2]
    ta = np.tan(alpha) / L
    s, c = np.sin(be), np.cos(be)
    jac = np.tile(np.eye(3), (len(x), 1, 1))
    jac[:, 0, 2] = DT * vc * (-s - ta * (A * c - B * s))
    jac[:, 1, 2] = DT * vc * (c + ta * (-A * s - B * c))
    return jac


def observe(x, m):
    """Predicted (range, bearing), dx = x - m1, dy = y - m2 and range for rows x, m (spec §3.2)."""
    dx, dy = x[:, 0] - m[:, 0], x[:, 1] - m[:, 1]
    q = dx**2 + dy**2
    r = np.sqrt(q)
    b = np.arctan2(-dy, -dx) - x[:, 2] + np.pi / 2
    return np.stack([r, b], 1), dx, dy, r


def residual(x, m, z):
    """e = (r - z_r, wrap(b - z_b)) per row; z is one measurement or one per row."""
    h, dx, dy, r = observe(x, m)
    return np.stack([h[:, 0] - z[..., 0], wrap(h[:, 1] - z[..., 1])], 1), dx, dy, r


def jacobians(dx, dy, r):
    """H_x = d h / d pose (2x3) and H_m = d h / d landmark (2x2) per row."""
    q = r**2
    hx = np.zeros((len(dx), 2, 3))
    hx[:, 0, 0], hx[:, 0, 1] = dx / r, dy / r
    hx[:, 1, 0], hx[:, 1, 1], hx[:, 1, 2] = -dy / q, dx / q, -1.0
    return hx, -hx[:, :, :2]


def place(x, z):
    """New landmark g(x, z) and its Jacobians G_x (2x3), G_z (2x2) per row of x (spec §3.2)."""
    ang = x[:, 2] + z[1] - np.pi / 2
    ca, sa = np.cos(ang), np.sin(ang)
    m = x[:, :2] + z[0] * np.stack([ca, sa], 1)
    gx = np.zeros((len(x), 2, 3))
    gx[:, 0, 0], gx[:, 1, 1] = 1.0, 1.0
    gx[:, 0, 2], gx[:, 1, 2] = -z[0] * sa, z[0] * ca
    gz = np.empty((len(x), 2, 2))
    gz[:, 0, 0], gz[:, 0, 1] = ca, -z[0] * sa
    gz[:, 1, 0], gz[:, 1, 1] = sa, z[0] * ca
    return m, gx, gz


def log_normal2(e, s):
    """log N(e; 0, s) for rows e (n, 2) and covariances s (n, 2, 2)."""
    quad = np.einsum("ni,nij,nj->n", e, np.linalg.inv(s), e)
    return -0.5 * quad - 0.5 * np.log(np.linalg.det(2 * np.pi * s))


def systematic_resample(w, rng):
    m = len(w)
    u = (rng.random() + np.arange(m)) / m
    return np.minimum(np.searchsorted(np.cumsum(w), u), m - 1)


def align(est, true):
    """est after the best rotation + translation onto true (Umeyama/Horn, no scale)."""
    me, mt = est.mean(0), true.mean(0)
    u, _, vt = np.linalg.svd((est - me).T @ (true - mt))
    d = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    return (est - me) @ (u @ d @ vt) + mt


def map_shape(est, true):
    """Landmark RMSE after the best rigid alignment of est onto true."""
    return float(np.sqrt(((align(est, true) - true) ** 2).sum(1).mean()))


def metrics(path, d, map_est, landmarks, seen):
    """The spec §4.1-4.2 numbers of one run: path holds the position estimates of steps 1..N."""
    truth = np.stack([d["x_true"][1:], d["y_true"][1:]], 1)
    sq = ((path - truth) ** 2).sum(1)
    est, true = map_est[seen], landmarks[seen]
    return {"error_percent": 100 * math.sqrt(sq.sum() / (truth**2).sum()),
            "rmse_pose_m": math.sqrt(sq.mean()),
            "rmse_map_m": float(np.sqrt(((est - true) ** 2).sum(1).mean())),
            "map_shape_m": map_shape(est, true)}


# ---- Comparison with the reference of results.json ---------------------------------------------

# (key of a run's metrics, label, key of the reference row, decimals the reference table has:
# spec §3.10 prints err% and the RMSEs with 2, map shape and ESS/M with 3, resamplings with 0).
QUANTITIES = [("error_percent", "err%", "error_percent_mean", 2),
              ("rmse_pose_m", "pose RMSE [m]", "rmse_pose_m", 2),
              ("rmse_map_m", "landmark RMSE [m]", "rmse_map_m", 2),
              ("map_shape_m", "map shape [m]", "map_shape_m", 3),
              ("ess_mean", "ESS/M", "ess_mean", 3),
              ("resamplings", "resamplings", "resamplings", 0)]


def read_reference(path, method):
    """The table6 reference row of `method` and the table's particles and data-set counts."""
    with open(path) as fh:
        table = json.load(fh)["reference"]["table6"]
    row = next(r for r in table["rows"] if r["method"] == method)
    return row, int(table["particles"]), int(table["datasets"])


def summarise(runs):
    """Mean, SE and the single-run sd of every quantity.

    A data set is the unit of sampling: runs on one data set are averaged first, and the SE is
    that of the mean over data sets (runs on one set share its observation noise). The single-run
    sd (all runs pooled) estimates the spread of one run on a fresh data set, which is what a
    reference mean over one run per data set averages.
    """
    out = {}
    sets = sorted({r["data"] for r in runs})
    for key, _, _, _ in QUANTITIES:
        if key not in runs[0] or runs[0][key] is None:
            continue
        per_set = np.array([np.mean([r[key] for r in runs if r["data"] == s]) for s in sets])
        single = np.array([r[key] for r in runs], float)
        se = per_set.std(ddof=1) / math.sqrt(len(sets)) if len(sets) > 1 else float("nan")
        sd = single.std(ddof=1) if len(single) > 1 else float("nan")
        out[key] = (float(per_set.mean()), float(se), float(sd))
    return out


def rounding_sd(decimals):
    """The sd of a value rounded to `decimals` (uniform over one unit of the last digit): the
    reference's ESS/M of 0.657 is known only to +-0.0005, about its standard error."""
    return 0.5 * 10.0**-decimals / math.sqrt(3)


def compare(summary, row, datasets):
    """Prints numpy vs reference per quantity; returns the number of disagreements.

    SE_ref = sd_ref / sqrt(datasets) where the reference gives an sd (err%); elsewhere the
    reference gives only a mean, and its SE is estimated from this run's single-run sd. The
    rounding of the reference's printed value adds its own sd (rounding_sd).
    """
    bad = 0
    print(f"{'quantity':<18} {'numpy':>20}  {'reference':>20}  {'|diff|/SE':>9}  check")
    for key, label, ref_key, decimals in QUANTITIES:
        if key not in summary or row.get(ref_key) is None:
            continue
        mean, se, sd = summary[key]
        ref = float(row[ref_key])
        ref_sd = row.get("error_percent_std") if key == "error_percent" else None
        ref_se = math.hypot((float(ref_sd) if ref_sd is not None else sd) / math.sqrt(datasets),
                            rounding_sd(decimals))
        comb = math.hypot(se, ref_se)
        z = abs(mean - ref) / comb if comb > 0 else float("inf")
        ok = z <= 4.5
        bad += not ok
        print(f"{label:<18} {mean:>10.4f} ± {se:<7.4f}  {ref:>10.4f} ± {ref_se:<7.4f}  "
              f"{z:>9.2f}  {'ok' if ok else 'DISAGREES'}")
    return bad
