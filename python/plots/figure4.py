# Figure 4 of the paper: two-link robot arm under path integral control, with the exact model
# (solid) and with the controller's wrong model m1 = 1.4 (dashed): joint angles, angular
# velocities and torques.
#
# Input (written by `implicit arm --out DIR`):
#   figure4_arm.csv  t (time [s]); for each model suffix in {exact, wrong}: theta1_*, theta2_*
#                    (joint angles [rad]), dtheta1_*, dtheta2_* (angular velocities [rad/s]),
#                    tau1_*, tau2_* (torques [N m]; nan at the final time).
import numpy as np
import matplotlib.pyplot as plt

from common import figure_main, load_csv, save

COLS = [f"{q}{j}_{m}" for m in ("exact", "wrong") for q in ("theta", "dtheta", "tau")
        for j in (1, 2)]


def draw(d):
    data = load_csv(d, "figure4_arm.csv", ["t", *COLS])
    t = data["t"]
    fig = plt.figure(figsize=(11, 7))
    grid = fig.add_gridspec(2, 2)
    panels = [(fig.add_subplot(grid[0, 0]), "theta", "joint angle θ [rad]"),
              (fig.add_subplot(grid[1, 0]), "dtheta",
               r"angular velocity $\dot{\theta}$ [rad/s]"),
              (fig.add_subplot(grid[:, 1]), "tau", "torque τ [N m]")]
    colors = {("exact", 1): "#1fa0a8", ("exact", 2): "#ff7f0e",
              ("wrong", 1): "#d62728", ("wrong", 2): "#1f3fb4"}
    for ax, q, label in panels:
        for model, style, name in (("exact", "-", "exact model"), ("wrong", "--", "m1 = 1.4")):
            for j in (1, 2):
                y = data[f"{q}{j}_{model}"]
                ok = np.isfinite(y)
                ax.plot(t[ok], y[ok], style, color=colors[(model, j)], lw=1.5,
                        label=f"joint {j}, {name}")
        ax.set_xlabel("time t [s]")
        ax.set_ylabel(label)
        ax.legend(fontsize=7)
    save(fig, d, 4)


if __name__ == "__main__":
    figure_main(draw)
