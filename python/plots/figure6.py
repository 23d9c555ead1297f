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
Writes <dir>/figure6.png and <dir>/figure6.svg. Exits 1 with a message naming the file (and line
and column) when an input is missing or malformed.
"""
import re
from pathlib import Path

import numpy as np

from common import DataError, figure_main, load_csv, save, subplots

SUMMARY_COLUMNS = ["particles", "runs", "error_percent_mean", "error_percent_std",
                   "error_percent_median", "cpu_ms_per_step"]
TRAJECTORY_COLUMNS = ["truth_x", "truth_y", "est_x", "est_y"]
# Colours and markers of the right panel's two methods (the paper's figure uses red and green).
METHOD_STYLE = (("standard", "tab:red"), ("implicit", "tab:green"))


def summary_rows(d):
    """{(method, particles, config): row index} of mcl_summary.csv; a repeated key's last row."""
    s = load_csv(d, "mcl_summary.csv", SUMMARY_COLUMNS, ["method", "config"])
    rows = {}
    for i, (method, config) in enumerate(zip(s["method"], s["config"])):
        rows[(method, int(s["particles"][i]), config)] = i
    return s, rows


def draw(d):
    s, rows = summary_rows(d)
    # Left panel: the trajectory of implicit MCL (config A), M = 100 preferred.
    pattern = re.compile(r"^mcl_implicit_M(\d+)_trajectory\.csv$")
    ms = sorted(int(m.group(1)) for f in Path(d).iterdir() if (m := pattern.match(f.name)))
    if not ms:
        raise DataError(f"{d}: no mcl_implicit_M<particles>_trajectory.csv (run implicit mcl "
                        "with --out)")
    m_traj = 100 if 100 in ms else ms[-1]
    traj = load_csv(d, f"mcl_implicit_M{m_traj}_trajectory.csv", TRAJECTORY_COLUMNS)
    beacons = load_csv(d, "mcl_beacons.csv", ["x", "y"])

    fig, (ax1, ax2) = subplots(1, 2, width=12, height=5.2)
    ax1.plot(traj["truth_x"], traj["truth_y"], "k-", lw=1.5, label="ground truth (GPS)")
    ax1.plot(traj["est_x"], traj["est_y"], "--", color="c", lw=1.2,
             label=f"implicit MCL, M = {m_traj} (median run)")
    ax1.plot(beacons["x"], beacons["y"], "o", color="tab:blue", ms=8, label="beacons")
    ax1.set_xlabel("east [m]")
    ax1.set_ylabel("north [m]")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.legend(loc="best", fontsize=8)
    ax1.set_title("Car Park: path and reconstruction")

    plotted = False
    for method, color in METHOD_STYLE:
        sel = sorted((m, i) for (meth, m, cfg), i in rows.items() if meth == method and cfg == "A")
        if not sel:
            continue
        plotted = True
        idx = np.array([i for _, i in sel])
        cpu = s["cpu_ms_per_step"][idx]
        mean = s["error_percent_mean"][idx]
        se = s["error_percent_std"][idx] / np.sqrt(np.maximum(s["runs"][idx], 1))
        ax2.errorbar(mean, cpu, xerr=se, fmt="s", color=color, capsize=3,
                     label=f"{method} (mean err% ± SE)")
        ax2.plot(s["error_percent_median"][idx], cpu, "o", color=color, mfc="none",
                 label=f"{method} (median err%)")
        for (m, _), x, y in zip(sel, mean, cpu):
            ax2.annotate(str(m), (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
    if not plotted:
        raise DataError(f"{d}/mcl_summary.csv: expected config A rows for 'standard' or "
                        "'implicit', got none")
    ax2.set_xscale("log")
    ax2.set_yscale("log")
    ax2.set_xlabel("error [%] (paper metric)")
    ax2.set_ylabel("CPU time per filter step [ms]")
    ax2.set_title("CPU time vs error (config A; labels = M)")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=8)
    save(fig, d, 6)


if __name__ == "__main__":
    figure_main(draw)
