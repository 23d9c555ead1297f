"""Shared helpers for the figure scripts python/plots/figureN.py.

Every figure script is called as

    /usr/bin/python3 python/plots/figureN.py DIR

by `implicit reproduce` (or by hand), reads CSV files that the experiments wrote into DIR, and
writes DIR/figureN.png and DIR/figureN.svg. A script must fail loudly (non-zero exit, a message
naming the file, line and column) on missing or malformed data, never draw an empty figure.

A figure script looks like this:

    # Figure 2 of the paper: double slit, trajectory and control, exact vs implicit sampling.
    from common import figure_main, load_csv, save, subplots

    def draw(d):
        t = load_csv(d, "figure2_slit.csv", ["t", "x_exact", "x_implicit"])
        fig, ax = subplots(1, 2)
        ax[0].plot(t["t"], t["x_exact"], label="exact")
        ax[0].set_xlabel("time t [s]")
        ...
        save(fig, d, 2)

    if __name__ == "__main__":
        figure_main(draw)

Common mistakes: forgetting axis units, and catching exceptions in a figure script (let
DataError propagate: figure_main turns it into a clear message and exit code 1).
"""

import csv
import json
import math
import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display: the report is drawn on servers and in CI
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import (FormatStrFormatter, FuncFormatter, LogLocator,  # noqa: E402
                               MaxNLocator, NullFormatter)

# One colour per role, used by every figure (close to the paper's turquoise/red pairs).
COLORS = {
    "exact": "#1fa0a8",  # exact solution, ground truth
    "implicit": "#d62728",  # implicit sampling
    "standard": "#1f77b4",  # standard / bootstrap / plain Monte Carlo
    "ekf": "#7f7f7f",
    "fastslam1": "#9467bd",
    "fastslam2": "#ff7f0e",
    "implicit-rb": "#8c564b",
    "landmark": "#0b3d91",
    "wall": "#333333",
    "paper": "#000000",
}


# The double slit's wall (Figures 1 and 2): closed at the wall time except for the two slits.
SLITS = [(-6.0, -4.0), (6.0, 8.0)]
WALL_TIME = 1.0


def draw_slit_wall(ax, ymin, ymax):
    """Draws the closed parts of the wall between ymin and ymax, with one legend entry."""
    edges = [ymin] + [v for s in SLITS for v in s] + [ymax]
    label = "wall (open at the slits)"
    for lo, hi in zip(edges[0::2], edges[1::2]):
        if hi > lo:
            ax.plot([WALL_TIME, WALL_TIME], [lo, hi], color=COLORS["wall"], lw=4, label=label)
            label = None


class DataError(Exception):
    """Missing or malformed figure data; the message names the file, line and column."""


def _parse_float(text):
    text = text.strip()
    if text == "":
        return math.nan  # missing value (e.g. a table cell the paper does not have)
    return float(text)  # accepts nan, inf


def load_csv(directory, name, columns=(), text_columns=()):
    """Reads DIR/name into a dict column -> numpy array.

    `columns` must exist and be numeric (empty cells become NaN); `text_columns` must exist and
    are kept as strings. Other columns are numeric when every value parses, text otherwise.
    Raises DataError for a missing file, a missing column, a row with the wrong number of
    fields, a non-numeric value in a numeric column, or a file without data rows.
    """
    path = Path(directory) / name
    if not path.is_file():
        raise DataError(
            f"{path}: figure data not found (expected a CSV file written by the experiment; "
            f"run `implicit reproduce --out {directory}` or the experiment with --out)")
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    if not rows:
        raise DataError(f"{path}: expected a header line, got an empty file")
    header = [h.strip() for h in rows[0]]
    data = rows[1:]
    if not data:
        raise DataError(f"{path}: expected at least one data row after the header, got none")
    missing = [c for c in list(columns) + list(text_columns) if c not in header]
    if missing:
        raise DataError(f"{path}: expected column(s) {', '.join(missing)}, got columns "
                        f"{', '.join(header)}")
    for i, row in enumerate(data):
        if len(row) != len(header):
            raise DataError(f"{path}:{i + 2}: expected {len(header)} fields as in the header, "
                            f"got {len(row)}")
    out = {}
    for j, col in enumerate(header):
        values = [row[j] for row in data]
        if col in text_columns:
            out[col] = np.array(values, dtype=object)
            continue
        parsed = []
        bad = None
        for i, v in enumerate(values):
            try:
                parsed.append(_parse_float(v))
            except ValueError:
                bad = (i, v)
                break
        if bad is None:
            out[col] = np.array(parsed, dtype=float)
        elif col in columns:
            raise DataError(f"{path}:{bad[0] + 2}: column '{col}': expected a number, got "
                            f"'{bad[1]}'")
        else:
            out[col] = np.array(values, dtype=object)
    return out


def load_results(directory):
    """Reads DIR/results.json (written by `implicit reproduce`) as a dict."""
    path = Path(directory) / "results.json"
    if not path.is_file():
        raise DataError(f"{path}: not found (run `implicit reproduce --out {directory}`)")
    try:
        with open(path) as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise DataError(f"{path}:{e.lineno}: malformed JSON: {e.msg}") from e


def subplots(nrows=1, ncols=1, width=None, height=None, **kwargs):
    """A figure with the project's default size (about 5 x 4 inches per panel).

    Like matplotlib's: one Axes for 1 x 1, a 1-D array for one row or column, else 2-D; other
    keywords (sharey=True, ...) go to plt.subplots.
    """
    return plt.subplots(nrows, ncols, figsize=(width or 5.0 * ncols, height or 4.0 * nrows),
                        **kwargs)


def labelled_ticks(axis):
    """[(value, label)] of the ticks of `axis` (major and minor) inside its view interval whose
    label is not empty, as the axis' locators and formatters give them."""
    lo, hi = sorted(axis.get_view_interval())
    out = []
    for locs, formatter in ((axis.get_majorticklocs(), axis.get_major_formatter()),
                            (axis.get_minorticklocs(), axis.get_minor_formatter())):
        locs = [v for v in locs if lo <= v <= hi]
        out += [(v, s) for v, s in zip(locs, formatter.format_ticks(locs)) if s.strip()]
    return out


# Tick labels on a log axis that spans little more than a decade: plain numbers ("0.02"), which
# read without counting minor ticks, rather than powers of ten.
_PLAIN = FuncFormatter(lambda v, _: f"{v:.6g}")


def label_log_axis(axis):
    """Makes a log axis show at least two labelled ticks.

    Matplotlib labels only powers of ten (and, below about one decade, some minor ticks), so an
    axis from 0.004 to 0.06 reads "10^-2" and nothing else: the reader cannot tell the scale.
    Tries, in order, matplotlib's ticks, then 1-2-5 per decade, then every integer multiple, then
    evenly spaced round numbers (a range narrower than a factor 10/9); call it once the limits are
    final (save() does, for every log axis of the figure).
    """
    if axis.get_scale() != "log" or len(labelled_ticks(axis)) >= 2:
        return
    for subs in ((1.0, 2.0, 5.0), tuple(float(k) for k in range(1, 10))):
        axis.set_major_locator(LogLocator(base=10, subs=subs, numticks=30))
        axis.set_major_formatter(_PLAIN)
        axis.set_minor_locator(LogLocator(base=10, subs=tuple(range(1, 10)), numticks=30))
        axis.set_minor_formatter(NullFormatter())
        if len(labelled_ticks(axis)) >= 2:
            return
    axis.set_major_locator(MaxNLocator(nbins=4, min_n_ticks=2))


def label_log_axes(fig):
    """label_log_axis for both axes of every panel of `fig`."""
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            label_log_axis(axis)


def save(fig, directory, number):
    """Writes DIR/figureN.png (150 dpi) and DIR/figureN.svg, and closes the figure.

    Every log axis gets at least two labelled ticks first (label_log_axes).
    """
    directory = Path(directory)
    label_log_axes(fig)
    fig.tight_layout()
    png = directory / f"figure{number}.png"
    svg = directory / f"figure{number}.svg"
    fig.savefig(png, dpi=150)
    fig.savefig(svg)
    plt.close(fig)
    print(f"wrote {png} and {svg}")
    return png, svg


def figure_main(draw, argv=None):
    """Entry point of a figure script: parses DIR from the command line, calls draw(DIR).

    Exit codes: 0 drawn, 1 missing or malformed data (message on stderr), 2 bad usage.
    """
    argv = sys.argv if argv is None else argv
    script = os.path.basename(argv[0]) if argv else "figure"
    if len(argv) != 2:
        print(f"usage: {script} DIR   (DIR holds the CSV files of `implicit reproduce`)",
              file=sys.stderr)
        sys.exit(2)
    directory = Path(argv[1])
    if not directory.is_dir():
        print(f"{script}: error: {directory}: expected a folder with the experiment CSV files, "
              f"got no such folder", file=sys.stderr)
        sys.exit(2)
    try:
        draw(directory)
    except DataError as e:
        print(f"{script}: error: {e}", file=sys.stderr)
        sys.exit(1)


# Cells per image pixel at most: a 5 cm wall is far below a pixel of the panel, so blocks of
# cells are drawn occupied when any of their cells is.
MAP_PIXELS = 500


def map_image(cells, name):
    """The occupied cells as an image (1 occupied, 0 not), pooled to about MAP_PIXELS across,
    and its extent in metres."""
    res = cells["resolution_m"]
    if not np.all(np.isfinite(res)) or np.any(res <= 0) or np.ptp(res) > 0:
        raise DataError(f"{name}: column 'resolution_m': expected one positive value in every "
                        f"row, got {np.unique(res)[:5]}")
    h = float(res[0])
    x0, y0 = cells["x_m"].min(), cells["y_m"].min()
    ix = np.rint((cells["x_m"] - x0) / h).astype(int)
    iy = np.rint((cells["y_m"] - y0) / h).astype(int)
    block = max(1, int(np.ceil(max(ix.max(), iy.max()) / MAP_PIXELS)))
    ix, iy = ix // block, iy // block
    image = np.zeros((iy.max() + 1, ix.max() + 1))
    image[iy, ix] = 1.0
    b = h * block
    left, bottom = x0 - h / 2, y0 - h / 2
    return image, (left, left + b * (ix.max() + 1), bottom, bottom + b * (iy.max() + 1))


def label_error_axis(ax, low, high):
    """A log y-axis from `low` to `high` with labels at 1, 2 and 5 of each decade, so that an
    error axis reads without counting minor ticks."""
    ax.set_yscale("log")
    ax.set_ylim(low, high)
    ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_minor_formatter(NullFormatter())
