#!/usr/bin/python3
"""EKF-SLAM, FastSLAM 2.0 and implicit SLAM (A) and (B) written again from spec §3.5 in numpy.

Usage: /usr/bin/python3 python/crosscheck/slam_numpy.py --method METHOD [--runs R]
           [--particles M] [--seed S] [--compare RESULTS.json] [DATA.csv.gz ...]

METHOD is ekf, fastslam2, implicit (variant A, the paper's: point landmarks fixed at creation)
or implicit-rb (variant B, Rao-Blackwellised with EKF landmarks). DATA are synthetic data sets in
the reference format of data/slam-synthetic (default: the ten paper_le1_seed*.csv.gz there).
Known association; systematic resampling when ESS < M/2; the pose estimate is the weighted mean
before resampling and the map estimate the weighted mean of the particles' landmarks with the
weights before the last resampling. Run r on data set i uses seed + 1000 i + r (EKF-SLAM is
deterministic and runs once per data set). The code shares nothing with the C++ library (its own
model, Jacobians, minimiser, alignment and random numbers); the model and metrics are in
slam_common.py, the filters in slam_filters.py.

Prints one line per run (data set, seed, err%, pose RMSE, landmark RMSE, map shape, ESS/M,
resamplings, steps at which every particle failed and the weights restarted equal), then the
mean ± SE of each quantity over data sets. With --compare, reads the
method's row of ["reference"]["table6"] from a results.json written by `implicit reproduce` and
prints numpy against reference with |diff| in combined standard errors; exits 1 when a quantity
differs by more than 4.5 SE. The numpy SE is that of the mean over data sets; the reference's is
its sd/sqrt(50) for err% and, for the quantities it gives without an sd, this run's single-run
sd/sqrt(50) (both average one run per data set of the same generator), with the sd of the
rounding of the reference's printed digits added in quadrature. The reference is at
M = 100 over 50 data sets, so --compare requires --particles to equal it and at least ten data
sets (the SE comes from their spread; with t(9) a correct implementation still exceeds 4.5 SE
with probability about 0.0015 per quantity).
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

from slam_common import DATA_DIR, QUANTITIES, compare, load, read_reference, summarise
from slam_filters import run_ekf, run_particle_filter

METHODS = ("ekf", "fastslam2", "implicit", "implicit-rb")
# The SE is estimated from the spread over data sets. With few of them the estimate is itself so
# noisy that 4.5 "SE" means little (two sets: a t with 1 degree of freedom exceeds 4.5 with
# probability 0.14; ten sets: 0.0015 per quantity).
MIN_COMPARE_SETS = 10


def default_data():
    return sorted(DATA_DIR.glob("paper_le1_seed*.csv.gz"),
                  key=lambda p: int(p.name.split("seed")[1].split(".")[0]))


def check_ekf_trace(path, trace):
    """EKF-SLAM is deterministic: where a reference trace ekf_<data set> (n, x_hat, y_hat,
    beta_hat) lies beside the data set, the numpy poses must equal it to round-off. Returns 1 on
    a mismatch."""
    ref_path = path.parent / ("ekf_" + path.name)
    if not ref_path.exists():
        return 0
    ref = load(ref_path)
    n = ref["n"].astype(int)
    rows = n >= 1
    got = trace[n[rows] - 1]
    want = np.stack([ref["x_hat"], ref["y_hat"], ref["beta_hat"]], 1)[rows]
    diff = float(np.abs(got - want).max())
    ok = diff <= 1e-6
    print(f"EKF trace against {ref_path.name}: max |diff| {diff:.1e} over {rows.sum()} steps "
          f"({'ok' if ok else 'DISAGREES'}, tolerance 1e-6)")
    return 0 if ok else 1


def fmt(v, digits):
    return "-" if v is None else f"{v:.{digits}f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data", nargs="*", type=Path, help="data sets (default: paper_le1_seed1..10)")
    ap.add_argument("--method", required=True, choices=METHODS)
    ap.add_argument("--runs", type=int, default=1, help="filter runs per data set")
    ap.add_argument("--particles", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1, help="run r of data set i uses seed + 1000 i + r")
    ap.add_argument("--compare", metavar="RESULTS_JSON", help="results.json of implicit reproduce")
    a = ap.parse_args()
    if a.runs < 1 or a.particles < 1:
        ap.error("--runs and --particles must be at least 1")
    paths = a.data or default_data()
    row = None
    if a.compare:
        try:
            row, ref_m, ref_sets = read_reference(a.compare, a.method)
        except (OSError, ValueError, KeyError, StopIteration) as err:
            print(f"{a.compare}: cannot read the table6 reference of {a.method}: {err}",
                  file=sys.stderr)
            return 1
        if (a.method != "ekf" and a.particles != ref_m) or len(paths) < MIN_COMPARE_SETS:
            ap.error(f"--compare needs --particles {ref_m} (the reference's M; another M "
                     f"estimates other quantities) and at least {MIN_COMPARE_SETS} data sets "
                     "(the SE is estimated from them)")
    runs, bad_trace = [], 0
    t0 = time.monotonic()
    print("data seed err% pose_rmse_m map_rmse_m map_shape_m ess/M resamplings "
          "degenerate_steps")
    for i, path in enumerate(paths):
        try:
            d = load(path)
        except (OSError, ValueError) as err:
            print(f"{path}: cannot read a reference data set: {err}", file=sys.stderr)
            return 1
        for r in range(1 if a.method == "ekf" else a.runs):
            seed = a.seed + 1000 * i + r
            if a.method == "ekf":
                out, trace = run_ekf(d)
                bad_trace += check_ekf_trace(path, trace)
            else:
                out = run_particle_filter(a.method, d, a.particles, seed)
            out["data"] = path.name
            runs.append(out)
            print(f"{path.name} {seed} {out['error_percent']:.4f} {out['rmse_pose_m']:.4f} "
                  f"{out['rmse_map_m']:.4f} {out['map_shape_m']:.5f} {fmt(out['ess_mean'], 4)} "
                  f"{fmt(out['resamplings'], 0)} {fmt(out.get('degenerate_steps'), 0)}",
                  flush=True)
    summary = summarise(runs)
    for key, label, _, _ in QUANTITIES:
        if key in summary:
            mean, se, sd = summary[key]
            print(f"mean {label}: {mean:.4f} ± {se:.4f} (SE over data sets), single-run sd "
                  f"{sd:.4f}")
    m_text = "" if a.method == "ekf" else f", M = {a.particles}"
    print(f"{a.method}: {len(runs)} runs on {len(paths)} data sets{m_text}, seed {a.seed}, "
          f"{time.monotonic() - t0:.0f} s")
    if bad_trace:
        return 1
    if row is None:
        return 0
    print(f"against the reference (M = {ref_m}, {ref_sets} data sets):")
    bad = compare(summary, row, ref_sets)
    if bad:
        print(f"{a.method}: {bad} quantities disagree with the reference", file=sys.stderr)
        return 1
    print(f"{a.method}: every quantity agrees with the reference within 4.5 SE")
    return 0


if __name__ == "__main__":
    sys.exit(main())
