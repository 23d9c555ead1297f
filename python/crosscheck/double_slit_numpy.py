#!/usr/bin/python3
"""The double slit closed loop of Table 2 written again from spec §2.4 in numpy.

Usage: /usr/bin/python3 python/crosscheck/double_slit_numpy.py [--runs R] [--samples 10,50,...]
           [--seed S] [--compare RESULTS.json]

Both estimators of the control before the wall are implemented from the spec, sharing no code
with the C++ library: "paper" (P, dominant slit only, pass fraction without weights, FD-CRN,
spec §2.4.4-2.4.5) and "corrected" (W2 with the wall coordinate frozen, the weighted mean of the
wall samples of both slits, M samples per slit). The path sampler is used in its exact 1-D form
(spec §2.4.4: the wall offset of a path sample is N(0, tau^2)), and the exact control of §2.4.1
drives the other trajectory with the same noise (§2.4.6). Random numbers: numpy's Generator.

Prints mean ± SE (over runs) of 100 e_x, 100 e_u and the crash fraction per estimator and M.
With --compare, reads the reference numbers from the "reference" section of a results.json
written by `implicit reproduce` (the C++ report's own source of them) and exits 1 when
|numpy - reference| > 4.5 sqrt(SE_numpy^2 + SE_ref^2) for any quantity.
"""
import argparse
import json
import math
import sys

import numpy as np

SIGMA, GAMMA, DT, K, K1 = 1.0, 0.1, 0.02, 100, 50
TF, T1, X0, H = K * DT, K1 * DT, 1.0, 1e-3
SLITS = ((-6.0, -4.0), (6.0, 8.0))
_erfc = np.frompyfunc(math.erfc, 1, 1)


def log_ndtr(z):
    """log Phi_N(z), accurate in the far left tail (asymptotic series below -20)."""
    z = np.asarray(z, dtype=float)
    out = np.empty_like(z)
    far = z < -20
    out[~far] = np.log(0.5 * _erfc(-z[~far] / math.sqrt(2)).astype(float))
    zf = z[far]
    out[far] = (-0.5 * zf**2 - np.log(-zf) - 0.5 * math.log(2 * math.pi)
                + np.log1p(-1 / zf**2 + 3 / zf**4 - 15 / zf**6))
    return out


def log_interval(a, b):
    """log(Phi_N(b) - Phi_N(a)) for a < b without cancellation (spec §2.4.1)."""
    right = a > 0  # use the upper tails: Phi(b) - Phi(a) = Q(a) - Q(b)
    la = np.where(right, log_ndtr(-a), log_ndtr(b))
    lb = np.where(right, log_ndtr(-b), log_ndtr(a))
    return la + np.log1p(-np.exp(np.minimum(lb - la, 0.0)))


def geometry(x, t):
    v = SIGMA * (T1 - t)
    c = GAMMA + SIGMA * (TF - T1)
    return v, c, x * c / (v + c), math.sqrt(v * c / (v + c))


def exact_control(x, t):
    """u(x, t) of spec §2.4.1: truncated-normal mean of the wall position, or the free part."""
    if t >= T1 - 1e-12:
        return -SIGMA * x / (GAMMA + SIGMA * (TF - t))
    v, c, m, tau = geometry(x, t)
    log_p, log_pa, log_pb = [], [], []
    for lo, hi in SLITS:
        a, b = (lo - m) / tau, (hi - m) / tau
        log_p.append(log_interval(a, b))
        log_pa.append(-0.5 * a**2)
        log_pb.append(-0.5 * b**2)
    log_s = np.logaddexp(log_p[0], log_p[1])
    shift = sum(np.exp(pa - log_s) - np.exp(pb - log_s) for pa, pb in zip(log_pa, log_pb))
    mean_wall = m + tau * shift / math.sqrt(2 * math.pi)
    return (mean_wall - x) / (T1 - t)


def slit_terms(x, m, v, c, lo, hi):
    e = np.clip(m, lo, hi)
    return e, (e - x) ** 2 / (2 * v) + e**2 / (2 * c)


def corrected_control(x, t, samples, rng):
    """W2 with the frozen wall: weighted mean of the wall samples of both slits (spec §2.4.5)."""
    v, c, m, tau = geometry(x, t)
    log_w, wall = [], []
    for lo, hi in SLITS:
        e, phi = slit_terms(x, m, v, c, lo, hi)
        nu = (e - m) / tau**2
        delta = tau * rng.standard_normal((x.size, samples))
        y = e[:, None] + delta
        lw = -phi[:, None] - nu[:, None] * delta
        log_w.append(np.where((y >= lo) & (y <= hi), lw, -np.inf))
        wall.append(y)
    log_w, wall = np.concatenate(log_w, 1), np.concatenate(wall, 1)
    top = log_w.max(1, keepdims=True)
    none = ~np.isfinite(top[:, 0])
    w = np.exp(log_w - np.where(np.isfinite(top), top, 0.0))
    u = ((w * wall).sum(1) / np.maximum(w.sum(1), 1e-300) - x) / (T1 - t)
    if none.any():  # no sample passed: the Laplace control towards the dominant slit
        u[none] = laplace_control(x, t)[none]
    return u


def dominant(x, t):
    v, c, m, _ = geometry(x, t)
    terms = [slit_terms(x, m, v, c, lo, hi) for lo, hi in SLITS]
    pick = terms[0][1] <= terms[1][1]
    return pick, v, c


def laplace_control(x, t):
    pick, v, c = dominant(x, t)
    m = x * c / (v + c)
    e = np.where(pick, np.clip(m, *SLITS[0]), np.clip(m, *SLITS[1]))
    return SIGMA * (e - x) / v


def paper_control(x, t, samples, rng):
    """P: exp(-phi) times the pass fraction of the dominant slit, differentiated by FD-CRN."""
    pick, _, _ = dominant(x, t)
    lo = np.where(pick, SLITS[0][0], SLITS[1][0])[:, None]
    hi = np.where(pick, SLITS[0][1], SLITS[1][1])[:, None]
    xi = rng.standard_normal((x.size, samples))

    def log_psi(xs):
        v, c, m, tau = geometry(xs, t)
        e = np.clip(m[:, None], lo, hi)
        phi = (e[:, 0] - xs) ** 2 / (2 * v) + e[:, 0] ** 2 / (2 * c)
        y = e + tau * xi
        passed = ((y >= lo) & (y <= hi)).sum(1)
        return -phi + np.log(np.maximum(passed, 1)), passed == 0

    plus, empty_p = log_psi(x + H)
    minus, empty_m = log_psi(x - H)
    u = SIGMA * (plus - minus) / (2 * H)
    empty = empty_p | empty_m
    if empty.any():
        u[empty] = laplace_control(x, t)[empty]
    return u


def run(estimator, samples, runs, rng):
    """Closed loop of spec §2.4.6 for all runs at once; returns per-run e_x, e_u, crashes."""
    noise = rng.standard_normal((runs, K))
    xs = {"ex": np.full(runs, X0), "is": np.full(runs, X0)}
    traj = {k: [v.copy()] for k, v in xs.items()}
    ctrl = {"ex": [], "is": []}
    control = paper_control if estimator == "paper" else corrected_control
    for k in range(K):
        t = k * DT
        u_ex = np.array([exact_control(x, t) for x in xs["ex"]])
        if k < K1:
            u_is = control(xs["is"], t, samples, rng)
        else:
            u_is = -SIGMA * xs["is"] / (GAMMA + SIGMA * (TF - t))
        for key, u in (("ex", u_ex), ("is", u_is)):
            ctrl[key].append(u)
            xs[key] = xs[key] + u * DT + math.sqrt(SIGMA * DT) * noise[:, k]
            traj[key].append(xs[key].copy())
    X = {k: np.array(v).T for k, v in traj.items()}
    U = {k: np.array(v).T for k, v in ctrl.items()}
    e_x = np.linalg.norm(X["is"] - X["ex"], axis=1) / np.linalg.norm(X["ex"], axis=1)
    e_u = np.linalg.norm(U["is"] - U["ex"], axis=1) / np.linalg.norm(U["ex"], axis=1)

    def crashed(x50):
        return ~(((x50 >= -6) & (x50 <= -4)) | ((x50 >= 6) & (x50 <= 8)))

    return 100 * e_x, 100 * e_u, crashed(X["is"][:, K1]), crashed(X["ex"][:, K1])


def mean_se(a):
    a = np.asarray(a, dtype=float)
    return a.mean(), a.std(ddof=1) / math.sqrt(a.size)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--runs", type=int, default=500)
    p.add_argument("--samples", default="10,50,100,500", help="comma-separated M values")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--compare", metavar="RESULTS_JSON")
    a = p.parse_args()
    if a.runs < 2:
        p.error("--runs must be at least 2")
    try:
        samples = [int(s) for s in a.samples.split(",")]
    except ValueError:
        p.error(f"--samples: not a comma-separated list of integers: {a.samples!r}")
    if min(samples) < 1:
        p.error("--samples: every M must be at least 1")
    ref = None
    if a.compare:
        try:
            with open(a.compare) as f:
                ref = json.load(f)["reference"]["table2"]
        except (OSError, ValueError, KeyError) as e:
            print(f"{a.compare}: cannot read reference.table2: {e}", file=sys.stderr)
            return 1
    rng = np.random.default_rng(a.seed)
    bad = 0
    print(f"{'estimator':<10} {'M':>4} {'quantity':<15} {'numpy':>18} {'reference':>18}  check")
    for est in ("paper", "corrected"):
        for m in samples:
            e_x, e_u, crash, crash_exact = run(est, m, a.runs, rng)
            rows = [("error_x_mean", e_x), ("error_u_mean", e_u), ("crash_fraction", crash)]
            for key, vals in rows:
                mean, se = mean_se(vals)
                ref_txt, verdict = "", ""
                if ref is not None:
                    r = ref[est]
                    if key == "crash_fraction":
                        rv = r[key]
                        rse = math.sqrt(rv * (1 - rv) / ref["runs"])
                    else:
                        i = ref["samples"].index(m) if m in ref["samples"] else None
                        rv = None if i is None else r[key][i]
                        rse = None if i is None else r[key.replace("mean", "std")][i] / math.sqrt(
                            ref["runs"])
                    if rv is not None:
                        ok = abs(mean - rv) <= 4.5 * math.hypot(se, rse)
                        bad += not ok
                        ref_txt = f"{rv:.4g} ± {rse:.3g}"
                        verdict = "ok" if ok else "DISAGREES"
                print(f"{est:<10} {m:>4} {key:<15} {mean:>9.4g} ± {se:<7.3g} {ref_txt:>18}  "
                      f"{verdict}")
            if est == "corrected" and m == samples[0]:
                mean, se = mean_se(crash_exact)
                print(f"{'exact':<10} {'':>4} {'crash_fraction':<15} {mean:>9.4g} ± {se:<7.3g}")
    print(f"{a.runs} runs per cell, seed {a.seed}")
    if bad:
        print(f"{bad} quantities disagree with the reference", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
