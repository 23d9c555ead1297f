#!/usr/bin/python3
"""Figure 10 (beyond the paper): laser localization on the ACES log, implicit against bootstrap MCL.

Usage: /usr/bin/python3 python/plots/figure10.py <dir>

Reads, as `implicit reproduce --only laser_mcl --out <dir>` writes them
(experiments/laser_reproduce.hpp):
  laser_mcl_map.csv                 x_m,y_m,resolution_m: centres of the map's occupied cells
  laser_mcl_reference.csv           update,time_s,x_m,y_m,heading_rad: the reference poses
  laser_mcl_track_implicit.csv      update,time_s,x_m,y_m,heading_rad,error_m,particles: the
  laser_mcl_track_bootstrap.csv     first run of each proposal from a known start

Left panel: the map around the paths (their bounding box with a margin) with the reference path and
both estimated paths. Right panel: the position error of both at each update against the time
since the first update, on a log axis (one y-range for both).
Writes <dir>/figure10.png and <dir>/figure10.svg.
"""
import numpy as np

from common import (COLORS, figure_main, label_error_axis, load_csv, map_image, save,
                    subplots)

PROPOSALS = (("implicit", "implicit MCL"), ("bootstrap", "bootstrap MCL"))
# An exact zero error would leave the log axis; errors below a millimetre are drawn at it.
ERROR_FLOOR = 1e-3
# The least margin around the paths in the map panel [m].
PATH_MARGIN_M = 3.0
# Height over width of the map panel's zoom window (about the panel's own shape).
PANEL_ASPECT = 0.85


def draw(d):
    cells = load_csv(d, "laser_mcl_map.csv", ["x_m", "y_m", "resolution_m"])
    ref = load_csv(d, "laser_mcl_reference.csv", ["update", "time_s", "x_m", "y_m"])
    tracks = {p: load_csv(d, f"laser_mcl_track_{p}.csv",
                          ["update", "time_s", "x_m", "y_m", "error_m", "particles"])
              for p, _ in PROPOSALS}
    image, extent = map_image(cells, f"{d}/laser_mcl_map.csv")

    fig, ax = subplots(1, 2, width=13, height=5.5)
    a = ax[0]
    a.imshow(image, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.2,
             interpolation="nearest")
    a.plot(ref["x_m"], ref["y_m"], color=COLORS["exact"], lw=2.5, alpha=0.6,
           label="reference (corrected poses)")
    for p, name in PROPOSALS:
        t = tracks[p]
        a.plot(t["x_m"], t["y_m"], color=COLORS["implicit" if p == "implicit" else "standard"],
               lw=0.8, label=f"{name}, M = {int(t['particles'][0])}")
    # The map is far larger than a short run's path, which drawn on all of it is a few pixels:
    # zoom to the paths with a margin that keeps the walls around them in view.
    xs = np.concatenate([ref["x_m"]] + [tracks[p]["x_m"] for p, _ in PROPOSALS])
    ys = np.concatenate([ref["y_m"]] + [tracks[p]["y_m"] for p, _ in PROPOSALS])
    cx, cy = (np.nanmax(xs) + np.nanmin(xs)) / 2, (np.nanmax(ys) + np.nanmin(ys)) / 2
    hx, hy = (np.nanmax(xs) - np.nanmin(xs)) / 2, (np.nanmax(ys) - np.nanmin(ys)) / 2
    margin = max(PATH_MARGIN_M, 0.15 * max(hx, hy))
    hx, hy = hx + margin, hy + margin
    # A window of about the panel's shape: a path along one corridor would leave a thin strip.
    hx, hy = max(hx, hy / PANEL_ASPECT), max(hy, hx * PANEL_ASPECT)
    a.set_xlim(cx - hx, cx + hx)
    a.set_ylim(cy - hy, cy + hy)
    a.set_aspect("equal")
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_title("ACES map near the path: reference and estimates (first run)")
    a.legend(fontsize=7, loc="best")

    a = ax[1]
    top = 0.0
    for p, name in PROPOSALS:
        t = tracks[p]
        e = np.maximum(t["error_m"], ERROR_FLOOR)
        top = max(top, float(np.nanmax(e)))
        # Markers at the updates: the filter updates only after the robot moved, so long
        # straight pieces are stretches without an update, not a constant error.
        a.plot(t["time_s"], e, color=COLORS["implicit" if p == "implicit" else "standard"],
               lw=0.7, marker="o", ms=2.5, alpha=0.85,
               label=f"{name}, M = {int(t['particles'][0])}")
    # At least two decades with labels at 1, 2 and 5 of each, so the axis reads without counting
    # minor ticks.
    low = min(float(np.nanmin(np.maximum(tracks[p]["error_m"], ERROR_FLOOR))) for p, _ in PROPOSALS)
    label_error_axis(a, min(0.01, 0.8 * low), max(1.0, 1.5 * top))
    a.set_xlabel("time since the first update [s]")
    a.set_ylabel("position error [m]")
    a.set_title("position error against time (first run)")
    a.grid(True, which="major", alpha=0.3)
    a.legend(fontsize=7)
    save(fig, d, 10)


if __name__ == "__main__":
    figure_main(draw)
