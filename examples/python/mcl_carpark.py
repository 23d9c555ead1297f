"""Monte Carlo localization on the Car Park data, stepped from Python, with a trajectory plot.

    PYTHONPATH=build/python python3 examples/python/mcl_carpark.py --out out/examples

Implicit MCL (spec §3.8) with M particles over the whole drive; the estimate is compared with the
GPS track, and the figure shows both with the 15 beacons.
"""
import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import implicit  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/examples", help="folder of the figure")
    parser.add_argument("--particles", type=int, default=100)
    parser.add_argument("--proposal", default="implicit", choices=["implicit", "bootstrap"])
    args = parser.parse_args()
    model = implicit.models.Ute()
    steps = implicit.data.steps(implicit.data.carpark(), model)
    pf = implicit.ParticleFilter(model, implicit.models.RangeBearing(), steps.landmarks,
                                 proposal=args.proposal, particles=args.particles, seed=1)
    pf.initialize(steps.initial_mean, steps.initial_covariance)
    path = np.empty((len(steps), 3))
    for n, (u, dt, z) in enumerate(zip(steps.controls, steps.dt, steps.detections)):
        pf.step(u, dt, z)
        path[n] = pf.mean()
    ok = np.isfinite(steps.truth).all(axis=1)
    rmse = math.sqrt(((path[ok, :2] - steps.truth[ok]) ** 2).sum(axis=1).mean())
    print(f"{args.proposal} MCL, M = {args.particles}: {len(steps)} steps, RMSE {rmse:.3f} m "
          "against GPS")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(steps.truth[:, 0], steps.truth[:, 1], "k-", lw=1, label="GPS")
    ax.plot(path[:, 0], path[:, 1], "C1-", lw=1, label=f"{args.proposal} MCL")
    ax.plot(steps.landmarks[:, 0], steps.landmarks[:, 1], "b^", label="beacons")
    ax.set(xlabel="east [m]", ylabel="north [m]", aspect="equal", title="Car Park")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "mcl_carpark.png", dpi=100)
    print(f"wrote {out / 'mcl_carpark.png'}")


if __name__ == "__main__":
    main()
