# Figure 2 of the paper: double slit, trajectory (left) and control (right) under the exact
# optimal control and under implicit-sampling control (M = 50), driven by the same noise.
#
# Input (written by `implicit slit --out DIR`):
#   figure2_slit.csv  t (time [s]), x_exact, x_implicit (positions [m]), u_exact, u_implicit
#                     (controls [m/s]; empty at the final time t = tf, where no control acts).
import numpy as np

from common import COLORS, DataError, draw_slit_wall, figure_main, load_csv, save, subplots


def draw(d):
    data = load_csv(d, "figure2_slit.csv", ["t", "x_exact", "x_implicit", "u_exact", "u_implicit"])
    t = data["t"]
    if not np.all(np.isfinite(data["x_exact"])):
        raise DataError(f"{d / 'figure2_slit.csv'}: column 'x_exact': expected finite values")
    fig, ax = subplots(1, 2, width=11)
    ax[0].plot(t, data["x_exact"], color=COLORS["exact"], lw=2, label="exact control")
    ax[0].plot(t, data["x_implicit"], "--", color=COLORS["implicit"], lw=1.5,
               label="implicit sampling")
    xs = np.concatenate([data["x_exact"], data["x_implicit"]])
    ymin, ymax = min(-10.0, xs.min() - 1), max(10.0, xs.max() + 1)
    draw_slit_wall(ax[0], ymin, ymax)
    ax[0].set_ylim(ymin, ymax)
    ax[0].set_ylabel("position x [m]")
    u = np.isfinite(data["u_exact"])
    ax[1].plot(t[u], data["u_exact"][u], color=COLORS["exact"], lw=2, label="exact control")
    ax[1].plot(t[u], data["u_implicit"][u], "--", color=COLORS["implicit"], lw=1.5,
               label="implicit sampling")
    ax[1].set_ylabel("control u [m/s]")
    for a in ax:
        a.set_xlabel("time t [s]")
        a.legend(fontsize=8)
    save(fig, d, 2)


if __name__ == "__main__":
    figure_main(draw)
