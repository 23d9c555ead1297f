#!/usr/bin/python3
"""Figure 11 (beyond the paper): grid SLAM on a laser log, the three proposals on one filter.

Usage: /usr/bin/python3 python/plots/figure11.py <dir>

Reads, as `implicit reproduce --only grid_slam --out <dir>` writes them
(experiments/grid_slam_reproduce.hpp):
  grid_slam_map.csv                x_m,y_m,resolution_m: centres of the occupied cells of the
                                   first implicit run's map
  grid_slam_reference.csv          scan,time_s,x_m,y_m,heading_rad: the reference poses
  grid_slam_track_<proposal>.csv   scan,time_s,x_m,y_m,heading_rad,relation_error_m: the first
                                   run of each proposal (implicit, gmapping, bootstrap); the
                                   error is empty at the first scan

Left panel: the map with the reference path and the three estimated paths (the filter's own
frame, which starts at the first reference pose: no alignment). Right panel: the translational
error of each relation against the time since the first scan, on a log axis.
Writes <dir>/figure11.png and <dir>/figure11.svg.
"""
import numpy as np

from common import (COLORS, DataError, figure_main, label_error_axis, load_csv, map_image,
                    save, subplots)

PROPOSALS = (("implicit", "implicit", COLORS["implicit"]),
             ("gmapping", "GMapping-style", COLORS["fastslam2"]),
             ("bootstrap", "bootstrap", COLORS["standard"]))
# An exact zero error would leave the log axis; errors below a tenth of a millimetre are drawn
# at it.
ERROR_FLOOR = 1e-4
# The margin around the map and paths in the map panel [m].
MARGIN_M = 1.0


def draw(d):
    cells = load_csv(d, "grid_slam_map.csv", ["x_m", "y_m", "resolution_m"])
    ref = load_csv(d, "grid_slam_reference.csv", ["scan", "time_s", "x_m", "y_m"])
    tracks = {p: load_csv(d, f"grid_slam_track_{p}.csv",
                          ["scan", "time_s", "x_m", "y_m", "relation_error_m"])
              for p, _, _ in PROPOSALS}
    for p, _, _ in PROPOSALS:
        if len(tracks[p]["scan"]) != len(ref["scan"]):
            raise DataError(f"{d}/grid_slam_track_{p}.csv: expected one row per reference pose "
                            f"({len(ref['scan'])}), got {len(tracks[p]['scan'])}")
    image, extent = map_image(cells, f"{d}/grid_slam_map.csv")

    fig, ax = subplots(1, 2, width=13, height=5.5)
    a = ax[0]
    a.imshow(image, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.2,
             interpolation="nearest")
    a.plot(ref["x_m"], ref["y_m"], color=COLORS["exact"], lw=2.5, alpha=0.6,
           label="reference (corrected poses)")
    for p, name, color in PROPOSALS:
        t = tracks[p]
        a.plot(t["x_m"], t["y_m"], color=color, lw=0.8, label=f"{name} (first run)")
    paths = [ref] + [tracks[p] for p, _, _ in PROPOSALS]
    xs = np.concatenate([extent[:2]] + [t["x_m"] for t in paths])
    ys = np.concatenate([extent[2:]] + [t["y_m"] for t in paths])
    a.set_xlim(np.nanmin(xs) - MARGIN_M, np.nanmax(xs) + MARGIN_M)
    a.set_ylim(np.nanmin(ys) - MARGIN_M, np.nanmax(ys) + MARGIN_M)
    a.set_aspect("equal")
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_title("map of the first implicit run, reference and estimated paths")
    a.legend(fontsize=7, loc="best")

    a = ax[1]
    top, low = 0.0, np.inf
    for p, name, color in PROPOSALS:
        t = tracks[p]
        e = t["relation_error_m"]
        keep = np.isfinite(e)
        e = np.maximum(e[keep], ERROR_FLOOR)
        if e.size == 0:
            raise DataError(f"{d}/grid_slam_track_{p}.csv: expected relation errors after the "
                            f"first scan, got none")
        top, low = max(top, float(e.max())), min(low, float(e.min()))
        a.plot(t["time_s"][keep], e, color=color, lw=0.6, marker="o", ms=2, alpha=0.8,
               label=f"{name}: mean {np.mean(t['relation_error_m'][keep]):.3f} m")
    # At least two decades.
    label_error_axis(a, min(0.8 * low, 0.015 * top), 1.5 * top)
    a.set_xlabel("time since the first scan [s]")
    a.set_ylabel("relation error, translation [m]")
    a.set_title("error of each relation (consecutive processed scans), first run")
    a.grid(True, which="major", alpha=0.3)
    a.legend(fontsize=7)
    save(fig, d, 11)


if __name__ == "__main__":
    figure_main(draw)
