"""implicit.mcl.run, implicit.slam.run, the landmark filters and data.steps with bad input:
each refuses what the command-line tool refuses, as implicit.InvalidArgument (a ValueError)
whose message names the argument (and the range), before anything runs."""
import inspect
import math
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

import implicit
from implicit import _implicit


def mcl(**changes):
    return lambda: implicit.mcl.run(**{"runs": 1, "particles": 5, **changes})


def slam(**changes):
    return lambda: implicit.slam.run(**{"datasets": 1, "particles": 5, **changes})


INT_MCL_M = r"an integer in \[1, 10000000\]"
BAD_RUNS = [
    # implicit.mcl.run: the ranges of `implicit mcl`'s flags
    (mcl(p=math.nan), r"^p: expected a number in \[0, 10\], got nan"),
    (mcl(p=-0.1), r"^p: expected a number in \[0, 10\], got -0\.1"),
    (mcl(p=10.5), r"^p: expected a number in \[0, 10\], got 10\.5"),
    (mcl(p="0.5"), r"^p: expected a number in \[0, 10\], got str"),
    (mcl(q=0.0), r"^q: expected a number in \[1e-06, 10\], got 0"),
    (mcl(range_sd=-1.0), r"^range_sd: expected a number in \[0, 100\], got -1"),
    (mcl(bearing_sd_deg=math.inf), r"^bearing_sd_deg: expected a number in \[0, 90\], got inf"),
    (mcl(bearing_sd_deg=-2.0), r"^bearing_sd_deg: expected a number in \[0, 90\], got -2"),
    (mcl(bearing_sd_deg=1.0, bearing_sd=2.0),
     r"^bearing_sd_deg: pass it or the deprecated bearing_sd, not both \(got 1\.0 and 2\.0\)"),
    (mcl(label_gate=-1.0), r"^label_gate: expected a number in \[0, 1000000\], got -1"),
    (mcl(label_gate=math.nan), r"^label_gate: expected a number in \[0, 1000000\], got nan"),
    (mcl(label_gate="9"), r"^label_gate: expected a number in \[0, 1000000\], got str"),
    (mcl(control_sd=[0.1, -0.1]), r"^control_sd\[1\]: expected a number in \[0, 100\], got -0\.1"),
    (mcl(control_sd=[0.1]), r"^control_sd: expected 2 numbers in \[0, 100\], got 1"),
    (mcl(state_sd=[0.1, 0.1, 0.0]), r"^state_sd\[2\]: expected a number in \[1e-09, 100\], got 0"),
    (mcl(state_sd=[0.1, math.nan, 0.1]), r"^state_sd\[1\]: expected a number in .* got nan"),
    (mcl(gps_std=0.0), r"^gps_std: expected a number in \[0\.001, 100\], got 0"),
    (mcl(particles=0), r"^particles: expected " + INT_MCL_M + ", got 0"),
    (mcl(particles=10_000_001), r"^particles: expected " + INT_MCL_M + ", got 10000001"),
    (mcl(particles=2**40), r"^particles: expected " + INT_MCL_M + ", got 1099511627776"),
    (mcl(particles=10**30), r"^particles: expected " + INT_MCL_M + ", got 10{30}$"),
    (mcl(particles=2.5), r"^particles: expected " + INT_MCL_M + ", got float"),
    (mcl(particles=True), r"^particles: expected " + INT_MCL_M + ", got bool"),
    (mcl(runs=2**31), r"^runs: expected an integer in \[1, 100000\], got 2147483648"),
    (mcl(runs=0), r"^runs: expected an integer in \[1, 100000\], got 0"),
    (mcl(reference_particles=0), r"^reference_particles: expected " + INT_MCL_M),
    (mcl(threads=-3), r"^threads: expected an integer in \[0, 1024\], got -3"),
    (mcl(threads=1025), r"^threads: expected an integer in \[0, 1024\], got 1025"),
    (mcl(seed=-1), r"^seed: expected an integer in \[0, 2\^64 - 1\], got -1"),
    (mcl(seed=2**64), r"^seed: expected an integer in \[0, 2\^64 - 1\], got 18446744073709551616"),
    (mcl(seed=1.0), r"^seed: expected an integer in \[0, 2\^64 - 1\], got float"),
    (mcl(start_span=-1.0), r"^start_span: expected a number in \[0, 1000000\], got -1"),
    (mcl(duration=math.nan), r"^duration: expected a number in \[0, 1000000\], got nan"),
    (mcl(kidnap_at=-5.0), r"^kidnap_at: expected a number in \[0, 1000000\], got -5"),
    (mcl(kidnap_at=5.0, kidnap_skip=0.0),
     r"^kidnap_skip: expected a number in \[1e-06, 1000000\], got 0"),
    (mcl(recovery_alpha_slow=0.0), r"^recovery_alpha_slow: expected a number in \[1e-09, 1\]"),
    (mcl(recovery_alpha_fast=2.0), r"^recovery_alpha_fast: expected a number in \[1e-09, 1\]"),
    (mcl(kidnap_probability=0.6), r"^kidnap_probability: expected a number in \[1e-300, 0\.5\]"),
    (mcl(kld_err=0.0), r"^kld_err: expected a number in \[1e-06, 1\], got 0"),
    (mcl(kld_z=11.0), r"^kld_z: expected a number in \[0, 10\], got 11"),
    (mcl(min_particles=0), r"^min_particles: expected " + INT_MCL_M + ", got 0"),
    (mcl(max_particles=10**8), r"^max_particles: expected " + INT_MCL_M + ", got 100000000"),
    (mcl(cover_spacing=0.01), r"^cover_spacing: expected a number in \[0\.05, 100\], got 0\.01"),
    (mcl(cover_headings=361), r"^cover_headings: expected an integer in \[1, 360\], got 361"),
    (mcl(clutter="yes"), r"^clutter: expected True or False, got str"),
    (mcl(kld=1), r"^kld: expected True or False, got int"),
    (mcl(method=3), r"^method: expected a str, got int"),
    (mcl(model=5), r"^model: expected a str, got int"),
    (mcl(data=5), r"^data: expected a path \(str or os\.PathLike\), got int"),
    (mcl(out=5), r"^out: expected a path \(str or os\.PathLike\), got int"),
    # ... the text settings: the tool's own check and message
    (mcl(method="x"), r"^mcl --method: expected 'standard' or 'implicit', got 'x'"),
    (mcl(init="nowhere"), r"^mcl --init: expected known or global, got 'nowhere'"),
    (mcl(model="tank"), r"^mcl --model: expected one of 'ute', 'unicycle'.*, got 'tank'"),
    # implicit.slam.run: the ranges of `implicit slam`'s flags
    (slam(particles=1_000_001), r"^particles: expected an integer in \[1, 1000000\], got 1000001"),
    (slam(particles=2**31), r"^particles: expected an integer in \[1, 1000000\], got 2147483648"),
    (slam(datasets=0), r"^datasets: expected an integer in \[1, 100000\], got 0"),
    (slam(laser_every=0), r"^laser_every: expected an integer in \[1, 10000\], got 0"),
    (slam(control_noise=0.0), r"^control_noise: expected a number in \[1e-06, 10\], got 0"),
    (slam(control_noise=math.nan), r"^control_noise: expected a number in \[1e-06, 10\], got nan"),
    (slam(min_range=-1.0), r"^min_range: expected a number in \[0, 100\], got -1"),
    (slam(range_sd=-0.5), r"^range_sd: expected a number in \[0, 100\], got -0\.5"),
    (slam(bearing_sd_deg=-1.0), r"^bearing_sd_deg: expected a number in \[0, 90\], got -1"),
    (slam(gate_chi2=-1.0), r"^gate_chi2: expected a number in \[0, 1000000\], got -1"),
    (slam(new_landmark_density=math.inf), r"^new_landmark_density: expected a number in "
     r"\[0, 1000000\], got inf"),
    (slam(control_sd=[1.0, 2.0, 3.0]), r"^control_sd: expected 2 numbers in \[0, 100\], got 3"),
    (slam(state_sd=[-1.0, 0.1, 0.1]), r"^state_sd\[0\]: expected a number in \[1e-09, 100\]"),
    (slam(threads=-3), r"^threads: expected an integer in \[0, 1024\], got -3"),
    (slam(seed=-1), r"^seed: expected an integer in \[0, 2\^64 - 1\], got -1"),
    (slam(association=None), r"^association: expected a str, got NoneType"),
    (slam(out=3.5), r"^out: expected a path"),
    (slam(method="kalman"), r"^SLAM method: expected ekf\|fastslam1\|.* got 'kalman'"),
    (slam(association="nearest"), r"^SLAM association: expected known\|ml, got 'nearest'"),
    # the control runs share seed, out and threads
    (lambda: implicit.control.himmelblau(runs=1, samples=5, seed=-1),
     r"^seed: expected an integer in \[0, 2\^64 - 1\], got -1"),
    (lambda: implicit.control.arm(threads=-3), r"^threads: expected an integer in \[0, 1024\]"),
]


@pytest.mark.parametrize("call,message", BAD_RUNS, ids=[f"row{k}" for k in range(len(BAD_RUNS))])
@pytest.mark.filterwarnings("ignore:.*bearing_sd is deprecated:DeprecationWarning")
def test_bad_run_settings_are_named(call, message):
    with pytest.raises(implicit.InvalidArgument, match=message):
        call()


UTE, SENSOR = implicit.models.Ute(), implicit.models.RangeBearing()


def particle_filter(**changes):
    return lambda: implicit.ParticleFilter(UTE, SENSOR, np.zeros((2, 2)),
                                           **{"particles": 5, **changes})


def slam_filter(**changes):
    return lambda: implicit.slam.Filter(**{"method": "fastslam1", "particles": 5, **changes})


def simulate(**changes):
    return lambda: implicit.data.simulate(UTE, SENSOR, **{"steps": 30, **changes})


def slit_control(**changes):
    return lambda: implicit.control.estimate_control(
        implicit.control.DoubleSlit(), **{"x": 1.0, "samples": 5, **changes})


def himmelblau_control(**changes):
    return lambda: implicit.control.estimate_control(
        "himmelblau", **{"x": [-1.0, -4.0], "samples": 5, **changes})


def before_initialize(what):
    pf = implicit.ParticleFilter(UTE, SENSOR, np.zeros((2, 2)), particles=5)
    return lambda: getattr(pf, what)() if what in ("mean", "covariance") else getattr(pf, what)


def step_with_dt(make, dt):
    def call():
        f = make()
        if isinstance(f, implicit.ParticleFilter):
            f.initialize([0.0, 0.0, 0.0], np.eye(3) * 0.01)
        f.step([1.0, 0.0], dt)
    return call


INT_M = r"an integer in \[1, 10000000\]"
INT_SLAM_M = r"an integer in \[1, 1000000\]"
SEED = r"expected an integer in \[0, 2\^64 - 1\], got "
# The other bindings: negative or fractional integers, counts beyond the tool's cap (with the
# memory they would take), wrong types: InvalidArgument naming the argument, never pybind11's
# TypeError listing the signature, nor a silent truncation.
BAD_BINDINGS = [
    (particle_filter(particles=-1), r"^particles: expected " + INT_M + ", got -1$"),
    (particle_filter(particles=0), r"^particles: expected " + INT_M + ", got 0$"),
    (particle_filter(particles=2.5), r"^particles: expected " + INT_M + ", got float$"),
    (particle_filter(particles=True), r"^particles: expected " + INT_M + ", got bool$"),
    (particle_filter(particles=10**8), r"^particles: expected " + INT_M + r", got 100000000: "
     r"100000000 particles would take at least 5\.96 GiB \(64 bytes each\)$"),
    (particle_filter(seed=-1), r"^seed: " + SEED + "-1$"),
    (particle_filter(seed=1.5), r"^seed: " + SEED + "float$"),
    (particle_filter(proposal=3), r"^proposal: expected a str, got int$"),
    (particle_filter(map=None), r"^map: expected a str, got NoneType$"),
    (particle_filter(resampling="best"), r"^resampling: expected 'multinomial', 'systematic', "
     r"'stratified' or 'residual', got 'best'$"),
    (particle_filter(resample_threshold=math.nan),
     r"^resample_threshold: expected a number in \[0, 1\], got nan$"),
    (particle_filter(resample_threshold="0.5"),
     r"^resample_threshold: expected a number in \[0, 1\], got str$"),
    (particle_filter(clutter=1), r"^clutter: expected True or False, got int$"),
    (lambda: implicit.ParticleFilter(UTE, 3, np.zeros((2, 2))),
     r"^sensor: expected implicit\.models\.RangeBearing, got int$"),
    (before_initialize("mean"), r"^ParticleFilter\.mean: call initialize\(mean, covariance\) "
     r"first$"),
    (before_initialize("covariance"), r"^ParticleFilter\.covariance: call initialize"),
    (before_initialize("particles"), r"^ParticleFilter\.particles: call initialize"),
    (before_initialize("weights"), r"^ParticleFilter\.weights: call initialize"),
    (before_initialize("ess"), r"^ParticleFilter\.ess: call initialize"),
    (before_initialize("last"), r"^ParticleFilter\.last: call initialize"),
    (step_with_dt(particle_filter(), -1.0),
     r"^particle filter: expected a positive step length, got -1$"),
    (step_with_dt(particle_filter(), "0.1"), r"^dt: expected a finite number, got str$"),
    (slam_filter(particles=-1), r"^particles: expected " + INT_SLAM_M + ", got -1$"),
    (slam_filter(particles=2.5), r"^particles: expected " + INT_SLAM_M + ", got float$"),
    (slam_filter(particles=2 * 10**6), r"^particles: expected " + INT_SLAM_M + r", got 2000000: "
     r"2000000 particles would take at least 122 MiB \(64 bytes each\)$"),
    (slam_filter(seed=-1), r"^seed: " + SEED + "-1$"),
    (slam_filter(method=None), r"^method: expected a str, got NoneType$"),
    (slam_filter(association=1), r"^association: expected a str, got int$"),
    (slam_filter(model=3), r"^model: expected implicit\.models\.Ute, implicit\.models\.Unicycle "
     r"or None, got int$"),
    (slam_filter(sensor="rb"), r"^sensor: expected implicit\.models\.RangeBearing, got str$"),
    (step_with_dt(slam_filter(), math.nan), r"^dt: expected a finite number, got nan$"),
    (step_with_dt(slam_filter(), -0.5), r"^SLAM: expected a positive step length, got -0\.5$"),
    (simulate(steps=-1), r"^steps: expected an integer in \[1, 10000000\], got -1$"),
    (simulate(steps=2.5), r"^steps: expected an integer in \[1, 10000000\], got float$"),
    (simulate(landmarks=0), r"^landmarks: expected an integer in \[1, 100000\], got 0$"),
    (simulate(scan_every=-3), r"^scan_every: expected an integer in \[1, 100000\], got -3$"),
    (simulate(max_range=-1.0), r"^max_range: expected a finite number > 0, got -1$"),
    (simulate(speed=0.0), r"^speed: expected a finite number > 0, got 0$"),
    (simulate(seed=-1), r"^seed: " + SEED + "-1$"),
    (lambda: implicit.data.simulate(UTE, None, steps=30),
     r"^sensor: expected implicit\.models\.RangeBearing, got NoneType$"),
    (slit_control(samples=2.5), r"^samples: expected an integer in \[-2147483648, 2147483647\], "
     r"got float$"),
    (slit_control(samples=-1), r"^double slit control estimate: expected at least 1 sample, "
     r"got -1$"),
    (slit_control(k=1.0), r"^k: expected an integer in .* got float$"),
    (slit_control(seed=-1), r"^seed: " + SEED + "-1$"),
    (slit_control(step=-1), r"^step: " + SEED + "-1$"),
    (slit_control(estimator=2), r"^estimator: expected a str, got int$"),
    (slit_control(x=math.nan), r"^x: expected a finite number, got nan$"),
    (himmelblau_control(samples=2.5), r"^samples: expected an integer in .* got float$"),
    (himmelblau_control(k=-1), r"^Himmelblau control: expected a step in \[0, 20\), got -1$"),
    (himmelblau_control(seed=2**64), r"^seed: " + SEED + "18446744073709551616$"),
    (lambda: implicit.control.double_slit(samples=5, runs=2.5),
     r"^runs: expected an integer, got float 2\.5$"),
    (lambda: implicit.control.double_slit(samples=-5, runs=1),
     r"^samples: expected an integer >= 1, got -5$"),
    (lambda: implicit.control.himmelblau(runs=0, samples=5),
     r"^runs: expected an integer >= 1, got 0$"),
    (mcl(verbose=1), r"^verbose: expected True or False, got int$"),
    (slam(verbose="yes"), r"^verbose: expected True or False, got str$"),
    (mcl(progress=3),
     r"^progress: expected a callable progress\(done, total\) or None, got int$"),
    (slam(progress="bar"),
     r"^progress: expected a callable progress\(done, total\) or None, got str$"),
    (mcl(particles=2 * 10**7), r"^particles: expected " + INT_MCL_M + r", got 20000000: "
     r"20000000 particles would take at least 1\.19 GiB \(64 bytes each\)$"),
    (lambda: implicit.ssm.particle_filter(
        implicit.ssm.Model(dim=2, initial=lambda z: z, transition=lambda t, x, z: x,
                           observation_logpdf=lambda t, x, y: x[:, 0]), [1.0], particles=10**8),
     r"^particles: expected " + INT_M + r", got 100000000: 100000000 particles would take at "
     r"least 5\.96 GiB \(64 bytes each\)$"),
]


@pytest.mark.parametrize("call,message", BAD_BINDINGS,
                         ids=[f"row{k}" for k in range(len(BAD_BINDINGS))])
def test_bad_binding_arguments_are_named(call, message):
    with pytest.raises(implicit.InvalidArgument, match=message):
        call()


@pytest.mark.parametrize("run,size", [(implicit.mcl.run, "runs"), (implicit.slam.run, "datasets")])
def test_deprecated_bearing_sd_is_bearing_sd_deg(run, size):
    # The old keyword (degrees, the unit not in its name) warns and gives the same run.
    kw = {size: 1, "particles": 5, "seed": 3, "range_sd": 0.2}
    new = run(bearing_sd_deg=2.0, **kw)
    with pytest.warns(DeprecationWarning, match=r"bearing_sd is deprecated .* pass bearing_sd_deg"):
        old = run(bearing_sd=2.0, **kw)
    assert new["error_percent_mean"] == old["error_percent_mean"]
    assert new["error_percent_mean"] != run(**kw)["error_percent_mean"]  # the noise is used
    with pytest.warns(DeprecationWarning), pytest.raises(implicit.InvalidArgument,
                                                         match=r"^bearing_sd: expected a number"):
        run(bearing_sd=-1.0, **kw)


def test_verbose_runs_give_the_same_numbers(capfd):
    # The progress bar is drawn by the tool's code on the process's stderr; the numbers are those
    # of a quiet run (timing keys aside).
    quiet = implicit.mcl.run(runs=2, particles=10, seed=4)
    loud = implicit.mcl.run(runs=2, particles=10, seed=4, verbose=True)
    err = capfd.readouterr().err
    assert "mcl implicit M=10" in err
    timing = ("ms_per_step", "seconds", "memory_mb")
    assert ({k: v for k, v in quiet.items() if not any(t in k for t in timing)}
            == {k: v for k, v in loud.items() if not any(t in k for t in timing)})


def cli_exe():
    exe = os.environ.get("IMPLICIT_CLI") or shutil.which("implicit")
    assert exe, "set IMPLICIT_CLI to the implicit executable"
    return exe


# `implicit CMD --help` shows each range check as "--flag FLOAT:FLOAT in [lo - hi]" (x n for a
# flag of n values).
CLI_RANGE = re.compile(r"^\s+(?:-\w,)?(--[\w-]+) (INT|FLOAT):(?:INT|FLOAT) in \[(\S+) - (\S+)\]"
                       r"(?: x (\d+))?")


def cli_ranges(command):
    out = subprocess.run([cli_exe(), command, "--help"], check=True, capture_output=True,
                         text=True).stdout
    ranges = {}
    for line in out.splitlines():
        m = CLI_RANGE.match(line)
        if m:
            ranges[m[1]] = (m[2] == "INT", float(m[3]), float(m[4]), int(m[5] or 0))
    return ranges


@pytest.mark.parametrize("command,run", [("mcl", implicit.mcl.run), ("slam", implicit.slam.run)])
def test_run_ranges_are_those_of_the_cli(command, run):
    # The oracle is the tool itself: every range the bindings check is the range of the flag of
    # the same name, and every keyword of run() whose flag has a range is checked.
    cli = cli_ranges(command)
    assert len(cli) > 8, "the --help format changed: no ranges found"
    table = _implicit._run_setting_ranges(command)
    keywords = set(inspect.signature(run).parameters)
    for r in table:
        assert r["key"] in keywords, r
        # The keyword is the flag's name, with the unit when the flag's help gives it (degrees).
        key = r["key"].removesuffix("_deg")
        assert r["flag"] == "--" + key.replace("_", "-"), r
        assert cli.get(r["flag"]) == (r["integer"], r["lo"], r["hi"], r["count"]), r
    checked = {r["key"].removesuffix("_deg") for r in table}
    for flag in cli:
        key = flag[2:].replace("-", "_")
        assert key not in keywords or key in checked, f"{command}.run({key}=...) is not checked"


LIBRARY_REFUSALS = [
    # Within the flags' ranges, refused by the filter's own checks (KldOptions, RecoveryOptions);
    # they were checked only inside each run, so the refusal read "1 of 1 runs failed", a
    # RuntimeError in Python.
    (dict(kld=True, min_particles=500, max_particles=100),
     r"KldOptions\.min_particles: expected <= max_particles \(100\), got 500"),
    (dict(recovery_alpha_slow=1.0), r"recovery: expected recovery_alpha_slow in \(0, 1\), got 1"),
    (dict(recovery_alpha_fast=0.0005), r"recovery: expected recovery_alpha_fast in "
     r"\(recovery_alpha_slow, 1\], got 0\.0005"),
]


@pytest.mark.parametrize("changes,message", LIBRARY_REFUSALS)
def test_library_refusals_are_value_errors_as_in_the_cli(changes, message):
    with pytest.raises(implicit.InvalidArgument, match="^" + message):
        implicit.mcl.run(init="global", runs=1, particles=5, **changes)
    flags = [f"--{k.replace('_', '-')}" + ("" if v is True else f"={v}")
             for k, v in changes.items()]
    assert re.match(message, cli_error("mcl", "--init", "global", "--runs", "1", "-M", "5",
                                       *flags))


# Detections: column 0 is -1 or a landmark id in [0, 2^31 - 1], refused otherwise (a larger
# value was cast to int out of range, undefined behaviour, and read as unlabelled).
LANDMARKS = np.array([[0.0, 10.0], [10.0, 0.0], [10.0, 10.0], [-5.0, 5.0]])
BAD_IDS = [
    (2.0**31, r"got 2147483648$"),
    (2.0**32 + 1, r"got 4294967297$"),
    (1e20, r"got 1e\+20$"),
    (-2.0, r"got -2$"),
    (-(2.0**31), r"got -2147483648$"),
    (1.5, r"got 1\.5$"),
]
ID_PREFIX = (r"^detections: row 1: expected a landmark id in \[0, 2147483647\] or -1 "
             r"\(unlabelled\) in column 0, ")


def landmark_filter(**kw):
    pf = implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(), LANDMARKS,
                                 particles=20, seed=3, **kw)
    pf.initialize([0.0, 0.0, 0.0], np.diag([0.01, 0.01, 0.001]))
    return pf


def detections_with(label):
    return np.array([[0.0, 10.0, math.pi / 2], [label, 10.0, 0.0]])


@pytest.mark.parametrize("label,got", BAD_IDS)
def test_detection_ids_out_of_int_range_are_refused(label, got):
    with pytest.raises(implicit.InvalidArgument, match=ID_PREFIX + got):
        landmark_filter().step([1.0, 0.0], 0.025, detections_with(label))
    f = implicit.slam.Filter(method="fastslam1", particles=5, seed=1)
    with pytest.raises(implicit.InvalidArgument, match=ID_PREFIX + got):
        f.step([1.0, 0.0], 0.025, detections_with(label))


def test_particle_filter_takes_landmark_ids():
    # The same landmarks under other ids, given as landmark_ids: detections naming a landmark by
    # its id must give bit-identical particles to the filter whose ids are the rows.
    ids = np.array([17, 3, 2**31 - 1, 40])
    by_row, by_id = landmark_filter(), landmark_filter(landmark_ids=ids)
    for step in range(5):
        z_rows = np.array([[0.0, 10.0, math.pi / 2], [1.0, 10.0, 0.0], [-1.0, 14.1, 0.78]])
        z_ids = z_rows.copy()
        z_ids[:2, 0] = ids[[0, 1]]
        by_row.step([1.0, 0.0], 0.025, z_rows)
        by_id.step([1.0, 0.0], 0.025, z_ids)
        np.testing.assert_array_equal(by_row.particles, by_id.particles)
        assert by_row.last["detections_used"] == by_id.last["detections_used"]
    # ... the same as slam.Filter, whose map() gives ids that a ParticleFilter then takes.
    positions, map_ids = np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([7, 9])
    pf = implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(), positions,
                                 landmark_ids=map_ids, particles=4)
    pf.initialize([0.0, 0.0, 0.0], np.eye(3) * 0.01)
    pf.step([1.0, 0.0], 0.025, np.array([[9.0, 4.9, 0.9]]))


ROW_IDS = r"\(its ids are 0 to 3, the rows of `landmarks`\)"
GIVEN_IDS = r"\(its ids are those of `landmark_ids`: 17, 3, 5, 40\)"
BAD_MAP_IDS = [
    # an id that is not in the map: a row index where ids are expected, or the other way round
    (dict(), 4.0, r"^detections: row 1: landmark id 4 is not in the map " + ROW_IDS +
     r": column 0 takes landmark ids, or -1 \(unlabelled\)$"),
    (dict(landmark_ids=[17, 3, 5, 40]), 1.0,
     r"^detections: row 1: landmark id 1 is not in the map " + GIVEN_IDS),
]


@pytest.mark.parametrize("kw,label,message", BAD_MAP_IDS)
def test_particle_filter_refuses_ids_not_in_its_map(kw, label, message):
    z = detections_with(label)
    z[0, 0] = kw.get("landmark_ids", [0])[0]  # row 0 names the first landmark by its id
    with pytest.raises(implicit.InvalidArgument, match=message):
        landmark_filter(**kw).step([1.0, 0.0], 0.025, z)


@pytest.mark.parametrize("ids,message", [
    ([1, 2, 3], r"^landmark_ids: expected shape \(4,\), got shape \(3,\)"),
    ([1, 2, 2, 3], r"^landmark_ids: expected unique ids, got 2 at indices 1 and 2"),
    ([1, 2, -3, 4], r"^landmark_ids: expected integer ids in \[0, 2147483647\], got -3 at index 2"),
    ([1, 2, 2.5, 4], r"^landmark_ids: expected integer ids .* got 2\.5 at index 2"),
    ([1, 2, 2**31, 4], r"^landmark_ids: expected integer ids .* got 2147483648 at index 2"),
    ([1, 2, math.nan, 4], r"^landmark_ids: expected finite values"),
])
def test_bad_landmark_ids_are_named(ids, message):
    with pytest.raises(implicit.InvalidArgument, match=message):
        landmark_filter(landmark_ids=ids)


def cli_error(*args):
    """The message of `implicit ARGS` failing with exit code 1 (warnings before it aside)."""
    out = subprocess.run([cli_exe(), *args], capture_output=True, text=True)
    assert out.returncode == 1, out
    errors = [line for line in out.stderr.splitlines() if line.startswith("implicit: error: ")]
    assert len(errors) == 1, out.stderr
    return errors[0][len("implicit: error: "):]


@pytest.mark.parametrize("drove,given", [("unicycle", "ute"), ("ute", "unicycle")])
def test_steps_refuses_the_other_model_as_the_cli_does(tmp_path, drove, given):
    models = {"ute": implicit.models.Ute(), "unicycle": implicit.models.Unicycle()}
    path = tmp_path / f"{drove}.log"
    implicit.data.simulate(models[drove], implicit.models.RangeBearing(), steps=60,
                           landmarks=5).write(str(path))
    log = implicit.data.read_log(str(path))
    with pytest.raises(implicit.InvalidArgument) as refused:
        implicit.data.steps(log, models[given])
    message = str(refused.value)
    assert message.startswith(f"steps --model {given}: the log '{path}' declares vehicle "
                              f"'{drove}'"), message
    # The same message as `implicit mcl --model`, the command's name aside.
    cli = cli_error("mcl", "--model", given, "--data", str(path), "--runs", "1", "-M", "5")
    assert message == cli.replace(f"mcl --model {given}", f"steps --model {given}", 1)
    # In memory (no file): the same refusal.
    with pytest.raises(implicit.InvalidArgument, match=rf"^steps --model {given}: the log "
                       rf"'\(in memory\)' declares vehicle '{drove}'"):
        implicit.data.steps(implicit.data.simulate(models[drove], implicit.models.RangeBearing(),
                                                   steps=60, landmarks=5), models[given])
    assert len(implicit.data.steps(log, models[drove])) > 0
