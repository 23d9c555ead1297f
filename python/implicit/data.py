"""Robot logs and the bundled data sets (docs/formats.md).

    carpark()            the Car Park data set (paper §4.1) as a Log
    victoria_park()      the Victoria Park log
    read_log(path)       a log in the text format (.gz accepted)
    read_bag(path, scan_topic=None, odom_topic=None, base_frame=None, laser_frame=None)
                         a ROS bag (MCAP, rosbag2, ROS 1) as implicit.laser.read_carmen's dict
    simulate(model, sensor, steps=1200, landmarks=40, ..., seed=1)   a synthetic log
    steps(log, model)    the log as filter steps: controls, dt, detections, truth

Example::

    import implicit
    log = implicit.data.carpark()
    s = implicit.data.steps(log, implicit.models.Ute())
    len(s), s.controls.shape, s.landmarks.shape
"""
from ._implicit.data import (Log, Steps, carpark, read_bag, read_log, simulate, steps,
                             victoria_park)

__all__ = ["Log", "Steps", "carpark", "read_bag", "read_log", "simulate", "steps",
           "victoria_park"]
