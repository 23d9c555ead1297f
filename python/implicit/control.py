"""Path integral control (paper §3): the double slit, the robot arm and Himmelblau problems.

One control estimate at a state:

    slit = DoubleSlit()                                  # Table 1's parameters
    estimate_control(slit, x=1.0, k=0, samples=50, estimator="corrected", seed=1)
    estimate_control("himmelblau", x=[-1.0, -4.0], k=0, samples=50, seed=3)

The closed-loop studies of the command-line tool, as dicts of its JSON:

    double_slit(samples=50, runs=500, mode="corrected", seed=1)   `implicit slit --json`
    arm(seed=1)                                                    `implicit arm --json`
    himmelblau(runs=70, samples=50, seed=1)                        `implicit himmelblau --json`
"""
import json

from . import _implicit
from ._core import _count
from ._implicit.control import DoubleSlit, himmelblau_control

__all__ = ["DoubleSlit", "arm", "double_slit", "estimate_control", "himmelblau",
           "himmelblau_control"]


def estimate_control(problem, x, k=0, samples=50, estimator="corrected", seed=1, step=0):
    """The path integral control at state x and grid step k (t = k dt), from `samples` samples.

    Args:
        problem: a DoubleSlit, or "himmelblau" (the Table 4 problem with its defaults).
        x: the state (a float for the double slit, (2,) for Himmelblau).
        k: grid step.
        samples: reference samples M (per slit for the corrected double-slit estimator).
        estimator: double slit only: "paper" (dominant slit, unweighted; biased), "corrected"
            (both slits, exact weights, frozen wall) or "plain" (plain finite differences).
            Himmelblau uses implicit sampling with the linear map.
        seed, step: the random stream (seed, step, ...) of the reference samples.

    Returns:
        dict with "u" (float or (2,)), "log_psi", "ess" and diagnostics.
    """
    if isinstance(problem, DoubleSlit):
        # Passed as given: the compiled side refuses a float count or a negative seed, naming
        # the argument (int() would truncate 2.5 samples to 2 without a word).
        return problem.estimate_control(x, k, samples, estimator, seed, step)
    if problem == "himmelblau":
        if estimator not in ("corrected", "implicit"):
            raise ValueError(f"estimate_control: the Himmelblau problem has one estimator "
                             f"(implicit sampling), got '{estimator}'")
        return himmelblau_control(x, k, samples, seed, step)
    raise ValueError(f"estimate_control: problem: expected a DoubleSlit or 'himmelblau', "
                     f"got {problem!r}")


def _json(text):
    return json.loads(text)


def double_slit(samples=50, runs=500, mode="corrected", seed=1, out=None, threads=0,
                estimator="generic"):
    """The double slit closed loop (Table 2): mode "paper" (estimator P) or "corrected" (W2).

    estimator: "generic" (the library's path integral estimator) or "wall-space" (the double
    slit's own, the same runs to rounding). Returns the dict of `implicit slit --json`
    (error_x_mean, error_u_mean in %, ...).
    """
    return _json(_implicit._run_slit(_count(samples, "samples", 1), _count(runs, "runs", 1), mode,
                                     str(estimator), seed, out, threads))


def arm(seed=1, out=None, threads=0, estimator="generic"):
    """The two-link robot arm against LQR (Figure 4); the dict of `implicit arm --json`.

    estimator: "generic" (the library's path integral estimator on each joint, a control problem
    with partial noise) or "closed-form" (each joint's path integral in closed form, faster).
    """
    return _json(_implicit._run_arm(str(estimator), seed, out, threads))


def himmelblau(runs=70, samples=50, seed=1, out=None, threads=0):
    """The Himmelblau control problem (Table 4); the dict of `implicit himmelblau --json`."""
    return _json(_implicit._run_himmelblau(_count(runs, "runs", 1), _count(samples, "samples", 1),
                                           seed, out, threads))
