"""Trajectory scoring: APE and RPE as the evo package computes them (user guide §10).

    ape(ref, est, align="none", ...)     absolute pose error of every associated pose pair
    rpe(ref, est, delta=1, ...)          relative pose error over pairs (i, j) of those

A trajectory is a numpy array with one pose per row: (n, 4) rows t, x, y, heading (a planar pose,
heading in radians) or (n, 8) rows t, x, y, z, qx, qy, qz, qw (the TUM format's columns); times
must increase. Each reference pose is paired with the estimated pose nearest in time (after
`offset` is added to the estimate's times) if within `max_diff` seconds. `align` ("none", "se2",
"se3", "sim3") first moves the estimate onto the reference by the least-squares (Umeyama)
transform. The result is a dict: per-pair arrays "translation_m", "rotation_deg" (degrees),
"full" (|E - I|, 4x4 Frobenius) and the times "t_i", "t_j" of each pair; "pairs" (associated
poses); "stats" (for each of the three: count, mean, median, rmse, max, min, std and 95 %
bootstrap intervals "mean_ci", "rmse_ci" drawn with `seed`); "alignment" (kind, rotation 3x3,
translation, scale). The numbers are those of `implicit eval --json` on the same files.
Bad arguments raise implicit.InvalidArgument naming the argument (and the row).

Example::

    import numpy as np, implicit
    t = np.arange(5.0)
    ref = np.column_stack([t, t, np.zeros(5), np.zeros(5)])           # along x
    est = ref + [0.0, 0.0, 0.1, 0.0]                                   # 0.1 m to the left
    implicit.eval.ape(ref, est)["stats"]["translation_m"]["rmse"]     # 0.1
"""
from . import _implicit
from ._implicit import InvalidArgument

__all__ = ["InvalidArgument", "ape", "rpe"]


def ape(ref, est, align="none", max_diff=0.01, offset=0.0, seed=1):
    """Absolute pose error: E = ref^-1 est for every associated pair (see the module doc)."""
    return _implicit.eval._ape(ref, est, align, max_diff, offset, seed)


def rpe(ref, est, delta=1, delta_unit="frames", all_pairs=False, align="none", max_diff=0.01,
        offset=0.0, seed=1):
    """Relative pose error: E = (ref_i^-1 ref_j)^-1 (est_i^-1 est_j) over pairs (i, j).

    j = i + delta (delta_unit "frames": an integer count of associated poses), or the first pose
    whose path length along the reference from i reaches delta (delta_unit "m"). Pairs do not
    overlap (evo's default) unless all_pairs=True.
    """
    return _implicit.eval._rpe(ref, est, delta, delta_unit, all_pairs, align, max_diff, offset,
                               seed)
