"""Cost of stepping the particle filter from Python against the command-line tool's own loop.

    PYTHONPATH=build/python python3 python/bench/filter_step.py --cli build/apps/implicit

Both run implicit MCL on the Car Park data with the same M and seed: the tool's
`wall_ms_per_step` (its filter loop, `implicit mcl --runs 1 --json`) against the Python loop
`pf.step(u, dt, z); pf.mean()` timed the same way (initialisation and data loading excluded).
Repetitions alternate between the two so that a change in machine load hits both; the medians
are compared. The Python overhead per step is the argument conversion (control, detections)
and the call itself: a few microseconds against milliseconds of filtering at M = 1000.
"""
import argparse
import json
import statistics
import subprocess
import time

import implicit


def python_ms_per_step(steps, particles, proposal, seed):
    pf = implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(),
                                 steps.landmarks, proposal=proposal, particles=particles,
                                 seed=seed)
    pf.initialize(steps.initial_mean, steps.initial_covariance)
    controls, dts, detections = list(steps.controls), list(steps.dt), steps.detections
    start = time.perf_counter()
    for u, dt, z in zip(controls, dts, detections):
        pf.step(u, dt, z)
        pf.mean()
    return 1e3 * (time.perf_counter() - start) / len(controls)


def cli_ms_per_step(cli, particles, method, seed):
    out = subprocess.run([cli, "mcl", "--method", method, "-M", str(particles), "--runs", "1",
                          "--seed", str(seed), "--json"], check=True, capture_output=True,
                         text=True)
    return json.loads(out.stdout)["wall_ms_per_step"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cli", default="implicit", help="the implicit executable")
    parser.add_argument("--particles", type=int, default=1000)
    parser.add_argument("--proposal", default="implicit", choices=["implicit", "bootstrap"])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    method = "implicit" if args.proposal == "implicit" else "standard"
    steps = implicit.data.steps(implicit.data.carpark(), implicit.models.Ute())
    py, cli = [], []
    for _ in range(args.repeats):
        cli.append(cli_ms_per_step(args.cli, args.particles, method, args.seed))
        py.append(python_ms_per_step(steps, args.particles, args.proposal, args.seed))
    mp, mc = statistics.median(py), statistics.median(cli)
    print(f"{args.proposal} MCL, M = {args.particles}, {len(steps)} steps, "
          f"{args.repeats} alternating repetitions")
    print(f"  CLI    ms/step: median {mc:.4f}  (runs: {', '.join(f'{x:.4f}' for x in cli)})")
    print(f"  Python ms/step: median {mp:.4f}  (runs: {', '.join(f'{x:.4f}' for x in py)})")
    print(f"  Python / CLI: {mp / mc:.3f} (overhead {100 * (mp / mc - 1):+.1f} %)")


if __name__ == "__main__":
    main()
