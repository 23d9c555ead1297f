#!/usr/bin/python3
"""Figure 12 (beyond the paper): data assimilation, rmse.a against N beside DAPPER.

Usage: /usr/bin/python3 python/plots/figure12.py <dir>

Reads, as `implicit reproduce --only da --out <dir>` writes it:
  table_da.csv   setting,method,members,jitter,inflation,resample_threshold,lag,bandwidth,
                 seeds,rmse_a_mean,rmse_a_lo,rmse_a_hi,spread_a,mean_ess,ms_per_cycle,
                 dapper_rmse_a: one row per configuration (the 95 % interval is empty for a
                 single seed; DAPPER's value is empty where it lists none; the bandwidth is the
                 implicit smoother's, empty for the filters)

One panel per setting (sakov2012: Lorenz-63; bocquet2010: Lorenz-96; its variant
bocquet2010-k4-q0.5, observed after every 4th interval with model noise 0.5, where implicit and
optimal-proposal sampling differ): rmse.a from 0 against N
on a log axis (a two-seed interval can reach below 0), a line per method through its
configurations with the interval as error bars (the implicit smoother with a kernel background,
bandwidth below 1, is a line of its own), and DAPPER's value for the same method and N as an open
marker in the method's colour.
Writes <dir>/figure12.png and <dir>/figure12.svg.
"""
import numpy as np

from common import COLORS, DataError, figure_main, load_csv, save, subplots

SETTINGS = (("sakov2012", "Lorenz-63 (sakov2012)"),
            ("bocquet2010", "Lorenz-96, n = 10 (bocquet2010)"),
            ("bocquet2010-k4-q0.5", "Lorenz-96, observed every 4th interval, q = 0.5"))
METHODS = (("etkf", "ETKF", COLORS["ekf"], "s"),
           ("enkf", "EnKF (perturbed obs.)", COLORS["fastslam1"], "D"),
           ("bootstrap", "bootstrap PF", COLORS["standard"], "o"),
           ("implicit", "implicit PF", COLORS["implicit"], "^"),
           ("implicit-smoother", "implicit smoother", COLORS["implicit-rb"], "v"),
           ("implicit-smoother-kernels", "implicit smoother, kernels", COLORS["fastslam2"], "P"))
# The series of a row: its method, or the smoother's kernel variant (bandwidth below 1).
KERNELS = "implicit-smoother-kernels"


def draw(d):
    t = load_csv(d, "table_da.csv", ["members", "bandwidth", "rmse_a_mean", "rmse_a_lo",
                                     "rmse_a_hi", "dapper_rmse_a"], ["setting", "method"])
    known = {m for m, _, _, _ in METHODS} - {KERNELS}
    for i, (setting, method) in enumerate(zip(t["setting"], t["method"])):
        if setting not in dict(SETTINGS) or method not in known:
            raise DataError(f"{d}/table_da.csv:{i + 2}: expected a setting in "
                            f"{', '.join(dict(SETTINGS))} and a method in {', '.join(sorted(known))}, "
                            f"got '{setting}', '{method}'")
    series = np.where((t["method"] == "implicit-smoother") & (t["bandwidth"] < 1.0), KERNELS,
                      t["method"])
    fig, ax = subplots(1, 3, width=17, height=4.8)
    for a, (setting, title) in zip(ax, SETTINGS):
        drawn = False
        for method, name, color, marker in METHODS:
            rows = np.flatnonzero((t["setting"] == setting) & (series == method))
            if rows.size == 0:
                continue
            rows = rows[np.argsort(t["members"][rows], kind="stable")]
            n, mean = t["members"][rows], t["rmse_a_mean"][rows]
            lo, hi = t["rmse_a_lo"][rows], t["rmse_a_hi"][rows]
            # Error bars where there is an interval (more than one seed).
            err = np.vstack([np.where(np.isfinite(lo), mean - lo, 0.0),
                             np.where(np.isfinite(hi), hi - mean, 0.0)])
            a.errorbar(n, mean, yerr=err, color=color, marker=marker, ms=5, lw=1.2, capsize=3,
                       label=name)
            dapper = t["dapper_rmse_a"][rows]
            keep = np.isfinite(dapper)
            if keep.any():
                a.plot(n[keep], dapper[keep], linestyle="none", marker=marker, ms=9,
                       markerfacecolor="none", markeredgecolor=color, markeredgewidth=1.5,
                       label=f"{name}: DAPPER")
            drawn = True
        if not drawn:
            a.text(0.5, 0.5, "no configuration of this setting ran", transform=a.transAxes,
                   ha="center", va="center")
            a.set_axis_off()
            continue
        a.set_xscale("log")
        a.set_ylim(bottom=0.0)
        a.set_xlabel("N (members or particles)")
        a.set_ylabel("rmse.a")
        a.set_title(title)
        a.grid(True, which="major", alpha=0.3)
        a.legend(fontsize=7)
    save(fig, d, 12)


if __name__ == "__main__":
    figure_main(draw)
