"""Motion and sensor models (spec §3.1-3.2).

    Ute(dt=0.025, control_std=(0.5, 0.5), state_std=...)   the Car Park vehicle
    Unicycle(dt=0.1, control_std=(0.1, 0.05), ...)          a unicycle robot
    RangeBearing(range_variance, bearing_variance)          the laser's range-bearing sensor
    register_motion_model(name, predict, process_covariance, ...)   your own robot, by name
    motion_models()                                         the models the runners know by name

Poses are (x [m], y [m], heading [rad]); each model has predict(x, u, dt=0),
process_covariance(x, u, dt=0) and jacobian_state(x, u).

Example::

    import implicit
    ute = implicit.models.Ute(control_std=(0.1, 0.1))
    ute.predict([0.0, 0.0, 0.0], [2.0, 0.0])      # 2 m/s straight ahead for dt = 0.025 s
"""
import math

from ._implicit.models import RangeBearing, Unicycle, Ute
from ._implicit.models import motion_models as _motion_models
from ._implicit.models import register_motion_model as _register

__all__ = ["RangeBearing", "Unicycle", "Ute", "motion_models", "register_motion_model"]


def register_motion_model(name, predict, process_covariance, jacobian_state=None, dt=0.1,
                          control_sd=(0.1, 0.05), state_sd=(0.02, 0.02, 0.2 * math.pi / 180),
                          controls="u1, u2", description="a motion model written in Python"):
    """Registers a motion model written in Python under `name`, for the runners that take a
    model by name: `implicit.mcl.run(model=name)`, `implicit.slam.run(model=name)`, and logs
    whose `vehicle` record declares `name` (docs/design.md, "A new motion model").

    predict(x, u, dt) returns the noise-free next pose (3,) from pose x (3,) [m, m, rad] and
    control u (2,) over a step of dt seconds; process_covariance(x, u, dt, control_sd, state_sd)
    its covariance (3, 3), given the run's noise (the `control_sd=` and `state_sd=` of the
    runner, else the defaults given here); jacobian_state(x, u, dt) the (3, 3) derivative of
    predict by x (None: central differences of predict). dt is the nominal control period (the
    `vehicle` record's key dt overrides it). controls and description are the text
    `motion_models()` lists. A registration lasts as long as the process; a name that is
    taken raises ValueError. The filters call the functions once per particle and step, each
    time with the GIL: a model in Python runs correctly but slowly.

    Example::

        import math, numpy as np, implicit
        def predict(x, u, dt):                       # a unicycle
            return x + dt * np.array([u[0] * math.cos(x[2]), u[0] * math.sin(x[2]), u[1]])
        def covariance(x, u, dt, control_sd, state_sd):
            c, s = math.cos(x[2]), math.sin(x[2])
            j = np.array([[c, 0.0], [s, 0.0], [0.0, 1.0]])
            return dt * (j @ np.diag(control_sd ** 2) @ j.T + np.diag(state_sd ** 2))
        implicit.models.register_motion_model("my-robot", predict, covariance)
        implicit.mcl.run(data="my_robot.log", model="my-robot", runs=4)
    """
    return _register(name, predict, process_covariance, jacobian_state, dt, control_sd, state_sd,
                     controls, description)


def motion_models():
    """The motion models the runners know by name, built-ins first: a list of dicts with
    `name`, `description`, `controls`, `keys` ({key: (default, meaning)} of the `vehicle`
    record) and the default `control_sd` and `state_sd`."""
    return _motion_models()
