"""implicit.da: run() is `implicit da --json` (same keys, same bits for the same seed), the Lorenz
models' steps and their Jacobian (spec §3.14), progress=."""
import math
import re
import subprocess

import numpy as np
import pytest

import implicit
from implicit import _implicit

# Wall-clock keys and the worker count differ from run to run; everything else is the same bits.
TIMING = ("ms_per_cycle", "seconds", "threads")
PROVENANCE = {"version", "commit"}  # the tool's printout adds them to every result


def without_timing(r):
    out = {k: v for k, v in r.items() if k not in TIMING}
    out["runs"] = [{k: v for k, v in run.items() if k not in TIMING} for run in r["runs"]]
    return out


# Few cycles: sakov2012 scores the cycles after 4 time units (16 cycles), bocquet2010 after 20
# (400 cycles).
@pytest.mark.parametrize("kw,flags", [
    (dict(model="lorenz63", method="bootstrap", members=30, jitter=0.3, cycles=40),
     ["--model", "lorenz63", "--method", "bootstrap", "-N", "30", "--jitter", "0.3",
      "--cycles", "40"]),
    (dict(model="lorenz96", method="etkf", members=10, inflation=1.05, dim=12, cycles=420),
     ["--model", "lorenz96", "--method", "etkf", "-N", "10", "--inflation", "1.05", "--dim", "12",
      "--cycles", "420"]),
    (dict(model="lorenz63", method="implicit-smoother", members=20, lag=2, cycles=30),
     ["--model", "lorenz63", "--method", "implicit-smoother", "-N", "20", "--lag", "2",
      "--cycles", "30"]),
    (dict(model="lorenz96", method="implicit", members=10, obs_every=4, model_noise=0.3,
          cycles=110),
     ["--model", "lorenz96", "--method", "implicit", "-N", "10", "--obs-every", "4",
      "--model-noise", "0.3", "--cycles", "110"]),
    (dict(model="lorenz63", method="implicit-smoother", members=12, starts=1, cycles=30),
     ["--model", "lorenz63", "--method", "implicit-smoother", "-N", "12", "--starts", "1",
      "--cycles", "30"]),
    (dict(model="lorenz63", method="implicit-smoother", members=12, bandwidth=0.6, cycles=30),
     ["--model", "lorenz63", "--method", "implicit-smoother", "-N", "12", "--bandwidth", "0.6",
      "--cycles", "30"]),
])
def test_run_equals_the_cli_json(cli, kw, flags):
    py = implicit.da.run(seeds=2, seed=7, **kw)
    tool = {k: v for k, v in cli("da", "--seeds", "2", "--seed", "7", *flags).items()
            if k not in PROVENANCE}
    assert set(py) == set(tool)
    assert without_timing(py) == without_timing(tool)  # floats compared exactly
    assert py["seeds"] == 2 and len(py["runs"]) == 2 and py["cycles"] == kw["cycles"]
    smoother = kw["method"] == "implicit-smoother"
    assert py["starts"] == (kw.get("starts", 3) if smoother else None)
    assert py["bandwidth"] == (kw.get("bandwidth", 1.0) if smoother else None)


def test_run_does_not_depend_on_threads_or_progress():
    calls = []
    one = implicit.da.run(method="enkf", members=8, seeds=3, cycles=20, threads=1)
    two = implicit.da.run(method="enkf", members=8, seeds=3, cycles=20, threads=2,
                          progress=lambda done, total: calls.append((done, total)))
    assert without_timing(one) == without_timing(two)
    assert calls and calls[-1] == (3, 3)
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))  # monotone


def test_progress_exception_reaches_the_caller():
    class Stop(Exception):
        pass

    def stop(done, total):
        raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        implicit.da.run(method="etkf", seeds=4, cycles=20, threads=1, progress=stop)


def test_rmse_summary_reproduces_from_the_runs():
    # rmse_a.mean is the mean of the per-run rmse.a, sd their sample standard deviation and
    # ci95 mean +- t_{0.975, n-1} sd / sqrt(n) (docs/cli.md, "implicit da"); t_{0.975, 2} =
    # 4.303 from the table of experiments/da.cpp. Only the order of the additions may differ:
    # tolerances of a few ulps.
    r = implicit.da.run(method="etkf", members=10, seeds=3, cycles=60, seed=11)
    per_run = [run["rmse_a"] for run in r["runs"]]
    assert [run["seed"] for run in r["runs"]] == [11, 12, 13]
    mean = sum(per_run) / 3
    sd = math.sqrt(sum((x - mean) ** 2 for x in per_run) / 2)
    assert r["rmse_a"]["mean"] == pytest.approx(mean, rel=1e-14)
    assert r["rmse_a"]["sd"] == pytest.approx(sd, rel=1e-12)
    half = 4.303 * sd / math.sqrt(3)
    assert r["rmse_a"]["ci95"] == pytest.approx([mean - half, mean + half], rel=1e-12)
    assert r["spread_a"] == pytest.approx(sum(run["spread_a"] for run in r["runs"]) / 3,
                                          rel=1e-14)


def test_one_seed_has_no_interval():
    r = implicit.da.run(seeds=1, cycles=20)
    assert r["rmse_a"]["ci95"] is None and r["rmse_a"]["mean"] == r["runs"][0]["rmse_a"]


X63 = np.array([1.509, -1.531, 25.46])


def test_lorenz63_tendency_is_the_formula():
    l = implicit.da.Lorenz63(sigma=9.0, rho=27.0, beta=2.5)
    x, y, z = X63
    np.testing.assert_array_equal(l.tendency(X63),
                                  [9.0 * (y - x), x * (27.0 - z) - y, x * y - 2.5 * z])
    assert (l.sigma, l.rho, l.beta, l.dim) == (9.0, 27.0, 2.5, 3)


def test_lorenz63_steps_are_rk4():
    # One step by hand: the classical RK4 weights 1/6, 2/6, 2/6, 1/6 of the formula's tendency.
    l, dt = implicit.da.Lorenz63(), 0.01
    k1 = l.tendency(X63)
    k2 = l.tendency(X63 + 0.5 * dt * k1)
    k3 = l.tendency(X63 + 0.5 * dt * k2)
    k4 = l.tendency(X63 + dt * k3)
    np.testing.assert_allclose(l.steps(X63, dt, 1), X63 + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4),
                               rtol=1e-15, atol=1e-14)
    np.testing.assert_array_equal(l.steps(X63, dt, 0), X63)
    np.testing.assert_array_equal(l.steps(l.steps(X63, dt, 10), dt, 15), l.steps(X63, dt, 25))


@pytest.mark.parametrize("model,x0", [
    (implicit.da.Lorenz63(), X63),
    (implicit.da.Lorenz96(6, forcing=8.0), np.array([8.1, 7.3, 9.0, 6.2, 8.8, 7.7])),
])
def test_steps_jacobian_against_central_differences(model, x0):
    # The 25-step map (one sakov2012 cycle for Lorenz-63) is smooth, so central differences with
    # step h have error O(h^2 |M'''|) plus round-off O(eps |M| / h); h = 1e-5 balances them
    # near 1e-7 relative to the Jacobian's size (entries O(1-10) here), so 1e-5 * max|J| is a
    # bound with two orders of margin, while a wrong stage (an O(dt) error) would be far off.
    dt, k, h = 0.01, 25, 1e-5
    x, jac = model.steps(x0, dt, k, jacobian=True)
    np.testing.assert_array_equal(x, model.steps(x0, dt, k))
    n = len(x0)
    fd = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        fd[:, j] = (model.steps(x0 + e, dt, k) - model.steps(x0 - e, dt, k)) / (2 * h)
    assert jac.shape == (n, n)
    np.testing.assert_allclose(jac, fd, rtol=0, atol=1e-5 * np.abs(jac).max())


def test_lorenz96_tendency_is_the_formula():
    l = implicit.da.Lorenz96(5, forcing=3.0)
    x = np.array([1.0, 2.0, -1.0, 0.5, 4.0])
    want = [(x[(i + 1) % 5] - x[i - 2]) * x[i - 1] - x[i] + 3.0 for i in range(5)]
    np.testing.assert_allclose(l.tendency(x), want, rtol=1e-15)
    assert (l.n, l.dim, l.forcing) == (5, 5, 3.0)


def cli_da_ranges(cli_exe):
    out = subprocess.run([cli_exe, "da", "--help"], check=True, capture_output=True,
                         text=True).stdout
    pattern = re.compile(r"^\s+(?:-\w,)?(--[\w-]+) (INT|FLOAT):(?:INT|FLOAT) in \[(\S+) - (\S+)\]")
    return {m[1]: (m[2] == "INT", float(m[3]), float(m[4]))
            for m in map(pattern.match, out.splitlines()) if m}


def test_run_ranges_are_those_of_the_cli():
    # The oracle is the tool's --help: every range run() checks is its flag's, and every flag
    # with a range that run() takes is checked.
    import inspect
    import os
    import shutil
    exe = os.environ.get("IMPLICIT_CLI") or shutil.which("implicit")
    assert exe, "set IMPLICIT_CLI to the implicit executable"
    cli = cli_da_ranges(exe)
    assert len(cli) >= 8, "the --help format changed: no ranges found"
    table = _implicit.da._setting_ranges()
    keywords = set(inspect.signature(implicit.da.run).parameters)
    for r in table:
        assert r["key"] in keywords, r
        assert r["flag"] == "--" + r["key"].replace("_", "-"), r
        assert cli.get(r["flag"]) == (r["integer"], r["lo"], r["hi"]), r
    checked = {r["key"] for r in table}
    for flag in cli:
        key = flag[2:].replace("-", "_")
        assert key not in keywords or key in checked, f"da.run({key}=...) is not checked"
