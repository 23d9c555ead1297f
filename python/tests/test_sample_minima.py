"""implicit.sample on a target with two minima: one start, several starts, and the warnings.

The target is a two-component Gaussian mixture, exp(-F(x)) = 0.8 N(x; -2, 0.5^2) + 0.2 N(x; 2,
0.5^2), so Z = 1 and F has minima near x = -2 and x = +2, eight widths apart: a Gaussian centred
at one minimum practically never samples the other (e^-32), and the minimum at +2 holds a fifth
of the mass. Z is also integrated by the trapezoid rule, as an independent check of the oracle.
"""
import math
import warnings

import numpy as np
import pytest

import implicit

W, MU, S = np.array([0.8, 0.2]), np.array([-2.0, 2.0]), 0.5
N = 4000


def F_values(x):
    """F at every point of the array x (any shape)."""
    x = np.asarray(x, dtype=float)[..., None]
    log_n = -0.5 * ((x - MU) / S) ** 2 - math.log(S * math.sqrt(2 * math.pi))
    return -np.logaddexp.reduce(np.log(W) + log_n, axis=-1)


def F(x):
    return float(F_values(x[0]))


def F_batch(x):
    return F_values(x[:, 0])


def exact_log_z():
    # The mixture integrates to 1; the trapezoid rule on a fine grid agrees (checked below).
    return 0.0


def test_the_oracle_agrees_with_quadrature():
    x = np.linspace(-8.0, 8.0, 160001)
    assert abs(math.log(np.trapz(np.exp(-F_values(x)), x)) - exact_log_z()) < 1e-9


def minima_exact():
    # The other component changes F' by about e^-32 near each mean: the minima are the means
    # to far below the minimiser's tolerance.
    return MU[0], MU[1]


def log_z_and_se(r):
    """log of the mean weight and its standard error (delta method: sd(w) / (sqrt(n) mean w))."""
    w = np.exp(r.log_weights - r.log_weights.max())
    return r.log_Z, w.std(ddof=1) / (math.sqrt(w.size) * w.mean())


def no_warnings(call):
    with warnings.catch_warnings():
        warnings.simplefilter("error", implicit.SamplerWarning)
        return call()


def test_one_start_at_a_convex_point_finds_one_minimum_and_misses_the_other_mass():
    # The failure mode multi-start exists for: converged, ESS about n (the well is nearly
    # Gaussian), and log Z about log 0.2, wrong by 1.6 nats (the weights are unbiased, but the
    # samples reach the other well's mass with probability about e^-32). From x0 = 1.5, where F
    # is convex, nothing in one start can tell (no warning).
    r = no_warnings(lambda: implicit.sample(F, np.array([1.5]), n=N, seed=1))
    _, right = minima_exact()
    assert r.minima.shape == (1, 1) and abs(r.mode[0] - right) < 1e-6
    assert np.array_equal(r.mixture_weights, [1.0])
    assert r.ess > 0.99 * N
    assert exact_log_z() - r.log_Z > 1.5


def test_multi_start_finds_both_minima_and_log_z_agrees_with_quadrature():
    with pytest.warns(implicit.SamplerWarning, match="minimum found from x0 .* is not the lowest"):
        r = implicit.sample(F, np.array([1.5]), n=N, seed=1, starts=[[-1.5]])
    left, right = minima_exact()
    assert r.minima.shape == (2, 1)
    assert abs(r.minima[0, 0] - left) < 1e-6 and abs(r.minima[1, 0] - right) < 1e-6
    assert r.mode[0] == r.minima[0, 0] and r.phi == r.minima_phi[0] < r.minima_phi[1]
    # pi_k proportional to exp(-phi_k) / sqrt(F''(mu_k)) = the Laplace mass of each well, here
    # the component weights 0.8, 0.2 (F'' = 1 / S^2 at each mean, up to e^-32); the sampler's
    # Hessian is a finite difference (relative error about 1e-6).
    np.testing.assert_allclose(r.mixture_weights, W, rtol=1e-5)
    log_z, se = log_z_and_se(r)
    # 4.5 standard errors (a false alarm about once in 1e5 runs) plus the finite-difference
    # error of the Hessians (a relative 1e-6 in each component's mass).
    assert abs(log_z - exact_log_z()) <= 4.5 * se + 1e-5, (log_z, exact_log_z(), se)
    assert r.ess > 0.99 * N  # the mixture of the two Laplace approximations is the target
    # Both wells are sampled, in proportion to their mass: the self-normalised share of x < 0
    # against quadrature, within 4.5 of its delta-method standard errors.
    x = np.linspace(-8.0, 8.0, 160001)
    p_exact = np.trapz(np.exp(-F_values(x)) * (x < 0), x) / math.exp(exact_log_z())
    inside = (r.samples[:, 0] < 0).astype(float)
    p_hat = r.weights @ inside
    se_p = math.sqrt(np.sum(r.weights**2 * (inside - p_hat) ** 2))
    assert abs(p_hat - p_exact) <= 4.5 * se_p, (p_hat, p_exact, se_p)
    # Closed form: each component's normal CDF at 0. The trapezoid rule errs at the jump of the
    # indicator by up to h/2 * exp(-F(0)) = 5e-5 * 2.1e-4 = 1e-8.
    cdf = 0.5 * (1 + np.vectorize(math.erf)((0.0 - MU) / (S * math.sqrt(2))))
    assert abs(p_exact - W @ cdf) < 1e-7


def test_the_mixture_does_not_depend_on_which_start_comes_first():
    r1 = no_warnings(lambda: implicit.sample(F, np.array([-1.5]), n=500, seed=2, starts=[[1.5]]))
    with pytest.warns(implicit.SamplerWarning):
        r2 = implicit.sample(F, np.array([1.5]), n=500, seed=2, starts=[[-1.5]])
    np.testing.assert_array_equal(r1.log_weights, r2.log_weights)
    np.testing.assert_array_equal(r1.samples, r2.samples)


def test_starts_of_one_minimum_are_merged():
    r = no_warnings(lambda: implicit.sample(
        F, np.array([-1.9]), n=100, seed=1, starts=[[-2.2], [-2.5], [1.8], [2.4]]))
    assert r.minima.shape == (2, 1)


def test_vectorized_mixture_gives_the_same_weights():
    kw = dict(n=300, seed=4, starts=[[2.0]])
    r = no_warnings(lambda: implicit.sample(F, np.array([-2.0]), **kw))
    rv = no_warnings(lambda: implicit.sample(F_batch, np.array([-2.0]), vectorized=True, **kw))
    np.testing.assert_allclose(rv.log_weights, r.log_weights, rtol=0, atol=1e-12)


def test_start_where_F_is_not_convex_warns():
    # F has its maximum between the wells, near 0 (F'' < 0 there): Newton goes downhill to one.
    with pytest.warns(implicit.SamplerWarning, match="F is not locally convex at x0"):
        r = implicit.sample(F, np.array([0.0]), n=100, seed=1)
    assert r.minima.shape == (1, 1)
    # The same start among several: the multi-start covers it, no such warning.
    no_warnings(lambda: implicit.sample(F, np.array([0.0]), n=100, seed=1, starts=[[-2.0], [2.0]]))


def test_a_start_that_fails_is_left_out_but_all_failing_raises():
    # F = x has no minimum: every start fails.
    with pytest.raises(implicit.InvalidArgument,
                       match=r"minimising F failed with status .* \(and from all 2 other starts\)"):
        implicit.sample(lambda x: x[0], np.array([0.0]), n=10, starts=[[1.0], [2.0]])


@pytest.mark.parametrize(
    "kwargs, error",
    [
        (dict(starts=[[1.0, 2.0]]), r"starts: expected shape \(n, 1\), got shape \(1, 2\)"),
        (dict(starts=[1.0]), r"starts: expected shape \(n, 1\), got shape \(1,\)"),
        (dict(starts=np.zeros((0, 1))), r"starts: expected at least one row, got shape \(0, 1\)"),
        (dict(starts=[[float("nan")]]), "starts: expected finite values"),
        (dict(starts="left"), "starts: expected an array of numbers, got str"),
        (dict(starts=[[1.0]], map="random"),
         "the mixture over 2 minima uses the linear map, got 'random'"),
    ],
)
def test_bad_starts_raise_invalid_argument(kwargs, error):
    with pytest.raises(implicit.InvalidArgument, match=error):
        implicit.sample(F, np.array([-2.0]), n=10, **kwargs)


# A cubic observation y = x^3 + noise (sd 1) of x with prior N(0, 1), observed y = 8:
# F(x) = x^2 / 2 + (8 - x^3)^2 / 2. The prior mean x = 0 is a stationary point and a local
# minimum (F'(0) = 0, F''(0) = 1 > 0, F(0) = 32); the global minimum is near x = 1.99 (F = 2).
def F_cubic(x):
    return 0.5 * x[0] ** 2 + 0.5 * (8.0 - x[0] ** 3) ** 2


def cubic_log_z():
    x = np.linspace(-4.0, 4.0, 800001)
    f = 0.5 * x**2 + 0.5 * (8.0 - x**3) ** 2
    return -f.min() + math.log(np.trapz(np.exp(-(f - f.min())), x))


def test_start_at_the_prior_mean_of_a_cubic_observation_warns_from_the_samples():
    # Newton stops at once at x = 0 ("converged"); the samples of N(0, 1) reach the lower well,
    # where F is far below F(0): the warning names such a sample.
    with pytest.warns(implicit.SamplerWarning, match=r"a sample has F = .* below the lowest minimum"):
        r = implicit.sample(F_cubic, np.array([0.0]), n=1000, seed=1)
    assert r.mode[0] == 0.0 and r.phi == 32.0
    # Started near the global minimum too, the mixture is right (and x0 = 2 is the lowest: no
    # warning), within 4.5 standard errors of quadrature.
    r = no_warnings(lambda: implicit.sample(F_cubic, np.array([2.0]), n=N, seed=1, starts=[[0.0]]))
    assert r.minima.shape == (2, 1)
    log_z, se = log_z_and_se(r)
    assert abs(log_z - cubic_log_z()) <= 4.5 * se, (log_z, cubic_log_z(), se)
