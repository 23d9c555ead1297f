"""Tests of the Python bindings against the closed-form oracle T2 of the core (quartic, m = 1)."""
import math
import sys

import numpy as np

import implicit_py as ip

Z1 = 1.9352478184967  # integral of exp(-u^2/2 - u^4/4)
M = 20000


def check(name, s):
    w = np.exp(np.array(s["log_weights"]) - max(s["log_weights"]))
    scale = math.exp(max(s["log_weights"]))
    # Z-hat is the mean weight; its standard error is sd(w)/sqrt(M). 4.5 SE: false alarm ~7e-6.
    z_hat = w.mean() * scale
    se = w.std(ddof=1) * scale / math.sqrt(M)
    assert abs(z_hat - Z1) <= 4.5 * se, f"{name}: Z-hat {z_hat} vs {Z1} (SE {se})"
    assert abs(math.exp(s["log_Z"]) - z_hat) <= 1e-12 * z_hat, f"{name}: log_Z inconsistent"


F = lambda x: 0.5 * x @ x + 0.25 * (x**4).sum()
check("random map, numeric derivatives", ip.sample(F, x0=np.array([1.0]), samples=M, seed=1,
                                                   map="random"))
check("linear map, analytic derivatives",
      ip.sample(F, grad=lambda x: x + x**3, hess=lambda x: np.diag(1 + 3 * x**2),
                x0=np.array([1.0]), samples=M, seed=2))

# Systematic resampling: every count is floor(n w) or ceil(n w).
w = np.array([0.1, 0.25, 0.4, 0.25])
idx = ip.resample("systematic", w.tolist(), [0.37], 10)
counts = np.bincount(idx, minlength=4)
assert all(math.floor(10 * p) <= c <= math.ceil(10 * p) for p, c in zip(w, counts)), counts

try:
    ip.sample(F, x0=np.array([1.0]), samples=10, map="banana")
    sys.exit("expected an error for an unknown map")
except ValueError as e:
    assert "expected 'linear' or 'random'" in str(e), str(e)

print("python bindings: 4 passed, 0 failed")
