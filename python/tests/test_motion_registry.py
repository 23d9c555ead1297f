"""A motion model written in Python and registered by name (implicit.models.register_motion_model)
runs in implicit.mcl.run and implicit.slam.run like a built-in. The oracle: the unicycle written
again in Python, operation for operation, must give the built-in unicycle's numbers exactly on the
same log (the log declaring the Python model instead), times aside."""
import math
import re

import numpy as np
import pytest

import implicit

NAME = "py-unicycle"


def predict(x, u, dt):
    return x + dt * np.array([u[0] * math.cos(x[2]), u[0] * math.sin(x[2]), u[1]])


def covariance(x, u, dt, control_sd, state_sd):
    # The order of robot::UnicycleModel::process_covariance, so that the sums round alike.
    c, s = math.cos(x[2]), math.sin(x[2])
    v2 = control_sd[0] * control_sd[0]
    m = np.array([[v2 * c * c, v2 * c * s, 0.0], [v2 * c * s, v2 * s * s, 0.0],
                  [0.0, 0.0, control_sd[1] * control_sd[1]]])
    m[np.diag_indices(3)] += state_sd * state_sd
    return dt * m


def jacobian(x, u, dt):
    j = np.eye(3)
    j[0, 2] = -dt * u[0] * math.sin(x[2])
    j[1, 2] = dt * u[0] * math.cos(x[2])
    return j


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """The same simulated log twice: declaring the unicycle, and declaring the Python model."""
    if NAME not in [m["name"] for m in implicit.models.motion_models()]:
        implicit.models.register_motion_model(
            NAME, predict, covariance, jacobian, dt=0.1,
            controls="u1 = v [m/s], u2 = omega [rad/s]", description="the unicycle in Python")
    folder = tmp_path_factory.mktemp("registry")
    log = implicit.data.simulate(implicit.models.Unicycle(), implicit.models.RangeBearing(),
                                 steps=300, seed=3)
    unicycle = folder / "unicycle.log"
    log.write(str(unicycle))
    text = unicycle.read_text()
    mine_text, n = re.subn(r"^vehicle unicycle ", f"vehicle {NAME} ", text, flags=re.M)
    assert n == 1
    mine = folder / "mine.log"
    mine.write_text(mine_text)
    return str(unicycle), str(mine)


NOT_RESULTS = re.compile(r"cpu|memory|seconds|time_s|_ms|_us|^data$|^model$|commit")


def results(value, path=""):
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            if not NOT_RESULTS.search(k):
                out.update(results(v, f"{path}.{k}"))
        return out
    if isinstance(value, list):
        out = {}
        for i, v in enumerate(value):
            out.update(results(v, f"{path}[{i}]"))
        return out
    return {path: value}


def test_the_registry_lists_the_built_ins_first_and_the_python_model(logs):
    models = implicit.models.motion_models()
    assert [m["name"] for m in models[:2]] == ["ute", "unicycle"]
    mine = next(m for m in models if m["name"] == NAME)
    assert mine["keys"] == {"dt": (0.1, "control period [s]")}
    assert mine["controls"] == "u1 = v [m/s], u2 = omega [rad/s]"
    assert mine["control_sd"] == [0.1, 0.05]


@pytest.mark.parametrize("method", ["implicit", "standard"])
def test_mcl_runs_the_python_model_as_the_built_in(logs, method):
    unicycle, mine = logs
    a = implicit.mcl.run(method=method, particles=20, runs=2, data=unicycle, threads=2)
    b = implicit.mcl.run(method=method, particles=20, runs=2, data=mine, threads=2)
    assert b["model"] == NAME
    ra, rb = results(a), results(b)
    assert len(ra) > 10
    assert ra == rb


def test_slam_runs_the_python_model_as_the_built_in(logs):
    unicycle, mine = logs
    a = implicit.slam.run(method="implicit-rb", particles=5, data=unicycle, threads=2)
    b = implicit.slam.run(method="implicit-rb", particles=5, data=mine, threads=2)
    assert b["model"] == NAME
    assert len(results(a)) > 10
    assert results(a) == results(b)


def test_a_python_model_is_refused_where_the_log_declares_another(logs):
    unicycle, _ = logs
    with pytest.raises(implicit.InvalidArgument, match=f"declares vehicle 'unicycle'.*not '{NAME}'"):
        implicit.mcl.run(particles=10, runs=1, data=unicycle, model=NAME)
