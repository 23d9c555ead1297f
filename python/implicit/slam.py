"""SLAM (paper §4.2): a steppable Filter and the one-call runner of `implicit slam --json`.

    f = implicit.slam.Filter(method="implicit-rb", particles=100, seed=1,
                             model=implicit.models.Ute(), association="known",
                             initial_pose=[0, 0, 0])
    f.step(control, dt, detections)   # detections (k, 3): [landmark id or -1, range, bearing]
    f.mean(), f.covariance(), f.map() # map(): positions (K, 2) and ids (K,)

Methods: "ekf", "fastslam1", "fastslam2", "implicit", "implicit-rb"; association "known"
(column 0 of the detections is the landmark's id) or "ml" (maximum likelihood).
"""
from . import _implicit, _runs
from ._implicit.slam import Filter

__all__ = ["Filter", "run"]


def run(method="implicit", particles=100, datasets=50, seed=1, data=None, association="known",
        truth="paper", laser_every=1, control_noise=0.5, min_range=0.0, range_sd=0.0,
        bearing_sd=0.0, gate_chi2=0.0, new_landmark_density=0.0, model=None, control_sd=None,
        state_sd=None, out=None, threads=0):
    """Runs `implicit slam` with these settings and returns its JSON result as a dict.

    Each argument is the CLI flag of the same name (docs/cli.md); data None means the synthetic
    Car Park data sets, else a robot log; bearing_sd in degrees; out a folder for CSV files.

    Returns:
        dict with the keys of `implicit slam --json` (error_percent_mean, map_shape_m,
        rmse_pose_m, ess_mean, ...), the same numbers for the same seed.

    Raises:
        implicit.InvalidArgument (a ValueError) naming the keyword, for a value the CLI refuses:
        each number is checked against the range of its flag (`particles` in [1, 10^6],
        `bearing_sd` in [0, 90], `threads` in [0, 1024], ...; `implicit slam --help` lists
        them), a wrong type likewise; the text settings (method, association, ...) with the
        CLI's own message.
    """
    settings = dict(
        method=method, particles=particles, datasets=datasets, data=data,
        association=association, truth=truth, laser_every=laser_every,
        control_noise=control_noise, min_range=min_range, range_sd=range_sd,
        bearing_sd=bearing_sd, gate_chi2=gate_chi2, new_landmark_density=new_landmark_density,
        model=model, control_sd=control_sd, state_sd=state_sd)
    return _runs.call(_implicit._run_slam, settings, seed, out, threads)
