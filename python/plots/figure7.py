#!/usr/bin/python3
"""Figure 7 of the paper (SLAM on synthetic Car Park data): truth vs reconstruction; CPU vs error.

Usage: /usr/bin/python3 python/plots/figure7.py <dir>

Reads from <dir> the CSV files written by `implicit slam --out <dir>` (run_slam):
  slam_summary.csv   one row per run_slam call (appended): method,particles,datasets,association,
                     truth,error_percent_mean,error_percent_std,error_aligned_percent_mean,
                     map_shape_m,rmse_pose_m,rmse_map_m,ess_mean,resamplings,cpu_ms_per_step,
                     peak_memory_mb (for a repeated (method, particles) the last row wins)
  slam_<method>_M<particles>_path.csv  first data set: n,x_true,y_true,beta_true,x_hat,y_hat,beta_hat
  slam_<method>_M<particles>_map.csv   first data set: kind (true|estimate),id,x,y
Left panel: true path and landmarks, and the reconstruction of implicit SLAM at M = 100 (the
paper's variant "implicit" if present, else "implicit-rb"). Right panel: CPU time per filter step
against err% (mean over data sets, with its standard error std/sqrt(datasets) as a bar; markers
only, no lines through the noisy means) for every method and particle number.
Writes <dir>/figure7.png and <dir>/figure7.svg; exits non-zero naming the file and column when an
input is missing or malformed.
"""
import sys

import numpy as np

from common import COLORS, DataError, figure_main, load_csv, save, subplots

# The methods as the report names them (slam_summary.csv's method column holds the CLI's names).
METHOD_NAMES = {"ekf": "EKF-SLAM", "fastslam1": "FastSLAM 1.0", "fastslam2": "FastSLAM 2.0",
                "implicit": "implicit SLAM (A)", "implicit-rb": "implicit SLAM (B)"}
SUMMARY = ["particles", "datasets", "error_percent_mean", "error_percent_std", "cpu_ms_per_step",
           "map_shape_m"]


def draw(d):
    s = load_csv(d, "slam_summary.csv", SUMMARY, text_columns=["method"])
    runs = {}
    for i, m in enumerate(s["method"]):
        runs[(m, int(s["particles"][i]))] = i  # the last row wins
    if not runs:
        raise DataError(f"{d}/slam_summary.csv: expected at least one data row")
    choice = None
    for m in ("implicit", "implicit-rb"):
        if (m, 100) in runs:
            choice = (m, 100)
            break
    if choice is None:
        cands = [k for k in runs if k[0] in ("implicit", "implicit-rb")]
        if not cands:
            raise DataError(f"{d}/slam_summary.csv: expected a row with method implicit or "
                            "implicit-rb (Figure 7 shows implicit SLAM)")
        choice = max(cands, key=lambda k: k[1])
    stem = f"slam_{choice[0]}_M{choice[1]}"
    path = load_csv(d, f"{stem}_path.csv", ["x_true", "y_true", "x_hat", "y_hat"])
    mp = load_csv(d, f"{stem}_map.csv", ["x", "y"], text_columns=["kind"])
    kind = np.array(mp["kind"])
    for k in kind:
        if k not in ("true", "estimate"):
            raise DataError(f"{d}/{stem}_map.csv: column 'kind': expected true|estimate, got '{k}'")

    fig, ax = subplots(1, 2, width=12, height=5)
    a = ax[0]
    a.plot(path["x_true"], path["y_true"], color=COLORS["exact"], lw=1.5, label="true path")
    a.plot(path["x_hat"], path["y_hat"], color=COLORS["implicit"], lw=1.0,
           label=f"{METHOD_NAMES[choice[0]]}, M = {choice[1]}")
    t = kind == "true"
    a.plot(mp["x"][t], mp["y"][t], "^", color=COLORS["landmark"], ms=7, mfc="none",
           label="true landmarks")
    a.plot(mp["x"][~t], mp["y"][~t], "x", color=COLORS["implicit"], ms=6,
           label="estimated landmarks")
    a.set_xlabel("east [m]")
    a.set_ylabel("north [m]")
    a.set_aspect("equal", adjustable="datalim")
    a.legend(fontsize=8, loc="best")
    a.set_title("path and map (first data set)")

    b = ax[1]
    methods = sorted({m for m, _ in runs})
    for m in methods:
        pts = sorted((p, runs[(m, p)]) for mm, p in runs if mm == m)
        x = [s["cpu_ms_per_step"][i] for _, i in pts]
        y = [s["error_percent_mean"][i] for _, i in pts]
        color = COLORS.get(m, COLORS["implicit"] if m == "implicit" else "#2ca02c")
        se = [s["error_percent_std"][i] / max(s["datasets"][i], 1) ** 0.5 for _, i in pts]
        b.errorbar(x, y, yerr=se, fmt="o", color=color, capsize=3,
                   label=METHOD_NAMES.get(m, m))
        for (p, i), xx, yy in zip(pts, x, y):
            if m != "ekf":
                b.annotate(f"{p}", (xx, yy), fontsize=7, xytext=(3, 3), textcoords="offset points")
    b.set_xscale("log")
    b.set_xlabel("CPU time per filter step [ms]")
    b.set_ylabel("err% of the path (mean ± SE over data sets)")
    b.set_title("cost vs error (labels: particles M)")
    b.legend(fontsize=8)
    save(fig, d, 7)


if __name__ == "__main__":
    figure_main(draw)
