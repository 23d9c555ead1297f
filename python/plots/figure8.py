#!/usr/bin/python3
"""Figure 8 (beyond the paper): when the implicit proposal pays in MCL.

Usage: /usr/bin/python3 python/plots/figure8.py <dir>

Reads <dir>/proposal_gain.csv, written by `implicit proposal-gain --out <dir>` (one row per point
and method: sweep,dt,range_sd,ratio,method,ess,ess_se,rmse_m,rmse_m_se,cpu_ms_per_step,
cpu_ms_per_step_se), and, when present, <dir>/results.json of `implicit reproduce` for the two
Car Park points: their noise ratio from the proposal_gain result, their ESS/M, RMSE and CPU time
from the mcl runs with M = 100 in configs A and B (reused, not rerun).

Top row: ESS/M, position RMSE and CPU time per step against the ratio of the per-step process
noise to the sensor noise (log axis). Bottom row: the same against the step length. Error bars
are one standard error over the simulated logs (over the runs for the Car Park points); the
Car Park points are open squares (config A) and triangles (config B), coloured by method.
Writes <dir>/figure8.png and <dir>/figure8.svg.
"""
import math

import numpy as np

from common import COLORS, DataError, figure_main, load_csv, load_results, save, subplots

# One marker per Car Park configuration (open markers, coloured by method).
CARPARK_MARKERS = {"A": "s", "B": "^"}
METRICS = [("ess", "ESS / M"), ("rmse_m", "position RMSE [m]"),
           ("cpu_ms_per_step", "CPU time per step [ms]")]


def carpark_points(d):
    """[(config, ratio, {method: (ess, ess_se, rmse, rmse_se, cpu, cpu_se)})] from results.json.

    Empty when there is no results.json (the figure of a lone `implicit proposal-gain` run).
    """
    try:
        results = load_results(d)
    except DataError:
        return []
    exps = results.get("experiments", {})
    ratio = None
    for run in exps.get("proposal_gain", {}).get("runs", []):
        if run.get("status") == "ok":
            ratio = run["result"].get("carpark_ratio")
    if not ratio:
        return []
    points = []
    for config in ("A", "B"):
        found = {}
        for run in exps.get("mcl", {}).get("runs", []):
            s, r = run.get("settings", {}), run.get("result", {})
            if (run.get("status") != "ok" or s.get("config") != config
                    or s.get("particles") != 100 or s.get("p", -1) >= 0):
                continue
            n = math.sqrt(r["runs"])
            found[s["method"]] = (r["ess_mean"], r["ess_std"] / n, r["rmse_m"],
                                  r["rmse_m_std"] / n, r["cpu_ms_per_step"],
                                  r["cpu_ms_per_step_std"] / n)
        if len(found) == 2:
            points.append((config, ratio[config], found))
    return points


def draw(d):
    data = load_csv(d, "proposal_gain.csv",
                    ["dt", "ratio"] + [k for m, _ in METRICS for k in (m, m + "_se")],
                    ["sweep", "method"])
    fig, ax = subplots(2, 3, width=14, height=8)
    for row, (sweep, xkey, xlabel) in enumerate(
            [("ratio", "ratio", "per-step process sd / sensor range sd"),
             ("dt", "dt", "step length dt [s]")]):
        for col, (key, ylabel) in enumerate(METRICS):
            a = ax[row, col]
            for method, name in (("implicit", "implicit"), ("standard", "bootstrap")):
                sel = (data["sweep"] == sweep) & (data["method"] == method)
                if not np.any(sel):
                    raise DataError(f"{d}/proposal_gain.csv: no rows for sweep {sweep}, "
                                    f"method {method}")
                a.errorbar(data[xkey][sel], data[key][sel], yerr=data[key + "_se"][sel],
                           fmt="o-", color=COLORS[method], capsize=3, label=name)
            if sweep == "ratio":
                for config, ratio, m in carpark_points(d):
                    for method, name in (("implicit", "implicit"), ("standard", "bootstrap")):
                        v = m[method]
                        # The marker tells the configuration, the colour the method, as in the
                        # legend: no text next to the points, which overlapped where A and B
                        # (or the two methods) lie close.
                        a.errorbar([ratio], [v[2 * col]], yerr=[v[2 * col + 1]],
                                   fmt=CARPARK_MARKERS[config], mfc="none", ms=7,
                                   color=COLORS[method], capsize=3,
                                   label=f"Car Park {config}, {name}")
            a.set_xscale("log")
            a.set_xlabel(xlabel)
            a.set_ylabel(ylabel)
            if key == "rmse_m":
                a.set_yscale("log")
            if col == 0:
                a.legend(fontsize=7, loc="best")
    save(fig, d, 8)


if __name__ == "__main__":
    figure_main(draw)
