"""The names mcl and slam outputs share (docs/cli.md, "Names shared by mcl and slam"): the same
quantity has the same key in mcl.run and slam.run, and the older names are aliases holding the
same numbers."""
import math

import implicit


def test_mcl_and_slam_share_the_position_heading_and_resampling_keys():
    m = implicit.mcl.run(runs=3, particles=20, seed=5, threads=1)
    s = implicit.slam.run(datasets=2, particles=10, seed=5, threads=1)
    for key in ("position_rmse_m", "heading_rmse_rad", "resamplings_mean", "ess_mean"):
        assert key in m and key in s, key
    assert m["position_rmse_m"] == m["rmse_m"]
    assert s["position_rmse_m"] == s["rmse_pose_m"]
    assert s["resamplings_mean"] == s["resamplings"]
    # The synthetic data have a true heading: the slam alias holds a number, equal to the new key.
    assert s["heading_rmse_rad"] == s["rmse_heading_rad"]
    assert math.isfinite(s["heading_rmse_rad"]) and s["heading_rmse_rad"] >= 0


def test_ekf_slam_has_no_resamplings_under_either_name():
    s = implicit.slam.run(method="ekf", datasets=2, seed=5, threads=1)
    assert s["resamplings"] is None and s["resamplings_mean"] is None
