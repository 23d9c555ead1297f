"""Data assimilation (spec §3.14): the benchmarks of `implicit da` and the Lorenz models.

    run(model="lorenz63", method="etkf", members=10, seeds=10, ...)   `implicit da --json`
    Lorenz63(sigma=10, rho=28, beta=8/3)                               3 variables
    Lorenz96(n, forcing=8)                                             n >= 4 variables

Each model has tendency(x) (dx/dt) and steps(x, dt, k, jacobian=False): the state after k
classical RK4 steps of length dt and, with jacobian=True, also the derivative of that k-step map
at x (the tangent linear of every RK4 stage: exact for the discrete map).

Example::

    import implicit
    r = implicit.da.run(method="etkf", members=10, seeds=2, cycles=100, seed=1)
    r["rmse_a"]["mean"], [run["rmse_a"] for run in r["runs"]]
"""
import json

from ._implicit import da as _da
from ._implicit.da import Lorenz63, Lorenz96

__all__ = ["Lorenz63", "Lorenz96", "run"]


def run(model="lorenz63", method="etkf", members=10, seeds=10, seed=1, jitter=0.0,
        regularisation="iso", inflation=1.0, resample_threshold=0.5, map="linear", lag=None,
        starts=None, bandwidth=1.0, obs_every=1, model_noise=0.0, cycles=0, dim=10, forcing=8.0,
        threads=None, progress=None):
    """Runs `implicit da` with these settings and returns its JSON result as a dict.

    Each argument is the flag of the same name (docs/cli.md, "implicit da"), with its default:
    model "lorenz63" (the setting sakov2012) or "lorenz96" (bocquet2010, dim n >= 4 and
    forcing F); method "bootstrap" or "implicit" (particle filters), "enkf" (perturbed
    observations), "etkf" or "implicit-smoother" (its window lag L in [1, 1000] cycles; None:
    the tool's default 3; refused with the filters) and starts (its Newton starts per window in
    [1, 1000]: the background and the heaviest members; None: the tool's default 3; refused with
    the filters) and bandwidth (its kernel bandwidth h in (0, 1]: below 1 a kernel per member;
    refused below 1 with the filters); members N >= 2; seeds independent runs with the seeds seed,
    seed + 1, ...; jitter the regularisation's size (required > 0 for "implicit"),
    regularisation "iso" or "cov"; inflation >= 1 (enkf, etkf); resample_threshold in [0, 1]
    (particle filters); map "linear" or "random" (implicit); obs_every K >= 1, the model
    intervals per observation, and model_noise q >= 0, the std of the noise N(0, q^2 I) after
    every interval (K > 1 or q > 0: the variant "<setting>-k<K>-q<q>", where implicit and
    optimal-proposal sampling differ); cycles the observation cycles (0: the setting's, 1000 or
    1280, divided by K). threads None or 0: all cores. progress, if given, is called
    as progress(seeds done, seeds in all) with the interpreter's lock held, at most about 10
    times a second and once more with done = total at the end; an exception it raises stops the
    run (no other seed starts) and reaches the caller unchanged. The result does not depend on
    threads or progress.

    Returns:
        dict with the keys of `implicit da --json` (rmse_a {mean, sd, ci95}, spread_a, mean_ess,
        runs [{seed, rmse_a, ...}], ...), the same numbers for the same seed; the timing keys
        (ms_per_cycle, seconds) and threads differ from run to run. A filter that diverged (its
        analysis mean left the finite numbers) is no exception: diverged_runs counts those runs,
        each gives its diverged_at_cycle, and their scores and the summary's are None.

    Raises:
        implicit.InvalidArgument (a ValueError) naming the argument, for a value the tool
        refuses (members in [2, 10^7], inflation in [1, 1000], a str for a number, a float for a
        count, ...); the filter's own refusals (jitter 0 with method "implicit") with the tool's
        message. Nothing runs before every argument is checked.
    """
    settings = dict(model=model, method=method, members=members, seeds=seeds, jitter=jitter,
                    regularisation=regularisation, inflation=inflation,
                    resample_threshold=resample_threshold, map=map, lag=lag, starts=starts,
                    bandwidth=bandwidth, obs_every=obs_every, model_noise=model_noise,
                    cycles=cycles, dim=dim, forcing=forcing)
    return json.loads(_da._run(settings, seed, 0 if threads is None else threads, progress))
