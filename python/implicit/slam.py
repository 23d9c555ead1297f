"""SLAM (paper §4.2): a steppable Filter and the one-call runner of `implicit slam --json`.

    f = implicit.slam.Filter(method="implicit-rb", particles=100, seed=1,
                             model=implicit.models.Ute(), association="known",
                             initial_pose=[0, 0, 0])
    f.step(control, dt, detections)   # detections (k, 3): [landmark id or -1, range, bearing]
    f.mean(), f.covariance(), f.map() # map(): positions (K, 2) and ids (K,)

Methods: "ekf", "fastslam1", "fastslam2", "implicit", "implicit-rb"; association "known"
(column 0 of the detections is the landmark's id) or "ml" (maximum likelihood).

Grid SLAM on a laser log (spec §3.13), `implicit slam --sensor laser` with one seed:

    r = implicit.slam.grid(implicit.laser.bundled_log("aces"), method="implicit",
                           particles=8, max_scans=200)
    r["trajectory"], r["reference"]   # (n, 3) poses at the processed scans
    r["map"]                          # int8 (height, width), -1 unknown, 0..100; row 0 lowest y
    r["relation_translation_m"]       # the relation error, beside the odometry's
"""
from . import _implicit, _runs
from ._implicit.slam import Filter

__all__ = ["Filter", "grid", "run"]


def run(method="implicit", particles=100, datasets=50, seed=1, data=None, association="known",
        truth="paper", laser_every=1, control_noise=0.5, min_range=0.0, range_sd=0.0,
        bearing_sd_deg=0.0, gate_chi2=0.0, new_landmark_density=0.0, model=None, control_sd=None,
        state_sd=None, out=None, threads=0, verbose=False, bearing_sd=None, progress=None):
    """Runs `implicit slam` with these settings and returns its JSON result as a dict.

    Each argument is the CLI flag of the same name (docs/cli.md); data None means the synthetic
    Car Park data sets, else a robot log; range_sd [m] and bearing_sd_deg [deg] (--range-sd,
    --bearing-sd; bearing_sd, the same in degrees, is deprecated); out a folder for CSV files;
    model a motion model by name (None: the one the log declares; see
    implicit.models.motion_models and register_motion_model). verbose: True draws the tool's progress bar (steps done, ETA) on stderr, as `implicit slam`
    without --json does; the result is the same either way. progress, if given, is called as
    progress(steps done, steps in all) (steps over all data sets, so that one long run moves
    too), with the interpreter's lock held, at most about 10 times a second and once more with
    done = total at the end; done never decreases. An exception it raises stops the run (with
    several threads too: each data set stops at its next step) and reaches the caller
    unchanged. The result is the same with or without it.

    Returns:
        dict with the keys of `implicit slam --json` (error_percent_mean, map_shape_m,
        position_rmse_m (alias rmse_pose_m), heading_rmse_rad, ess_mean, resamplings_mean,
        ...), the same numbers for the same seed.

    Raises:
        implicit.InvalidArgument (a ValueError) naming the keyword, for a value the CLI refuses:
        each number is checked against the range of its flag (`particles` in [1, 10^6],
        `bearing_sd_deg` in [0, 90], `threads` in [0, 1024], ...; `implicit slam --help` lists
        them), a wrong type likewise; the text settings (method, association, ...) with the
        CLI's own message.
    """
    settings = dict(
        method=method, particles=particles, datasets=datasets, data=data,
        association=association, truth=truth, laser_every=laser_every,
        control_noise=control_noise, min_range=min_range, range_sd=range_sd,
        bearing_sd_deg=_runs.bearing_sd_deg(bearing_sd_deg, bearing_sd, "slam.run"),
        gate_chi2=gate_chi2, new_landmark_density=new_landmark_density,
        model=model, control_sd=control_sd, state_sd=state_sd)
    return _runs.call(_implicit._run_slam, settings, seed, out, threads, verbose,
                      given_as=None if bearing_sd is None else {"bearing_sd_deg": "bearing_sd"},
                      progress=progress)


def grid(data, method="implicit", particles=30, seed=1, alphas=(0.002,) * 4, max_scans=0,
         threads=0, progress=None, map_min_echoes=1):
    """Grid SLAM on a CARMEN laser log: one run of `implicit slam --sensor laser` (spec §3.13).

    Every particle carries its own occupancy grid; the proposal is "bootstrap" (the odometry
    motion model), "gmapping" (scan matching against the particle's map, GMapping's weights) or
    "implicit" (Newton's method on the pose's negative log posterior, exact weights). The run
    follows the semi-synthetic protocol of spec §3.13.4: odometry is synthesised from the log's
    corrected poses with the noise `alphas`, the filter uses the same motion model, and the
    estimate is scored by the relation error of consecutive processed scans against the
    corrected poses (docs/cli.md, "Grid SLAM on a laser log").

    Each argument is the tool's flag of the same name, with the tool's default: data the log
    (--data: a str or os.PathLike naming a CARMEN file, plain or gzip, or the dict
    implicit.laser.read_carmen returns; bundled_log("aces") is one), method (--method),
    particles (-M, in [1, 10^6]), seed (--seed: the odometry's noise and the filter's draws),
    alphas alpha1..alpha4 of the odometry noise and of the filter's motion model (--alphas, each
    in [0, 10]), max_scans the first N scans of the log (--max-scans; 0: all; of these the
    filter processes those where the corrected pose moved past the map-update gate),
    map_min_echoes (--map-min-echoes, in [0, 255]: a cell where beams of that many scans ended is
    occupied in the particles' maps whatever its log-odds; 0 log-odds alone), threads
    (--threads; 0: all cores; the results do not depend on it). The tool's --datasets N runs
    seeds seed, seed + 1, ...: grid(seed=s + r) is its run r. progress, if given, is called as
    progress(done, total) after each scan the filter steps on: done = 2 .. total, total the
    scans processed (scan 1 only starts the filter); an exception it raises stops the run and
    reaches the caller.

    Returns:
        dict: trajectory (n, 3) the best particle's poses (x [m], y [m], heading [rad]) at the n
        processed scans, reference (n, 3) the corrected poses there, times (n,) the scans' times
        [s]; map (height, width) int8 the best particle's occupancy grid as map_server values
        (-1 unknown, 0 free .. 100 occupied), row 0 the lowest y (an image shows the highest y
        first: np.flipud(r["map"]), or origin="lower" in matplotlib's imshow), resolution [m]
        and origin (x, y) [m] of cell [0, 0]'s lower-left corner, grid the same map as an
        implicit.laser.OccupancyGrid (save_map(r["grid"], "map.yaml") writes the files of
        --map-out; None if no beam hit anything); relation_translation_m, relation_rotation_deg
        and odometry_relation_translation_m, odometry_relation_rotation_deg (the synthesised
        odometry's, what the scans improve on); ate_m and odometry_ate_m (the position RMSE
        against the reference after the best SE(2) alignment; None with fewer than two
        scans processed); cpu_seconds (the filter's process CPU time),
        resamplings, ess_fraction (mean ESS/M), evaluations_per_particle_and_scan, fallbacks
        (particles that sampled the motion model instead of their proposal), failures (weight
        zero); the map score of spec §3.13.5, the map against the one the corrected poses draw
        from the same scans: map_agreement, map_occupied_precision, map_occupied_recall, map_f1
        (None for a fraction with nothing to count), the same of the dead-reckoning map as
        odometry_map_agreement, ..., odometry_map_f1, map_tolerance_m, reference_map_cpu_s and
        map_score_cpu_s; scans_processed (= n) and the settings (data, method, particles, seed,
        alphas, map_min_echoes).
        The numbers are those of `implicit slam --sensor laser --json` for the same settings
        and seed.

    Raises:
        implicit.InvalidArgument (a ValueError) naming the argument, for a wrong type or a value
        out of the flag's range, before the log is read; implicit.ParseError (a ValueError) for
        a malformed log, naming the file and line.

    Example::

        r = implicit.slam.grid(implicit.laser.bundled_log("aces"), particles=8, max_scans=100)
        r["map"].shape, r["relation_translation_m"], r["odometry_relation_translation_m"]
    """
    settings = dict(data=data, method=method, particles=particles, seed=seed, alphas=alphas,
                    max_scans=max_scans, threads=threads, map_min_echoes=map_min_echoes)
    return _implicit.slam._grid(settings, progress)
