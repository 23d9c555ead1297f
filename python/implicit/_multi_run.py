"""Many runs of one experiment: seeds x settings, in this process or a process pool, with a
progress bar, and a summary (mean and standard error per numeric result) without pandas.

    rows = implicit.multi_run(implicit.mcl.run, seeds=range(1, 11),
                              settings=[{"method": "standard", "runs": 1},
                                        {"method": "implicit", "runs": 1}])
    for group in implicit.summarize(rows):
        print(group["method"], group["rmse_m"], "+-", group["rmse_m_se"])

Each run is fn(seed=seed, **setting) and depends on its seed and setting alone, so the rows are
the same whatever `processes` is (the pool only changes where a run executes, never its inputs
or the order of the rows).
"""
import math
import multiprocessing
import numbers
import pickle
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Callable, Iterable, Mapping, Optional, Sequence

from . import _implicit
from ._core import _count, _seed

__all__ = ["MultiRunError", "RunList", "multi_run", "summarize"]


class MultiRunError(RuntimeError):
    """A run of implicit.multi_run failed. The message names the seed and the setting; the
    original exception is __cause__ (its type and message are repeated in the text, since a
    process pool hands it over without its traceback).

    Attributes:
        seed: the run's seed.
        settings: the run's setting (a dict).
    """

    def __init__(self, message, seed, settings):
        super().__init__(message)
        self.seed = seed
        self.settings = settings


class RunList(list):
    """The rows of implicit.multi_run, one dict per run, in the order (setting, seed): all seeds
    of settings[0], then of settings[1], ... The attribute setting_keys lists the keys the
    settings set (summarize groups by them)."""

    setting_keys: tuple = ()


def _one_run(fn, seed, setting):
    """One run: the row of its result merged with its seed and setting. Module-level, so that a
    spawned worker can unpickle it."""
    result = fn(seed=seed, **setting)
    if not isinstance(result, Mapping):
        raise TypeError(f"expected the run to return a dict, got {type(result).__name__}")
    # The run's own keys last: a result that echoes a setting (mcl.run's "particles") keeps its
    # value, which is the setting's.
    return {"seed": seed, **setting, **result}


def _failure(error, seed, setting):
    return MultiRunError(
        f"multi_run: the run with seed={seed} and settings={setting!r} failed: "
        f"{type(error).__name__}: {error}", seed, dict(setting))


class _Progress:
    """A plain-text bar on stderr: redrawn in place on a terminal, else one line per update at
    most once a second (a log file should not fill with carriage returns)."""

    def __init__(self, total, enabled):
        self.total, self.done, self.enabled = total, 0, enabled
        self.tty = enabled and sys.stderr.isatty()
        self.start = self.last = time.monotonic()

    def tick(self):
        self.done += 1
        if not self.enabled:
            return
        now = time.monotonic()
        final = self.done == self.total
        # At most ~10 redraws a second on a terminal, one line a second elsewhere.
        if not final and now - self.last < (0.1 if self.tty else 1.0):
            return
        self.last = now
        elapsed = now - self.start
        eta = elapsed / self.done * (self.total - self.done)
        width = 30
        filled = width * self.done // self.total
        line = (f"multi_run {self.done}/{self.total} [{'#' * filled}{'.' * (width - filled)}] "
                f"{elapsed:.1f} s, ETA {eta:.1f} s")
        sys.stderr.write(("\r" + line + ("\n" if final else "")) if self.tty else line + "\n")
        sys.stderr.flush()


def _settings_list(settings):
    if settings is None:
        return [{}]
    if isinstance(settings, Mapping) or not isinstance(settings, Iterable):
        raise _implicit.InvalidArgument(
            f"multi_run: settings: expected a list of dicts, got {type(settings).__name__}")
    out = []
    for k, s in enumerate(settings):
        if not isinstance(s, Mapping):
            raise _implicit.InvalidArgument(
                f"multi_run: settings[{k}]: expected a dict, got {type(s).__name__}")
        for key in s:
            if not isinstance(key, str):
                raise _implicit.InvalidArgument(
                    f"multi_run: settings[{k}]: expected str keys, got {key!r}")
        if "seed" in s:
            raise _implicit.InvalidArgument(
                f"multi_run: settings[{k}]: 'seed' is set by seeds=, not by a setting")
        out.append(dict(s))
    if not out:
        raise _implicit.InvalidArgument("multi_run: settings: expected at least one dict, got "
                                        "an empty list")
    return out


def _seeds_list(seeds):
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Iterable):
        raise _implicit.InvalidArgument(
            f"multi_run: seeds: expected a list of integers, got {type(seeds).__name__}")
    out = [_seed(s, f"multi_run: seeds[{k}]") for k, s in enumerate(seeds)]
    if not out:
        raise _implicit.InvalidArgument("multi_run: seeds: expected at least one seed, got none")
    return out


def multi_run(fn: Callable[..., Mapping[str, Any]], seeds: Iterable[int],
              settings: Optional[Sequence[Mapping[str, Any]]] = None,
              processes: Optional[int] = None, progress: Optional[bool] = None) -> RunList:
    """Runs fn(seed=seed, **setting) for every setting and seed, and returns one dict per run.

    Args:
        fn: a callable taking seed= and the settings' keywords and returning a dict, e.g.
            implicit.mcl.run or implicit.slam.run (whose `runs` / `datasets` then usually is 1:
            the seeds are the repetitions), or your own function.
        seeds: the seeds, integers in [0, 2^64 - 1].
        settings: a list of dicts of keyword arguments (None: one run per seed with fn's
            defaults). A setting may not set "seed".
        processes: None: every run in this process, one after the other; N >= 1: a pool of N
            worker processes (started with "spawn", so it works the same on every platform:
            fn must then be picklable, a module-level function, and a script must guard its
            own code with `if __name__ == "__main__":`). The rows do not depend on it. A run of
            the library uses all cores already (threads=0): a pool helps with callables that
            do not, or with threads=1 in the settings.
        progress: a bar on stderr: None shows it when stderr is a terminal, True always (one
            line per update, at most one a second, when stderr is not a terminal), False never.

    Returns:
        RunList (a list) of dicts, in the order (setting, seed): {"seed": seed, **setting,
        **result}; the result's keys win over a setting's of the same name.

    Raises:
        implicit.InvalidArgument (a ValueError) for bad seeds, settings, processes or progress,
        naming which; MultiRunError (a RuntimeError) when a run fails, naming its seed and
        setting, with the run's exception as __cause__ (the first failure in row order stops
        the remaining runs).
    """
    if not callable(fn):
        raise _implicit.InvalidArgument(
            f"multi_run: fn: expected a callable, got {type(fn).__name__}")
    seed_list = _seeds_list(seeds)
    setting_list = _settings_list(settings)
    if processes is not None:
        processes = _count(processes, "multi_run: processes", 1)
    if progress is not None and not isinstance(progress, bool):
        raise _implicit.InvalidArgument(
            f"multi_run: progress: expected True, False or None, got {type(progress).__name__}")
    jobs = [(seed, s) for s in setting_list for seed in seed_list]
    bar = _Progress(len(jobs), sys.stderr.isatty() if progress is None else progress)
    rows = RunList()
    keys = []
    for s in setting_list:
        keys += [k for k in s if k not in keys]
    rows.setting_keys = tuple(keys)
    if processes is None:
        for seed, s in jobs:
            try:
                rows.append(_one_run(fn, seed, s))
            except Exception as e:
                raise _failure(e, seed, s) from e
            bar.tick()
        return rows
    try:
        pickle.dumps(fn)
    except Exception as e:
        raise _implicit.InvalidArgument(
            f"multi_run: fn: processes={processes} needs a function the worker processes can "
            f"unpickle (defined at a module's top level, not a lambda or a local function), "
            f"got {fn!r}: {e}") from e
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=processes, mp_context=context) as pool:
        futures = [pool.submit(_one_run, fn, seed, s) for seed, s in jobs]
        # Ticks in completion order would be nicer to watch; row order keeps the first failure
        # the same whatever the pool's timing.
        for (seed, s), future in zip(jobs, futures):
            try:
                rows.append(future.result())
            except Exception as e:
                for f in futures:
                    f.cancel()
                raise _failure(e, seed, s) from e
            bar.tick()
    return rows


def _is_number(v):
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def _group_key(row, by):
    # repr: a setting may be a list (control_sd), which cannot key a dict.
    return tuple(repr(row.get(k)) for k in by)


def summarize(rows: Sequence[Mapping[str, Any]],
              by: Optional[Sequence[str]] = None) -> list[dict[str, Any]]:
    """Mean and standard error of every numeric result, per group of runs with equal settings.

    Args:
        rows: the dicts of implicit.multi_run (or any list of dicts).
        by: the keys that define a group (None: the rows' setting_keys when they come from
            multi_run, else none: one group).

    Returns:
        one dict per group, in the order of the groups' first rows: the `by` values, "runs"
        (the group's size) and, for every key other than "seed" and `by` whose value is a
        number (not a bool) in every row of the group, KEY the mean and KEY_se the standard
        error s / sqrt(n) (s the sample standard deviation; None for one run).

    Raises:
        implicit.InvalidArgument: rows empty or not dicts; a `by` key that no row has.
    """
    if isinstance(rows, Mapping) or not isinstance(rows, Sequence) or not rows:
        raise _implicit.InvalidArgument("summarize: rows: expected a non-empty list of dicts")
    for k, r in enumerate(rows):
        if not isinstance(r, Mapping):
            raise _implicit.InvalidArgument(
                f"summarize: rows[{k}]: expected a dict, got {type(r).__name__}")
    by = tuple(getattr(rows, "setting_keys", ()) if by is None else by)
    for key in by:
        if not any(key in r for r in rows):
            raise _implicit.InvalidArgument(f"summarize: by: no row has the key {key!r}")
    groups: dict = {}
    for r in rows:
        groups.setdefault(_group_key(r, by), []).append(r)
    out = []
    for members in groups.values():
        g = {k: members[0].get(k) for k in by}
        g["runs"] = n = len(members)
        for key in members[0]:
            if key == "seed" or key in by or not all(_is_number(m.get(key)) for m in members):
                continue
            values = [float(m[key]) for m in members]
            mean = math.fsum(values) / n
            g[key] = mean
            g[key + "_se"] = (math.sqrt(math.fsum((v - mean) ** 2 for v in values) / (n - 1) / n)
                              if n > 1 else None)
        out.append(g)
    return out
