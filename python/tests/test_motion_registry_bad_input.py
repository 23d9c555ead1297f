"""Bad input to implicit.models.register_motion_model and to the runs of a registered model:
each refused registration names the argument (and registers nothing), and a callback that raises
or returns the wrong thing stops the run with a message naming the model and the callback."""
import re

import numpy as np
import pytest

import implicit
from test_motion_registry import covariance, logs, predict  # noqa: F401 (logs: a fixture)


def _register(name, **changes):
    args = dict(name=name, predict=predict, process_covariance=covariance)
    args.update(changes)
    implicit.models.register_motion_model(**args)


@pytest.mark.parametrize("changes, message", [
    (dict(name="unicycle"), "the name 'unicycle' is taken"),
    (dict(name="has blank"), "expected a name without blanks"),
    (dict(name=""), "expected a name without blanks"),
    (dict(predict=3), "expected predict to be callable, got int"),
    (dict(process_covariance=None), "expected process_covariance to be callable"),
    (dict(jacobian_state="no"), "expected jacobian_state to be callable"),
    (dict(dt=0.0), "dt"),
    (dict(dt=float("nan")), "dt"),
    (dict(control_sd=(0.1,)), "control_sd"),
    (dict(state_sd=(0.1, -1.0, 0.1)), "state_sd of finite values >= 0"),
])
def test_bad_registrations_are_refused_naming_the_argument(changes, message):
    name = changes.pop("name", "bad-model")
    with pytest.raises(implicit.InvalidArgument, match=re.escape(message)):
        _register(name, **changes)
    assert "bad-model" not in [m["name"] for m in implicit.models.motion_models()]


def test_a_failing_callback_names_the_model_and_the_callback(logs):
    unicycle, _ = logs
    text = open(unicycle).read()
    for name, changes, message in [
            ("raises", dict(predict=lambda x, u, dt: 1 / 0), "'raises': predict raised"),
            ("bad-shape", dict(process_covariance=lambda *a: np.eye(2)),
             "'bad-shape': process_covariance"),
            ("not-finite", dict(predict=lambda x, u, dt: x * np.nan), "'not-finite': predict")]:
        _register(name, **changes)
        path = unicycle.replace("unicycle.log", f"{name}.log")
        with open(path, "w") as f:
            f.write(re.sub(r"^vehicle unicycle ", f"vehicle {name} ", text, flags=re.M))
        with pytest.raises(implicit.InvalidArgument, match=re.escape(message)):
            implicit.mcl.run(particles=5, runs=1, data=path, threads=1)
