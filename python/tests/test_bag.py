"""implicit.data.read_bag on the fixtures of tests/data/bags (written by independent tools from the
Intel log): the same log as implicit.laser.read_carmen gives for the CARMEN text `implicit convert`
writes, every format alike, and bad arguments refused naming them."""
import pathlib

import numpy as np
import pytest

import implicit
from implicit import laser

BAGS = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "bags"


def test_read_bag_equals_the_converted_carmen_log(cli, tmp_path):
    bag = implicit.data.read_bag(BAGS / "intel-zstd.mcap")
    log = tmp_path / "intel.log"
    written = cli("convert", "--data", str(BAGS / "intel-zstd.mcap"), "--out", str(log))
    assert written["scans"] == 30
    carmen = laser.read_carmen(log)
    for key in ("laser_poses", "odometry_poses", "times", "ranges", "angle_min",
                "angle_increment", "range_min", "range_max"):
        np.testing.assert_array_equal(bag[key], carmen[key], err_msg=key)
    assert bag["ranges"].shape == (30, 180)
    assert bag["odometry"]["poses"].shape == (31, 3)
    np.testing.assert_allclose(bag["mount"], [0.1, 0.02, 0.05], rtol=0, atol=1e-15)
    assert bag["mount_from_tf"] and bag["base_frame"] == "base_footprint"
    assert bag["laser_frame"] == "laser" and bag["scans_outside_odometry"] == 0
    # The generator's twist: 0.01 j m/s and -0.02 j rad/s.
    j = np.arange(31)
    np.testing.assert_array_equal(bag["odometry"]["tv"], 0.01 * j)
    np.testing.assert_array_equal(bag["odometry"]["rv"], -0.02 * j)


@pytest.mark.parametrize("name", ["intel-lz4.mcap", "intel-plain.mcap", "intel-rosbag2",
                                  "intel.bag", "intel-bz2.bag"])
def test_every_format_reads_the_same_log(name):
    a = implicit.data.read_bag(BAGS / "intel-zstd.mcap")
    b = implicit.data.read_bag(BAGS / name)
    np.testing.assert_array_equal(a["ranges"], b["ranges"])
    np.testing.assert_array_equal(a["laser_poses"], b["laser_poses"])


def test_ground_truth_topic_and_frames():
    b = implicit.data.read_bag(BAGS / "intel-zstd.mcap", odom_topic="/ground_truth",
                               base_frame="laser")
    assert b["base_frame"] == "laser" and b["mount_from_tf"]
    np.testing.assert_array_equal(b["mount"], [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(b["laser_poses"], b["odometry_poses"])


@pytest.mark.parametrize("call, error, message", [
    (lambda: implicit.data.read_bag(None), implicit.InvalidArgument, r"^path: expected"),
    (lambda: implicit.data.read_bag(BAGS / "intel-zstd.mcap", scan_topic=5),
     implicit.InvalidArgument, r"^scan_topic: expected a str, got int"),
    (lambda: implicit.data.read_bag(BAGS / "intel-zstd.mcap", odom_topic=""),
     implicit.InvalidArgument, r"^odom_topic: expected a name"),
    (lambda: implicit.data.read_bag(BAGS / "intel-zstd.mcap", base_frame=1.5),
     implicit.InvalidArgument, r"^base_frame: expected a str"),
    (lambda: implicit.data.read_bag(BAGS / "intel-zstd.mcap", laser_frame=[]),
     implicit.InvalidArgument, r"^laser_frame: expected a str"),
    (lambda: implicit.data.read_bag(BAGS / "intel-zstd.mcap", scan_topic="/nope"),
     implicit.ParseError, r"intel-zstd.mcap: expected topic '/nope' \(--scan-topic\)"),
    (lambda: implicit.data.read_bag(BAGS / "backwards.mcap"),
     implicit.ParseError, r"backwards.mcap: topic '/scan' message 20: .*runs backwards"),
    (lambda: implicit.data.read_bag(BAGS / "README.md"),
     implicit.ParseError, r"README.md: expected a ROS bag"),
])
def test_bad_arguments_are_refused_naming_them(call, error, message):
    with pytest.raises(error, match=message):
        call()
