"""Cost per step of a state-space model defined in Python (implicit.ssm), and how much of it the
Python callbacks take.

    PYTHONPATH=build/python python3 python/bench/user_model_step.py --particles 1000

The growth model (x_t = x/2 + 25x/(1+x^2) + 8 cos(1.2t) + v, y = x^2/20 + w; 50 steps) with
the bootstrap and the implicit proposal (finite-difference derivatives, linear map), once with
its numpy callbacks and once with trivial ones (one numpy operation each, F = x^2/2: the layer's
fixed cost per call). Every callback is wrapped in a timer, so the table splits a step into the
time inside Python and the rest (the C++ engine: draws, Newton's linear algebra, weights,
resampling, array conversion). A last row times the same bootstrap filter written in numpy alone.
Repetitions alternate between the rows; medians.
"""
import argparse
import math
import statistics
import time

import numpy as np

from implicit import ssm

V, W = 10.0, 1.0


def drift(t, x):
    return 0.5 * x + 25.0 * x / (1.0 + x * x) + 8.0 * math.cos(1.2 * t)


def gauss(e, var):
    return -0.5 * (e * e / var + math.log(2 * math.pi * var))


GROWTH = dict(
    initial=lambda z: math.sqrt(5.0) * z,
    transition=lambda t, xp, z: drift(t, xp) + math.sqrt(V) * z,
    transition_logpdf=lambda t, x, xp: gauss(x[:, 0] - drift(t, xp[:, 0]), V),
    observation_logpdf=lambda t, x, y: gauss(y - x[:, 0] ** 2 / 20.0, W))
TRIVIAL = dict(
    initial=lambda z: z,
    transition=lambda t, xp, z: z,
    transition_logpdf=lambda t, x, xp: -0.25 * x[:, 0] ** 2,
    observation_logpdf=lambda t, x, y: -0.25 * x[:, 0] ** 2)


class Timed:
    """A callback that adds its wall time to a shared total."""

    def __init__(self, f, clock):
        self.f, self.clock = f, clock

    def __call__(self, *args):
        start = time.perf_counter()
        try:
            return self.f(*args)
        finally:
            self.clock["s"] += time.perf_counter() - start
            self.clock["calls"] += 1


def measure(callbacks, ys, particles, proposal):
    clock = {"s": 0.0, "calls": 0}
    model = ssm.Model(dim=1, **{k: Timed(f, clock) for k, f in callbacks.items()})
    start = time.perf_counter()
    r = ssm.particle_filter(model, ys, particles=particles, proposal=proposal, seed=1)
    total = time.perf_counter() - start
    steps = len(ys)
    return (1e3 * total / steps, 1e3 * clock["s"] / steps, clock["calls"] / steps,
            float(np.mean(r.ess)))


def numpy_bootstrap(ys, particles, seed=1):
    """The filter a researcher would write by hand: bootstrap, systematic resampling at
    ESS < N/2, all in numpy (ms per step)."""
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    x = math.sqrt(5.0) * rng.normal(size=particles)
    logw = np.full(particles, -math.log(particles))
    for t, y in enumerate(ys, start=1):
        x = drift(t, x) + math.sqrt(V) * rng.normal(size=particles)
        logw = logw + gauss(y - x * x / 20.0, W)
        m = logw.max()
        w = np.exp(logw - m)
        w /= w.sum()
        if 1.0 / np.sum(w * w) < 0.5 * particles:
            u = (rng.uniform() + np.arange(particles)) / particles
            x = x[np.minimum(np.searchsorted(np.cumsum(w), u), particles - 1)]
            logw = np.full(particles, -math.log(particles))
        else:
            with np.errstate(divide="ignore"):  # a weight of exactly 0: log w = -inf
                logw = np.log(w)
    return 1e3 * (time.perf_counter() - start) / len(ys)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--particles", type=int, default=1000)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(3)
    x, ys = rng.normal() * math.sqrt(5.0), []
    for t in range(1, args.steps + 1):
        x = drift(t, x) + math.sqrt(V) * rng.normal()
        ys.append(x * x / 20.0 + math.sqrt(W) * rng.normal())
    rows = [(name, cb, proposal) for proposal in ("bootstrap", "implicit")
            for name, cb in (("growth", GROWTH), ("trivial", TRIVIAL))]
    results = {row[:1] + row[2:]: [] for row in rows}
    by_hand = []
    for _ in range(args.repeats):
        for name, cb, proposal in rows:
            results[(name, proposal)].append(measure(cb, ys, args.particles, proposal))
        by_hand.append(numpy_bootstrap(ys, args.particles))
    print(f"M = {args.particles}, {args.steps} steps, medians of {args.repeats}")
    print("| callbacks | proposal | ms per step | in Python | C++ and conversion | "
          "calls per step | mean ESS |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for (name, proposal), runs in results.items():
        total, python, calls, ess = (statistics.median(c) for c in zip(*runs))
        print(f"| {name} | {proposal} | {total:.3f} | {python:.3f} | {total - python:.3f} | "
              f"{calls:.1f} | {ess:.0f} |")
    print(f"| growth, numpy by hand | bootstrap | {statistics.median(by_hand):.3f} | all | - | "
          "- | - |")


if __name__ == "__main__":
    main()
