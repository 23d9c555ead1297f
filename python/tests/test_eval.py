"""implicit.eval: APE and RPE on numpy arrays against hand-computed values and against
`implicit eval --json` on the same files; bad arguments raise implicit.InvalidArgument naming the
argument (and the row)."""
import math
import pathlib

import numpy as np
import pytest

import implicit

DATA = pathlib.Path(__file__).resolve().parents[2] / "data" / "trajectories"


def line_path(n=5):
    t = np.arange(float(n))
    return np.column_stack([t, t, np.zeros(n), np.zeros(n)])


def tum_rows(path):
    return np.loadtxt(path, comments="#")


def test_ape_by_hand():
    ref = line_path()
    est = ref.copy()
    est[2, 2] = 0.3                  # pose 2 is 0.3 m to the left
    est[3, 3] = math.radians(10)     # pose 3 is turned by 10 degrees
    r = implicit.eval.ape(ref, est)
    assert r["pairs"] == 5
    np.testing.assert_allclose(r["translation_m"], [0, 0, 0.3, 0, 0], atol=1e-15)
    np.testing.assert_allclose(r["rotation_deg"], [0, 0, 0, 10, 0], atol=1e-12)
    # |E - I|_F with |R - I|_F^2 = 4 (1 - cos a)
    assert r["full"][3] == pytest.approx(math.sqrt(4 * (1 - math.cos(math.radians(10)))), abs=1e-15)
    s = r["stats"]["translation_m"]
    assert s["mean"] == pytest.approx(0.06, abs=1e-15)
    assert s["rmse"] == pytest.approx(0.3 / math.sqrt(5), abs=1e-15)
    assert s["std"] == pytest.approx(np.std(r["translation_m"]), abs=1e-15)
    assert s["mean_ci"][0] <= s["mean"] <= s["mean_ci"][1]
    assert r["alignment"]["kind"] == "none"


def test_rpe_by_hand_and_alignment():
    ref = line_path()
    est = ref.copy()
    est[:, 1] *= 1.1                 # every step 10 % too long
    r = implicit.eval.rpe(ref, est)
    np.testing.assert_allclose(r["translation_m"], [0.1] * 4, atol=1e-14)
    np.testing.assert_allclose(r["t_i"], [0, 1, 2, 3])
    two = implicit.eval.rpe(ref, est, delta=2, all_pairs=True)
    np.testing.assert_allclose(two["translation_m"], [0.2] * 3, atol=1e-14)
    metres = implicit.eval.rpe(ref, est, delta=2.0, delta_unit="m")
    np.testing.assert_allclose(metres["t_j"], [2, 4])
    # Sim(3) takes a scale out (on a bent path: a straight one does not fix a 3-D rotation).
    bent = np.column_stack([ref[:, 0], ref[:, 1], ref[:, 1] ** 2 / 4, np.zeros(5)])
    big = bent * [1.0, 1.1, 1.1, 1.0]
    sim = implicit.eval.rpe(bent, big, align="sim3")
    assert sim["alignment"]["scale"] == pytest.approx(1 / 1.1, abs=1e-12)
    assert max(sim["translation_m"]) < 1e-12
    # Rows of 8 (TUM) give what rows of 4 give.
    tum = np.column_stack([ref[:, :3], np.zeros(5), np.zeros(5), np.zeros(5), np.zeros(5),
                           np.ones(5)])
    assert implicit.eval.ape(tum, est)["translation_m"].tolist() == \
        implicit.eval.ape(ref, est)["translation_m"].tolist()


def test_same_numbers_as_the_command_line(cli):
    ref, est = DATA / "circle_ref.tum", DATA / "circle_est.tum"
    j = cli("eval", "--ref", str(ref), "--est", str(est), "--align", "se2", "--seed", "3")
    a = implicit.eval.ape(tum_rows(ref), tum_rows(est), align="se2", seed=3)
    r = implicit.eval.rpe(tum_rows(ref), tum_rows(est), align="se2", seed=3)
    for key in ("translation_m", "rotation_deg", "full"):
        for stat in ("mean", "median", "rmse", "max", "min", "std"):
            assert a["stats"][key][stat] == pytest.approx(j["ape"][key][stat], rel=1e-12)
            assert r["stats"][key][stat] == pytest.approx(j["rpe"][key][stat], rel=1e-12)
        assert list(a["stats"][key]["rmse_ci"]) == pytest.approx(j["ape"][key]["rmse_ci"],
                                                                 rel=1e-12)
    assert a["alignment"]["scale"] == j["alignment"]["scale"]


REF = line_path()
BAD = [
    (lambda: implicit.eval.ape("x", REF), "ref"),
    (lambda: implicit.eval.ape(REF[:, :3], REF), "ref"),
    (lambda: implicit.eval.ape(REF, np.zeros((0, 4))), "est"),
    (lambda: implicit.eval.ape(REF, REF[::-1]), "est: row 1"),
    (lambda: implicit.eval.ape(np.where(np.isin(REF, [2.0]), np.nan, REF), REF), "ref"),
    (lambda: implicit.eval.ape(np.column_stack([REF, REF]), REF), "ref: row 0"),
    (lambda: implicit.eval.ape(REF, REF, align="se4"), "align"),
    (lambda: implicit.eval.ape(REF, REF, align="se3"), "alignment"),
    (lambda: implicit.eval.ape(REF, REF, max_diff=-1), "max_diff"),
    (lambda: implicit.eval.ape(REF, REF, max_diff=math.nan), "max_diff"),
    (lambda: implicit.eval.ape(REF, REF, offset=math.inf), "offset"),
    (lambda: implicit.eval.ape(REF, REF, offset=100), "trajectory association"),
    (lambda: implicit.eval.ape(REF, REF, seed=-1), "seed"),
    (lambda: implicit.eval.rpe(REF, REF, delta=0), "delta"),
    (lambda: implicit.eval.rpe(REF, REF, delta=1.5), "delta"),
    (lambda: implicit.eval.rpe(REF, REF, delta=-1.0, delta_unit="m"), "delta"),
    (lambda: implicit.eval.rpe(REF, REF, delta=5), "relative pose error"),
    (lambda: implicit.eval.rpe(REF, REF, delta_unit="km"), "delta_unit"),
    (lambda: implicit.eval.rpe(REF, REF, all_pairs="yes"), "all_pairs"),
]


@pytest.mark.parametrize("call,name", BAD)
def test_bad_arguments_name_the_argument(call, name):
    with pytest.raises(implicit.InvalidArgument) as e:
        call()
    assert str(e.value).startswith(name), str(e.value)


def numpy_umeyama(x, y):
    """Umeyama (1991) in numpy, written from the paper: R, t with y ~ R x + t (no scale)."""
    mx, my = x.mean(axis=0), y.mean(axis=0)
    u, _, vt = np.linalg.svd((y - my).T @ (x - mx) / len(x))
    s = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        s[2, 2] = -1
    r = u @ s @ vt
    return r, my - r @ mx


def test_se3_ape_agrees_with_numpy():
    ref, est = tum_rows(DATA / "circle_ref.tum"), tum_rows(DATA / "circle_est.tum")
    # Lift the estimate out of its plane, so that SE(3) has a 3-D rotation to find.
    est[:, 3] = 0.2 * est[:, 1] - 0.1 * est[:, 2] + 0.05 * np.sin(np.arange(len(est)))
    r, t = numpy_umeyama(est[:, 1:4], ref[:, 1:4])
    expected = np.linalg.norm(est[:, 1:4] @ r.T + t - ref[:, 1:4], axis=1)
    got = implicit.eval.ape(ref, est, align="se3")
    np.testing.assert_allclose(got["alignment"]["rotation"], r, atol=1e-12)
    np.testing.assert_allclose(got["translation_m"], expected, atol=1e-12)
