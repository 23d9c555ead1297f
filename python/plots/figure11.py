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
  grid_slam_<log>_map.csv, grid_slam_<log>_reference.csv, grid_slam_<log>_track_implicit.csv
                                   the same of the first implicit run on the other logs (<log>
                                   aces, freiburg-079), when the run wrote them (not --quick)

Top left: the map with the reference path and the three estimated paths (the filter's own
frame, which starts at the first reference pose: no alignment). Top right: the translational
error of each relation against the time since the first scan, on a log axis. Below, when their
files are there: the map of the first implicit run on each other log with its reference and
estimated paths.
Writes <dir>/figure11.png and <dir>/figure11.svg.
"""
from pathlib import Path

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
# The other logs' map panels: file tag and title.
OTHER_LOGS = (("aces", "ACES"), ("freiburg-079", "Freiburg 079"))


def map_panel(a, d, cells_file, ref, tracks):
    """The occupied cells of `cells_file` with the reference path and `tracks` [(name, color,
    columns)], zoomed to the map and the paths."""
    cells = load_csv(d, cells_file, ["x_m", "y_m", "resolution_m"])
    image, extent = map_image(cells, f"{d}/{cells_file}")
    a.imshow(image, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.2,
             interpolation="nearest")
    a.plot(ref["x_m"], ref["y_m"], color=COLORS["exact"], lw=2.5, alpha=0.6,
           label="reference (corrected poses)")
    for name, color, t in tracks:
        a.plot(t["x_m"], t["y_m"], color=color, lw=0.8, label=name)
    paths = [ref] + [t for _, _, t in tracks]
    xs = np.concatenate([extent[:2]] + [t["x_m"] for t in paths])
    ys = np.concatenate([extent[2:]] + [t["y_m"] for t in paths])
    a.set_xlim(np.nanmin(xs) - MARGIN_M, np.nanmax(xs) + MARGIN_M)
    a.set_ylim(np.nanmin(ys) - MARGIN_M, np.nanmax(ys) + MARGIN_M)
    a.set_aspect("equal")
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.legend(fontsize=7, loc="best")


def other_log(d, tag):
    """The reference and implicit track of another log's first implicit run, or None when the
    run did not write them."""
    names = [f"grid_slam_{tag}_{f}.csv" for f in ("map", "reference", "track_implicit")]
    there = [(Path(d) / n).is_file() for n in names]
    if not any(there):
        return None
    if not all(there):
        missing = [n for n, ok in zip(names, there) if not ok]
        raise DataError(f"{d}: expected {', '.join(names)} together, missing {', '.join(missing)}")
    ref = load_csv(d, names[1], ["scan", "time_s", "x_m", "y_m"])
    track = load_csv(d, names[2], ["scan", "time_s", "x_m", "y_m"])
    if len(track["scan"]) != len(ref["scan"]):
        raise DataError(f"{d}/{names[2]}: expected one row per reference pose "
                        f"({len(ref['scan'])}), got {len(track['scan'])}")
    return ref, track


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
    others = [(title, tag, other_log(d, tag)) for tag, title in OTHER_LOGS]
    others = [(title, tag, o) for title, tag, o in others if o is not None]

    if others:
        fig, grid = subplots(2, 2, width=13, height=11)
        ax = grid[0]
    else:
        fig, ax = subplots(1, 2, width=13, height=5.5)
    a = ax[0]
    map_panel(a, d, "grid_slam_map.csv", ref,
              [(f"{name} (first run)", color, tracks[p]) for p, name, color in PROPOSALS])
    a.set_title("map of the first implicit run, reference and estimated paths")
    for k, (title, tag, (other_ref, track)) in enumerate(others):
        a = grid[1][k]
        map_panel(a, d, f"grid_slam_{tag}_map.csv", other_ref,
                  [("implicit (first run)", COLORS["implicit"], track)])
        a.set_title(f"{title}: map of the first implicit run")
    if len(others) == 1:
        grid[1][1].set_axis_off()

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
