"""implicit.slam.grid: grid SLAM on a CARMEN log, the numbers of `implicit slam --sensor laser
--json` for the same settings and seed, its map the files of --map-out, its trajectories those of
--trajectory and --truth-trajectory."""
import math
import pathlib
import threading
import time

import numpy as np
import pytest

import implicit
from implicit import laser, slam

# A short run: the first 80 scans of ACES, of which the map-update gate keeps about 50.
SHORT = dict(particles=5, max_scans=80, seed=3)
# The map score of spec §3.13.5: the map against the reference poses' map.
MAP_SCORES = ("map_agreement", "map_occupied_precision", "map_occupied_recall", "map_f1")


@pytest.fixture(scope="module")
def aces():
    return laser.bundled_log("aces")


def cli_grid(cli, data, *flags):
    return cli("slam", "--sensor", "laser", "--data", data, *flags)


def assert_same_numbers(r, c, run=0):
    """r (one Python run) has the numbers of the tool's run `run` and, for one run, its summary."""
    p = c["per_run"][run]
    assert r["seed"] == p["seed"]
    assert r["relation_translation_m"] == p["relation_translation_m"]
    assert r["relation_rotation_deg"] == p["relation_rotation_deg"]
    assert r["resamplings"] == p["resamplings"]
    for key in MAP_SCORES:
        assert r[key] == p[key], key
    if c["datasets"] != 1:
        return
    for key in MAP_SCORES:  # the mean over one run, and the dead-reckoning map's
        assert r[key] == c[key]["mean"] and r["odometry_" + key] == c["odometry_" + key], key
    assert r["map_tolerance_m"] == c["map_tolerance_m"]
    assert r["relation_translation_m"] == c["relation_translation_m"]["mean"]
    assert r["relation_rotation_deg"] == c["relation_rotation_deg"]["mean"]
    assert r["odometry_relation_translation_m"] == c["odometry_relation_translation_m"]
    assert r["odometry_relation_rotation_deg"] == c["odometry_relation_rotation_deg"]
    assert r["ate_m"] == c["ate_m"]["mean"] and r["odometry_ate_m"] == c["odometry_ate_m"]
    assert r["ess_fraction"] == c["ess_fraction"]
    assert r["evaluations_per_particle_and_scan"] == c["evaluations_per_particle_and_scan"]
    assert r["resamplings"] == c["resamplings_mean"]
    for key in ("scans_processed", "fallbacks", "failures", "method", "particles"):
        assert r[key] == c[key], key
    assert list(r["alphas"]) == c["alphas"]


def read_tum(path):
    rows = np.loadtxt(path, comments="#", ndmin=2)
    return rows[:, 0], rows[:, 1:3], 2.0 * np.arctan2(rows[:, 6], rows[:, 7])


def increasing(times):
    """The rows the tool writes to a TUM file: each time after the last one kept."""
    keep, last = [], -math.inf
    for k, t in enumerate(times):
        if t > last:
            keep.append(k)
            last = t
    return np.array(keep)


def assert_tum_equals(path, times, poses):
    t, xy, yaw = read_tum(path)
    keep = increasing(times)
    # Times and positions are written in the shortest form that reads back exactly; the heading
    # goes through the quaternion (cos, sin of half of it) and atan2, a few ulps.
    np.testing.assert_array_equal(t, times[keep])
    np.testing.assert_array_equal(xy, poses[keep, :2])
    turn = np.angle(np.exp(1j * (yaw - poses[keep, 2])))
    assert np.abs(turn).max() < 1e-12


def read_map_files(yaml_path):
    """The YAML's resolution and origin, and the PGM's pixels (top row first), read directly."""
    yaml = dict(line.split(": ", 1) for line in pathlib.Path(yaml_path).read_text().splitlines())
    origin = [float(v) for v in yaml["origin"].strip("[]").split(",")]
    pgm = pathlib.Path(yaml_path).with_suffix(".pgm").read_bytes()
    magic, size, depth, pixels = pgm.split(b"\n", 3)
    assert magic == b"P5" and depth == b"255"
    width, height = (int(v) for v in size.split())
    return float(yaml["resolution"]), origin, np.frombuffer(pixels, np.uint8).reshape(height, width)


def map_server_pixels(cells):
    """map_server's grey for each occupancy value (docs/formats.md): -1 -> 205, 0 -> 254,
    v -> round(255 (100 - v) / 100)."""
    v = cells.astype(np.int64)
    grey = (255 * (100 - v) + 50) // 100
    return np.where(v == -1, 205, np.where(v == 0, 254, grey)).astype(np.uint8)


def test_grid_equals_the_cli_json_and_files(cli, aces, tmp_path):
    calls = []
    r = slam.grid(aces, method="implicit", **SHORT, progress=lambda d, t: calls.append((d, t)))
    out = tmp_path / "map.yaml"
    c = cli_grid(cli, aces, "--method", "implicit", "-M", "5", "--max-scans", "80", "--seed", "3",
                 "--map-out", str(out), "--trajectory", str(tmp_path / "est.tum"),
                 "--truth-trajectory", str(tmp_path / "ref.tum"))
    assert_same_numbers(r, c)
    n = r["scans_processed"]
    assert 10 < n < 80  # the gate skipped some of the 80 scans, and kept more than a few
    # One call per scan the filter steps on; the first scan starts it.
    assert calls == [(k, n) for k in range(2, n + 1)]
    for key in ("trajectory", "reference"):
        assert r[key].shape == (n, 3) and r[key].dtype == np.float64
    assert r["times"].shape == (n,)
    assert_tum_equals(tmp_path / "est.tum", r["times"], r["trajectory"])
    assert_tum_equals(tmp_path / "ref.tum", r["times"], r["reference"])
    # The reference is the log's corrected poses at the processed scans, the first scan first.
    log = laser.read_carmen(aces)
    np.testing.assert_array_equal(r["reference"][0], log["laser_poses"][0])
    assert r["times"][0] == log["times"][0]
    # The map: the --map-out files, read without the library.
    m = r["map"]
    assert m.dtype == np.int8 and m.ndim == 2
    assert np.all((m == -1) | ((m >= 0) & (m <= 100)))
    resolution, origin, pixels = read_map_files(out)
    assert (resolution, origin) == (r["resolution"], [*r["origin"], 0.0])
    assert pixels.shape == m.shape
    np.testing.assert_array_equal(pixels, map_server_pixels(np.flipud(m)))  # row 0: lowest y
    # The OccupancyGrid beside it is the same map.
    g = r["grid"]
    np.testing.assert_array_equal(g.cells, m)
    assert (g.resolution, g.origin) == (r["resolution"], r["origin"])
    # The scans drew walls (occupied: >= 65), and the estimate beat the odometry it was given.
    assert (m >= 65).sum() > 100
    assert r["relation_translation_m"] < r["odometry_relation_translation_m"]
    # ... and its map is closer to the reference poses' map than the dead-reckoning map.
    assert all(0 <= r[key] <= 1 for key in MAP_SCORES)
    assert r["map_f1"] > r["odometry_map_f1"]
    assert r["map_tolerance_m"] == r["resolution"]  # one cell, the default


@pytest.mark.parametrize("method", ["bootstrap", "gmapping"])
def test_other_proposals_and_alphas_equal_the_cli(cli, aces, method):
    alphas = (0.01, 0.005, 0.004, 0.003)
    r = slam.grid(aces, method=method, particles=4, seed=2, alphas=alphas, max_scans=60,
                  threads=1)
    c = cli_grid(cli, aces, "--method", method, "-M", "4", "--seed", "2", "--max-scans", "60",
                 "--alphas", *[str(a) for a in alphas])
    assert_same_numbers(r, c)  # one thread here, all of them in the tool: the same numbers
    assert r["alphas"] == alphas and r["method"] == method


@pytest.mark.parametrize("echoes", [0, 3])
def test_map_min_echoes_equals_the_cli(cli, aces, echoes):
    r = slam.grid(aces, particles=4, seed=4, max_scans=60, map_min_echoes=echoes, threads=1)
    c = cli_grid(cli, aces, "-M", "4", "--seed", "4", "--max-scans", "60", "--map-min-echoes",
                 str(echoes))
    assert_same_numbers(r, c)
    assert r["map_min_echoes"] == echoes == c["map_min_echoes"]
    # The default (1) is another map, so other numbers: the setting reached the filter.
    assert slam.grid(aces, particles=4, seed=4, max_scans=60)["map_f1"] != r["map_f1"]


def test_the_tools_datasets_are_seeds(cli, aces):
    c = cli_grid(cli, aces, "-M", "4", "--max-scans", "50", "--seed", "7", "--datasets", "2")
    for run in range(2):
        assert_same_numbers(slam.grid(aces, particles=4, max_scans=50, seed=7 + run), c, run)


def test_the_default_settings_are_the_tools(cli, aces):
    # Only the scan count given: method, particles (30), alphas and seed are the defaults.
    r = slam.grid(aces, max_scans=12)
    c = cli_grid(cli, aces, "--max-scans", "12")
    assert_same_numbers(r, c)
    assert (r["method"], r["particles"], r["seed"]) == ("implicit", 30, 1)


def test_same_seed_same_run_and_the_log_dict_is_the_file(aces):
    a = slam.grid(aces, **SHORT)
    b = slam.grid(laser.read_carmen(aces), **SHORT)  # the dict form of the same log
    c = slam.grid(pathlib.Path(aces), **SHORT)  # os.PathLike
    for other in (b, c):
        assert set(other) == set(a)
        for key in set(a) - {"cpu_seconds", "reference_map_cpu_s", "map_score_cpu_s", "grid"}:
            np.testing.assert_array_equal(np.asarray(other[key]), np.asarray(a[key]), key)
    d = slam.grid(aces, **{**SHORT, "seed": 4})
    assert d["trajectory"].shape == a["trajectory"].shape  # the same scans pass the gate
    assert not np.array_equal(d["trajectory"], a["trajectory"])


def test_one_scan_starts_the_filter_only(aces):
    calls = []
    r = slam.grid(aces, particles=2, max_scans=1, progress=lambda d, t: calls.append((d, t)))
    assert r["scans_processed"] == 1 and calls == []
    log = laser.read_carmen(aces)
    np.testing.assert_array_equal(r["trajectory"], log["laser_poses"][:1])
    np.testing.assert_array_equal(r["reference"], log["laser_poses"][:1])


def test_an_exception_in_progress_reaches_the_caller(aces):
    seen = []

    def stop(done, total):
        seen.append(done)
        if done == 5:
            raise KeyError("stop here")

    with pytest.raises(KeyError, match="stop here"):
        slam.grid(aces, **SHORT, progress=stop)
    assert seen == [2, 3, 4, 5]  # the run stopped at the raise
    # The interpreter is in order afterwards: the next run completes.
    assert slam.grid(aces, particles=2, max_scans=10)["scans_processed"] >= 1


def test_the_run_releases_the_interpreter(aces):
    # The run in a second thread; this one keeps running Python meanwhile. Were the lock held
    # through the run, this loop would stall for all of it: its longest pause would be the run.
    result, ticks = {}, []
    worker = threading.Thread(
        target=lambda: result.update(slam.grid(aces, particles=8, max_scans=150, threads=1)))
    start = time.perf_counter()
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)  # leaves the lock to the run's callbacks between ticks
    elapsed = time.perf_counter() - start
    assert result["scans_processed"] > 50 and elapsed > 0.5
    assert np.diff([start, *ticks]).max() < elapsed / 2
