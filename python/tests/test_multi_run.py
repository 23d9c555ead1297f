"""implicit.multi_run and implicit.summarize: the rows (seed x settings, merged), their
independence of the process pool, the progress bar, errors naming the run, and the summary
against a direct computation."""
import math
import statistics

import numpy as np
import pytest

import implicit
from implicit import ssm


def linear_gaussian_run(seed, particles=200, proposal="bootstrap"):
    """A small run of the library's engine (module level: a spawned worker must unpickle it)."""
    model = ssm.Model(
        dim=1, initial=lambda z: z, transition=lambda t, xp, z: 0.9 * xp + z,
        transition_logpdf=lambda t, x, xp: -0.5 * (x[:, 0] - 0.9 * xp[:, 0]) ** 2,
        observation_logpdf=lambda t, x, y: -0.5 * (y - x[:, 0]) ** 2)
    r = ssm.particle_filter(model, [0.3, -0.2, 1.1, 0.4], particles=particles,
                            proposal=proposal, seed=seed)
    return {"log_likelihood": r.log_likelihood, "last_mean": float(r.mean[-1, 0]),
            "proposal_name": proposal}


def fails_for_seed_3(seed, scale=1.0):
    if seed == 3:
        raise ValueError("no good")
    return {"value": scale * seed}


SETTINGS = [{"proposal": "bootstrap"}, {"proposal": "implicit", "particles": 100}]


def test_rows_are_seed_times_settings_in_order():
    rows = implicit.multi_run(linear_gaussian_run, seeds=[4, 2, 9], settings=SETTINGS,
                              progress=False)
    assert [(r["seed"], r["proposal"]) for r in rows] == [
        (4, "bootstrap"), (2, "bootstrap"), (9, "bootstrap"),
        (4, "implicit"), (2, "implicit"), (9, "implicit")]
    assert rows.setting_keys == ("proposal", "particles")
    # Each row is the run called directly with its seed and setting.
    direct = linear_gaussian_run(seed=2, proposal="implicit", particles=100)
    assert rows[4] == {"seed": 2, "proposal": "implicit", "particles": 100, **direct}


def test_rows_do_not_depend_on_processes():
    kw = dict(seeds=[1, 2, 3], settings=SETTINGS, progress=False)
    alone = implicit.multi_run(linear_gaussian_run, **kw)
    pooled = implicit.multi_run(linear_gaussian_run, processes=2, **kw)
    assert pooled == alone  # floats compared exactly: bit-identical


def test_builtin_runner_through_a_pool():
    kw = dict(seeds=[5, 6], settings=[{"runs": 1, "particles": 10}], progress=False)
    alone = implicit.multi_run(implicit.mcl.run, **kw)
    pooled = implicit.multi_run(implicit.mcl.run, processes=2, **kw)
    timing = ("ms_per_step", "seconds", "memory_mb")  # differ from run to run

    def strip(rows):
        return [{k: v for k, v in r.items() if not any(t in k for t in timing)} for r in rows]

    assert strip(pooled) == strip(alone)
    assert alone[0]["rmse_m"] == implicit.mcl.run(runs=1, particles=10, seed=5)["rmse_m"]


@pytest.mark.parametrize("processes", [None, 2])
def test_a_failing_run_names_its_seed_and_setting(processes):
    with pytest.raises(implicit.MultiRunError,
                       match=r"^multi_run: the run with seed=3 and settings=\{'scale': 2\.0\} "
                             r"failed: ValueError: no good$") as e:
        implicit.multi_run(fails_for_seed_3, seeds=[1, 2, 3, 4], settings=[{"scale": 2.0}],
                           processes=processes, progress=False)
    assert e.value.seed == 3 and e.value.settings == {"scale": 2.0}
    assert isinstance(e.value.__cause__, ValueError)


def test_progress_bar_when_forced(capsys):
    implicit.multi_run(fails_for_seed_3, seeds=[1, 2], progress=True)
    err = capsys.readouterr().err
    # Not a terminal under pytest: plain lines, the last one complete.
    assert err.splitlines()[-1].startswith("multi_run 2/2 [") and "\r" not in err
    implicit.multi_run(fails_for_seed_3, seeds=[1, 2])  # default: off without a terminal
    assert capsys.readouterr().err == ""


def test_summarize_against_a_direct_computation():
    rows = implicit.multi_run(linear_gaussian_run, seeds=range(1, 7), settings=SETTINGS,
                              progress=False)
    groups = implicit.summarize(rows)
    assert [g["proposal"] for g in groups] == ["bootstrap", "implicit"]
    assert groups[0]["particles"] is None and groups[1]["particles"] == 100
    for g, proposal in zip(groups, ["bootstrap", "implicit"]):
        values = [r["log_likelihood"] for r in rows if r["proposal"] == proposal]
        assert g["runs"] == 6
        assert g["log_likelihood"] == pytest.approx(statistics.fmean(values), rel=1e-14)
        assert g["log_likelihood_se"] == pytest.approx(
            statistics.stdev(values) / math.sqrt(6), rel=1e-12)
        assert "seed" not in g and "seed_se" not in g
        assert "proposal_name" not in g  # text: not summarised
    # One group of everything; a single run has no standard error.
    (whole,) = implicit.summarize(rows, by=())
    assert whole["runs"] == 12
    (one,) = implicit.summarize(rows[:1], by=())
    assert one["log_likelihood_se"] is None


def test_summary_is_a_valid_standard_error():
    # The SE must describe the spread of the mean over independent repetitions: the means of
    # 40 groups of 10 seeds each have a standard deviation close to the typical reported SE.
    # For normal data the ratio sd(means) / rms(SE) over 40 groups has a relative standard
    # error of about 1 / sqrt(2 * 39) = 0.11; 0.6 .. 1.6 is beyond 4 of those either side.
    rows = [{"seed": s, "g": s // 10, "x": float(np.random.default_rng(s).normal())}
            for s in range(400)]
    groups = implicit.summarize(rows, by=("g",))
    means = np.array([g["x"] for g in groups])
    rms_se = math.sqrt(np.mean([g["x_se"] ** 2 for g in groups]))
    assert 0.6 < means.std(ddof=1) / rms_se < 1.6


BAD = [
    (dict(seeds=[1, -2]), r"^multi_run: seeds\[1\]: expected an integer >= 0, got -2"),
    (dict(seeds=[1.5]), r"^multi_run: seeds\[0\]: expected an integer, got float 1\.5"),
    (dict(seeds=[True]), r"^multi_run: seeds\[0\]: expected an integer, got bool"),
    (dict(seeds=[2**64]), r"^multi_run: seeds\[0\]: expected an integer below 2\^64"),
    (dict(seeds=[]), r"^multi_run: seeds: expected at least one seed, got none"),
    (dict(seeds=5), r"^multi_run: seeds: expected a list of integers, got int"),
    (dict(seeds=[1], settings={"scale": 1.0}),
     r"^multi_run: settings: expected a list of dicts, got dict"),
    (dict(seeds=[1], settings=[{"scale": 1.0}, 3]),
     r"^multi_run: settings\[1\]: expected a dict, got int"),
    (dict(seeds=[1], settings=[{"seed": 1}]),
     r"^multi_run: settings\[0\]: 'seed' is set by seeds=, not by a setting"),
    (dict(seeds=[1], settings=[]), r"^multi_run: settings: expected at least one dict"),
    (dict(seeds=[1], processes=0), r"^multi_run: processes: expected an integer >= 1, got 0"),
    (dict(seeds=[1], processes=-2), r"^multi_run: processes: expected an integer >= 1, got -2"),
    (dict(seeds=[1], processes=2.0), r"^multi_run: processes: expected an integer, got float"),
    (dict(seeds=[1], progress="yes"),
     r"^multi_run: progress: expected True, False or None, got str"),
]


@pytest.mark.parametrize("kw,message", BAD)
def test_bad_arguments_are_named(kw, message):
    with pytest.raises(implicit.InvalidArgument, match=message):
        implicit.multi_run(fails_for_seed_3, **kw)


def test_unpicklable_function_with_a_pool_is_named():
    with pytest.raises(implicit.InvalidArgument, match=r"^multi_run: fn: processes=2 needs a "
                       r"function the worker processes can unpickle"):
        implicit.multi_run(lambda seed: {"x": seed}, seeds=[1], processes=2)
    with pytest.raises(implicit.InvalidArgument, match=r"^multi_run: fn: expected a callable"):
        implicit.multi_run(5, seeds=[1])


def test_summarize_bad_input():
    with pytest.raises(implicit.InvalidArgument, match=r"^summarize: rows: expected a non-empty"):
        implicit.summarize([])
    with pytest.raises(implicit.InvalidArgument, match=r"^summarize: rows\[1\]: expected a dict"):
        implicit.summarize([{"x": 1.0}, 2])
    with pytest.raises(implicit.InvalidArgument, match=r"^summarize: by: no row has the key 'y'"):
        implicit.summarize([{"x": 1.0}], by=("y",))
