"""implicit.laser: grids and map files, the likelihood field and the beam model against closed
forms computed here, the odometry model against its equations, filters tracking a simulated path,
and the one-call run against `implicit mcl --sensor laser --json`."""
import math

import numpy as np
import pytest

from implicit import laser

EPS = np.finfo(float).eps
U24 = 2.0 ** -24  # unit roundoff of float, in which the field stores what it tabulates


def compose(a, d):
    """a ⊕ d for poses (..., 3), written out here, independently of the library."""
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([a[..., 0] + c * d[..., 0] - s * d[..., 1],
                     a[..., 1] + s * d[..., 0] + c * d[..., 1], a[..., 2] + d[..., 2]], axis=-1)


def between(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, b[2] - a[2]])


def end_points(pose, mount, ranges, angle_min, angle_increment, used):
    """World end points (k, 2) of the beams `used` at robot pose, and their offsets from it."""
    b = angle_min + angle_increment * np.flatnonzero(used)
    r = ranges[used]
    sensor = np.stack([r * np.cos(b), r * np.sin(b), np.zeros_like(r)], axis=-1)
    e = compose(np.asarray(mount, float), sensor)  # in the robot frame
    p = compose(np.asarray(pose, float), e)
    return p[:, :2], p[:, :2] - np.asarray(pose, float)[:2]


def beam_log_density(d, z_hit, z_rand, sigma, z_max):
    """log(z_hit N(d; 0, sigma^2) + z_rand / z_max) per beam, and the hit share gamma."""
    hit = z_hit / (math.sqrt(2 * math.pi) * sigma) * np.exp(-0.5 * d**2 / sigma**2)
    return np.log(hit + z_rand / z_max), hit / (hit + z_rand / z_max)


# One wall: column 80 of a grid of 1/16 m cells (x in [5, 5.0625)), every row. Distances between
# cell centres are then multiples of 1/16 m, exact in the float the distance field stores, and
# the nearest occupied cell of a cell is the wall cell in its own row.
RES = 1.0 / 16
WALL = 80


@pytest.fixture(scope="module")
def wall_grid():
    cells = np.zeros((80, 96), np.int8)
    cells[:, WALL] = 100
    return laser.OccupancyGrid(cells, RES, origin=(0.0, 0.0))


def room_cells():
    """A 6 m x 4 m room of 5 cm cells with a box and a stub wall (so no pose looks like another)."""
    cells = np.zeros((80, 120), np.int8)
    cells[[0, -1], :] = 100
    cells[:, [0, -1]] = 100
    cells[30:40, 70:80] = 100   # a box, x 3.5-4.0 m, y 1.5-2.0 m
    cells[60:, 30] = 100        # a stub wall at x = 1.5 m from y = 3 m up
    return cells


@pytest.fixture(scope="module")
def room():
    return laser.OccupancyGrid(room_cells(), 0.05)


def test_grid_numpy_round_trip():
    rng = np.random.default_rng(1)
    cells = rng.integers(-1, 101, size=(7, 11)).astype(np.int8)
    g = laser.OccupancyGrid(cells, 0.25, origin=(-1.5, 2.0))
    assert g.cells.dtype == np.int8 and g.cells.shape == (7, 11)
    np.testing.assert_array_equal(g.cells, cells)
    assert (g.width, g.height, g.resolution, g.origin) == (11, 7, 0.25, (-1.5, 2.0))
    g.cells[0, 0] = 55  # a copy: the grid keeps its own cells
    assert g.cells[0, 0] == cells[0, 0]
    # Any integer dtype is taken (a list of lists is int64 to numpy).
    np.testing.assert_array_equal(laser.OccupancyGrid(cells.tolist(), 0.25).cells, cells)
    assert "width=11" in repr(g)


def test_save_and_load_map_round_trip(tmp_path):
    rng = np.random.default_rng(2)
    trinary = rng.choice(np.array([-1, 0, 100], np.int8), size=(30, 45))
    g = laser.OccupancyGrid(trinary, 0.05, origin=(-3.2, 1.15))
    laser.save_map(g, tmp_path / "room.yaml")
    back = laser.load_map(str(tmp_path / "room.yaml"))
    np.testing.assert_array_equal(back.cells, trinary)  # row 0 stays the lowest y
    assert back.resolution == 0.05 and back.origin == (-3.2, 1.15)
    # Other values load back on the right side of map_server's thresholds (occupied >= 65,
    # free 0..19), as save_map documents.
    grey = rng.integers(-1, 101, size=(20, 20)).astype(np.int8)
    laser.save_map(laser.OccupancyGrid(grey, 0.1), tmp_path / "grey.yaml")
    c = laser.load_map(tmp_path / "grey.yaml").cells
    np.testing.assert_array_equal(c >= 65, grey >= 65)
    np.testing.assert_array_equal((c >= 0) & (c <= 19), (grey >= 0) & (grey <= 19))


def wall_scan(rng, beams=37, range_max=4.0, range_min=0.1):
    ranges = rng.uniform(0.2, 1.4, beams)
    ranges[[3, 17, 30]] = range_max       # no return: not a wall, skipped
    ranges[[8, 25]] = 0.05                # below range_min: skipped
    return dict(ranges=ranges, angle_min=-math.pi / 2, angle_increment=math.pi / 36,
                range_min=range_min, range_max=range_max)


def beam_model_log_density(r, no_return, zhat, weights, sigma, lam, range_max):
    """Spec §3.12, "The beam model", per beam, written out here: log p(r | zhat) of a reading r <
    range_max, log P(no return | zhat) where no_return. weights = (z_hit, z_short, z_max, z_rand)."""
    z_hit, z_short, z_max, z_rand = weights
    total = sum(weights)
    hit = z_hit * np.exp(-0.5 * ((r - zhat) / sigma) ** 2) / (math.sqrt(2 * math.pi) * sigma)
    short = np.where(r <= zhat, z_short * lam * np.exp(-lam * r) / -np.expm1(-lam * zhat), 0.0)
    density = (hit + short + z_rand / range_max) / total
    upper_tail = np.array([0.5 * math.erfc((range_max - e) / (sigma * math.sqrt(2))) for e in zhat])
    missed = (z_hit * upper_tail + z_max) / total
    return np.log(np.where(no_return, missed, density))


def range_to_wall(origin, heading, range_max, height=80 * RES):
    """Where a ray from origin (x < 5 m) along heading meets the one-wall grid's wall, whose face
    is the line x = 5 m (column 80's left edge): (5 - x) / cos(heading) if the ray gets there
    inside the grid (0 <= y < height) within range_max, else range_max (nothing else is occupied,
    and outside the grid is empty)."""
    c, s = np.cos(heading), np.sin(heading)
    ahead = c > 0  # the others leave the grid on the left, where nothing is occupied
    t = np.where(ahead, (WALL * RES - origin[0]) / np.where(ahead, c, 1.0), 0.0)
    y = origin[1] + t * s
    inside = ahead & (y >= 0) & (y < height)
    # No ray passes within a hair of the grid's corners or of range_max: the cases are clear.
    assert np.all(np.abs(np.where(ahead, y, 1.0)) > 1e-6)
    assert np.all(np.abs(np.where(ahead, y - height, 1.0)) > 1e-6)
    assert np.all(np.abs(np.where(inside, t - range_max, 1.0)) > 1e-6)
    return np.where(inside & (t < range_max), t, range_max)


@pytest.mark.parametrize("max_beams,max_range,min_range", [(60, None, None), (10, 3.5, 0.15)])
def test_beam_model_equals_the_closed_form_on_one_wall(wall_grid, max_beams, max_range,
                                                       min_range):
    # The expected range of a beam is the distance to the wall along it (the ray cast enters the
    # wall cell at its left face); the density of each reading is the spec's, so log p has a
    # closed form. laser_max_range and laser_min_range, when given, replace the scan's.
    weights, sigma, lam = (0.6, 0.1, 0.05, 0.3), 0.15, 0.3
    mount = (0.1, -0.05, 0.2)
    beam = laser.BeamModel(wall_grid, z_hit=weights[0], z_short=weights[1], z_max=weights[2],
                           z_rand=weights[3], sigma_hit=sigma, lambda_short=lam,
                           max_beams=max_beams, laser_max_range=max_range,
                           laser_min_range=min_range, mount=mount)
    assert not beam.differentiable
    rng = np.random.default_rng(8)
    n = 37
    ranges = rng.uniform(0.2, 3.9, n)
    ranges[[3, 17, 30]] = 4.0             # the scan's range_max: no return
    ranges[[8, 25]] = 0.05                # below the scan's range_min
    ranges[[12, 27]] = 0.12               # below min_range only
    ranges[[6, 36]] = 3.7                 # beyond max_range only: no return there
    scan = dict(ranges=ranges, angle_min=-math.pi / 2, angle_increment=math.pi / 36,
                range_min=0.1, range_max=4.0)
    range_max = max_range or scan["range_max"]
    range_min = min_range or scan["range_min"]
    poses = np.column_stack([rng.uniform(2.5, 3.5, 6), rng.uniform(2.0, 3.0, 6),
                             rng.uniform(-math.pi / 2, math.pi / 2, 6)])
    got = beam.log_likelihood(poses, **scan)
    picked = np.zeros(n, bool)
    m = min(n, max_beams)
    picked[np.rint(np.arange(m) * (n - 1) / (m - 1)).astype(int)] = True
    no_return = ranges >= range_max
    used = picked & (no_return | (ranges >= range_min))
    assert 0 < (picked & no_return).sum() and used.sum() < picked.sum()  # both cases are met
    bearings = scan["angle_min"] + scan["angle_increment"] * np.flatnonzero(used)
    saw = {"hit": 0, "short": 0, "open": 0}
    for pose, value in zip(poses, got):
        origin = compose(pose, np.array(mount))
        zhat = range_to_wall(origin[:2], origin[2] + bearings, range_max)
        r = np.where(no_return[used], range_max, ranges[used])
        reading = ~no_return[used]
        assert np.abs(r - zhat)[reading].min() > 1e-9  # none on the short term's edge r = zhat
        saw["hit"] += int((zhat < range_max).sum())
        saw["short"] += int((r < zhat).sum())
        saw["open"] += int((zhat == range_max).sum())
        terms = beam_model_log_density(r, no_return[used], zhat, weights, sigma, lam, range_max)
        # Rounding: each term's few dozen operations, and the ray cast's zhat (a few roundings
        # of numbers below 10 m) times how fast the term changes with zhat (bounded by the
        # hit's |r - zhat| / sigma^2, the short term's 1 / zhat + lambda and the censored
        # hit's z_hit / (sigma z_max)).
        slope = np.abs(r - zhat) / sigma**2 + 1 / zhat + lam + weights[0] / (sigma * weights[2])
        tol = 1e3 * EPS * (np.abs(terms).sum() + 10 * slope.sum())
        assert value == pytest.approx(terms.sum(), rel=0, abs=tol)
    assert min(saw.values()) > 0, saw  # walls seen, short readings, and beams with open space


def test_beam_density_and_no_return_add_up_to_one(wall_grid):
    # Spec §3.12: per beam the density over [0, R) and the mass of "no return" add to one, less
    # the hit's Gaussian mass below zero, Phi(-zhat / sigma) z_hit / S. One beam straight at the
    # wall from 2 m away (zhat = 2 exactly), scored at readings r across [0, R).
    weights, sigma, lam, range_max = (0.5, 0.2, 0.1, 0.3), 0.6, 0.4, 4.0
    beam = laser.BeamModel(wall_grid, z_hit=weights[0], z_short=weights[1], z_max=weights[2],
                           z_rand=weights[3], sigma_hit=sigma, lambda_short=lam)
    pose = np.array([[3.0, 2.5, 0.0]])

    def density(r):
        return math.exp(beam.log_likelihood(pose, ranges=[r], angle_min=0.0, angle_increment=0.1,
                                            range_min=0.0, range_max=range_max)[0])

    def simpson(a, b, pieces):
        r = np.linspace(a, b, 2 * pieces + 1)
        f = np.array([density(x) for x in r])
        return (b - a) / (6 * pieces) * (f[0] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum() + f[-1])

    zhat = 2.0
    # The short term stops at r = zhat, and a reading of R is "no return", a point mass: the
    # density is integrated on each side of zhat, up to just below R (the slivers left out
    # weigh below 1e-11).
    mass = simpson(0.0, zhat, 500) + simpson(zhat + 1e-12, range_max - 1e-12, 500)
    mass += density(range_max)
    want = 1 - 0.5 * math.erfc(zhat / (sigma * math.sqrt(2))) * weights[0] / sum(weights)
    # Simpson's error is (b - a) h^4 / 180 times the largest fourth derivative, which is at most
    # 3 z_hit / (sqrt(2 pi) sigma^5 S) = 7 for the Gaussian (and lambda^4 times the short term's
    # 0.2 for the rest): with h = 2e-3, about 1e-12; the slivers and rounding (2000 terms of
    # about eps each) add as much again.
    assert mass == pytest.approx(want, rel=0, abs=1e-10)
    assert want < 1 - 1e-4  # the hit's mass below zero is visible at this sigma


@pytest.mark.parametrize("max_beams", [60, 10])
def test_log_likelihood_equals_the_closed_form_on_one_wall(wall_grid, max_beams):
    # Nearest-cell interpolation reads the distance of the cell an end point falls in: with one
    # wall that is |column - 80| cells, capped at max_dist, so log p has a closed form.
    z_hit, z_rand, sigma, max_dist, mount = 0.6, 0.4, 0.15, 1.0, (0.1, -0.05, 0.2)
    field = laser.LikelihoodField(wall_grid, z_hit=z_hit, z_rand=z_rand, sigma_hit=sigma,
                                  max_dist=max_dist, max_beams=max_beams,
                                  interpolation="nearest", mount=mount)
    rng = np.random.default_rng(3)
    scan = wall_scan(rng)
    n = len(scan["ranges"])
    poses = np.column_stack([rng.uniform(2.5, 3.5, 6), rng.uniform(2.0, 3.0, 6),
                             rng.uniform(-math.pi, math.pi, 6)])
    got = field.log_likelihood(poses, **scan)
    # nav2's subsampling: max_beams beams at round(k (n - 1) / (max_beams - 1)); here the
    # products are whole numbers, so rounding has no ties.
    picked = np.zeros(n, bool)
    m = min(n, max_beams)
    picked[np.rint(np.arange(m) * (n - 1) / (m - 1)).astype(int)] = True
    used = picked & (scan["ranges"] >= scan["range_min"]) & (scan["ranges"] < scan["range_max"])
    assert 0 < used.sum() < picked.sum()  # some beams are skipped, so skipping is checked
    for pose, value in zip(poses, got):
        p, _ = end_points(pose, mount, scan["ranges"], scan["angle_min"],
                          scan["angle_increment"], used)
        g = p / RES
        assert (p >= 0).all() and (g[:, 0] < 96).all() and (g[:, 1] < 80).all()
        frac = g[:, 0] - np.floor(g[:, 0])
        assert np.minimum(frac, 1 - frac).min() > 1e-9  # no end point on a cell border
        d = np.minimum(np.abs(np.floor(g[:, 0]) - WALL) * RES, max_dist)
        terms, _ = beam_log_density(d, z_hit, z_rand, sigma, scan["range_max"])
        # The field may tabulate each beam's log density as float (likelihood_field.hpp); the
        # rest is double arithmetic.
        tol = np.abs(terms).sum() * (U24 + 1e3 * EPS)
        assert value == pytest.approx(terms.sum(), rel=0, abs=tol)


def test_bicubic_value_gradient_and_gauss_newton_equal_the_closed_form(wall_grid):
    # Catmull-Rom reproduces linear data, so where every cell of an end point's 4 x 4 stencil is
    # left of the wall and within max_dist of it the interpolated distance is exactly
    # d = 5.03125 - x (the wall cell's centre minus x), with gradient (-1, 0).
    z_hit, z_rand, sigma, max_dist, mount = 0.7, 0.3, 0.2, 1.0, (0.1, 0.05, 0.2)
    field = laser.LikelihoodField(wall_grid, z_hit=z_hit, z_rand=z_rand, sigma_hit=sigma,
                                  max_dist=max_dist, mount=mount)
    pose = np.array([3.5, 2.5, 0.1])
    rng = np.random.default_rng(4)
    bearings = np.linspace(-0.6, 0.6, 25)
    target_x = rng.uniform(4.15, 4.9, bearings.size)  # stencil columns 65..79: linear region
    sensor = compose(pose, np.array(mount))
    ranges = (target_x - sensor[0]) / np.cos(sensor[2] + bearings)
    scan = dict(ranges=ranges, angle_min=bearings[0], angle_increment=bearings[1] - bearings[0],
                range_min=0.0, range_max=10.0)
    used = np.ones(ranges.size, bool)
    p, offset = end_points(pose, mount, ranges, scan["angle_min"], scan["angle_increment"], used)
    np.testing.assert_allclose(p[:, 0], target_x, rtol=0, atol=1e-12)
    assert (p[:, 1] > 0.2).all() and (p[:, 1] < 4.8).all()  # y stencils inside the grid
    d = (WALL + 0.5) * RES - p[:, 0]
    terms, gamma = beam_log_density(d, z_hit, z_rand, sigma, scan["range_max"])
    # d p / d pose = [[1, 0, -oy], [0, 1, ox]]; with grad d = (-1, 0) the chain rule gives
    # J^T grad d = (-1, 0, oy).
    j = np.column_stack([-np.ones_like(d), np.zeros_like(d), offset[:, 1]])
    slope = gamma * d / sigma**2
    want_g = (slope[:, None] * j).sum(axis=0)
    want_h = np.einsum("k,ki,kj->ij", gamma / sigma**2, j, j)
    value, g, h = field.negative_log_likelihood(pose, **scan)
    # Rounding only: the stored distances are exact (multiples of 1/16 m), and each of the few
    # dozen operations per beam rounds once.
    assert value == pytest.approx(-terms.sum(), rel=0, abs=1e3 * EPS * np.abs(terms).sum())
    np.testing.assert_allclose(g, want_g, rtol=0, atol=1e3 * EPS * np.abs(slope * j.T).sum())
    np.testing.assert_allclose(h, want_h, rtol=0, atol=1e3 * EPS * np.abs(want_h).sum())
    assert field.log_likelihood(pose[None], **scan)[0] == pytest.approx(-value, rel=1e-14)


def test_gradient_equals_central_differences(room):
    field = laser.LikelihoodField(room, sigma_hit=0.1, max_dist=3.0)  # no distance reaches 3 m
    truth = np.array([2.3, 1.1, 0.4])
    scan = laser.simulate_scan(room, truth, beams=60, seed=5)
    rng = np.random.default_rng(6)
    hs = (1e-4, 5e-5)
    checked = 0
    for _ in range(20):
        pose = truth + rng.normal(0, [0.05, 0.05, 0.03])
        # Central differences converge as h^2 where the function is smooth: no end point may
        # cross a cell centre line (where Catmull-Rom's pieces meet) within the steps.
        used = scan["ranges"] < scan["range_max"]
        pieces = set()
        for k in range(3):
            for h in (0.0, *hs, *(-x for x in hs)):
                q = pose.copy()
                q[k] += h
                p, _ = end_points(q, (0, 0, 0), scan["ranges"], scan["angle_min"],
                                  scan["angle_increment"], used)
                pieces.add(np.floor(p / 0.05 - 0.5).astype(int).tobytes())
        if len(pieces) > 1:
            continue
        checked += 1
        value, g, _ = field.negative_log_likelihood(pose, **scan)

        def f(k, h):
            q = pose.copy()
            q[k] += h
            return field.negative_log_likelihood(q, **scan)[0]

        for k in range(3):
            d1, d2 = ((f(k, h) - f(k, -h)) / (2 * h) for h in hs)
            # Richardson: the error of d2 is about (d1 - d2) / 3; |d1 - d2| bounds it with room
            # for the h^4 term, and rounding adds about 1e3 eps |f| / h.
            tol = abs(d1 - d2) + 1e3 * EPS * abs(value) / hs[1]
            assert g[k] == pytest.approx(d2, rel=0, abs=tol), (k, g[k], d1, d2)
    assert checked >= 5


def test_odometry_model_equals_its_equations():
    alphas = (0.01, 0.02, 0.03, 0.04)
    model = laser.OdometryModel(*alphas)
    assert model.alphas == alphas
    x, u = np.array([1.0, -2.0, 0.7]), np.array([0.5, 0.1, 0.3])
    np.testing.assert_allclose(model.predict(x, u), compose(x, u), rtol=0, atol=1e-15)
    rot1, trans = math.atan2(u[1], u[0]), math.hypot(u[0], u[1])
    rot2 = u[2] - rot1
    var = np.array([alphas[0] * rot1**2 + alphas[1] * trans**2,
                    alphas[2] * trans**2 + alphas[3] * (rot1**2 + rot2**2),
                    alphas[0] * rot2**2 + alphas[1] * trans**2])
    a = x[2] + rot1
    jac = np.array([[-trans * math.sin(a), math.cos(a), 0], [trans * math.cos(a), math.sin(a), 0],
                    [1, 0, 1]])
    floor = np.array([0.005, 0.005, 0.002])  # OdometryModel's default floor_std
    np.testing.assert_allclose(model.covariance(x, u), jac @ np.diag(var) @ jac.T
                               + np.diag(floor**2), rtol=1e-12, atol=1e-18)
    # The exact sampler perturbs rot1, trans and rot2 by independent N(0, var): recover them
    # from the draws and compare means and variances within 4.5 standard errors.
    n = 20000
    draws = model.sample(x, u, seed=7, n=n)
    assert draws.shape == (n, 3)
    np.testing.assert_array_equal(model.sample(x, u, seed=7), draws[0])
    dx, dy = draws[:, 0] - x[0], draws[:, 1] - x[1]
    got_trans = np.hypot(dx, dy)
    got_rot1 = np.angle(np.exp(1j * (np.arctan2(dy, dx) - x[2])))
    got_rot2 = draws[:, 2] - x[2] - got_rot1
    for got, mean, v in zip((got_rot1, got_trans, got_rot2), (rot1, trans, rot2), var):
        assert abs(got.mean() - mean) < 4.5 * math.sqrt(v / n)
        assert abs(got.var(ddof=1) - v) < 4.5 * v * math.sqrt(2 / (n - 1))


def room_path(steps=60):
    """An ellipse around the box, heading along the path (unwrapped)."""
    t = np.linspace(0, 2 * math.pi, steps + 1)
    x, y = 3.0 + 2.0 * np.cos(t), 2.0 + 1.2 * np.sin(t)
    heading = np.unwrap(np.arctan2(1.2 * np.cos(t), -2.0 * np.sin(t)))
    return np.column_stack([x, y, heading])


@pytest.mark.parametrize("proposal,model", [("implicit", "field"), ("bootstrap", "field"),
                                            ("bootstrap", "beam")])
def test_particle_filter_tracks_a_simulated_path(room, proposal, model):
    truth = room_path()
    noise = laser.OdometryModel(*(0.05,) * 4)
    # Odometry as a robot would report it: the true increments with the alpha noise.
    odometry = [noise.sample([0, 0, 0], between(truth[k - 1], truth[k]), seed=100 + k)
                for k in range(1, len(truth))]
    dead = [truth[0]]
    for u in odometry:
        dead.append(compose(dead[-1], u))
    dead_rmse = np.sqrt(((np.array(dead)[:, :2] - truth[:, :2]) ** 2).sum(axis=1).mean())
    assert dead_rmse > 0.2  # the odometry alone drifts: the scans have something to correct
    if model == "beam":
        pf = laser.ParticleFilter(room, proposal=proposal, particles=100, seed=3,
                                  alphas=(0.05,) * 4, laser=laser.BeamModel(room, sigma_hit=0.1))
    else:
        pf = laser.ParticleFilter(room, proposal=proposal, particles=100, seed=3,
                                  alphas=(0.05,) * 4, sigma_hit=0.1)
    pf.initialize(truth[0], np.diag([0.05, 0.05, 0.02]) ** 2)
    # A prediction alone moves the particles and leaves the weights alone.
    w = pf.weights
    r = pf.step([0.0, 0.0, 0.0])
    assert not r["updated"] and np.array_equal(pf.weights, w)
    means = [truth[0]]
    for k, u in enumerate(odometry, start=1):
        r = pf.step(u, **laser.simulate_scan(room, truth[k], beams=91, seed=k))
        means.append(r["mean"])
        assert r["updated"] and 1.0 <= r["ess"] <= 100.0 + 1e-9 and r["failures"] == 0
    err = np.linalg.norm(np.array(means)[:, :2] - truth[:, :2], axis=1)
    # Localized within two cells (the scans' 2 cm noise on a 5 cm grid), far below the drift.
    assert np.sqrt((err**2).mean()) < 0.1 and err[-1] < 0.1, (err.max(), dead_rmse)
    assert pf.particles.shape == (100, 3) and pf.weights.shape == (100,)
    assert abs(pf.weights.sum() - 1) < 1e-12
    np.testing.assert_allclose(pf.last["mean"][:2], pf.weights @ pf.particles[:, :2], atol=1e-9)


def test_more_newton_starts_cost_more_evaluations(room):
    # starts reaches the implicit proposal: each further start runs Newton once more per particle.
    truth = room_path()
    scan = laser.simulate_scan(room, truth[1], beams=91, seed=1)
    evaluations = []
    for starts in (1, 3):
        pf = laser.ParticleFilter(room, particles=50, seed=3, sigma_hit=0.1, starts=starts)
        pf.initialize(truth[0], np.diag([0.05, 0.05, 0.02]) ** 2)
        evaluations.append(pf.step(between(truth[0], truth[1]), **scan)["newton_evaluations"])
    assert evaluations[1] > evaluations[0] > 0, evaluations


TIMING = {"seconds", "cpu_us_per_update", "cpu_us_per_update_per_particle"}
PROVENANCE = {"version", "commit"}  # the tool's printout adds them to every result


def same_numbers(a, b, where="result"):
    """a equals b exactly, but for the timing keys (they differ from run to run)."""
    if isinstance(a, dict):
        assert set(a) == set(b) - (PROVENANCE if where == "result" else set()), where
        for k in a:
            if k not in TIMING:
                same_numbers(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b)):
            same_numbers(x, y, f"{where}[{k}]")
    else:
        assert a == b, where


@pytest.fixture(scope="module")
def aces():
    return laser.bundled_log("aces")


def test_run_equals_the_cli_json(cli, aces):
    done = []
    r = laser.run(aces, proposal="implicit", particles=50, runs=2, seed=1, max_updates=30,
                  progress=lambda k, n: done.append((k, n)))
    c = cli("mcl", "--sensor", "laser", "--data", aces, "--method", "implicit", "-M", "50",
            "--runs", "2", "--seed", "1", "--max-updates", "30")
    same_numbers(r, c)
    assert done == [(1, 2), (2, 2)] and r["updates"] == 30 and len(r["per_run"]) == 2
    # The map run builds is the map build_map makes from the log (the laser is the robot's
    # pose in these logs).
    log = laser.read_carmen(aces)
    assert log["ranges"].shape == (r["scans_in_log"], 180)
    grid = laser.build_map(log["laser_poses"], log)
    assert (grid.width, grid.height) == (r["map"]["width"], r["map"]["height"])


def test_run_passes_every_setting_as_the_cli(cli, aces):
    r = laser.run(aces, proposal="bootstrap", particles=30, runs=1, seed=4, max_updates=20,
                  alphas=(0.04,) * 4, filter_alphas=(0.03,) * 4, z_hit=0.8, z_rand=0.2,
                  sigma_hit=0.15, max_dist=1.5, max_beams=30, laser_max_range=45.0,
                  interpolation="nearest", aggregation="cubed-sum", update_min_d=0.3,
                  update_min_a=0.25, map_resolution=0.1, map_min_echoes=3)
    c = cli("mcl", "--sensor", "laser", "--data", aces, "--method", "standard", "-M", "30",
            "--runs", "1", "--seed", "4", "--max-updates", "20", "--alphas", *["0.04"] * 4,
            "--filter-alphas", *["0.03"] * 4, "--z-hit", "0.8", "--z-rand", "0.2",
            "--sigma-hit", "0.15", "--max-beams", "30", "--laser-max-dist", "1.5",
            "--laser-max-range", "45", "--interpolation", "nearest", "--aggregation",
            "cubed-sum", "--update-min-d", "0.3", "--update-min-a", "0.25",
            "--map-resolution", "0.1", "--map-min-echoes", "3")
    same_numbers(r, c)
    assert r["proposal"] == "bootstrap" and r["map"]["resolution"] == 0.1
    assert r["map"]["min_echoes"] == 3
    g = laser.run(aces, particles=200, runs=2, max_updates=40, start="global", global_updates=8,
                  global_radius=0.6, implicit_map="random", starts=3, start_probe=3)
    c = cli("mcl", "--sensor", "laser", "--data", aces, "-M", "200", "--runs", "2",
            "--max-updates", "40", "--init", "global", "--global-updates", "8",
            "--global-radius", "0.6", "--implicit-map", "random", "--starts", "3",
            "--start-probe", "3")
    same_numbers(g, c)
    assert g["start"] == "global" and g["implicit_map"] == "random" and g["implicit_starts"] == 3
    assert g["implicit_start_probe"] == 3
    t = laser.run(aces, particles=20, runs=1, max_updates=5, tracks=True)
    assert np.array(t["per_run"][0]["estimates"]).shape == (5, 3)


def test_run_beam_model_kld_and_recovery_equal_the_cli(cli, aces):
    r = laser.run(aces, proposal="bootstrap", laser_model="beam", particles=200, runs=1, seed=2,
                  max_updates=15, sigma_hit=0.15, max_beams=30, z_short=0.1, z_max=0.02,
                  lambda_short=0.2, kld=True, kld_err=0.05, kld_z=0.9, recovery="uniform",
                  recovery_alpha_slow=0.002, recovery_alpha_fast=0.2, kidnap_probability=0.01)
    c = cli("mcl", "--sensor", "laser", "--data", aces, "--method", "standard", "--laser-model",
            "beam", "-M", "200", "--runs", "1", "--seed", "2", "--max-updates", "15",
            "--sigma-hit", "0.15", "--max-beams", "30", "--z-short", "0.1", "--z-max", "0.02",
            "--lambda-short", "0.2", "--kld", "--kld-err", "0.05", "--kld-z", "0.9",
            "--recovery", "uniform", "--recovery-alpha-slow", "0.002", "--recovery-alpha-fast",
            "0.2", "--kidnap-probability", "0.01")
    same_numbers(r, c)
    assert r["laser_model"] == "beam" and "laser" not in r
    assert r["beam"] == dict(z_hit=0.5, z_short=0.1, z_max=0.02, z_rand=0.5, sigma_hit=0.15,
                             lambda_short=0.2, max_beams=30)
    # KLD-sampling's bounds are the tool's, min(100, M) and max(5000, M); a tracking filter
    # needs fewer particles than it starts with.
    assert r["kld"] == dict(kld_err=0.05, kld_z=0.9, min_particles=100, max_particles=5000)
    assert 100 <= r["particles_mean"]["mean"] < 200
    assert r["recovery"] == dict(source="uniform", recovery_alpha_slow=0.002,
                                 recovery_alpha_fast=0.2, kidnap_probability=0.01)
    # Without them: no recovery (the tool's "auto" for laser runs, also for a global start) and
    # a fixed particle count.
    g = laser.run(aces, proposal="bootstrap", laser_model="beam", particles=100, runs=1,
                  max_updates=12, start="global")
    c = cli("mcl", "--sensor", "laser", "--data", aces, "--method", "standard", "--laser-model",
            "beam", "-M", "100", "--runs", "1", "--max-updates", "12", "--init", "global")
    same_numbers(g, c)
    assert g["recovery"] is None and g["kld"] is None and g["particles_mean"]["mean"] == 100


def test_carmen_scans_and_mapping_forms(aces):
    log = laser.read_carmen(aces)
    n = len(log["times"])
    assert log["laser_poses"].shape == (n, 3) and log["odometry_poses"].shape == (n, 3)
    assert np.all(log["angle_increment"] == math.pi / 180) and np.all(log["range_min"] == 0)
    s = laser.scan_at(log, 7)
    np.testing.assert_array_equal(s["ranges"], log["ranges"][7])
    # The list-of-scans form maps the same cells as the dict form.
    k = slice(0, 40)
    part = {key: log[key][k] for key in ("ranges", "angle_min", "angle_increment", "range_min",
                                         "range_max")}
    as_list = [laser.scan_at(log, i) for i in range(40)]
    a = laser.build_map(log["laser_poses"][k], part, resolution=0.1)
    b = laser.build_map(log["laser_poses"][k], as_list, resolution=0.1)
    np.testing.assert_array_equal(a.cells, b.cells)
    assert (a.cells >= 65).sum() > 100  # the scans drew walls (occupied: >= 65)


def test_echoes_of_two_scans_keep_a_cell_the_crossing_beams_clear():
    # Two scans end a beam in cell (3, 0) of a 1 m grid; then two scans of three beams each
    # cross it on their way to cell 6: log-odds 2 (0.85) + 6 (-0.4) = -0.7, free; with
    # min_echoes=2 it stays occupied (spec §3.12, "The map's echoes").
    hit = dict(ranges=[3.2], angle_min=0.0, angle_increment=0.01, range_min=0.1, range_max=8.0)
    cross = dict(hit, ranges=[6.2, 6.2, 6.2], angle_increment=1e-6)
    poses = [[0.5, 0.5, 0.0]] * 4
    scans = [hit, hit, cross, cross]
    log_odds = laser.build_map(poses, scans, resolution=1.0, min_echoes=0)
    echoes = laser.build_map(poses, scans, resolution=1.0)
    ox = int(round(-log_odds.origin[0]))  # the margin's cells west of x = 0
    assert log_odds.cells[0 + 1, ox + 3] == round(100 * (1 - 1 / (1 + math.exp(-0.7))))
    assert echoes.cells[0 + 1, ox + 3] == 100
    # One scan's echo is not enough.
    once = laser.build_map(poses[1:], scans[1:], resolution=1.0)
    assert once.cells[1, ox + 3] < 50


def test_bad_files_raise_value_errors_naming_them(tmp_path):
    missing = tmp_path / "missing.yaml"
    with pytest.raises(ValueError, match="missing.yaml"):
        laser.load_map(missing)
    with pytest.raises(ValueError, match="missing.log"):
        laser.read_carmen(tmp_path / "missing.log")
    with pytest.raises(ValueError, match="missing.log"):
        laser.run(tmp_path / "missing.log", runs=1)
    # An exception in the progress callback stops the run and reaches the caller.
    def stop(done, total):
        raise KeyError("stop here")
    with pytest.raises(KeyError, match="stop here"):
        laser.run(laser.bundled_log("aces"), particles=5, runs=2, max_updates=3, progress=stop)
