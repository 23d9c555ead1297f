"""Implicit sampling of a banana-shaped density, and a plot of the weighted samples.

    PYTHONPATH=build/python python3 examples/python/banana.py --out out/examples

F(x) = x1^2 / 2 + (x2 - b x1^2)^2 / 2: a Gaussian in x1, and x2 bent around the parabola
b x1^2. F is written for a batch of points (vectorized=True), so the weights of all samples cost
one call. The random map follows the curvature; the linear map uses the Gaussian at the mode.
"""
import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, never a window
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import implicit  # noqa: E402

B = 0.8


def F(x):
    """Negative log density of a batch x (k, 2) -> (k,)."""
    return 0.5 * x[:, 0] ** 2 + 0.5 * (x[:, 1] - B * x[:, 0] ** 2) ** 2


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/examples", help="folder of the figure")
    parser.add_argument("--samples", type=int, default=5000)
    args = parser.parse_args()
    # Z = 2 pi exactly (the change of variables x2 -> x2 - b x1^2 has Jacobian 1).
    for kind in ("linear", "random"):
        r = implicit.sample(F, x0=np.array([0.5, 0.5]), n=args.samples, map=kind, seed=1,
                            vectorized=True)
        z = np.exp(r.log_weights)
        se = z.std(ddof=1) / math.sqrt(z.size) / z.mean()
        print(f"{kind:6s} map: log Z = {r.log_Z:.4f} (exact {math.log(2 * math.pi):.4f}, "
              f"SE {se:.4f}), ESS = {r.ess:.0f} of {args.samples}, mean = {r.mean().round(3)}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5, 4))
    s = ax.scatter(r.samples[:, 0], r.samples[:, 1], c=r.weights * args.samples, s=3,
                   cmap="viridis")
    fig.colorbar(s, label="weight x n")
    ax.set(xlabel="$x_1$", ylabel="$x_2$", title="banana density, random map")
    fig.tight_layout()
    fig.savefig(out / "banana.png", dpi=100)
    print(f"wrote {out / 'banana.png'}")


if __name__ == "__main__":
    main()
