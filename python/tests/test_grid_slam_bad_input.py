"""implicit.slam.grid with bad input: every argument gets an implicit.InvalidArgument whose
message starts with the argument's name (the ranges are those of the tool's flags), checked
before the log is read; a missing or malformed log raises implicit.ParseError naming the file."""
import math

import numpy as np
import pytest

import implicit
from implicit import laser, slam

ACES = laser.bundled_log("aces")


def grid_with(**changes):
    settings = dict(data=ACES, particles=2, max_scans=3)
    return lambda: slam.grid(**{**settings, **changes})


def one_scan_log(**changes):
    """A log of one scan in read_carmen's layout, with some keys changed (None: left out)."""
    log = dict(ranges=np.ones((1, 5)), angle_min=np.array([-0.5]),
               angle_increment=np.array([0.25]), range_min=np.zeros(1),
               range_max=np.array([10.0]), times=np.zeros(1), laser_poses=np.zeros((1, 3)))
    log.update(changes)
    return {k: v for k, v in log.items() if v is not None}


BAD = [
    # data: a path or read_carmen's dict
    (grid_with(data=None), r"^data: expected a path \(str or os\.PathLike\), got NoneType"),
    (grid_with(data=3), r"^data: expected a path \(str or os\.PathLike\), got int"),
    (grid_with(data=""), r"^data: expected a file name, got an empty string"),
    (grid_with(data=[ACES]), r"^data: expected a path \(str or os\.PathLike\), got list"),
    (grid_with(data={}), r"^data: expected the key 'ranges'"),
    (grid_with(data=one_scan_log(times=None)), r"^data: expected the key 'times'"),
    (grid_with(data=one_scan_log(laser_poses=None)), r"^data: expected the key 'laser_poses'"),
    (grid_with(data=one_scan_log(angle_min=None)), r"^data: expected the key 'angle_min'"),
    (grid_with(data=one_scan_log(laser_poses=np.zeros((1, 2)))),
     r"^data\['laser_poses'\]: expected shape \(1, 3\), got shape \(1, 2\)"),
    (grid_with(data=one_scan_log(laser_poses=np.array([[0.0, math.nan, 0.0]]))),
     r"^data\['laser_poses'\]: expected finite values, got nan"),
    (grid_with(data=one_scan_log(times=np.zeros(2))),
     r"^data\['times'\]: expected shape \(1,\), got shape \(2,\)"),
    (grid_with(data=one_scan_log(times=np.array([math.inf]))),
     r"^data\['times'\]: expected finite values, got inf"),
    (grid_with(data=one_scan_log(angle_increment=np.zeros(1))),
     r"^data\[0\]\.angle_increment: expected a finite non-zero number"),
    (grid_with(data=one_scan_log(ranges=np.array([[1.0, -1.0, 1.0]]))),
     r"^data\[0\]\.ranges: expected ranges >= 0"),
    (grid_with(data=one_scan_log(ranges=[], angle_min=[], angle_increment=[], range_min=[],
                                 range_max=[], times=[], laser_poses=np.zeros((0, 3)))),
     r"^data: expected at least one scan, got none"),
    # method: the grid-SLAM proposals only
    (grid_with(method="ekf"), r"^method: expected 'bootstrap', 'gmapping' or 'implicit', "
     r"got 'ekf'"),
    (grid_with(method="standard"), r"^method: expected 'bootstrap', 'gmapping' or 'implicit'"),
    (grid_with(method=None), r"^method: expected 'bootstrap', 'gmapping' or 'implicit', "
     r"got NoneType"),
    # particles: -M in_range(1, 1000000)
    (grid_with(particles=0), r"^particles: expected an integer in \[1, 1000000\], got 0"),
    (grid_with(particles=1_000_001), r"^particles: expected an integer in \[1, 1000000\], "
     r"got 1000001"),
    (grid_with(particles=2.5), r"^particles: expected an integer in \[1, 1000000\], got float"),
    (grid_with(particles=math.nan), r"^particles: expected an integer .* got float"),
    (grid_with(particles=True), r"^particles: expected an integer .* got bool"),
    (grid_with(particles="8"), r"^particles: expected an integer .* got str"),
    # seed: --seed, [0, 2^64 - 1]
    (grid_with(seed=-1), r"^seed: expected an integer in \[0, 2\^64 - 1\], got -1"),
    (grid_with(seed=2**64), r"^seed: expected an integer in \[0, 2\^64 - 1\], "
     r"got 18446744073709551616"),
    (grid_with(seed=1.0), r"^seed: expected an integer .* got float"),
    (grid_with(seed=None), r"^seed: expected an integer .* got NoneType"),
    # alphas: --alphas, four numbers in [0, 10]
    (grid_with(alphas=(0.1,) * 3), r"^alphas: expected shape \(4,\), got shape \(3,\)"),
    (grid_with(alphas=None), r"^alphas: expected shape \(4,\), got shape \(\)"),
    (grid_with(alphas="abcd"), r"^alphas: expected an array of numbers, got str"),
    (grid_with(alphas=(0.1, -0.1, 0.1, 0.1)), r"^alphas\[1\]: expected a number in \[0, 10\], "
     r"got -0\.1"),
    (grid_with(alphas=(0.1, 0.1, math.nan, 0.1)), r"^alphas\[2\]: expected a number in "
     r"\[0, 10\], got nan"),
    (grid_with(alphas=(0.1, 0.1, 0.1, math.inf)), r"^alphas\[3\]: expected a number in "
     r"\[0, 10\], got inf"),
    (grid_with(alphas=(10.5, 0, 0, 0)), r"^alphas\[0\]: expected a number in \[0, 10\], "
     r"got 10\.5"),
    # max_scans: --max-scans in_range(0, 100000000)
    (grid_with(max_scans=-1), r"^max_scans: expected an integer in \[0, 100000000\], got -1"),
    (grid_with(max_scans=100_000_001), r"^max_scans: expected an integer in \[0, 100000000\]"),
    (grid_with(max_scans=3.0), r"^max_scans: expected an integer .* got float"),
    (grid_with(max_scans=None), r"^max_scans: expected an integer .* got NoneType"),
    # map_min_echoes: --map-min-echoes in_range(0, 255)
    (grid_with(map_min_echoes=-1), r"^map_min_echoes: expected an integer in \[0, 255\], got -1"),
    (grid_with(map_min_echoes=256), r"^map_min_echoes: expected an integer in \[0, 255\], got 256"),
    (grid_with(map_min_echoes=1.0), r"^map_min_echoes: expected an integer .* got float"),
    (grid_with(map_min_echoes=None), r"^map_min_echoes: expected an integer .* got NoneType"),
    # threads: --threads in_range(0, 1024)
    (grid_with(threads=-1), r"^threads: expected an integer in \[0, 1024\], got -1"),
    (grid_with(threads=1025), r"^threads: expected an integer in \[0, 1024\], got 1025"),
    (grid_with(threads="all"), r"^threads: expected an integer .* got str"),
    # progress
    (grid_with(progress=3), r"^progress: expected a callable progress\(done, total\) or None, "
     r"got int"),
    (grid_with(progress="bar"), r"^progress: expected a callable .* got str"),
    # The settings are checked before the log is opened.
    (grid_with(data="/nonexistent/x.log", particles=0), r"^particles: expected an integer"),
]


@pytest.mark.parametrize("call,message", BAD, ids=[f"row{k}" for k in range(len(BAD))])
def test_bad_arguments_are_named(call, message):
    with pytest.raises(implicit.InvalidArgument, match=message):
        call()


def test_missing_and_malformed_logs_name_the_file(tmp_path):
    missing = tmp_path / "missing.log"
    with pytest.raises(implicit.ParseError, match=r"missing\.log: cannot open the file"):
        slam.grid(missing, particles=2)
    bad = tmp_path / "bad.log"
    bad.write_text("FLASER 3 1.0 2.0\n")
    with pytest.raises(implicit.ParseError, match=r"bad\.log:1: FLASER expected n = 3 ranges"):
        slam.grid(bad, particles=2)
    words = tmp_path / "words.log"
    words.write_text("# a log without a scan\nODOM 0 0 0 0 0 0 1.0 host 1.0\n")
    with pytest.raises(implicit.ParseError,
                       match=r"words\.log: expected at least one laser scan"):
        slam.grid(words, particles=2)
