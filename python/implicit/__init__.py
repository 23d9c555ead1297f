"""implicit: implicit sampling for Monte Carlo localization, SLAM and path integral control.

The package wraps the C++ library of the same name. Arrays go in and come out as numpy float64
arrays; large results (samples, weights, particles) are handed over without copies.

Core (spec §1):
    sample(F, x0, n, ...)       weighted samples of exp(-F) by implicit sampling; starts=...:
                                the mixture over several minima (SamplerWarning otherwise)
    resample(weights, ...)      multinomial, systematic, stratified or residual ancestors
    ess(weights), log_sum_exp(a)

Robotics (spec §3): implicit.models (Ute, Unicycle, RangeBearing), implicit.data (carpark(),
victoria_park(), read_log(), simulate(), steps()), ParticleFilter, implicit.slam (Filter, run;
grid: grid SLAM on a laser log, its map a numpy array), implicit.mcl.run; implicit.laser
(occupancy grids, CARMEN logs, the likelihood field, the odometry model, a laser ParticleFilter
and run). Control (spec §2): implicit.control.
Trajectory scoring (APE, RPE as evo computes them): implicit.eval.
Data assimilation (spec §3.14): implicit.da (run: the benchmarks of `implicit da` as a dict;
Lorenz63, Lorenz96: the models, their RK4 steps and the steps' Jacobian).
Many runs (seeds x settings, optionally in worker processes, with a progress bar):
multi_run(fn, seeds, settings); summarize(rows) gives the mean and standard error per group.
Your own state-space model (numpy callbacks on all particles at once; bootstrap, implicit or
guided proposal on the library's engine): implicit.ssm (Model, particle_filter).

Errors are raised as implicit.InvalidArgument (a ValueError) with the library's message.

Example::

    import numpy as np, implicit
    r = implicit.sample(lambda x: 0.5 * x @ x, x0=np.zeros(2), n=1000, seed=1)
    r.samples.shape, r.weights.sum(), r.log_Z   # (1000, 2), 1.0, log(2 pi)
"""
from . import _paths

_paths.configure()

from ._core import SampleResult, SamplerWarning, ess, log_sum_exp, resample, sample  # noqa: E402
from ._implicit import InvalidArgument, ParseError, __version__  # noqa: E402
from ._implicit import ParticleFilter  # noqa: E402
from ._multi_run import MultiRunError, RunList, multi_run, summarize  # noqa: E402
from . import control, da, data, eval, laser, mcl, models, slam, ssm  # noqa: E402

__all__ = [
    "InvalidArgument",
    "MultiRunError",
    "ParseError",
    "ParticleFilter",
    "RunList",
    "SampleResult",
    "SamplerWarning",
    "__version__",
    "control",
    "da",
    "data",
    "ess",
    "eval",
    "laser",
    "log_sum_exp",
    "mcl",
    "models",
    "multi_run",
    "resample",
    "sample",
    "slam",
    "ssm",
    "summarize",
]
