#!/usr/bin/python3
"""Figure 6 of the paper (MCL on the Car Park data): path and reconstruction; CPU time vs error.

Usage: /usr/bin/python3 python/plots/figure6.py <dir>

Reads from <dir> the CSV files written by `implicit mcl --out <dir>` (run_mcl):
  mcl_summary.csv   one row per run_mcl call (appended):
                    method,particles,runs,config,p,error_percent_mean,error_percent_std,
                    error_percent_median,rmse_m,heading_rmse_rad,lost_runs,ess_mean,
                    cpu_ms_per_step,seed
                    (for a repeated (method, particles, config) the last row wins)
  mcl_<method>_M<particles>_trajectory.csv   the median-err% run of a config-A call; columns
                    step,time_s,truth_x,truth_y,truth_heading,est_x,est_y,est_heading,std_x,std_y,
                    ess,resampled,updated,log_likelihood_increment
                    (other configurations add _config<X> before _trajectory)
  mcl_beacons.csv   id,x,y (the surveyed beacons)
Left panel: GPS path, the implicit MCL reconstruction (M = 100 if present, else the largest M
with a trajectory) and the beacons. Right panel: CPU time per filter step against err% (median
over runs, open markers; mean with its standard error std/sqrt(runs), filled markers with bars)
for standard and implicit MCL in config A; no lines join the noisy means.
Writes <dir>/figure6.png and <dir>/figure6.svg. Exits non-zero with a message naming the file
when an input is missing or malformed.
"""
import csv
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SUMMARY_COLUMNS = ["method", "particles", "runs", "config", "error_percent_mean",
                   "error_percent_std", "error_percent_median", "cpu_ms_per_step"]
TRAJECTORY_COLUMNS = ["truth_x", "truth_y", "est_x", "est_y"]


def fail(msg):
    sys.exit(f"figure6.py: {msg}")


def read_csv(path, required):
    if not os.path.isfile(path):
        fail(f"{path}: file not found (run `implicit mcl --out {os.path.dirname(path)}` first)")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        fail(f"{path}: expected a header and data rows, got none")
    missing = [c for c in required if c not in rows[0]]
    if missing:
        fail(f"{path}: missing column(s) {', '.join(missing)}")
    return rows


def number(path, line, row, key):
    try:
        return float(row[key])
    except (TypeError, ValueError):
        fail(f"{path}:{line}: field '{key}': expected a number, got {row[key]!r}")


def main():
    if len(sys.argv) != 2:
        fail("usage: figure6.py <dir>")
    d = sys.argv[1]
    spath = os.path.join(d, "mcl_summary.csv")
    summary = {}
    for i, r in enumerate(read_csv(spath, SUMMARY_COLUMNS)):
        key = (r["method"], int(number(spath, i + 2, r, "particles")), r["config"])
        summary[key] = {k: number(spath, i + 2, r, k)
                        for k in ("error_percent_mean", "error_percent_std", "runs",
                                  "error_percent_median", "cpu_ms_per_step")}

    # Left panel: the trajectory of implicit MCL (config A), M = 100 preferred.
    pattern = re.compile(r"^mcl_implicit_M(\d+)_trajectory\.csv$")
    ms = sorted(int(m.group(1)) for f in os.listdir(d) if (m := pattern.match(f)))
    if not ms:
        fail(f"{d}: no mcl_implicit_M<particles>_trajectory.csv (run implicit mcl with --out)")
    m_traj = 100 if 100 in ms else ms[-1]
    tpath = os.path.join(d, f"mcl_implicit_M{m_traj}_trajectory.csv")
    traj = read_csv(tpath, TRAJECTORY_COLUMNS)
    cols = {k: [number(tpath, i + 2, r, k) for i, r in enumerate(traj)] for k in TRAJECTORY_COLUMNS}
    bpath = os.path.join(d, "mcl_beacons.csv")
    beacons = read_csv(bpath, ["x", "y"])
    bx = [number(bpath, i + 2, r, "x") for i, r in enumerate(beacons)]
    by = [number(bpath, i + 2, r, "y") for i, r in enumerate(beacons)]

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5.2))
    ax1.plot(cols["truth_x"], cols["truth_y"], "k-", lw=1.5, label="ground truth (GPS)")
    ax1.plot(cols["est_x"], cols["est_y"], "--", color="c", lw=1.2,
             label=f"implicit MCL, M = {m_traj} (median run)")
    ax1.plot(bx, by, "o", color="tab:blue", ms=8, label="beacons")
    ax1.set_xlabel("east [m]")
    ax1.set_ylabel("north [m]")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.legend(loc="best", fontsize=8)
    ax1.set_title("Car Park: path and reconstruction")

    plotted = False
    for method, color in (("standard", "tab:red"), ("implicit", "tab:green")):
        rows = sorted((m, v) for (meth, m, cfg), v in summary.items()
                      if meth == method and cfg == "A")
        if not rows:
            continue
        plotted = True
        med = [v["error_percent_median"] for _, v in rows]
        mean = [v["error_percent_mean"] for _, v in rows]
        cpu = [v["cpu_ms_per_step"] for _, v in rows]
        se = [v["error_percent_std"] / max(v["runs"], 1) ** 0.5 for _, v in rows]
        ax2.errorbar(mean, cpu, xerr=se, fmt="s", color=color, capsize=3,
                     label=f"{method} (mean err% ± SE)")
        ax2.plot(med, cpu, "o", color=color, mfc="none", label=f"{method} (median err%)")
        for (m, _), x, y in zip(rows, mean, cpu):
            ax2.annotate(str(m), (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
    if not plotted:
        fail(f"{spath}: expected config A rows for 'standard' or 'implicit', got none")
    ax2.set_xscale("log")
    ax2.set_yscale("log")
    ax2.set_xlabel("error [%] (paper metric)")
    ax2.set_ylabel("CPU time per filter step [ms]")
    ax2.set_title("CPU time vs error (config A; labels = M)")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(d, f"figure6.{ext}"), dpi=130)


if __name__ == "__main__":
    main()
