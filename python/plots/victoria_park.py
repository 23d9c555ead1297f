#!/usr/bin/python3
"""Victoria Park (real data, maximum-likelihood association): GPS, estimated paths and maps.

Usage: /usr/bin/python3 python/plots/victoria_park.py <dir>

Reads from <dir> the CSV files written by
  implicit slam --method <m> --association ml --control-noise 0.1 --particles M \
      --data data/victoria_park/victoria_park.log.gz --datasets 1 --out <dir>
for every method that was run:
  slam_<method>_M<particles>_path.csv  n,x_true,y_true,beta_true,x_hat,y_hat,beta_hat (x_true,
                                       y_true = GPS interpolated to the step, NaN without a fix)
  slam_<method>_M<particles>_map.csv   kind,id,x,y (kind = estimate: the final map)
One panel per method: the GPS track, and the estimated path and landmarks after the best rigid
transform (rotation + translation, no scale) of the estimated path onto the GPS fixes, the same
alignment as error_aligned_percent. Writes <dir>/victoria_park.png and .svg; exits non-zero
naming the file and column when an input is missing or malformed.
"""
import re
from pathlib import Path

import numpy as np

from common import COLORS, DataError, figure_main, load_csv, plt

ORDER = ["ekf", "fastslam1", "fastslam2", "implicit", "implicit-rb"]


def rigid_alignment(src, dst):
    """R, t minimising sum |R src_i + t - dst_i|^2 (Umeyama without scale, det R = +1)."""
    ms, md = src.mean(axis=0), dst.mean(axis=0)
    c = (dst - md).T @ (src - ms)
    u, _, vt = np.linalg.svd(c)
    d = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    r = u @ d @ vt
    return r, md - r @ ms


def draw(d):
    runs = []
    for f in sorted(Path(d).glob("slam_*_M*_path.csv")):
        m = re.fullmatch(r"slam_(.+)_M(\d+)_path\.csv", f.name)
        if m:
            runs.append((m.group(1), int(m.group(2))))
    if not runs:
        raise DataError(f"{d}: expected slam_<method>_M<particles>_path.csv files, got none")
    runs.sort(key=lambda r: (ORDER.index(r[0]) if r[0] in ORDER else 99, r[1]))
    n = len(runs)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 4.6 * rows), squeeze=False)
    for k, (method, particles) in enumerate(runs):
        stem = f"slam_{method}_M{particles}"
        p = load_csv(d, f"{stem}_path.csv", ["x_true", "y_true", "x_hat", "y_hat"])
        mp = load_csv(d, f"{stem}_map.csv", ["x", "y"], text_columns=["kind"])
        est = np.column_stack([p["x_hat"], p["y_hat"]])
        gps = np.column_stack([p["x_true"], p["y_true"]])
        ok = np.all(np.isfinite(gps), axis=1) & np.all(np.isfinite(est), axis=1)
        if ok.sum() < 2:
            raise DataError(f"{d}/{stem}_path.csv: columns x_true, y_true: expected at least two "
                            "GPS fixes, got fewer")
        r, t = rigid_alignment(est[ok], gps[ok])
        path = est @ r.T + t
        lm = np.column_stack([mp["x"], mp["y"]])[np.array(mp["kind"]) == "estimate"]
        lm = lm @ r.T + t if len(lm) else lm
        rmse = float(np.sqrt(np.mean(np.sum((path[ok] - gps[ok]) ** 2, axis=1))))
        a = axes[k // cols][k % cols]
        a.plot(gps[ok, 0], gps[ok, 1], ".", color=COLORS["exact"], ms=1.5, label="GPS")
        a.plot(path[:, 0], path[:, 1], color=COLORS.get(method, COLORS["implicit"]), lw=0.7,
               label="estimated path (aligned)")
        if len(lm):
            a.plot(lm[:, 0], lm[:, 1], "+", color=COLORS["landmark"], ms=3, mew=0.6,
                   label=f"{len(lm)} landmarks")
        a.set_title(f"{method}, M = {particles}: aligned RMSE {rmse:.1f} m", fontsize=9)
        a.set_xlabel("east [m]")
        a.set_ylabel("north [m]")
        a.set_aspect("equal", adjustable="datalim")
        a.legend(fontsize=7, loc="best", markerscale=3)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    fig.tight_layout()
    for ext in ("png", "svg"):
        out = Path(d) / f"victoria_park.{ext}"
        fig.savefig(out, dpi=150) if ext == "png" else fig.savefig(out)
    plt.close(fig)
    print(f"wrote {Path(d) / 'victoria_park.png'} and .svg")


if __name__ == "__main__":
    figure_main(draw)
