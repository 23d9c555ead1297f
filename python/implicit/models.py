"""Motion and sensor models (spec §3.1-3.2).

    Ute(dt=0.025, control_std=(0.5, 0.5), state_std=...)   the Car Park vehicle
    Unicycle(dt=0.1, control_std=(0.1, 0.05), ...)          a unicycle robot
    RangeBearing(range_variance, bearing_variance)          the laser's range-bearing sensor

Poses are (x [m], y [m], heading [rad]); each model has predict(x, u, dt=0),
process_covariance(x, u, dt=0) and jacobian_state(x, u).

Example::

    import implicit
    ute = implicit.models.Ute(control_std=(0.1, 0.1))
    ute.predict([0.0, 0.0, 0.0], [2.0, 0.0])      # 2 m/s straight ahead for dt = 0.025 s
"""
from ._implicit.models import RangeBearing, Unicycle, Ute

__all__ = ["RangeBearing", "Unicycle", "Ute"]
