"""Renders every figure script (python/plots/figureN.py) on small synthetic data and checks, through
matplotlib's API rather than by eye, what a reader of the figure sees:

- every log axis shows at least two labelled ticks (the ticks drawn inside the axis' range with a
  non-empty label), also for the helper common.label_log_axis on ranges from a factor 1.001 to
  six decades;
- no two texts overlap (titles, axis labels, drawn tick labels, annotations, legend entries: their
  bounding boxes from the renderer);
- Figure 8: the Car Park configurations A and B have different markers;
- Figure 9: all panels have one y-range, and each a legend naming its runs;
- Figure 10: the map panel is zoomed to the path (a short path on a large map is not a few pixels);
- Figure 11: the map panel shows the whole map and every path;
- Figure 12: a panel per setting, each with every method of its rows and DAPPER's values as open
  markers.

The data are chosen so that matplotlib's own ticks label only one tick on several log axes (CPU
times from 0.004 to 0.06 ms, step lengths from 0.02 to 0.4 s, a narrow RMSE range), and so that
the two Car Park configurations lie close together in Figure 8.

Usage: plots_figures_check.py PLOTS_DIR TMP_DIR   (exit 0 when every check passes; the messages of
all failed checks otherwise)
"""
import importlib
import json
import math
import sys
from pathlib import Path

plots, tmp = Path(sys.argv[1]), Path(sys.argv[2])
sys.path.insert(0, str(plots))
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import common  # noqa: E402

FAILURES = []


def check(condition, message):
    if not condition:
        FAILURES.append(message)


def write_csv(name, header, rows):
    with open(tmp / name, "w") as f:
        f.write(",".join(header) + "\n")
        for r in rows:
            f.write(",".join(f"{v:.6g}" if isinstance(v, float) else str(v) for v in r) + "\n")


# ---- Synthetic data, one folder for all figures (as `implicit reproduce` writes it) ------------

def make_data():
    ts = np.linspace(0.0, 1.0, 11)
    write_csv("figure1_unguided.csv", ["path", "t", "x"],
              [(p, float(t), 1.0 + 0.5 * p * t) for p in range(3) for t in ts])
    t2 = np.linspace(0.0, 2.0, 21)
    write_csv("figure1_guided.csv", ["path", "t", "x", "passed"],
              [(p, float(t), 1.0 - 5.0 * min(t, 2 - t) + 0.1 * p, 1 - p) for p in range(2)
               for t in t2])
    write_csv("figure2_slit.csv", ["t", "x_exact", "x_implicit", "u_exact", "u_implicit"],
              [(float(t), 1 - t, 1 - 1.01 * t, -5.0 + t, -5.1 + t) for t in t2])
    cols = [f"{q}{j}_{m}" for m in ("exact", "wrong") for q in ("theta", "dtheta", "tau")
            for j in (1, 2)]
    write_csv("figure4_arm.csv", ["t", *cols],
              [(float(t), *[float(math.sin(t + k)) for k in range(len(cols))]) for t in t2])
    write_csv("figure5_newton.csv", ["k", "x1", "x2", "f"],
              [(0, -1.0, -4.0, 260.0), (1, 0.09, -2.9, 195.4), (2, -0.13, -1.95, 178.34)])
    write_csv("figure5_runs.csv", ["run", "k", "x1", "x2", "f"],
              [(r, k, -1.0 - 0.9 * k, -4.0 + 0.25 * k + 0.05 * r, 10.0 / (k + 1))
               for r in range(2) for k in range(4)])

    # Figure 6: CPU per step from 0.004 to 0.06 ms (one decade: matplotlib labels only 10^-2).
    summary = []
    for method, cpu in (("standard", (0.004, 0.04)), ("implicit", (0.005, 0.055))):
        for m, c, err in zip((10, 100), cpu, (110.0, 20.0)):
            summary.append((method, m, 4, "A", 0.5, err, 0.5 * err, 0.8 * err, 1.0, 0.1, 1, 0.4,
                            c, 1))
    write_csv("mcl_summary.csv", ["method", "particles", "runs", "config", "p",
                                  "error_percent_mean", "error_percent_std", "error_percent_median",
                                  "rmse_m", "heading_rmse_rad", "lost_runs", "ess_mean",
                                  "cpu_ms_per_step", "seed"], summary)
    angle = np.linspace(0.0, 2 * np.pi, 50)
    write_csv("mcl_implicit_M100_trajectory.csv", ["step", "truth_x", "truth_y", "est_x", "est_y"],
              [(k, 10 * math.cos(a), 15 * math.sin(a), 10.2 * math.cos(a), 15 * math.sin(a))
               for k, a in enumerate(angle)])
    write_csv("mcl_beacons.csv", ["id", "x", "y"], [(1, 12.0, 0.0), (2, -12.0, 3.0)])

    # Figure 7: CPU per step from 0.003 to 0.15 ms.
    write_csv("slam_summary.csv", ["method", "particles", "datasets", "error_percent_mean",
                                   "error_percent_std", "cpu_ms_per_step", "map_shape_m"],
              [("ekf", 1, 2, 5.0, 1.0, 0.003, 0.04), ("fastslam2", 100, 2, 7.8, 4.0, 0.09, 0.4),
               ("implicit", 100, 2, 5.4, 0.5, 0.11, 0.4), ("implicit-rb", 100, 2, 5.6, 3.0, 0.14,
                                                           0.4)])
    write_csv("slam_implicit_M100_path.csv", ["n", "x_true", "y_true", "x_hat", "y_hat"],
              [(k, 10 * math.cos(a), 15 * math.sin(a), 10.3 * math.cos(a), 15 * math.sin(a))
               for k, a in enumerate(angle)])
    write_csv("slam_implicit_M100_map.csv", ["kind", "id", "x", "y"],
              [("true", 0, 12.0, 0.0), ("estimate", 0, 12.2, 0.1)])

    # Figure 8: step lengths 0.02 to 0.4 s and an RMSE between 0.105 and 0.125 m on the bottom row.
    gain = []
    for sweep, xs in (("ratio", (0.1, 1.0, 10.0)), ("dt", (0.02, 0.05, 0.1, 0.2, 0.4))):
        for i, x in enumerate(xs):
            dt, ratio = (0.1, x) if sweep == "ratio" else (x, 1.0)
            for method, ess in (("implicit", 0.4), ("standard", 0.1)):
                rmse = 0.11 + 0.002 * i if sweep == "dt" else 0.1 * (1 + i)
                gain.append((sweep, dt, 0.2, ratio, method, ess, 0.01, rmse, 0.001,
                             0.05 + 0.01 * i, 0.002))
    write_csv("proposal_gain.csv", ["sweep", "dt", "range_sd", "ratio", "method", "ess", "ess_se",
                                    "rmse_m", "rmse_m_se", "cpu_ms_per_step",
                                    "cpu_ms_per_step_se"], gain)
    mcl_runs = []
    for config in ("A", "B"):
        for method in ("implicit", "standard"):
            mcl_runs.append({"status": "ok",
                             "settings": {"config": config, "particles": 100, "method": method},
                             "result": {"runs": 4, "ess_mean": 0.45, "ess_std": 0.01,
                                        "rmse_m": 0.5, "rmse_m_std": 0.01,
                                        "cpu_ms_per_step": 0.05, "cpu_ms_per_step_std": 0.001}})
    results = {"experiments": {
        "proposal_gain": {"runs": [{"status": "ok",
                                    "result": {"carpark_ratio": {"A": 0.8, "B": 0.75}}}]},
        "mcl": {"runs": mcl_runs}}}
    (tmp / "results.json").write_text(json.dumps(results))

    # Figure 9: the implicit errors reach 1 mm, the standard ones stay above 3 m.
    for study, start in (("global", (0.0, 2.5)), ("kidnap", (10.0, 10.0))):
        for method, m, low in (("implicit", 30, 1e-3), ("standard", 100, 3.0)):
            rows = []
            for r in range(2):
                for k in range(40):
                    t = 0.5 * k
                    if study == "kidnap" and 5.0 < t < 10.0:
                        continue
                    rows.append((r, start[r], t, max(low, 10.0 * math.exp(-0.4 * k)), m))
            write_csv(f"mcl_{study}_{method}_M{m}_errors.csv",
                      ["run", "start_s", "time_s", "error_m", "particles"], rows)

    # Figure 10: a 60 m map and a 4 m path; errors from 0.01 to 0.25 m.
    write_csv("laser_mcl_map.csv", ["x_m", "y_m", "resolution_m"],
              [(0.5 * i, y, 0.05) for i in range(121) for y in (-30.0, 30.0)])
    write_csv("laser_mcl_reference.csv", ["update", "time_s", "x_m", "y_m", "heading_rad"],
              [(k, 0.5 * k, 0.2 * k, 0.5, 0.0) for k in range(20)])
    for proposal, m, scale in (("implicit", 100, 0.01), ("bootstrap", 1000, 0.25)):
        write_csv(f"laser_mcl_track_{proposal}.csv",
                  ["update", "time_s", "x_m", "y_m", "heading_rad", "error_m", "particles"],
                  [(k, 0.5 * k, 0.2 * k, 0.5 + scale * (k % 3) / 2, 0.0,
                    max(0.01, scale * (k % 3) / 2), m) for k in range(20)])

    # Figure 11: a 20 m x 10 m room, a path around it; relation errors from 0.002 to 0.3 m (the
    # first scan has none: an empty field).
    write_csv("grid_slam_map.csv", ["x_m", "y_m", "resolution_m"],
              [(0.05 * i, y, 0.05) for i in range(401) for y in (-5.0, 5.0)])
    write_csv("grid_slam_reference.csv", ["scan", "time_s", "x_m", "y_m", "heading_rad"],
              [(k, 2.0 * k, 0.5 * k, 0.0, 0.0) for k in range(30)])
    for proposal, scale in (("implicit", 0.002), ("gmapping", 0.01), ("bootstrap", 0.3)):
        write_csv(f"grid_slam_track_{proposal}.csv",
                  ["scan", "time_s", "x_m", "y_m", "heading_rad", "relation_error_m"],
                  [(k, 2.0 * k, 0.5 * k, scale * (k % 4), 0.0,
                    "" if k == 0 else scale * (1 + k % 4)) for k in range(30)])
    # ... and the other logs' panels: rooms of 10 x 6 m and 30 x 4 m, offset from the origin.
    for tag, (w, h, dx) in (("aces", (10.0, 6.0, -40.0)), ("freiburg-079", (30.0, 4.0, 5.0))):
        write_csv(f"grid_slam_{tag}_map.csv", ["x_m", "y_m", "resolution_m"],
                  [(dx + 0.05 * i, y, 0.05) for i in range(int(w / 0.05) + 1) for y in (0, h)])
        write_csv(f"grid_slam_{tag}_reference.csv", ["scan", "time_s", "x_m", "y_m",
                                                     "heading_rad"],
                  [(k, 2.0 * k, dx + w * k / 20, h / 2, 0.0) for k in range(21)])
        write_csv(f"grid_slam_{tag}_track_implicit.csv",
                  ["scan", "time_s", "x_m", "y_m", "heading_rad", "relation_error_m"],
                  [(k, 2.0 * k, dx + w * k / 20, h / 2 + 0.1, 0.0, "" if k == 0 else 0.01)
                   for k in range(21)])

    # Figure 12: the three settings; one row without an interval (one seed), rows without DAPPER.
    write_csv("table_da.csv",
              ["setting", "method", "members", "jitter", "inflation", "resample_threshold", "lag",
               "bandwidth", "seeds", "rmse_a_mean", "rmse_a_lo", "rmse_a_hi", "spread_a",
               "mean_ess", "ms_per_cycle", "dapper_rmse_a"],
              [("sakov2012", "etkf", 10, 0, 1.1, 0.5, "", "", 10, 0.62, 0.60, 0.64, 0.7, 10, 0.01,
                0.6),
               ("sakov2012", "bootstrap", 100, 0.2, 1, 0.8, "", "", 10, 0.41, 0.38, 0.43, 0.5, 60,
                0.05, 0.38),
               ("sakov2012", "bootstrap", 800, 0.07, 1, 0.5, "", "", 1, 0.30, "", "", 0.4, 300,
                0.3, 0.28),
               ("sakov2012", "implicit-smoother", 100, 0, 1, 0.5, 3, 1, 10, 0.30, 0.29, 0.32, 0.37,
                97, 0.35, ""),
               ("sakov2012", "implicit-smoother", 100, 0, 1.03, 0.5, 3, 0.6, 10, 0.29, 0.28, 0.31,
                0.37, 87, 4.2, ""),
               ("bocquet2010", "implicit", 100, 0.3, 1, 0.5, "", "", 10, 0.80, 0.72, 0.88, 0.8, 45,
                0.15, 0.44),
               ("bocquet2010-k4-q0.5", "bootstrap", 100, 0, 1, 0.5, "", "", 10, 3.0, 2.7, 3.3, 1.0,
                7, 0.2, ""),
               ("bocquet2010-k4-q0.5", "implicit", 100, 0, 1, 0.5, "", "", 10, 1.8, 1.7, 1.9, 1.0,
                23, 20.0, "")])


# ---- What a reader sees ---------------------------------------------------------------------

def drawn_tick_labels(axis):
    """[(value, Text)] of the ticks of `axis` drawn inside its range with a visible, non-empty
    label (after fig.canvas.draw())."""
    lo, hi = sorted(axis.get_view_interval())
    span = hi - lo
    out = []
    for locs, ticks in ((axis.get_majorticklocs(), axis.get_major_ticks),
                        (axis.get_minorticklocs(), axis.get_minor_ticks)):
        for v, tick in zip(locs, ticks(len(locs))):
            if not lo - 1e-9 * span <= v <= hi + 1e-9 * span:
                continue
            for label in (tick.label1, tick.label2):
                if label.get_visible() and label.get_text().strip():
                    out.append((v, label))
    return out


def texts_of(fig):
    """Every visible, non-empty text of the figure with a name for the messages."""
    out = []
    for i, ax in enumerate(fig.axes):
        for t, what in ((ax.title, "title"), (ax.xaxis.label, "x label"),
                        (ax.yaxis.label, "y label")):
            out.append((t, f"panel {i} {what}"))
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            out += [(t, f"panel {i} {name} tick {v:g}") for v, t in drawn_tick_labels(axis)]
        out += [(t, f"panel {i} text") for t in ax.texts]
        legend = ax.get_legend()
        if legend is not None:
            out += [(t, f"panel {i} legend") for t in legend.get_texts()]
    out += [(t, "figure text") for t in fig.texts]
    return [(t, n) for t, n in out if t.get_visible() and t.get_text().strip()]


def check_texts_apart(fig, name):
    renderer = fig.canvas.get_renderer()
    boxes = [(t.get_window_extent(renderer), n, t.get_text()) for t, n in texts_of(fig)]
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            a, b = boxes[i][0], boxes[j][0]
            w = min(a.x1, b.x1) - max(a.x0, b.x0)
            h = min(a.y1, b.y1) - max(a.y0, b.y0)
            # More than a pixel of common area: touching boxes are fine.
            check(not (w > 1 and h > 1),
                  f"{name}: text '{boxes[i][2]}' ({boxes[i][1]}) overlaps '{boxes[j][2]}' "
                  f"({boxes[j][1]})")


def check_log_axes(fig, name):
    for i, ax in enumerate(fig.axes):
        for axis_name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            if axis.get_scale() != "log":
                continue
            labels = [t.get_text() for _, t in drawn_tick_labels(axis)]
            check(len(labels) >= 2,
                  f"{name}: panel {i} ('{ax.get_title()}') log {axis_name} axis "
                  f"{axis.get_view_interval()} has labelled ticks {labels}, expected at least 2")


def render(number):
    """Runs figureN.draw on the synthetic data; returns the drawn figure (also written to disk)."""
    module = importlib.import_module(f"figure{number}")
    captured = []

    def keep(fig, directory, n):
        captured.append(fig)
        return common.save(fig, directory, n)

    module.save = keep
    module.draw(tmp)
    check(len(captured) == 1, f"figure{number}: expected one figure, got {len(captured)}")
    fig = captured[0]
    fig.canvas.draw()
    return fig


def check_figure8(fig):
    ax = fig.axes[0]
    handles, labels = ax.get_legend_handles_labels()
    markers = {}
    for h, label in zip(handles, labels):
        if label.startswith("Car Park"):
            line = h[0] if isinstance(h, tuple) or hasattr(h, "lines") else h
            markers.setdefault(label.split(",")[0], set()).add(line.get_marker())
    check(set(markers) == {"Car Park A", "Car Park B"},
          f"figure8: expected legend entries of Car Park A and B, got {labels}")
    if len(markers) == 2:
        check(not (markers["Car Park A"] & markers["Car Park B"]),
              f"figure8: Car Park A and B share a marker: {markers}")


def check_figure9(fig):
    limits = {tuple(np.round(np.log10(ax.get_ylim()), 6)) for ax in fig.axes}
    check(len(limits) == 1, f"figure9: expected one y-range for all panels, got {limits}")
    for i, ax in enumerate(fig.axes):
        legend = ax.get_legend()
        names = [t.get_text() for t in legend.get_texts()] if legend else []
        check(sum(n.startswith("run ") for n in names) == 2,
              f"figure9: panel {i}: expected a legend naming its 2 runs, got {names}")


def check_figure10(fig):
    ax = fig.axes[0]
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    # The 4 m path on the 60 m map: zoomed, it spans a good part of the panel's width.
    check(4.0 / (x1 - x0) > 0.25, f"figure10: the map panel spans x {x0:.1f}..{x1:.1f} m for a "
                                  "4 m path: not zoomed to the path")
    check(x0 <= 0.0 and x1 >= 3.8 and y0 <= 0.5 and y1 >= 0.75,
          f"figure10: the map panel x {x0:.1f}..{x1:.1f}, y {y0:.1f}..{y1:.1f} cuts the path")


def check_figure11(fig):
    ax = fig.axes[0]
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    # The map spans x 0..20 m and y -5..5 m; the paths lie inside it.
    check(x0 <= -0.025 and x1 >= 20.025 and y0 <= -5.025 and y1 >= 5.025,
          f"figure11: the map panel x {x0:.1f}..{x1:.1f}, y {y0:.1f}..{y1:.1f} cuts the map")
    names = [t.get_text() for t in ax.get_legend().get_texts()] if ax.get_legend() else []
    check(len(names) == 4, f"figure11: expected the reference and three proposals, got {names}")
    # The other logs' maps below, each panel holding its room (ACES x -40..-30, y 0..6; Freiburg
    # 079 x 5..35, y 0..4).
    check(len(fig.axes) == 4, f"figure11: expected 4 panels with the other logs, got "
                              f"{len(fig.axes)}")
    for ax, title, (lo, hi) in zip(fig.axes[2:], ("ACES", "Freiburg 079"),
                                   (((-40, 0), (-30, 6)), ((5, 0), (35, 4)))):
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        check(title in ax.get_title() and x0 <= lo[0] and y0 <= lo[1] and x1 >= hi[0]
              and y1 >= hi[1], f"figure11: the {title} panel '{ax.get_title()}' x "
                               f"{x0:.1f}..{x1:.1f}, y {y0:.1f}..{y1:.1f}")


def check_figure12(fig):
    titles = [ax.get_title() for ax in fig.axes]
    check(len(fig.axes) == 3 and "Lorenz-63" in titles[0] and "Lorenz-96" in titles[1]
          and "every 4th interval" in titles[2],
          f"figure12: expected a Lorenz-63, a Lorenz-96 and its variant's panel, got {titles}")
    expected = ({"ETKF", "bootstrap PF", "implicit smoother", "implicit smoother, kernels"},
                {"implicit PF"}, {"bootstrap PF", "implicit PF"})
    for ax, methods in zip(fig.axes, expected):
        names = [t.get_text() for t in ax.get_legend().get_texts()] if ax.get_legend() else []
        check({n for n in names if not n.endswith(": DAPPER")} == methods,
              f"figure12: {ax.get_title()}: expected the methods {sorted(methods)}, got {names}")
        open_markers = [ln for ln in ax.get_lines()
                        if ln.get_linestyle() == "None" and ln.get_markerfacecolor() == "none"]
        dapper = sum(len(ln.get_xdata()) for ln in open_markers)
        want = 3 if "Lorenz-63" in ax.get_title() else 0 if "every" in ax.get_title() else 1
        check(dapper == want,
              f"figure12: {ax.get_title()}: expected {want} open DAPPER markers, got {dapper}")


def check_helper():
    """label_log_axis on ranges matplotlib labels once or never, and one it labels well."""
    for lo, hi in ((0.004, 0.06), (0.02, 0.4), (0.11, 0.13), (1.001, 1.002), (1e-3, 1e3),
                   (30.0, 70.0)):
        fig, ax = plt.subplots()
        ax.plot([lo, hi], [lo, hi])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
        common.label_log_axes(fig)
        fig.canvas.draw()
        for axis in (ax.xaxis, ax.yaxis):
            labels = [t.get_text() for _, t in drawn_tick_labels(axis)]
            check(len(labels) >= 2, f"label_log_axis on [{lo}, {hi}]: labelled ticks {labels}")
            check(len(set(labels)) == len(labels),
                  f"label_log_axis on [{lo}, {hi}]: repeated labels {labels}")
        plt.close(fig)


make_data()
check_helper()
for number in (1, 2, 4, 5, 6, 7, 8, 9, 10, 11, 12):
    figure = render(number)
    check_log_axes(figure, f"figure{number}")
    check_texts_apart(figure, f"figure{number}")
    {8: check_figure8, 9: check_figure9, 10: check_figure10,
     11: check_figure11, 12: check_figure12}.get(number, lambda f: None)(figure)
    check((tmp / f"figure{number}.png").is_file(), f"figure{number}: no PNG written")

# Figure 11 with one of another log's three files gone: an error naming it, not a panel short.
(tmp / "grid_slam_freiburg-079_map.csv").unlink()
try:
    importlib.import_module("figure11").draw(tmp)
    check(False, "figure11: drew without grid_slam_freiburg-079_map.csv")
except common.DataError as e:
    check("missing grid_slam_freiburg-079_map.csv" in str(e),
          f"figure11: the error does not name the missing file: {e}")

if FAILURES:
    print("\n".join(FAILURES))
    sys.exit(1)
print("ok")
