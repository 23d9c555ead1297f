"""implicit.da with bad input: run() refuses what `implicit da` refuses and the models refuse
wrong shapes, NaN, negative step counts and non-positive steps, as implicit.InvalidArgument (a
ValueError) naming the argument, before anything runs."""
import math

import numpy as np
import pytest

import implicit


def run(**changes):
    return lambda: implicit.da.run(**{"seeds": 1, "cycles": 5, **changes})


L63, L96 = implicit.da.Lorenz63(), implicit.da.Lorenz96(5)
SEED = r"expected an integer in \[0, 2\^64 - 1\], got "
BAD = [
    # run(): the ranges and choices of `implicit da`'s flags
    (run(model="lorenz84"), r"^model: expected 'lorenz63' or 'lorenz96', got 'lorenz84'$"),
    (run(model=63), r"^model: expected 'lorenz63' or 'lorenz96', got int$"),
    (run(method="kalman"), r"^method: expected 'bootstrap', 'implicit', 'enkf', 'etkf' or "
     r"'implicit-smoother', got 'kalman'$"),
    (run(method="implicit-smoother", lag=0), r"^lag: expected an integer in \[1, 1000\], got 0$"),
    (run(method="implicit-smoother", lag=1001),
     r"^lag: expected an integer in \[1, 1000\], got 1001$"),
    (run(method="implicit-smoother", lag=2.0),
     r"^lag: expected an integer in \[1, 1000\], got float$"),
    (run(method="etkf", lag=2), r"--lag is the window length of the implicit smoother"),
    (run(method="implicit-smoother", starts=0),
     r"^starts: expected an integer in \[1, 1000\], got 0$"),
    (run(method="implicit-smoother", starts=1001),
     r"^starts: expected an integer in \[1, 1000\], got 1001$"),
    (run(method="implicit-smoother", starts=2.0),
     r"^starts: expected an integer in \[1, 1000\], got float$"),
    (run(method="enkf", starts=2), r"--starts is the implicit smoother's number of Newton starts"),
    (run(method="implicit-smoother", bandwidth=1.5),
     r"^bandwidth: expected a number in \[0, 1\], got 1\.5$"),
    (run(method="implicit-smoother", bandwidth=math.nan),
     r"^bandwidth: expected a number in \[0, 1\], got nan$"),
    (run(method="implicit-smoother", bandwidth="0.5"),
     r"^bandwidth: expected a number in \[0, 1\], got str$"),
    (run(method="implicit-smoother", bandwidth=0.0), r"kernel bandwidth h in \(0, 1\], got 0"),
    (run(method="etkf", bandwidth=0.5), r"--bandwidth is the implicit smoother's kernel bandwidth"),
    (run(method="implicit-smoother", map="random"), r"--map is the implicit particle filter's"),
    (run(method="implicit-smoother", jitter=0.1), r"--jitter and --regularisation are the particle"),
    (run(method="implicit-smoother", resample_threshold=0.9),
     r"--resample-threshold is the particle filters'"),
    (run(method=None), r"^method: expected .* got NoneType$"),
    (run(members=1), r"^members: expected an integer in \[2, 10000000\], got 1$"),
    (run(members=10**7 + 1), r"^members: expected an integer in \[2, 10000000\], got 10000001$"),
    (run(members=10.0), r"^members: expected an integer in \[2, 10000000\], got float$"),
    (run(members=True), r"^members: expected an integer in \[2, 10000000\], got bool$"),
    (run(seeds=0), r"^seeds: expected an integer in \[1, 100000\], got 0$"),
    (run(seeds=2**64), r"^seeds: expected an integer in \[1, 100000\], got 18446744073709551616$"),
    (run(seed=-1), r"^seed: " + SEED + "-1$"),
    (run(seed=2**64), r"^seed: " + SEED + "18446744073709551616$"),
    (run(seed=1.0), r"^seed: " + SEED + "float$"),
    (run(jitter=-0.1), r"^jitter: expected a number in \[0, 1000000\], got -0\.1$"),
    (run(jitter=math.nan), r"^jitter: expected a number in \[0, 1000000\], got nan$"),
    (run(jitter="0.3"), r"^jitter: expected a number in \[0, 1000000\], got str$"),
    (run(regularisation="gauss"), r"^regularisation: expected 'iso' or 'cov', got 'gauss'$"),
    (run(inflation=0.9), r"^inflation: expected a number in \[1, 1000\], got 0\.9$"),
    (run(inflation=math.inf), r"^inflation: expected a number in \[1, 1000\], got inf$"),
    (run(resample_threshold=1.5),
     r"^resample_threshold: expected a number in \[0, 1\], got 1\.5$"),
    (run(resample_threshold=math.nan),
     r"^resample_threshold: expected a number in \[0, 1\], got nan$"),
    (run(map="curved"), r"^map: expected 'linear' or 'random', got 'curved'$"),
    (run(obs_every=0), r"^obs_every: expected an integer in \[1, 10000\], got 0$"),
    (run(obs_every=2.0), r"^obs_every: expected an integer in \[1, 10000\], got float$"),
    (run(model_noise=-0.1), r"^model_noise: expected a number in \[0, 1000000\], got -0\.1$"),
    (run(model_noise=math.nan), r"^model_noise: expected a number in \[0, 1000000\], got nan$"),
    (run(model_noise="0.1"), r"^model_noise: expected a number in \[0, 1000000\], got str$"),
    (run(method="implicit-smoother", obs_every=2), r"one model interval per observation"),
    (run(method="implicit", obs_every=2, jitter=0.5, regularisation="cov"),
     r"2 model intervals per observation"),
    (run(cycles=-1), r"^cycles: expected an integer in \[0, 100000000\], got -1$"),
    (run(cycles=2.5), r"^cycles: expected an integer in \[0, 100000000\], got float$"),
    (run(dim=3), r"^dim: expected an integer in \[4, 100000\], got 3$"),
    (run(dim=100001), r"^dim: expected an integer in \[4, 100000\], got 100001$"),
    (run(forcing=math.nan), r"^forcing: expected a number in \[-1000000, 1000000\], got nan$"),
    (run(forcing=2e6), r"^forcing: expected a number in \[-1000000, 1000000\], got 2000000$"),
    (run(threads=-1), r"^threads: expected an integer in \[0, 1024\], got -1$"),
    (run(threads=1025), r"^threads: expected an integer in \[0, 1024\], got 1025$"),
    (run(threads=1.0), r"^threads: expected an integer in \[0, 1024\], got float$"),
    (run(progress=3), r"^progress: expected a callable progress\(done, total\) or None, got int$"),
    # ... within the ranges, the filter's own refusal (both models are deterministic)
    (run(method="implicit", jitter=0.0), r"implicit"),
    # the models
    (lambda: implicit.da.Lorenz63(sigma=math.nan), r"^sigma: expected a finite number, got nan$"),
    (lambda: implicit.da.Lorenz63(rho="28"), r"^rho: expected a finite number, got str$"),
    (lambda: implicit.da.Lorenz63(beta=math.inf), r"^beta: expected a finite number, got inf$"),
    (lambda: implicit.da.Lorenz96(3), r"^n: expected an integer in \[4, 100000\], got 3$"),
    (lambda: implicit.da.Lorenz96(-5), r"^n: expected an integer in \[4, 100000\], got -5$"),
    (lambda: implicit.da.Lorenz96(10.0), r"^n: expected an integer in \[4, 100000\], got float$"),
    (lambda: implicit.da.Lorenz96(10, forcing=math.nan),
     r"^forcing: expected a finite number, got nan$"),
    (lambda: L63.tendency([1.0, 2.0]), r"^x: expected shape \(3,\), got shape \(2,\)$"),
    (lambda: L63.tendency([1.0, math.nan, 2.0]),
     r"^x: expected finite values, got nan at flat index 1$"),
    (lambda: L63.steps(np.zeros(4), 0.01, 1), r"^x: expected shape \(3,\), got shape \(4,\)$"),
    (lambda: L63.steps(np.zeros((3, 1)), 0.01, 1),
     r"^x: expected shape \(3,\), got shape \(3, 1\)$"),
    (lambda: L63.steps([0.0, math.inf, 0.0], 0.01, 1), r"^x: expected finite values, got inf"),
    (lambda: L63.steps("abc", 0.01, 1), r"^x: expected an array of numbers, got str$"),
    (lambda: L63.steps(np.zeros(3), 0.0, 1), r"^dt: expected a finite number > 0, got 0$"),
    (lambda: L63.steps(np.zeros(3), -0.01, 1), r"^dt: expected a finite number > 0, got -0\.01$"),
    (lambda: L63.steps(np.zeros(3), math.nan, 1), r"^dt: expected a finite number > 0, got nan$"),
    (lambda: L63.steps(np.zeros(3), math.inf, 1), r"^dt: expected a finite number > 0, got inf$"),
    (lambda: L63.steps(np.zeros(3), 0.01, -1), r"^k: expected an integer in \[0, 2147483647\], "
     r"got -1$"),
    (lambda: L63.steps(np.zeros(3), 0.01, 2.0), r"^k: expected an integer in .* got float$"),
    (lambda: L63.steps(np.zeros(3), 0.01, 2**31), r"^k: expected an integer in .* got 2147483648$"),
    (lambda: L63.steps(np.zeros(3), 0.01, 1, jacobian=1),
     r"^jacobian: expected True or False, got int$"),
    (lambda: L96.tendency(np.zeros(4)), r"^x: expected shape \(5,\), got shape \(4,\)$"),
    (lambda: L96.steps(np.zeros(6), 0.05, 1), r"^x: expected shape \(5,\), got shape \(6,\)$"),
    (lambda: L96.steps([0, 0, math.nan, 0, 0], 0.05, 1),
     r"^x: expected finite values, got nan at flat index 2$"),
    (lambda: L96.steps(np.zeros(5), -1.0, 1), r"^dt: expected a finite number > 0, got -1$"),
    (lambda: L96.steps(np.zeros(5), 0.05, -3), r"^k: expected an integer in .* got -3$"),
    (lambda: L96.steps(np.zeros(5), 0.05, 1, jacobian="yes"),
     r"^jacobian: expected True or False, got str$"),
]


@pytest.mark.parametrize("call,message", BAD, ids=[f"row{k}" for k in range(len(BAD))])
def test_bad_da_arguments_are_named(call, message):
    with pytest.raises(implicit.InvalidArgument, match=message):
        call()
