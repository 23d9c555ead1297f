"""implicit.sample, resample, ess, log_sum_exp against closed forms and the C++ results."""
import math

import numpy as np
import pytest

import implicit

Z_QUARTIC = 1.9352478184967  # integral of exp(-u^2/2 - u^4/4) over the line


def z_hat_and_se(r):
    """Mean weight and its standard error sd(w)/sqrt(n), scaled to avoid overflow."""
    top = r.log_weights.max()
    w = np.exp(r.log_weights - top)
    n = w.size
    return w.mean() * math.exp(top), w.std(ddof=1) * math.exp(top) / math.sqrt(n)


def gaussian_F(precision):
    return lambda x: 0.5 * x @ precision @ x


@pytest.mark.parametrize("map_kind", ["linear", "random"])
def test_gaussian_2d_log_z_within_4p5_se(map_kind):
    # F = x^T A x / 2: Z = 2 pi / sqrt(det A). For the linear map every weight equals Z (SE 0),
    # so finite-difference derivatives set the tolerance; the random map's weights vary.
    a = np.array([[2.0, 0.3], [0.3, 0.5]])
    exact = math.log(2 * math.pi / math.sqrt(np.linalg.det(a)))
    r = implicit.sample(gaussian_F(a), np.array([1.0, -1.0]), n=4000, map=map_kind, seed=3)
    assert r.samples.shape == (4000, 2) and r.samples.dtype == np.float64
    assert r.weights.shape == (4000,) and r.log_weights.shape == (4000,)
    assert abs(r.weights.sum() - 1.0) < 1e-12
    z, se = z_hat_and_se(r)
    # 4.5 SE (false alarm ~7e-6), plus the finite-difference error of the Hessian (~1e-6).
    assert abs(z - math.exp(exact)) <= 4.5 * se + 1e-5 * z, (z, math.exp(exact), se)
    assert abs(r.log_Z - math.log(z)) < 1e-12
    assert r.status == "converged"
    assert 1.0 <= r.ess <= 4000.0 * (1 + 1e-12)  # rounding: all-equal weights give n


def test_quartic_closed_form_both_maps_and_derivatives():
    F = lambda x: 0.5 * x @ x + 0.25 * (x**4).sum()
    r1 = implicit.sample(F, np.array([1.0]), n=20000, seed=1, map="random")
    r2 = implicit.sample(F, np.array([1.0]), n=20000, seed=2,
                         grad=lambda x: x + x**3, hess=lambda x: np.diag(1 + 3 * x**2))
    for r in (r1, r2):
        z, se = z_hat_and_se(r)
        assert abs(z - Z_QUARTIC) <= 4.5 * se, (z, se)


def test_vectorized_F_gives_the_same_samples_and_weights():
    # The batch path evaluates F once on all samples; the result must equal the per-point path.
    calls = []

    def batch(x):
        calls.append(x.shape)
        return 0.5 * (x**2).sum(axis=1) + 0.25 * (x**4).sum(axis=1)

    point = lambda x: 0.5 * x @ x + 0.25 * (x**4).sum()
    a = implicit.sample(batch, np.array([0.5, 0.2]), n=500, seed=7, vectorized=True)
    b = implicit.sample(point, np.array([0.5, 0.2]), n=500, seed=7)
    assert (500, 2) in calls
    np.testing.assert_allclose(a.samples, b.samples, rtol=0, atol=0)
    np.testing.assert_allclose(a.log_weights, b.log_weights, rtol=1e-13, atol=0)


def test_sample_is_reproducible_and_seed_dependent():
    F = lambda x: 0.5 * x @ x + 0.1 * x[0] ** 4
    a = implicit.sample(F, np.zeros(3), n=50, seed=5, map="random")
    b = implicit.sample(F, np.zeros(3), n=50, seed=5, map="random")
    c = implicit.sample(F, np.zeros(3), n=50, seed=6, map="random")
    assert np.array_equal(a.samples, b.samples) and not np.array_equal(a.samples, c.samples)


def test_sample_errors_carry_the_cpp_message():
    F = lambda x: 0.5 * x @ x
    with pytest.raises(ValueError, match="expected 'linear' or 'random', got 'banana'"):
        implicit.sample(F, np.zeros(2), n=10, map="banana")
    with pytest.raises(implicit.InvalidArgument, match=r"x0: expected shape \(n,\), got shape \(2, 2\)"):
        implicit.sample(F, np.zeros((2, 2)), n=10)
    with pytest.raises(implicit.InvalidArgument, match="x0: expected finite values"):
        implicit.sample(F, np.array([0.0, np.nan]), n=10)
    with pytest.raises(implicit.InvalidArgument, match="minimising F failed with status"):
        implicit.sample(lambda x: x.sum(), np.ones(2), n=10)  # no minimum


def test_resample_schemes_match_the_counts_rule():
    w = np.array([0.1, 0.25, 0.4, 0.25])
    # With given uniforms the result is the library's exactly (the old module's check).
    idx = implicit.resample(w, n=10, scheme="systematic", uniforms=[0.37])
    counts = np.bincount(idx, minlength=4)
    assert all(math.floor(10 * p) <= c <= math.ceil(10 * p) for p, c in zip(w, counts))
    # Systematic with u: ancestors are the cells containing (i + u) / n of the cumulative sum.
    expected = np.searchsorted(np.cumsum(w), (np.arange(10) + 0.37) / 10, side="right")
    np.testing.assert_array_equal(idx, expected)
    for scheme in implicit._core.SCHEMES:
        idx = implicit.resample(w, n=1000, scheme=scheme, seed=2)
        assert idx.dtype == np.int64 and idx.shape == (1000,)
        assert np.all(np.diff(idx) >= 0)
        # Each count is binomial at worst: within 4.5 sd of n w.
        counts = np.bincount(idx, minlength=4)
        assert np.all(np.abs(counts - 1000 * w) <= 4.5 * np.sqrt(1000 * w * (1 - w)))
    with pytest.raises(ValueError, match="bogus"):
        implicit.resample(w, scheme="bogus")
    with pytest.raises(ValueError):
        implicit.resample(np.array([0.5, np.nan]))


def test_ess_and_log_sum_exp():
    assert implicit.ess(np.full(8, 1 / 8)) == pytest.approx(8.0, rel=1e-14)
    w = np.array([0.5, 0.25, 0.25])
    assert implicit.ess(w) == pytest.approx(1 / (w**2).sum(), rel=1e-14)
    a = np.array([1000.0, 1000.0, 999.0])
    assert implicit.log_sum_exp(a) == pytest.approx(1000 + math.log(2 + math.exp(-1)), rel=1e-15)
    assert implicit.log_sum_exp(np.array([-np.inf, -np.inf])) == -np.inf
