"""SLAM on a simulated robot log, stepped from Python, with the estimated map.

    PYTHONPATH=build/python python3 examples/python/slam_simulated.py --out out/examples

A unicycle drives around a 40 m square among 40 landmarks (implicit.data.simulate); the
Rao-Blackwellised implicit SLAM filter (spec §3.5) builds the map with known association.
"""
import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import implicit  # noqa: E402


def aligned(p, q):
    """p moved by the rotation and translation that fit it best to q (Kabsch): a SLAM map is
    only defined up to the frame of its uncertain start."""
    pm, qm = p.mean(axis=0), q.mean(axis=0)
    u, _, vt = np.linalg.svd((p - pm).T @ (q - qm))
    r = (u @ np.diag([1.0, np.sign(np.linalg.det(u @ vt))]) @ vt).T
    return (p - pm) @ r.T + qm


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/examples", help="folder of the figure")
    parser.add_argument("--method", default="implicit-rb")
    parser.add_argument("--particles", type=int, default=50)
    args = parser.parse_args()
    model = implicit.models.Unicycle()
    log = implicit.data.simulate(model, implicit.models.RangeBearing(), steps=1200, seed=3)
    steps = implicit.data.steps(log, model)
    f = implicit.slam.Filter(method=args.method, particles=args.particles, seed=1, model=model,
                             initial_pose=steps.initial_mean)
    path = np.empty((len(steps), 3))
    for n, (u, dt, z) in enumerate(zip(steps.controls, steps.dt, steps.detections)):
        f.step(u, dt, z)
        path[n] = f.mean()
    positions, ids = f.map()
    truth = steps.landmarks[ids]
    err = np.linalg.norm(positions - truth, axis=1)
    shape = np.linalg.norm(aligned(positions, truth) - truth, axis=1)
    print(f"{args.method} SLAM, M = {args.particles}: {len(positions)} landmarks mapped, "
          f"median error {np.median(err):.3f} m, {np.median(shape):.3f} m after the best "
          "rigid alignment")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(steps.truth[:, 0], steps.truth[:, 1], "k-", lw=1, label="true path")
    ax.plot(path[:, 0], path[:, 1], "C1-", lw=1, label="estimate")
    ax.plot(steps.landmarks[:, 0], steps.landmarks[:, 1], "k+", label="true landmarks")
    ax.plot(positions[:, 0], positions[:, 1], "C0o", mfc="none", label="map")
    ax.set(xlabel="x [m]", ylabel="y [m]", aspect="equal", title=f"{args.method} SLAM")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "slam_simulated.png", dpi=100)
    print(f"wrote {out / 'slam_simulated.png'}")


if __name__ == "__main__":
    main()
