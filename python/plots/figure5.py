# Figure 5 of the paper: Newton's method and stochastic optimisation (path integral control with
# implicit sampling, M = 50) on the contours of Himmelblau's function, started at (-1, -4).
#
# Input (written by `implicit himmelblau --out DIR`):
#   figure5_newton.csv  k (iteration), x1, x2 (iterate, dimensionless), f (Himmelblau value)
#   figure5_runs.csv    run (run index), k (time step, dt = 1), x1, x2 (state), f (f(x_k))
import numpy as np

from common import COLORS, DataError, figure_main, load_csv, save, subplots


def himmelblau(x1, x2):
    return (x1 ** 2 + x2 - 11) ** 2 + (x1 + x2 ** 2 - 7) ** 2


def draw(d):
    newton = load_csv(d, "figure5_newton.csv", ["k", "x1", "x2", "f"])
    runs = load_csv(d, "figure5_runs.csv", ["run", "k", "x1", "x2", "f"])
    ids = runs["run"].astype(int)
    if np.any(np.diff(ids) < 0):
        raise DataError(f"{d / 'figure5_runs.csv'}: column 'run': expected rows grouped by run")
    fig, ax = subplots(1, 1, width=7, height=6)
    g1, g2 = np.meshgrid(np.linspace(-5.5, 5.5, 400), np.linspace(-5.5, 5.5, 400))
    levels = np.concatenate([[0.5, 2, 5, 10, 20], np.arange(40, 400, 30)])
    cs = ax.contour(g1, g2, himmelblau(g1, g2), levels=levels, colors="#999999", linewidths=0.6)
    ax.clabel(cs, cs.levels[::3], fontsize=6, fmt="%g")
    splits = np.flatnonzero(np.diff(ids)) + 1
    groups = np.split(np.arange(len(ids)), splits)
    for i, g in enumerate(groups):
        ax.plot(runs["x1"][g], runs["x2"][g], "-", color=COLORS["implicit"], lw=0.7, alpha=0.5,
                label="stochastic control runs" if i == 0 else None)
        ax.plot(runs["x1"][g][-1], runs["x2"][g][-1], "o", color=COLORS["implicit"], ms=3,
                label="end points of the runs" if i == 0 else None)
    ax.plot(newton["x1"], newton["x2"], "s-", color=COLORS["standard"], ms=4,
            label=f"Newton (ends at f = {newton['f'][-1]:.2f}, a saddle)")
    ax.plot([-1], [-4], "k*", ms=10, label="start (-1, -4)")
    ax.set_xlabel("x1 [-]")
    ax.set_ylabel("x2 [-]")
    ax.set_title(f"Himmelblau: Newton and {len(groups)} controlled runs")
    ax.legend(fontsize=8, loc="upper left")
    ax.set_aspect("equal")
    save(fig, d, 5)


if __name__ == "__main__":
    figure_main(draw)
