#!/usr/bin/python3
"""The figure of `implicit eval --plot FILE`: a trajectory against its reference, after alignment.

Usage: /usr/bin/python3 python/plots/eval_plot.py DATA.csv OUT.png|OUT.pdf|OUT.svg [TITLE]

Reads DATA.csv as `implicit eval` writes it for the plot (one row per associated pose pair, in
time order):
  t_s                 the reference pose's time
  ref_x_m, ref_y_m    the reference position
  est_x_m, est_y_m    the estimated position after the alignment of --align
  ape_translation_m   the APE translation error of the pair (|t| of ref^-1 est)
  path_m              the distance travelled along the reference from the first pair

Left panel: the two paths seen from above (x, y, equal axes), the start marked. Right panel: the
APE translation error against the distance along the reference path, with its mean and RMSE.
Writes OUT in the format its extension names (150 dpi for PNG).

Exit codes: 0 drawn, 1 missing or malformed data, 2 bad usage, 3 matplotlib or numpy missing.
"""
import os
import sys
from pathlib import Path

SCRIPT = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "eval_plot.py"

try:
    import numpy as np
    from common import COLORS, DataError, load_csv, subplots
except ImportError as e:  # no matplotlib (or numpy): say what to install, not a traceback
    print(f"{SCRIPT}: error: python module '{e.name}' not found: the plot needs matplotlib and "
          f"numpy (Debian: apt-get install python3-matplotlib), or IMPLICIT_PYTHON naming a "
          f"python3 that has them", file=sys.stderr)
    sys.exit(3)

COLUMNS = ["t_s", "ref_x_m", "ref_y_m", "est_x_m", "est_y_m", "ape_translation_m", "path_m"]
FORMATS = (".png", ".pdf", ".svg")


def draw(data, out, title):
    d = load_csv(data.parent, data.name, COLUMNS)
    for c in COLUMNS:
        if not np.all(np.isfinite(d[c])):
            raise DataError(f"{data}: column '{c}': expected finite numbers, got "
                            f"{int(np.sum(~np.isfinite(d[c])))} that are not")
    err = d["ape_translation_m"]
    fig, ax = subplots(1, 2, width=12, height=5)
    a = ax[0]
    a.plot(d["ref_x_m"], d["ref_y_m"], color=COLORS["exact"], lw=2.5,
           label="reference")
    a.plot(d["est_x_m"], d["est_y_m"], color=COLORS["implicit"], lw=1.0, label="estimate, aligned")
    a.plot(d["ref_x_m"][:1], d["ref_y_m"][:1], "o", color=COLORS["exact"], ms=6, label="start")
    a.set_aspect("equal", adjustable="datalim")
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_title("top view")
    a.legend(fontsize=8, loc="best")

    a = ax[1]
    mean, rmse = float(np.mean(err)), float(np.sqrt(np.mean(err ** 2)))
    a.plot(d["path_m"], err, color=COLORS["implicit"], lw=0.8, marker="o", ms=2,
           label=f"APE translation ({len(err)} poses)")
    a.axhline(mean, color=COLORS["standard"], lw=1, ls="--", label=f"mean {mean:.4g} m")
    a.axhline(rmse, color=COLORS["ekf"], lw=1, ls=":", label=f"RMSE {rmse:.4g} m")
    a.set_xlabel("distance along the reference [m]")
    a.set_ylabel("APE translation error [m]")
    a.set_ylim(bottom=0.0, top=max(float(err.max()), rmse) * 1.15 or 1.0)
    a.set_title("error along the path")
    a.legend(fontsize=8, loc="best")
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=150)
    print(f"wrote {out}")


def main(argv):
    if len(argv) not in (3, 4):
        print(f"usage: {SCRIPT} DATA.csv OUT.png|OUT.pdf|OUT.svg [TITLE]", file=sys.stderr)
        return 2
    data, out = Path(argv[1]), Path(argv[2])
    if out.suffix.lower() not in FORMATS:
        print(f"{SCRIPT}: error: {out}: expected a name ending in {', '.join(FORMATS)}",
              file=sys.stderr)
        return 2
    try:
        draw(data, out, argv[3] if len(argv) == 4 else "")
    except DataError as e:
        print(f"{SCRIPT}: error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
