"""implicit.control: estimates at one state against closed forms, and the runs against the tool."""
import numpy as np
import pytest

import implicit


def test_double_slit_after_the_wall_is_exact():
    # For t >= t1 the problem is linear-quadratic: every weight is 1 and the estimate equals the
    # closed form u = -sigma x / (gamma + sigma (tf - t)) (spec §2.4.1) up to rounding.
    slit = implicit.control.DoubleSlit()
    k = slit.wall_step + 10
    t = k * 0.02
    for x in (-3.0, 0.5, 4.0):
        e = implicit.control.estimate_control(slit, x, k, samples=20, estimator="corrected")
        assert e["u"] == pytest.approx(slit.exact_control(x, t), rel=1e-6, abs=1e-9)


def test_double_slit_estimators_before_the_wall():
    # The corrected estimator is unbiased for psi; its control at (x = 1, t = 0) over seeds must
    # agree with the exact control within 4.5 standard errors of the mean over seeds.
    slit = implicit.control.DoubleSlit()
    exact = slit.exact_control(1.0, 0.0)
    us = np.array([slit.estimate_control(1.0, 0, 50, "corrected", seed=s)["u"]
                   for s in range(1, 41)])
    se = us.std(ddof=1) / np.sqrt(us.size)
    assert abs(us.mean() - exact) <= 4.5 * se + 1e-9, (us.mean(), exact, se)
    for name in ("paper", "plain"):
        assert np.isfinite(slit.estimate_control(1.0, 0, 50, name)["u"])
    with pytest.raises(ValueError, match="expected 'paper', 'corrected' or 'plain', got 'best'"):
        slit.estimate_control(1.0, 0, 50, "best")


def test_himmelblau_control_matches_the_laplace_control():
    # gamma = sigma R is tiny, so the weights are uniform and u equals the Laplace control
    # (z* - x) / (n dt) to about 1e-6 (himmelblau.hpp).
    e = implicit.control.estimate_control("himmelblau", np.array([-1.0, -4.0]), 0, 50, seed=3)
    assert e["u"].shape == (2,)
    np.testing.assert_allclose(e["u"], e["laplace_u"], rtol=0, atol=1e-4)
    with pytest.raises(ValueError, match=r"x: expected shape \(2,\), got shape \(3,\)"):
        implicit.control.himmelblau_control(np.zeros(3))


def test_control_runs_equal_the_cli_json(cli):
    r = implicit.control.himmelblau(runs=3, samples=20, seed=2)
    c = cli("himmelblau", "--runs", "3", "--samples", "20", "--seed", "2")
    for key in ("runs_below_10", "mean_cost", "mean_final_f"):
        assert r[key] == c[key], key
    r = implicit.control.double_slit(samples=10, runs=4, seed=2)
    c = cli("slit", "--samples", "10", "--runs", "4", "--seed", "2")
    for key in ("error_x_mean", "error_u_mean"):
        assert r[key] == c[key], key
    w = implicit.control.double_slit(samples=10, runs=4, seed=2, estimator="wall-space")
    assert (r["estimator"], w["estimator"]) == ("generic", "wall-space")
    assert w["error_u_mean"] == pytest.approx(r["error_u_mean"], rel=1e-9)  # the same runs
    for estimator in ("generic", "closed-form"):
        r = implicit.control.arm(estimator=estimator)
        c = cli("arm", "--estimator", estimator)
        assert r["estimator"] == c["estimator"] == estimator
        assert r["lqr_max_abs_diff"] == c["lqr_max_abs_diff"]
        assert r["lqr_max_abs_diff"] < 1e-7  # generic: a central difference of the exact log psi
