"""Bad counts and seeds for implicit.sample, resample and uniforms_needed: InvalidArgument naming
the argument, never a raw binding TypeError, and a fractional count refused, not truncated."""
import numpy as np
import pytest

import implicit
from implicit._core import uniforms_needed


def F(x):
    return 0.5 * x @ x


W = np.array([0.25, 0.25, 0.5])


@pytest.mark.parametrize(
    "call, error",
    [
        (lambda: implicit.sample(F, np.zeros(1), n=-3), r"sample: n: expected an integer >= 1, got -3"),
        (lambda: implicit.sample(F, np.zeros(1), n=0), r"sample: n: expected an integer >= 1, got 0"),
        (lambda: implicit.sample(F, np.zeros(1), n=2.5), r"sample: n: expected an integer, got float 2\.5"),
        (lambda: implicit.sample(F, np.zeros(1), n=100.0), r"sample: n: expected an integer, got float 100\.0"),
        (lambda: implicit.sample(F, np.zeros(1), n="10"), r"sample: n: expected an integer, got str '10'"),
        (lambda: implicit.sample(F, np.zeros(1), n=True), r"sample: n: expected an integer, got bool True"),
        (lambda: implicit.sample(F, np.zeros(1), n=10, seed=-1), r"seed: expected an integer >= 0, got -1"),
        (lambda: implicit.sample(F, np.zeros(1), n=10, seed=1.5), r"seed: expected an integer, got float 1\.5"),
        (lambda: implicit.sample(F, np.zeros(1), n=10, seed=2**64), r"seed: expected an integer below 2\^64"),
        (lambda: implicit.resample(W, n=-1), r"resample: n: expected an integer >= 0, got -1"),
        (lambda: implicit.resample(W, n=2.5), r"resample: n: expected an integer, got float 2\.5"),
        (lambda: implicit.resample(W, seed=-2), r"seed: expected an integer >= 0, got -2"),
        (lambda: uniforms_needed("systematic", -1), r"uniforms_needed: n: expected an integer >= 0, got -1"),
        (lambda: uniforms_needed("systematic", 1.5), r"uniforms_needed: n: expected an integer, got float"),
    ],
)
def test_bad_counts_and_seeds_raise_invalid_argument(call, error):
    with pytest.raises(implicit.InvalidArgument, match=error):
        call()


def test_numpy_integers_and_the_largest_seed_are_accepted():
    r = implicit.sample(F, np.zeros(1), n=np.int64(5), seed=np.uint64(2**64 - 1))
    assert r.samples.shape == (5, 1)
    assert implicit.resample(W, n=np.int32(4), seed=2**64 - 1).shape == (4,)
