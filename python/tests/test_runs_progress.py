"""progress= of implicit.mcl.run and implicit.slam.run: the caller's view of the tool's progress
bar. The callback sees monotone counts ending at the total, is called at most about 10 times a
second plus a final call, does not change a single number, and an exception it raises stops the
run and reaches the caller as raised."""
import time

import pytest

import implicit

# Timing keys differ from run to run; every other key must be equal.
TIMING = ("ms_per_step", "seconds", "memory_mb")


def without_timing(result):
    return {k: v for k, v in result.items() if not any(t in k for t in TIMING)}


def mcl(**kw):
    return implicit.mcl.run(**{"runs": 6, "particles": 20, "seed": 5, "threads": 2, **kw})


def slam(**kw):
    return implicit.slam.run(**{"datasets": 4, "particles": 10, "seed": 5, "threads": 2, **kw})


def slam_total(result):
    # slam.run counts steps over every data set (each synthetic one has the same length).
    return result["datasets"] * result["steps_per_dataset"]


@pytest.mark.parametrize("run,total", [(mcl, lambda r: r["runs"]), (slam, slam_total)],
                         ids=["mcl", "slam"])
def test_progress_is_monotone_ends_at_total_and_changes_no_number(run, total):
    calls = []
    start = time.monotonic()
    with_progress = run(progress=lambda done, n: calls.append((done, n)))
    seconds = time.monotonic() - start
    without = run()
    # Same seed, same threads: the callback only reads a counter, so every number is the same.
    assert without_timing(with_progress) == without_timing(without)
    assert calls, "progress was never called"
    n = total(with_progress)
    assert all(t == n for _, t in calls), calls
    dones = [d for d, _ in calls]
    # Strictly increasing: counts are read under the bar's lock and a count is reported once.
    assert all(a < b for a, b in zip(dones, dones[1:])), dones
    assert dones[-1] == n
    # Calls other than the final one are at least 100 ms apart (measured before the call), so
    # a run of `seconds` makes at most seconds / 0.1 + 1 of them, plus the final call. A slow
    # machine only lowers the count; a missing throttle (one call per step) exceeds it.
    assert len(calls) <= seconds / 0.1 + 2, (len(calls), seconds)


class Stop(Exception):
    pass


@pytest.mark.parametrize("run", [mcl, slam], ids=["mcl", "slam"])
@pytest.mark.parametrize("threads", [1, 2])
def test_an_exception_in_progress_stops_the_run_and_reaches_the_caller(run, threads):
    raised = Stop("enough")
    calls = []

    def stop(done, total):
        calls.append((done, total))
        raise raised

    with pytest.raises(Stop) as caught:
        run(threads=threads, progress=stop)
    assert caught.value is raised  # the object raised, not a copy or a message about it
    # After the first exception no worker reports again (each stops at its next tick).
    assert len(calls) == 1, calls


def test_progress_none_is_no_callback():
    assert without_timing(mcl(runs=2, progress=None)) == without_timing(mcl(runs=2))
