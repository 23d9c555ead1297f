# Figure 1 of the paper: double slit, unguided random walks (plain Monte Carlo) and guided walks
# of implicit sampling, all started at x(0) = 1.
#
# Input (written by `implicit slit --out DIR`):
#   figure1_unguided.csv  path (walk index), t (time [s]), x (position); plain Monte Carlo walks
#                         from x(0) = 1 up to the wall time t1 = 1, every 2nd time step.
#   figure1_guided.csv    path, t [s], x, passed (1 if the walk passes its slit at t1, else 0);
#                         samples y = mu + L^-T xi of implicit sampling around the dominant slit's
#                         constrained minimum, over the whole horizon [0, tf].
import numpy as np

from common import (COLORS, WALL_TIME, DataError, draw_slit_wall, figure_main, load_csv, save,
                    subplots)


def walks(d, name, extra=()):
    data = load_csv(d, name, ["path", "t", "x", *extra])
    paths = data["path"].astype(int)
    if np.any(np.diff(paths) < 0):
        raise DataError(f"{d / name}: column 'path': expected rows grouped by walk (non-decreasing)")
    splits = np.flatnonzero(np.diff(paths)) + 1
    return data, np.split(np.arange(len(paths)), splits)


def draw(d):
    unguided, groups_u = walks(d, "figure1_unguided.csv")
    guided, groups_g = walks(d, "figure1_guided.csv", ["passed"])
    fig, ax = subplots(1, 2, width=11)
    for g in groups_u:
        ax[0].plot(unguided["t"][g], unguided["x"][g], color=COLORS["standard"], lw=0.3, alpha=0.3)
    ax[0].set_title(f"plain Monte Carlo: {len(groups_u)} unguided walks")
    passed = 0
    for g in groups_g:
        ok = guided["passed"][g][0] > 0.5
        passed += ok
        if not ok:  # a walk that hits the wall ends there
            g = g[guided["t"][g] <= WALL_TIME + 1e-9]
        ax[1].plot(guided["t"][g], guided["x"][g], lw=0.8,
                   color=COLORS["implicit"] if ok else COLORS["standard"], alpha=0.8)
    ax[1].set_title(f"implicit sampling: {len(groups_g)} guided walks, "
                    f"{len(groups_g) - passed} hit the wall")
    for a in ax:
        ymin, ymax = -10.0, 10.0
        draw_slit_wall(a, ymin, ymax)
        a.set_ylim(ymin, ymax)
        a.set_xlabel("time t [s]")
        a.set_ylabel("position x [m]")
    ax[1].plot([], [], color=COLORS["implicit"], label="passes a slit")
    ax[1].plot([], [], color=COLORS["standard"], label="hits the wall (ends there)")
    for a in ax:
        a.legend(loc="upper right", fontsize=8)
    save(fig, d, 1)


if __name__ == "__main__":
    figure_main(draw)
