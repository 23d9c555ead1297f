"""implicit.ssm: a linear-Gaussian model defined in Python against the Kalman filter, an exact
check of the implicit weights, the guided proposal, and thread-count independence.

The mean over R = 20 independent runs (seeds 1..20) is compared with the exact value in units
of its standard error estimated from the same runs: a t statistic with 19 degrees of freedom.
Z_SIGMA is its quantile for a probability of 1e-3 that a correct filter fails any of the
Kalman test's 405 checks (5 variants x 81; Bonferroni): scipy.stats.t.isf(1e-3 / (2 * 405), 19)
= 6.62, rounded up. A filter with Q wrong by 10 % fails them (likelihood at 8 to 20 SE).
"""
import math

import numpy as np
import pytest

import implicit
from implicit import ssm

Z_SIGMA = 6.7
A, Q, R = 0.9, 0.5, 0.3  # x_t = A x_{t-1} + N(0, Q), y_t = x_t + N(0, R), x_0 ~ N(0, 1)


def gauss_logpdf(e, var):
    return -0.5 * (e ** 2 / var + math.log(2 * math.pi * var))


def linear_gaussian(**extra):
    return ssm.Model(
        dim=1,
        initial=lambda z: z,
        transition=lambda t, xp, z: A * xp + math.sqrt(Q) * z,
        transition_logpdf=lambda t, x, xp: gauss_logpdf(x[:, 0] - A * xp[:, 0], Q),
        observation_logpdf=lambda t, x, y: gauss_logpdf(y - x[:, 0], R),
        **extra)


def observations(steps=40, seed=7):
    rng = np.random.default_rng(seed)
    x, ys = rng.normal(), []
    for _ in range(steps):
        x = A * x + math.sqrt(Q) * rng.normal()
        ys.append(x + math.sqrt(R) * rng.normal())
    return np.array(ys)


def kalman(ys):
    """Filtering means, variances and the log-likelihood of the linear-Gaussian model."""
    m, p, ll, means, variances = 0.0, 1.0, 0.0, [], []
    for y in ys:
        m, p = A * m, A * A * p + Q
        s = p + R
        ll += gauss_logpdf(y - m, s)
        k = p / s
        m, p = m + k * (y - m), (1 - k) * p
        means.append(m)
        variances.append(p)
    return np.array(means), np.array(variances), ll


def guided_proposal(scale):
    """The optimal proposal p(x | x', y) with its standard deviation times `scale`."""
    post_var = 1.0 / (1.0 / Q + 1.0 / R)
    sd = scale * math.sqrt(post_var)

    def propose(t, xp, y, z):
        centre = post_var * (A * xp[:, 0] / Q + y / R)
        x = centre + sd * z[:, 0]
        return x[:, None], gauss_logpdf(x - centre, sd * sd)

    return propose


def assert_within(runs, exact, what):
    """Mean over runs within Z_SIGMA standard errors of `exact` (elementwise)."""
    runs = np.asarray(runs)
    se = runs.std(axis=0, ddof=1) / math.sqrt(len(runs))
    z = np.abs(runs.mean(axis=0) - exact) / se
    assert np.all(z < Z_SIGMA), f"{what}: max |mean - exact| / SE = {z.max():.2f}"


@pytest.mark.parametrize("proposal,extra,settings", [
    ("bootstrap", {}, {}),
    ("implicit", {}, {}),
    ("implicit", {}, {"map": "random"}),
    ("implicit", {"gradient": lambda t, x, xp, y: (x - A * xp) / Q - (y - x) / R,
                  "hessian": lambda t, x, xp, y: np.full((len(x), 1, 1), 1 / Q + 1 / R)}, {}),
    ("guided", {"proposal": guided_proposal(1.5)}, {}),
])
def test_linear_gaussian_agrees_with_kalman(proposal, extra, settings):
    ys = observations()
    means, variances, ll = kalman(ys)
    model = linear_gaussian(**extra)
    runs = [ssm.particle_filter(model, ys, particles=500, proposal=proposal, seed=s, **settings)
            for s in range(1, 21)]
    assert_within([r.mean[:, 0] for r in runs], means, "filtering mean")
    assert_within([r.variance[:, 0] for r in runs], variances, "filtering variance")
    # The likelihood estimate Z-hat is unbiased (its log is not): compare Z-hat / Z with 1.
    assert_within([math.exp(r.log_likelihood - ll) for r in runs], 1.0, "likelihood")
    assert all(np.allclose(r.log_likelihood_increments.sum(), r.log_likelihood) for r in runs)


@pytest.mark.parametrize("implicit_map", ["linear", "random"])
def test_implicit_weights_are_exact_for_a_gaussian_step(implicit_map):
    # For a linear-Gaussian step the implicit proposal is the optimal one: particle j's weight
    # is p(y_1 | x_0^j) = N(y_1; A x_0^j, Q + R) exactly, so the first log-likelihood
    # increment is the log mean of those, computed here from the initial draws themselves.
    seen = {}

    def initial(z):
        seen["x0"] = z.copy()
        return z

    model = ssm.Model(dim=1, initial=initial, transition=linear_gaussian().transition,
                      transition_logpdf=linear_gaussian().transition_logpdf,
                      observation_logpdf=linear_gaussian().observation_logpdf)
    y1 = 0.7
    r = ssm.particle_filter(model, [y1], particles=300, proposal="implicit", seed=4,
                            map=implicit_map)
    inc = gauss_logpdf(y1 - A * seen["x0"][:, 0], Q + R)
    expected = np.log(np.mean(np.exp(inc)))
    # Both maps are exact for a Gaussian F (the random map's root is lambda = |xi|). With
    # finite-difference derivatives the Hessian is off by about 1e-8 relative, which moves the
    # linear map's weights by as much; the random map solves F's own level set.
    assert r.log_likelihood_increments[0] == pytest.approx(expected, abs=1e-9)
    assert r.ess[0] == pytest.approx(1.0 / np.sum((np.exp(inc) / np.exp(inc).sum()) ** 2),
                                     rel=1e-8)
    assert r.newton_failures[0] == 0 and r.map_failures[0] == 0 and r.newton_iterations[0] >= 1


@pytest.mark.parametrize("proposal,implicit_map", [("bootstrap", "linear"), ("implicit", "linear"),
                                                   ("implicit", "random"), ("guided", "linear")])
@pytest.mark.parametrize("scheme", ["multinomial", "systematic", "stratified", "residual"])
def test_threads_do_not_change_results(proposal, implicit_map, scheme):
    model = linear_gaussian(proposal=guided_proposal(1.2))
    ys = observations(steps=15)
    one, two = (ssm.particle_filter(model, ys, particles=400, proposal=proposal,
                                    resampling=scheme, threshold=0.9, seed=11, threads=k,
                                    map=implicit_map)
                for k in (1, 2))
    assert one.resampled.any()
    for name in ("mean", "variance", "ess", "log_likelihood_increments", "particles", "weights"):
        assert np.array_equal(getattr(one, name), getattr(two, name)), name


def test_numpy_random_state_does_not_matter():
    ys = observations(steps=10)
    np.random.seed(1)
    a = ssm.particle_filter(linear_gaussian(), ys, particles=200, seed=5)
    np.random.seed(2)
    b = ssm.particle_filter(linear_gaussian(), ys, particles=200, seed=5)
    c = ssm.particle_filter(linear_gaussian(), ys, particles=200, seed=6)
    assert np.array_equal(a.mean, b.mean) and not np.array_equal(a.mean, c.mean)


def test_threshold_zero_never_resamples_and_one_always_does():
    ys = observations(steps=10)
    never = ssm.particle_filter(linear_gaussian(), ys, particles=100, threshold=0.0)
    always = ssm.particle_filter(linear_gaussian(), ys, particles=100, threshold=1.0)
    assert not never.resampled.any() and always.resampled.all()
    assert np.allclose(always.weights, 1 / 100)


def test_stub_matches_the_module():
    # ssm.pyi declares particle_filter with the signature and defaults of ssm.py.
    import ast
    import inspect
    import pathlib
    stub = ast.parse(pathlib.Path(ssm.__file__).resolve().with_suffix(".pyi").read_text())
    (fn,) = [n for n in stub.body if isinstance(n, ast.FunctionDef)]
    defaults = [ast.literal_eval(d) for d in fn.args.defaults]
    params = list(inspect.signature(ssm.particle_filter).parameters.values())
    assert [a.arg for a in fn.args.args] == [p.name for p in params]
    assert defaults == [p.default for p in params if p.default is not inspect.Parameter.empty]
    fields = [n.target.id for c in stub.body if isinstance(c, ast.ClassDef)
              and c.name == "FilterResult" for n in c.body]
    assert fields == list(ssm.FilterResult.__dataclass_fields__)


def test_package_exports_the_module():
    assert implicit.ssm is ssm and "ssm" in implicit.__all__
