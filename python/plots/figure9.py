#!/usr/bin/python3
"""Figure 9 (beyond the paper): global localization and kidnapping, implicit against standard MCL.

Usage: /usr/bin/python3 python/plots/figure9.py <dir>

Reads <dir>/mcl_global_<method>_M<M>_errors.csv, written by `implicit mcl --init global --out
<dir>` (columns run,start_s,time_s,error_m,particles: the position error of the first runs per
step with truth, time from the log's first control), for method implicit and standard; when
several M are present, the largest of each method. When <dir> also holds
mcl_kidnap_<method>_M<M>_errors.csv (`implicit mcl --kidnap-at T --out <dir>`), a second row
shows the kidnapping runs.

Left panel implicit, right panel standard, all panels with one y-range: one line per run (told
apart by line style, named in the legend), error on a log axis, a dashed line at the 1 m success
threshold and a dotted line where each run's clock starts (the global start, or the end of the
kidnapping's dropped stretch, where the line breaks). Writes <dir>/figure9.png and
<dir>/figure9.svg.
"""
import re
from pathlib import Path

import numpy as np

from common import COLORS, DataError, figure_main, load_csv, save, subplots

METHODS = (("implicit", "implicit MCL"), ("standard", "standard (bootstrap) MCL"))
STUDIES = (("global", "global start"), ("kidnap", "kidnapping"))
# Errors below a millimetre (an exact zero included) are drawn at it, on the log axis.
ERROR_FLOOR = 1e-3
# Line styles of a panel's runs (the colour is the method's).
RUN_STYLES = ("-", "--", "-.", ":", (0, (6, 2, 1, 2, 1, 2)))


def largest(d, study, method):
    """The errors CSV of `study` and `method` with the largest M in d, or None."""
    best = None
    for p in Path(d).glob(f"mcl_{study}_{method}_M*_errors.csv"):
        m = re.fullmatch(rf"mcl_{study}_{method}_M(\d+)_errors\.csv", p.name)
        if m and (best is None or int(m.group(1)) > best[0]):
            best = (int(m.group(1)), p.name)
    return best


def with_gaps(t, e):
    """t, e with a NaN inserted where steps are more than 1 s apart (the kidnapping's dropped
    stretch), so the line breaks there instead of bridging the unseen part."""
    cut = np.nonzero(np.diff(t) > 1.0)[0] + 1
    return np.insert(t, cut, np.nan), np.insert(e, cut, np.nan)


def draw(d):
    rows = []
    for study, title in STUDIES:
        files = [largest(d, study, method) for method, _ in METHODS]
        if all(files):
            rows.append((study, title, files))
        elif study == "global":
            raise DataError(f"{d}: no mcl_global_implicit_M*_errors.csv and "
                            "mcl_global_standard_M*_errors.csv (run `implicit mcl --init global "
                            f"--out {d}` for both methods)")
    # One y-range for every panel, so that the methods and the studies compare at a glance.
    fig, ax = subplots(len(rows), 2, width=12, height=4.5 * len(rows), sharey=True, squeeze=False)
    for row, (study, title, files) in enumerate(rows):
        for col, ((method, name), (m, file)) in enumerate(zip(METHODS, files)):
            data = load_csv(d, file, ["run", "start_s", "time_s", "error_m"])
            a = ax[row, col]
            for k, r in enumerate(np.unique(data["run"])):
                sel = data["run"] == r
                t, e = with_gaps(data["time_s"][sel], data["error_m"][sel])
                # A floor keeps an exact zero on the log axis.
                a.plot(t, np.maximum(e, ERROR_FLOOR), lw=1, color=COLORS[method],
                       ls=RUN_STYLES[k % len(RUN_STYLES)], alpha=0.9,
                       label=f"run {int(r) + 1}, clock from {data['start_s'][sel][0]:g} s")
                a.axvline(data["start_s"][sel][0], color="grey", ls=":", lw=0.8,
                          label="a run's clock starts" if k == 0 else None)
            a.axhline(1.0, color="black", ls="--", lw=1, label="1 m (success threshold)")
            a.set_yscale("log")
            # Each panel keeps its own tick labels: the shared range reads in every panel.
            a.tick_params(labelleft=True)
            a.set_xlabel("time since the first control [s]")
            a.set_ylabel("position error [m]")
            a.set_title(f"{title}: {name}, M = {m}")
            # The runs first, then the two reference lines.
            handles, labels = a.get_legend_handles_labels()
            order = sorted(range(len(labels)), key=lambda i: not labels[i].startswith("run "))
            a.legend([handles[i] for i in order], [labels[i] for i in order], fontsize=7,
                     loc="lower left")
    save(fig, d, 9)


if __name__ == "__main__":
    figure_main(draw)
