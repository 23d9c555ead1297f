"""implicit.laser with bad input: every argument of every function gets an
implicit.InvalidArgument whose message starts with the argument's name, never a crash."""
import math

import numpy as np
import pytest

import implicit
from implicit import laser


def room_cells():
    cells = np.zeros((80, 120), np.int8)
    cells[[0, -1], :] = 100
    cells[:, [0, -1]] = 100
    return cells


# Bad input: each argument of each function, the exception type and the argument's name.
GRID = laser.OccupancyGrid(room_cells(), 0.05)
FIELD = laser.LikelihoodField(GRID)
BEAM = laser.BeamModel(GRID)
SCAN = dict(ranges=np.ones(5), angle_min=-0.5, angle_increment=0.25, range_min=0.0,
            range_max=10.0)


def initialized_filter():
    pf = laser.ParticleFilter(GRID, particles=10)
    pf.initialize([2.0, 2.0, 0.0], np.eye(3) * 0.01)
    return pf


def initialized_beam_filter():
    pf = laser.ParticleFilter(GRID, proposal="bootstrap", particles=10, laser=BEAM)
    pf.initialize([2.0, 2.0, 0.0], np.eye(3) * 0.01)
    return pf


def with_scan(fn, **changes):
    return lambda: fn(**{**SCAN, **changes})


SCAN_ROWS = [  # the scan's keywords, the same for every function that takes a scan
    (dict(ranges=np.array([1.0, np.nan])), r"^ranges: expected ranges >= 0"),
    (dict(ranges=np.array([1.0, -1.0])), r"^ranges: expected ranges >= 0 .* at index 1"),
    (dict(ranges=np.ones((2, 2))), r"^ranges: expected shape \(n,\)"),
    (dict(ranges=np.ones(0)), r"^ranges: expected at least one beam"),
    (dict(angle_min=math.nan), r"^angle_min: expected a finite number"),
    (dict(angle_min=None), r"^angle_min: expected a finite number, got NoneType"),
    (dict(angle_increment=0.0), r"^angle_increment: expected a finite non-zero number"),
    (dict(range_min=-1.0), r"^range_min: expected a finite number >= 0"),
    (dict(range_max=0.0), r"^range_max: expected a finite number > 0"),
    (dict(range_min=2.0, range_max=1.0), r"^range_max: expected a finite number > range_min"),
    (dict(range_max="far"), r"^range_max: expected .* got str"),
]
SCAN_TAKERS = {
    "log_likelihood": lambda **s: FIELD.log_likelihood(np.zeros((2, 3)) + 2.0, **s),
    "negative_log_likelihood": lambda **s: FIELD.negative_log_likelihood([2.0, 2.0, 0.0], **s),
    "step": lambda **s: initialized_filter().step([0.1, 0.0, 0.0], **s),
    "beam_log_likelihood": lambda **s: BEAM.log_likelihood(np.zeros((2, 3)) + 2.0, **s),
    "beam_step": lambda **s: initialized_beam_filter().step([0.1, 0.0, 0.0], **s),
}


@pytest.mark.parametrize("taker", sorted(SCAN_TAKERS))
@pytest.mark.parametrize("changes,message", SCAN_ROWS)
def test_bad_scan_arguments_are_named(taker, changes, message):
    with pytest.raises(implicit.InvalidArgument, match=message):
        with_scan(SCAN_TAKERS[taker], **changes)()


def run_with(**changes):
    settings = dict(data=laser.bundled_log("aces"), runs=1, particles=5, max_updates=3)
    return lambda: laser.run(**{**settings, **changes})


Z2 = np.zeros((2, 2), np.int8)
ONE_POSE = np.zeros((1, 3))
CARMEN_LIKE = dict(ranges=[np.ones(3)], angle_min=[0.0], angle_increment=[0.1], range_max=[5.0])
ODO = laser.OdometryModel()
X0, U0 = [0, 0, 0], [1, 0, 0]


def grid(*args):
    return lambda: laser.OccupancyGrid(*args)


def build(poses=ONE_POSE, scans=(SCAN,), **kw):
    return lambda: laser.build_map(poses, scans if isinstance(scans, (dict, int)) else list(scans),
                                   **kw)


def sim(*args, **kw):
    return lambda: laser.simulate_scan(*(args or (GRID, [1, 1, 0])), **kw)


def field(*args, **kw):
    return lambda: laser.LikelihoodField(*(args or (GRID,)), **kw)


def beam(*args, **kw):
    return lambda: laser.BeamModel(*(args or (GRID,)), **kw)


def pf(*args, **kw):
    return lambda: laser.ParticleFilter(*(args or (GRID,)), **kw)


def init(mean, cov):
    return lambda: laser.ParticleFilter(GRID).initialize(mean, cov)


GRID_TYPE = r"expected an implicit\.laser\.OccupancyGrid"
BAD = [
    # OccupancyGrid
    (grid(np.zeros((3, 3)), 0.1), r"^cells: expected integer .* got dtype float64"),
    (grid(np.zeros(3, np.int8), 0.1), r"^cells: expected a 2-D array"),
    (grid(np.zeros((0, 3), np.int8), 0.1), r"^cells: expected at least one row"),
    (grid(np.full((2, 2), 101), 0.1), r"^cells: expected values in -1\.\.100, got 101"),
    (grid(Z2, 0.0), r"^resolution: expected a finite number > 0, got 0"),
    (grid(Z2, "a"), r"^resolution: expected .* got str"),
    (grid(Z2, 0.1, (0, 0, 0)), r"^origin: expected shape \(2,\)"),
    (grid(Z2, 0.1, (0, math.nan)), r"^origin: expected finite values"),
    # map files and logs
    (lambda: laser.load_map(3), r"^yaml_path: expected a path"),
    (lambda: laser.save_map(np.zeros((2, 2)), "x.yaml"), r"^grid: " + GRID_TYPE),
    (lambda: laser.save_map(GRID, None), r"^yaml_path: expected a path"),
    (lambda: laser.read_carmen(None), r"^path: expected a path"),
    (lambda: laser.read_carmen(""), r"^path: expected a file name"),
    (lambda: laser.bundled_log("mars"), r"^name: expected 'intel', 'aces' or 'freiburg-079'"),
    (lambda: laser.scan_at([], 0), r"^log: expected the dict of read_carmen"),
    (lambda: laser.scan_at(CARMEN_LIKE, 1), r"^k: expected a scan index in \[0, 1\), got 1"),
    (lambda: laser.scan_at(CARMEN_LIKE, 0.5), r"^k: expected an integer scan index"),
    # build_map
    (build(poses=np.zeros(3)), r"^poses: expected shape \(n, 3\)"),
    (build(poses=np.zeros((2, 3))), r"^poses: expected one pose per scan"),
    (build(scans=5), r"^scans: expected the dict of read_carmen or a list"),
    (build(scans=(5,)), r"^scans\[0\]: expected a dict"),
    (build(scans=(dict(SCAN, angle_increment=0),)), r"^scans\[0\]\.angle_increment: expected"),
    (build(scans=dict(ranges=np.ones((1, 3)))), r"^scans: expected the key 'angle_min'"),
    (build(mount=(0, 0)), r"^mount: expected shape \(3,\)"),
    (build(resolution=-1), r"^resolution: expected a finite number > 0"),
    (build(max_range=math.nan), r"^max_range: expected a finite number >= 0"),
    (build(min_echoes=-1), r"^min_echoes: expected an integer in \[0, 255\], got -1"),
    (build(min_echoes=2.5), r"^min_echoes: expected an integer in \[0, 255\], got float"),
    # simulate_scan
    (sim("room", [1, 1, 0]), r"^grid: " + GRID_TYPE + ", got str"),
    (sim(GRID, [1, 1]), r"^pose: expected shape \(3,\)"),
    (sim(mount=[0, math.inf, 0]), r"^mount: expected finite values"),
    (sim(beams=0), r"^beams: expected an integer in \[1, 100000\], got 0"),
    (sim(beams=2.5), r"^beams: expected an integer .* got float"),
    (sim(field_of_view=0), r"^field_of_view: expected a number in \(0, 6\.28"),
    (sim(range_min=-1), r"^range_min: expected a finite number >= 0"),
    (sim(range_max=0.01), r"^range_max: expected a finite number > 0\.05, got 0\.01"),
    (sim(range_std=-0.1), r"^range_std: expected a finite number >= 0"),
    (sim(seed=-1), r"^seed: expected an integer in \[0, 2\^64 - 1\], got -1$"),
    # LikelihoodField
    (field(None), r"^grid: " + GRID_TYPE + ", got NoneType"),
    (field(z_hit=0), r"^z_hit: expected a finite number > 0"),
    (field(z_rand=-1), r"^z_rand: expected a finite number >= 0"),
    (field(sigma_hit=0), r"^sigma_hit: expected a finite number > 0"),
    (field(max_dist=math.nan), r"^max_dist: expected a finite number > 0, got nan"),
    (field(max_beams=0), r"^max_beams: expected an integer in"),
    (field(interpolation="cubic"), r"^interpolation: expected 'nearest', 'bilinear' or 'bicubic'"),
    (field(aggregation="sum"), r"^aggregation: expected 'product' or 'cubed-sum', got 'sum'"),
    (field(mount=(0, 0)), r"^mount: expected shape \(3,\)"),
    (lambda: FIELD.log_likelihood(np.zeros(3), **SCAN), r"^poses: expected shape \(n, 3\)"),
    (lambda: FIELD.negative_log_likelihood(ONE_POSE, **SCAN), r"^pose: expected shape \(3,\)"),
    (lambda: laser.LikelihoodField(GRID, interpolation="nearest").negative_log_likelihood(
        X0, **SCAN), r"^negative_log_likelihood: expected interpolation 'bilinear' or"),
    # BeamModel
    (beam("room"), r"^grid: " + GRID_TYPE + ", got str"),
    (beam(z_hit=0), r"^z_hit: expected a finite number > 0, got 0"),
    (beam(z_hit=math.nan), r"^z_hit: expected a finite number > 0, got nan"),
    (beam(z_short=-0.1), r"^z_short: expected a finite number >= 0, got -0\.1"),
    (beam(z_short=math.nan), r"^z_short: expected a finite number >= 0, got nan"),
    (beam(z_max=-1), r"^z_max: expected a finite number >= 0, got -1"),
    (beam(z_max=math.inf), r"^z_max: expected a finite number >= 0, got inf"),
    (beam(z_rand=-0.5), r"^z_rand: expected a finite number >= 0, got -0\.5"),
    (beam(z_rand="half"), r"^z_rand: expected .* got str"),
    (beam(sigma_hit=0), r"^sigma_hit: expected a finite number > 0, got 0"),
    (beam(sigma_hit=math.nan), r"^sigma_hit: expected a finite number > 0, got nan"),
    (beam(lambda_short=0), r"^lambda_short: expected a finite number > 0, got 0"),
    (beam(lambda_short=-1), r"^lambda_short: expected a finite number > 0, got -1"),
    (beam(max_beams=0), r"^max_beams: expected an integer in \[1, 1000000\], got 0"),
    (beam(max_beams=2.0), r"^max_beams: expected an integer .* got float"),
    (beam(laser_max_range=0), r"^laser_max_range: expected a finite number > 0, got 0"),
    (beam(laser_max_range=math.nan), r"^laser_max_range: expected a finite number > 0"),
    (beam(laser_min_range=-1), r"^laser_min_range: expected a finite number > 0, got -1"),
    (beam(mount=(0, 0)), r"^mount: expected shape \(3,\)"),
    (beam(mount=(0, math.nan, 0)), r"^mount: expected finite values"),
    (lambda: BEAM.log_likelihood(np.zeros(3), **SCAN), r"^poses: expected shape \(n, 3\)"),
    (lambda: BEAM.log_likelihood([[0, 0, math.nan]], **SCAN), r"^poses: expected finite values"),
    # OdometryModel
    (lambda: laser.OdometryModel(alpha1=-1), r"^alpha1: expected a finite number >= 0"),
    (lambda: laser.OdometryModel(alpha2=math.nan), r"^alpha2: expected a finite number"),
    (lambda: laser.OdometryModel(alpha3=math.inf), r"^alpha3: expected a finite number"),
    (lambda: laser.OdometryModel(alpha4="x"), r"^alpha4: expected .* got str"),
    (lambda: ODO.predict([0, 0], U0), r"^pose: expected shape \(3,\)"),
    (lambda: ODO.predict(X0, [1, 0]), r"^u: expected shape \(3,\)"),
    (lambda: ODO.covariance([0, 0, math.nan], U0), r"^pose: expected finite values"),
    (lambda: ODO.covariance(X0, None), r"^u: expected shape \(3,\), got shape \(\)"),
    (lambda: ODO.sample([0, 0], U0), r"^pose: expected shape \(3,\)"),
    (lambda: ODO.sample(X0, [1, 0]), r"^u: expected shape \(3,\)"),
    (lambda: ODO.sample(X0, U0, seed=-2),
     r"^seed: expected an integer in \[0, 2\^64 - 1\], got -2$"),
    (lambda: ODO.sample(X0, U0, n=-1), r"^n: expected an integer in"),
    (lambda: ODO.sample(X0, U0, n=2.0), r"^n: expected an integer .* got float"),
    # ParticleFilter
    (pf([[0]]), r"^grid: " + GRID_TYPE + ", got list"),
    (pf(proposal="magic"), r"^proposal: expected 'implicit' or 'bootstrap', got 'magic'"),
    (pf(particles=0), r"^particles: expected an integer in \[1, 10000000\], got 0"),
    (pf(particles=-5), r"^particles: expected an integer in"),
    (pf(particles=10.5), r"^particles: expected an integer .* got float"),
    (pf(seed=-1), r"^seed: expected an integer in \[0, 2\^64 - 1\], got -1$"),
    (pf(seed=2**64), r"^seed: expected an integer in \[0, 2\^64 - 1\], got 18446744073709551616$"),
    (pf(alphas=(0.1, 0.1)), r"^alphas: expected shape \(4,\)"),
    (pf(alphas=(0.1, -0.1, 0.1, 0.1)), r"^alphas: expected alpha1\.\.alpha4 >= 0, got -0\.1"),
    (pf(laser=[1]), r"^laser: expected a dict of LikelihoodField keywords"),
    (pf(laser={"sigma": 1}), r"^ParticleFilter: unknown keyword 'sigma'"),
    (pf(foo=1), r"^ParticleFilter: unknown keyword 'foo'"),
    (pf(laser={"z_hit": 1}, z_hit=2), r"^laser: 'z_hit' is given both"),
    (pf(laser={"sigma_hit": -1}), r"^sigma_hit: expected a finite number > 0"),
    (pf(max_beams=0), r"^max_beams: expected an integer"),
    (pf(interpolation="nearest"), r"^interpolation: the implicit proposal needs"),
    (pf(aggregation="cubed-sum"), r"^aggregation: the implicit proposal needs"),
    (pf(starts=0), r"^starts: expected an integer in \[1, 64\], got 0"),
    (pf(start_probe=-1), r"^start_probe: expected an integer in \[0, 20\], got -1"),
    (pf(start_probe=1.5), r"^start_probe: expected an integer"),
    (pf(resample_threshold=1.5), r"^resample_threshold: expected a number in \[0, 1\], got 1\.5"),
    # ... on the beam model: the bootstrap proposal only (the C++ filter's refusal, named)
    (pf(laser=BEAM), r"^proposal: the implicit proposal needs an observation model with "
     r"derivatives, and the beam model has none"),
    (pf(proposal="implicit", laser=BEAM, starts=3), r"^proposal: the implicit proposal needs"),
    (pf(proposal="bootstrap", laser=BEAM, sigma_hit=0.1),
     r"^laser: 'sigma_hit' is a LikelihoodField keyword, and laser is a BeamModel"),
    (pf(laser.OccupancyGrid(Z2, 0.05), proposal="bootstrap", laser=BEAM),
     r"^laser: expected a BeamModel built on grid, got one on another map"),
    (pf(proposal="bootstrap", laser=FIELD), r"^laser: expected a dict of LikelihoodField keywords "
     r".*, a BeamModel or None, got LikelihoodField"),
    (init([0, 0], np.eye(3)), r"^mean: expected shape \(3,\)"),
    (init(X0, np.eye(2)), r"^covariance: expected shape \(3, 3\)"),
    (init(X0, -np.eye(3)), r"^covariance: expected a positive definite matrix"),
    (init(X0, np.eye(3) + np.triu(np.ones((3, 3)), 1)), r"^covariance: expected a symmetric"),
    (lambda: laser.ParticleFilter(GRID).step(X0), r"^step: call initialize\(mean, covariance\)"),
    (lambda: initialized_filter().step([0, 0]), r"^u: expected shape \(3,\)"),
    (lambda: initialized_filter().step(X0, angle_min=0.0), r"^ranges: expected the scan's ranges"),
    # run
    (run_with(data=None), r"^data: expected a path"),
    (run_with(proposal="standard-ish"), r"^proposal: expected 'implicit' or 'bootstrap'"),
    (run_with(particles=0), r"^particles: expected an integer in \[1, 10000000\], got 0"),
    (run_with(runs=0), r"^runs: expected an integer in \[1, 100000\], got 0"),
    (run_with(seed=-1), r"^seed: expected an integer in \[0, 2\^64 - 1\], got -1$"),
    (run_with(alphas=(0.1,) * 3), r"^alphas: expected shape \(4,\)"),
    (run_with(filter_alphas=(-1, 0, 0, 0)), r"^filter_alphas: expected alpha1\.\.alpha4 >= 0"),
    (run_with(map=5), r"^map: expected a path"),
    (run_with(start="anywhere"), r"^start: expected 'known' or 'global', got 'anywhere'"),
    (run_with(max_updates=-1), r"^max_updates: expected an integer >= 0, got -1"),
    (run_with(implicit_map="curved"), r"^implicit_map: expected 'linear' or 'random'"),
    (run_with(starts=65), r"^starts: expected an integer in \[1, 64\], got 65"),
    (run_with(start_probe=21), r"^start_probe: expected an integer in \[0, 20\], got 21"),
    (run_with(z_hit=-1), r"^z_hit: expected a finite number > 0"),
    (run_with(z_rand=math.nan), r"^z_rand: expected a finite number >= 0"),
    (run_with(sigma_hit=0), r"^sigma_hit: expected a finite number > 0"),
    (run_with(max_dist=0), r"^max_dist: expected a finite number > 0"),
    (run_with(max_beams=1.5), r"^max_beams: expected an integer"),
    (run_with(laser_max_range=0), r"^laser_max_range: expected a finite number > 0"),
    (run_with(interpolation="nearest"), r"^interpolation: the implicit proposal needs"),
    (run_with(aggregation="max"), r"^aggregation: expected 'product' or 'cubed-sum'"),
    (run_with(laser_model="sonar"), r"^laser_model: expected 'likelihood-field' or 'beam', "
     r"got 'sonar'"),
    (run_with(laser_model=None), r"^laser_model: expected 'likelihood-field' or 'beam', got "
     r"NoneType"),
    (run_with(laser_model="beam"), r"^proposal: the implicit proposal needs an observation model "
     r"with derivatives, and the beam model has none"),
    (run_with(proposal="bootstrap", laser_model="beam", z_short=-1),
     r"^z_short: expected a finite number >= 0, got -1"),
    (run_with(z_max=math.nan), r"^z_max: expected a finite number >= 0, got nan"),
    (run_with(lambda_short=0), r"^lambda_short: expected a finite number > 0, got 0"),
    (run_with(proposal="bootstrap", laser_model="beam", sigma_hit=0),
     r"^sigma_hit: expected a finite number > 0, got 0"),
    (run_with(proposal="bootstrap", laser_model="beam", z_hit=0),
     r"^z_hit: expected a finite number > 0, got 0"),
    (run_with(proposal="bootstrap", laser_model="beam", max_beams=0),
     r"^max_beams: expected an integer in \[1, 1000000\], got 0"),
    (run_with(kld="yes"), r"^kld: expected True or False, got str"),
    (run_with(kld_err=0), r"^kld_err: expected a number in \[1e-06, 1\], got 0"),
    (run_with(kld_err=1e-7), r"^kld_err: expected a number in \[1e-06, 1\], got 1e-07"),
    (run_with(kld_z=math.nan), r"^kld_z: expected a number in \[0, 10\], got nan"),
    (run_with(recovery="mixture"), r"^recovery: 'mixture' is the landmark runs' source"),
    (run_with(recovery="auto"), r"^recovery: expected 'none' or 'uniform', got 'auto'"),
    (run_with(recovery=True), r"^recovery: expected 'none' or 'uniform', got bool"),
    (run_with(recovery_alpha_slow=0), r"^recovery_alpha_slow: expected a number in \(0, 1\]"),
    (run_with(recovery_alpha_fast=0.0005), r"^recovery_alpha_fast: expected a number > "
     r"recovery_alpha_slow = 0\.001, got 0\.0005"),
    (run_with(kidnap_probability=0.9), r"^kidnap_probability: expected a number in \(0, 0\.5\]"),
    (run_with(update_min_d=-1), r"^update_min_d: expected a finite number >= 0"),
    (run_with(update_min_a=math.nan), r"^update_min_a: expected a finite number >= 0"),
    (run_with(map_resolution=2.0), r"^map_resolution: expected a number in \[0\.005, 1\]"),
    (run_with(map_min_echoes=256), r"^map_min_echoes: expected an integer in \[0, 255\], got 256"),
    (run_with(map_min_echoes=None), r"^map_min_echoes: expected an integer in \[0, 255\], got None"),
    (run_with(global_updates=0), r"^global_updates: expected an integer in"),
    (run_with(global_radius=0), r"^global_radius: expected a finite number > 0"),
    (run_with(tracks="yes"), r"^tracks: expected True or False, got str"),
    (run_with(threads=-1), r"^threads: expected an integer in"),
    (run_with(progress=3), r"^progress: expected a callable"),
]


@pytest.mark.parametrize("call,message", BAD, ids=[f"row{k}" for k in range(len(BAD))])
def test_bad_arguments_are_named(call, message):
    with pytest.raises(implicit.InvalidArgument, match=message):
        call()
