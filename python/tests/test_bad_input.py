"""Bad input raises a clean RobokrigeError (a ValueError) with the library's
message, never a panic (pyo3's PanicException is a BaseException)."""

import warnings

import numpy as np
import pytest

import robokrige as rk


def q_e(m=40, n=6, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-30, 30, size=(m, n)), rng.normal(0, 0.3, size=(m, 3))


def raises(match):
    return pytest.raises(rk.RobokrigeError, match=match)


def test_error_class():
    assert issubclass(rk.RobokrigeError, ValueError)


def test_shapes():
    q, e = q_e()
    with raises(r"q must be a 2-D array"):
        rk.ErrorModel().fit(q[:, 0], errors=e)
    with raises(r"errors must have 3 columns"):
        rk.ErrorModel().fit(q, errors=e[:, :2])
    with raises(r"dirs must have 6 columns"):
        rk.ErrorModel().fit(q, np.ones((40, 5)), e)
    with raises(r"errors has 39 rows but q has 40"):
        rk.ErrorModel().fit(q, errors=e[:39])
    with raises(r"covariate 'temp' has 3 values but q has 40 rows"):
        rk.ErrorModel().fit(q, errors=e, covariates={"temp": [1.0, 2.0, 3.0]})
    with raises(r"no poses"):
        rk.ErrorModel().fit(np.zeros((0, 6)), errors=np.zeros((0, 3)))
    with raises(r"q must be numeric"):
        rk.ErrorModel().fit([["a", "b"]], errors=[[0, 0, 0]])


def test_values():
    q, e = q_e()
    bad = q.copy()
    bad[3, 2] = np.nan
    with raises(r"<memory>: q row 3 \(0-based\) has a NaN/inf value"):
        rk.ErrorModel().fit(bad, errors=e)
    d = np.ones_like(q)
    d[5, 1] = 0.5
    with raises(r"dir row 5 \(0-based\): direction must be \+1 or -1, found 0.5"):
        rk.ErrorModel().fit(q, d, e)
    e2 = e.copy()
    e2[0, 0] = np.inf
    with raises(r"errors"):
        rk.ErrorModel().fit(q, errors=e2)
    with raises(r"requires y to be passed, but the target y is None"):
        rk.ErrorModel().fit(q)
    with raises(r"has no ex,ey,ez columns"):
        rk.ErrorModel().fit({f"q{j}": q[:, j - 1] for j in range(1, 7)})


def test_parameters():
    q, e = q_e()
    with raises(r"^invalid parameter: space 'xyz': expected 'ejs' or 'js'$"):
        rk.ErrorModel(space="xyz").fit(q, errors=e)
    with raises(r"corr 'cubic'"):
        rk.ErrorModel(corr="cubic").fit(q, errors=e)
    with raises(r"starts is for optimizer 'bfgs' or 'gps'"):
        rk.ErrorModel(optimizer="hj", starts=3).fit(q, errors=e)
    with raises(r"starts, max_evals and tol must be positive"):
        rk.ErrorModel(starts=0).fit(q, errors=e)
    with raises(r"kinematic needs robot"):
        rk.ErrorModel(kinematic=True).fit(q, errors=e)
    with raises(r"unknown robot 'nope'"):
        rk.ErrorModel(robot="nope").fit(q, errors=e)
    with raises(r"has 4 joint columns .* robot 'comau-nj220' has 6 joints"):
        rk.ErrorModel(robot="comau-nj220").fit(q[:, :4], errors=e)
    with raises(r"unknown method 'best'"):
        rk.ErrorModel(method="best").fit(q, errors=e)
    with raises(r"method 'ejs-gps' fixes its own settings: leave space"):
        rk.ErrorModel(method="ejs-gps", space="js").fit(q, errors=e)
    with raises(r"periodic '9'"):
        rk.ErrorModel(periodic=[9]).fit(q, errors=e)
    with raises(r"seed must be an integer"):
        rk.ErrorModel(seed=-1).fit(q, errors=e)
    with raises(r"mode 'fast'"):
        rk.cross_validate(None, q, errors=e, mode="fast")
    with raises(r"K-fold needs 2 ≤ K ≤ rows, got K = 1 with 40 rows"):
        rk.cross_validate(None, q, errors=e, folds=1)


def test_predict_and_files(tmp_path, datasets):
    q, e = q_e()
    with raises(r"not fitted yet"):
        rk.ErrorModel().predict(q)
    m = rk.ErrorModel(corr="gaussian").fit(q, errors=e)
    with raises(r"X has 5 features, but ErrorModel is expecting 12 features as input"):
        m.predict(q[:, :5])
    with raises(r"has 5 joints but the model was fitted on 6"):
        m.predict(q[:, :5], np.ones((40, 5)))
    with raises(r"missing.csv: No such file"):
        rk.read_campaign(tmp_path / "missing.csv")
    with raises(r"missing.json: No such file"):
        rk.ErrorModel.load(tmp_path / "missing.json")
    (tmp_path / "m.json").write_text('{"format": "something else", "version": 2}')
    with raises(r"not a robokrige error model"):
        rk.ErrorModel.load(tmp_path / "m.json")
    with raises(r"not a robokrige error model"):
        rk.ErrorModel.from_json('{"format": 1}')
    with raises(r"^<memory>: expected ident at line 1 column 2$"):
        rk.ErrorModel.from_json("not json")
    with raises(r"compensate|model was fitted for"):
        m6 = rk.ErrorModel(corr="gaussian", robot="comau-nj220").fit(q, errors=e)
        rk.compensate(m6, "ur10", np.array([[1000.0, 0.0, 1000.0]]))


def test_csv_messages_are_the_cli_messages(cli, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("q1,q2,ex,ey,ez\n1,2,0.1,0.1,0.1\n3,abc,0.1,0.1,0.1\n")
    proc = cli("fit", bad, "-o", tmp_path / "m.json", check=False)
    assert proc.returncode == 1
    cli_message = proc.stderr.strip().splitlines()[-1].removeprefix("error: ")
    with pytest.raises(rk.RobokrigeError) as info:
        rk.ErrorModel().fit(bad)
    assert str(info.value) == cli_message
    assert "bad.csv:3: column 'q2'" in cli_message


@pytest.mark.parametrize(
    "flags, params, message",
    [
        # a named method fixes its own options
        (
            ["--method", "ejs-gps", "--space", "js", "--starts", "2"],
            dict(method="ejs-gps", space="js", starts=2),
            "method 'ejs-gps' fixes its own settings: leave space, starts at the defaults",
        ),
        # --starts with Hooke–Jeeves
        (["--optimizer", "hj", "--starts", "3"], dict(optimizer="hj", starts=3), "starts is for optimizer 'bfgs' or 'gps'"),
        # the kinematic trend needs a robot
        (["--kinematic"], dict(kinematic=True), "kinematic needs robot"),
        # only a selecting method takes the kinematic candidates
        (
            ["--method", "js-hj", "--robot", "comau-nj220", "--kinematic"],
            dict(method="js-hj", robot="comau-nj220", kinematic=True),
            "kinematic with method 'js-hj': it works for ejs-pca and ejs-ga",
        ),
    ],
)
def test_refused_combinations_give_the_cli_message(cli, datasets, tmp_path, flags, params, message):
    """One rule, one message: the library's (`methods::params_with`) from
    both front ends."""
    lhs = datasets / "comau_lhs.csv"
    proc = cli("fit", lhs, *flags, "-o", tmp_path / "m.json", check=False)
    assert proc.returncode == 1, proc.stderr
    cli_message = proc.stderr.strip().splitlines()[-1].removeprefix("error: ")
    with pytest.raises(rk.RobokrigeError) as info:
        rk.ErrorModel(**params).fit(lhs)
    assert str(info.value) == cli_message
    assert message in cli_message


def test_compensate_targets():
    q, e = q_e()
    m = rk.ErrorModel(corr="gaussian").fit(q, errors=e)
    with raises(r"targets array must be k × 3"):
        rk.compensate(m, "comau-nj220", np.zeros((4, 5)))
    with raises(r"xyz row 1 \(0-based\): NaN is not a finite value"):
        rk.compensate(m, "comau-nj220", np.array([[1000.0, 0, 1000], [np.nan, 0, 0]]))
    with raises(r"the trajectory has no points"):
        rk.compensate(m, "comau-nj220", np.zeros((0, 3)))
    with raises(r"compensation needs tol > 0"):
        rk.compensate(m, "comau-nj220", np.array([[1500.0, 0, 1000]]), tol=0)
    with raises(r"a joint vector has 2 values but the robot or model has 6 joints"):
        rk.compensate(m, "comau-nj220", np.array([[1500.0, 0, 1000]]), start=[0, 0])
    # position-only targets take the start pose's orientation: an
    # unreachable one says so, with what to give instead
    with raises(r"unreachable.*orientation of the start pose.*orientation=\(roll, pitch, yaw\)"):
        rk.compensate(m, "comau-nj220", np.array([[1e5, 0, 1000]]))
    # with their own orientation there is nothing to add
    with pytest.raises(rk.RobokrigeError) as info:
        rk.compensate(m, "comau-nj220", np.array([[1e5, 0, 1000, 180, 0, 0]]))
    assert "unreachable" in str(info.value) and "start pose" not in str(info.value)
    with raises(r"the start pose is outside the limits of robot 'comau-nj220': q2 = 200° not in"):
        rk.compensate(m, "comau-nj220", np.array([[1500.0, 0, 1000]]), start=[0, 200, 0, 0, 0, 0])
    # an orientation is for position-only targets, named as Python takes it
    with raises(r"orientation= \(roll, pitch, yaw\) is for position-only .*not for targets with their own"):
        rk.compensate(m, "comau-nj220", np.array([[1500.0, 0, 1000, 180, 0, 0]]), orientation=[0, 0, 0])
    with raises(r"orientation= needs three finite angles"):
        rk.compensate(m, "comau-nj220", np.array([[1500.0, 0, 1000]]), orientation=[0, 0])


def test_many_bad_inputs_never_panic():
    """Random garbage through every entry point: only RobokrigeError (or a
    TypeError for a wrong Python type), never a PanicException."""
    rng = np.random.default_rng(7)
    q, e = q_e(30, 3)
    good = rk.ErrorModel(corr="gaussian", starts=1).fit(q, errors=e)
    specials = [np.nan, np.inf, -np.inf, 1e308, -1e308, 0.0, 1e-320]
    for trial in range(200):
        m, n = int(rng.integers(0, 6)), int(rng.integers(0, 5))
        qq = rng.uniform(-200, 200, size=(m, n))
        ee = rng.normal(size=(m, 3))
        if m and n and rng.random() < 0.5:
            qq[rng.integers(m), rng.integers(n)] = specials[rng.integers(len(specials))]
        if m and rng.random() < 0.3:
            ee[rng.integers(m), rng.integers(3)] = specials[rng.integers(len(specials))]
        for call in (
            lambda: rk.ErrorModel(corr="gaussian", starts=1).fit(qq, errors=ee),
            lambda: good.predict(qq, return_std=True),
            lambda: rk.cross_validate({"corr": "gaussian", "starts": 1}, qq, errors=ee, folds=2),
        ):
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", rk.RobokrigeWarning)
                    call()
            except (rk.RobokrigeError, TypeError):
                pass
