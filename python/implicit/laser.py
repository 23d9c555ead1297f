"""Laser localization on occupancy grids (spec §3.12, user guide "Laser localization from Python").

    OccupancyGrid(cells, resolution, origin)    a map; cells (height, width) int8, row 0 lowest y
    load_map(yaml_path), save_map(grid, path)   ROS map_server map files
    read_carmen(path), bundled_log(name)        CARMEN laser logs as dicts of numpy arrays
    scan_at(log, k)                             scan k of such a log, as the keywords of a scan
    build_map(poses, scans, ...)                occupancy grid mapping with known poses
    simulate_scan(grid, pose, ...)              a scan ray-cast on a grid
    LikelihoodField(grid, ...)                  the laser model: log_likelihood, its derivatives
    BeamModel(grid, ...)                        the beam model (ray casting): log_likelihood
    OdometryModel(alpha1, ..., alpha4)          the motion model: predict, covariance, sample
    ParticleFilter(grid, proposal, ...)         Monte Carlo localization stepped from Python
                                                (laser=BeamModel(...): the beam model, bootstrap)
    run(data, ...)                              `implicit mcl --sensor laser --json` in one call

A scan travels as five keywords, ranges [m] (+inf: no return), angle_min and angle_increment
[rad], range_min and range_max [m]: simulate_scan and scan_at return them as a dict, which
LikelihoodField.log_likelihood(poses, **scan), BeamModel.log_likelihood(poses, **scan) and
ParticleFilter.step(u, **scan) take.
Poses are (x [m], y [m], heading [rad]); odometry increments (dx, dy, dtheta) are given in the
previous odometry frame. Bad arguments raise implicit.InvalidArgument naming the argument.

Example::

    import numpy as np, implicit
    cells = np.zeros((80, 120), np.int8)
    cells[[0, -1], :] = 100
    cells[:, [0, -1]] = 100                              # a 6 m x 4 m room
    grid = implicit.laser.OccupancyGrid(cells, 0.05)
    scan = implicit.laser.simulate_scan(grid, [2.0, 1.5, 0.3], seed=1)
    field = implicit.laser.LikelihoodField(grid, sigma_hit=0.1)
    field.log_likelihood(np.array([[2.0, 1.5, 0.3], [2.2, 1.5, 0.3]]), **scan)
"""
import json
import numbers

import numpy as np

from . import _implicit
from ._implicit import InvalidArgument
from ._implicit.laser import (BeamModel, LikelihoodField, OccupancyGrid, OdometryModel,
                              ParticleFilter, build_map, bundled_log, load_map, read_carmen,
                              save_map, simulate_scan)

__all__ = ["BeamModel", "LikelihoodField", "OccupancyGrid", "OdometryModel", "ParticleFilter",
           "build_map", "bundled_log", "load_map", "read_carmen", "run", "save_map", "scan_at",
           "simulate_scan"]

_SCAN_KEYS = ("ranges", "angle_min", "angle_increment", "range_max")


def scan_at(log, k):
    """Scan k of a dict returned by read_carmen, as the dict of a scan's five keywords.

    Example: ``pf.step(u, **implicit.laser.scan_at(log, 7))``
    """
    if not isinstance(log, dict) or any(key not in log for key in _SCAN_KEYS):
        raise InvalidArgument(f"log: expected the dict of read_carmen (keys "
                              f"{', '.join(_SCAN_KEYS)}), got {type(log).__name__}")
    n = len(log["ranges"])
    if isinstance(k, bool) or not isinstance(k, numbers.Integral):
        raise InvalidArgument(f"k: expected an integer scan index, got {type(k).__name__}")
    if not 0 <= k < n:
        raise InvalidArgument(f"k: expected a scan index in [0, {n}), got {k}")
    range_min = log["range_min"][k] if "range_min" in log else 0.0
    return dict(ranges=np.asarray(log["ranges"][k], dtype=np.float64),
                angle_min=float(log["angle_min"][k]),
                angle_increment=float(log["angle_increment"][k]), range_min=float(range_min),
                range_max=float(log["range_max"][k]))


def run(data, proposal="implicit", particles=100, runs=10, seed=1, alphas=None,
        filter_alphas=None, map=None, start="known", max_updates=0, implicit_map="linear",
        starts=2, start_probe=0,
        z_hit=0.5, z_rand=0.5, sigma_hit=0.2, max_dist=2.0, max_beams=60, laser_max_range=None,
        interpolation="bicubic", aggregation="product", laser_model="likelihood-field",
        z_short=0.05, z_max=0.05, lambda_short=0.1, update_min_d=0.25, update_min_a=0.2,
        map_resolution=0.05, map_min_echoes=2, global_updates=10, global_radius=0.5, kld=False,
        kld_err=0.01, kld_z=0.99, recovery="none", recovery_alpha_slow=0.001,
        recovery_alpha_fast=0.1, kidnap_probability=1e-3, tracks=False, threads=0, progress=None):
    """Laser MCL on a CARMEN log by the semi-synthetic protocol: `implicit mcl --sensor laser`.

    The map is built from the log's reference poses and scans (or read from `map`, a map_server
    YAML file), odometry between the update points is synthesised from the reference increments
    with the alpha noise, and each run's estimate is scored against the reference poses
    (spec §3.12; docs/cli.md, "Laser scans on an occupancy grid").

    Each argument is the tool's flag of the same meaning (docs/cli.md): data the log (--data;
    bundled_log("aces") is one); proposal "implicit" or "bootstrap" (--method implicit or
    standard); particles (-M), runs, seed (run r uses seed + r); alphas the synthesised
    odometry's alpha1..alpha4 (--alphas; None: the tool's default) and filter_alphas the filter's
    (--filter-alphas; None: alphas); start "known" or "global" (--init); max_updates the first N
    updates (0: all); implicit_map "linear" or "random" (--implicit-map) and starts, the
    implicit proposal's Newton starts per particle (--starts) and start_probe, the Newton
    iterations a further start runs before it must beat the best minimum (--start-probe); z_hit,
    z_rand,
    sigma_hit [m], max_dist [m] (--laser-max-dist), max_beams, laser_max_range [m] (None: the
    log's), interpolation, aggregation; laser_model "likelihood-field" or "beam" (--laser-model:
    the beam model, spec §3.12, takes the bootstrap proposal only, z_hit, z_rand, sigma_hit,
    max_beams and laser_max_range as above, and z_short, z_max, lambda_short [1/m]);
    update_min_d [m] and update_min_a [rad]; map_resolution [m] of the built map and
    map_min_echoes, the scans whose beams must end in a cell to make it occupied (0: log-odds
    only; --map-min-echoes);
    global_updates and global_radius [m] score a global start; kld=True (--kld) adapts the
    particle count by KLD-sampling between min(100, M) and max(5000, M), starting at M, with
    kld_err and kld_z; recovery "uniform" injects poses drawn uniformly over the free cells when
    the filter looks lost (AMCL's recovery; recovery_alpha_slow, recovery_alpha_fast,
    kidnap_probability), "none" does not (the tool's default for laser runs; the landmark runs'
    "mixture" is refused); threads (0: all cores). tracks=True adds each run's estimates and
    errors per update to "per_run". progress, if given, is called as progress(runs done, runs in
    all) after each run.

    Returns:
        the dict of `implicit mcl --sensor laser --json`: position_rmse_m and heading_rmse_rad
        (mean, se, median over runs), lost_runs, ess_fraction, particles_mean (the particle
        count averaged over updates), the map's size, the settings (laser_model, laser or beam,
        kld and recovery: None when off), per_run; the same numbers as the tool for the same
        arguments (timing keys differ).

    Example::

        r = implicit.laser.run(implicit.laser.bundled_log("aces"), particles=50, runs=2,
                               max_updates=30)
        r["position_rmse_m"]["mean"], r["lost_runs"]
    """
    settings = dict(
        data=data, proposal=proposal, particles=particles, runs=runs, seed=seed, alphas=alphas,
        filter_alphas=filter_alphas, map=map, start=start, max_updates=max_updates,
        implicit_map=implicit_map, starts=starts, start_probe=start_probe, z_hit=z_hit, z_rand=z_rand, sigma_hit=sigma_hit,
        max_dist=max_dist, max_beams=max_beams, laser_max_range=laser_max_range,
        interpolation=interpolation, aggregation=aggregation, laser_model=laser_model,
        z_short=z_short, z_max=z_max, lambda_short=lambda_short, update_min_d=update_min_d,
        update_min_a=update_min_a, map_resolution=map_resolution,
        map_min_echoes=map_min_echoes,
        global_updates=global_updates, global_radius=global_radius, kld=kld, kld_err=kld_err,
        kld_z=kld_z, recovery=recovery, recovery_alpha_slow=recovery_alpha_slow,
        recovery_alpha_fast=recovery_alpha_fast, kidnap_probability=kidnap_probability,
        tracks=tracks, threads=threads)
    return json.loads(_implicit.laser._run(settings, progress))
