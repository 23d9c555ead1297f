"""Models, data, the steppable filters and the one-call runners, against the C++ tool."""
import math

import numpy as np
import pytest

import implicit


def rmse(means, truth):
    """Position RMSE over the steps with ground truth (spec §4; localization_metrics)."""
    ok = np.isfinite(truth).all(axis=1)
    return math.sqrt(((means[ok, :2] - truth[ok]) ** 2).sum(axis=1).mean())


def run_filter(steps, proposal, particles, seed):
    pf = implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(),
                                 steps.landmarks, proposal=proposal, particles=particles,
                                 seed=seed)
    pf.initialize(steps.initial_mean, steps.initial_covariance)
    means = np.empty((len(steps), 3))
    for n, (u, dt, z) in enumerate(zip(steps.controls, steps.dt, steps.detections)):
        pf.step(u, dt, z)
        means[n] = pf.mean()
    return pf, means


@pytest.fixture(scope="module")
def carpark_steps():
    return implicit.data.steps(implicit.data.carpark(), implicit.models.Ute())


def test_mcl_run_equals_the_cli_json(cli):
    # The acceptance check: the same settings and seed give the same numbers as the tool.
    r = implicit.mcl.run(method="implicit", particles=100, runs=2, seed=1)
    c = cli("mcl", "--method", "implicit", "-M", "100", "--runs", "2", "--seed", "1")
    for key in ("rmse_m", "error_percent_mean", "heading_rmse_rad", "ess_mean",
                "error_percent_runs", "detections_used", "steps", "lost_runs"):
        assert r[key] == c[key], key


def test_global_start_and_kidnapping_equal_the_cli_json(cli):
    # Localization without a known start through Python: the same runs as the tool.
    r = implicit.mcl.run(method="implicit", particles=30, runs=2, seed=1, init="global",
                         duration=45, start_span=5)
    c = cli("mcl", "--method", "implicit", "-M", "30", "--runs", "2", "--seed", "1", "--init",
            "global", "--duration", "45", "--start-span", "5")
    for key in ("global_success_rate", "success_runs", "time_to_converge_s_runs",
                "rmse_after_settle_m_median", "particles_mean", "steps"):
        assert r[key] == c[key], key
    k = implicit.mcl.run(method="standard", particles=50, runs=1, kidnap_at=5, kidnap_skip=5,
                         duration=45, kld=True, min_particles=20, max_particles=200)
    assert 0.0 <= k["kidnap_recovery_rate"] <= 1.0 and k["particles_peak"] <= 200
    with pytest.raises(ValueError, match="--kidnap-at"):
        implicit.mcl.run(init="global", kidnap_at=5, runs=1)


@pytest.mark.parametrize("proposal,cli_method", [("implicit", "implicit"),
                                                 ("bootstrap", "standard")])
def test_stepping_from_python_reproduces_the_cli_run(carpark_steps, proposal, cli_method):
    # One run with seed s uses the filter seed s * runs + 0 = s: stepping the same filter from
    # Python must give the same trajectory, hence the same RMSE, as the C++ loop.
    seed, particles = 3, 50
    _, means = run_filter(carpark_steps, proposal, particles, seed)
    r = implicit.mcl.run(method=cli_method, particles=particles, runs=1, seed=seed)
    assert rmse(means, carpark_steps.truth) == pytest.approx(r["rmse_m"], rel=1e-12, abs=0)


def test_filter_arrays_shapes_dtypes_and_views(carpark_steps):
    pf = implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(),
                                 carpark_steps.landmarks, particles=64, seed=1)
    pf.initialize(carpark_steps.initial_mean, carpark_steps.initial_covariance)
    for n in range(200):
        pf.step(carpark_steps.controls[n], carpark_steps.dt[n], carpark_steps.detections[n])
    p, w = pf.particles, pf.weights
    assert p.shape == (64, 3) and p.dtype == np.float64 and w.shape == (64,)
    assert abs(w.sum() - 1.0) < 1e-12 and not p.flags.writeable
    assert np.allclose(pf.mean()[:2], w @ p[:, :2], rtol=0, atol=1e-9)
    assert 1.0 <= pf.ess <= 64.0
    assert pf.covariance().shape == (3, 3)


def test_filter_errors_are_python_exceptions(carpark_steps):
    lm = carpark_steps.landmarks
    with pytest.raises(ValueError, match="expected 'implicit' or 'bootstrap', got 'magic'"):
        implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(), lm,
                                proposal="magic")
    with pytest.raises(ValueError, match=r"landmarks: expected shape \(n, 2\), got shape \(15,\)"):
        implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(), lm[:, 0])
    pf = implicit.ParticleFilter(implicit.models.Ute(), implicit.models.RangeBearing(), lm)
    with pytest.raises(ValueError, match="call initialize"):
        pf.step([1.0, 0.0], 0.025)
    pf.initialize(carpark_steps.initial_mean, carpark_steps.initial_covariance)
    with pytest.raises(ValueError, match=r"detections: expected shape \(n, 3\), got shape \(2,\)"):
        pf.step([1.0, 0.0], 0.025, np.array([1.0, 2.0]))
    with pytest.raises(ValueError, match="control: expected finite values"):
        pf.step([np.nan, 0.0], 0.025)
    with pytest.raises(ValueError, match="positive step length"):
        pf.step([1.0, 0.0], -1.0)
    with pytest.raises(ValueError, match="mcl --method: expected 'standard' or 'implicit', got 'x'"):
        implicit.mcl.run(method="x", runs=1)
    with pytest.raises(ValueError, match="Ute time step dt: expected > 0"):
        implicit.models.Ute(dt=0.0)


def test_data_sets_and_logs(tmp_path):
    log = implicit.data.carpark()
    assert log.landmarks.shape == (15, 2) and log.controls.shape[1] == 2
    assert log.control_times.shape == (log.controls.shape[0],)
    assert log.initial_mean.shape == (3,)
    sim = implicit.data.simulate(implicit.models.Unicycle(), implicit.models.RangeBearing(),
                                 steps=300, landmarks=12, seed=4)
    assert sim.vehicle == "unicycle" and sim.landmarks.shape == (12, 2)
    path = tmp_path / "sim.log"
    sim.write(str(path))
    back = implicit.data.read_log(str(path))
    np.testing.assert_allclose(back.landmarks, sim.landmarks, rtol=1e-9)
    assert back.controls.shape == sim.controls.shape
    with pytest.raises(ValueError):
        implicit.data.read_log(str(tmp_path / "missing.log"))
    with pytest.raises(ValueError, match="steps: model: expected implicit.models.Ute or"):
        implicit.data.steps(log, implicit.models.RangeBearing())
    vp = implicit.data.victoria_park()
    assert vp.controls.shape[0] > 1000


def test_models_match_their_equations():
    ute = implicit.models.Ute()
    x = np.array([1.0, 2.0, 0.3])
    # Straight ahead (steering 0): the axle moves v dt along the heading (spec §3.1).
    y = ute.predict(x, [2.0, 0.0])
    np.testing.assert_allclose(y[:2] - x[:2], 2.0 * 0.025 * np.array([math.cos(0.3), math.sin(0.3)]),
                               rtol=0, atol=1e-12)
    s = implicit.models.RangeBearing()
    z = s.predict([0.0, 0.0, 0.0], [3.0, 4.0])
    assert z[0] == pytest.approx(5.0)
    np.testing.assert_allclose(s.noise_covariance, np.diag([0.05, 0.05 * math.pi / 180]))


def test_slam_run_equals_the_cli_json(cli):
    r = implicit.slam.run(method="fastslam2", particles=10, datasets=2, seed=2)
    c = cli("slam", "--method", "fastslam2", "-M", "10", "--datasets", "2", "--seed", "2")
    for key in ("error_percent_mean", "map_shape_m", "rmse_pose_m"):
        assert r[key] == c[key], key
    with pytest.raises(ValueError, match="unknown|expected"):
        implicit.slam.run(method="nonsense", datasets=1)


def aligned(p, q):
    """p moved by the rotation and translation that fit it best to q (least squares, Kabsch):
    a SLAM map is defined up to the frame of its start."""
    pm, qm = p.mean(axis=0), q.mean(axis=0)
    u, _, vt = np.linalg.svd((p - pm).T @ (q - qm))
    r = (u @ np.diag([1.0, np.sign(np.linalg.det(u @ vt))]) @ vt).T
    return (p - pm) @ r.T + qm


def test_slam_filter_on_a_simulated_log():
    model = implicit.models.Ute()
    log = implicit.data.simulate(model, implicit.models.RangeBearing(), steps=600, seed=2)
    steps = implicit.data.steps(log, model)
    # Baseline computed here, independently of the filters: each landmark placed by its first
    # detection from the dead-reckoned pose. SLAM must map the landmarks better than that.
    x, first = steps.initial_mean.copy(), {}
    for u, dt, z in zip(steps.controls, steps.dt, steps.detections):
        x = model.predict(x, u, dt)
        for i, r, b in z:
            first.setdefault(int(i), x[:2] + r * np.array([np.cos(x[2] + b), np.sin(x[2] + b)]))
    seen = np.array(sorted(first))
    guess = np.array([first[i] for i in seen])
    baseline = np.median(np.linalg.norm(aligned(guess, steps.landmarks[seen])
                                        - steps.landmarks[seen], axis=1))
    for method in ("ekf", "fastslam1", "fastslam2", "implicit", "implicit-rb"):
        f = implicit.slam.Filter(method=method, particles=20, seed=1, model=model,
                                 initial_pose=steps.initial_mean)
        for u, dt, z in zip(steps.controls, steps.dt, steps.detections):
            f.step(u, dt, z)
        positions, ids = f.map()
        assert positions.shape == (len(seen), 2) and ids.dtype.kind == "i"
        assert sorted(ids) == list(seen), method  # known association: one per landmark seen
        err = np.linalg.norm(aligned(positions, steps.landmarks[ids]) - steps.landmarks[ids],
                             axis=1)
        assert np.median(err) < baseline, (method, np.median(err), baseline)
        assert f.mean().shape == (3,) and f.covariance().shape == (3, 3)
    with pytest.raises(ValueError, match="ekf"):
        implicit.slam.Filter(method="kalman")
