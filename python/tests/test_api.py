"""The Python API: estimator protocol, predict, CV report, compensation,
diagnosis, progress, the GIL."""

import pickle
import threading
import time

import numpy as np
import pytest

import robokrige as rk

from conftest import need


@pytest.fixture(scope="module")
def lhs(datasets):
    return rk.read_campaign(datasets / "comau_lhs.csv", as_frame=False)


@pytest.fixture(scope="module")
def model(datasets):
    return rk.ErrorModel().fit(datasets / "comau_lhs.csv")


def arrays(table, rows=None):
    sl = slice(None) if rows is None else slice(0, rows)
    q = np.column_stack([table[f"q{j}"] for j in range(1, 7)])[sl]
    d = np.column_stack([table[f"dir{j}"] for j in range(1, 7)])[sl]
    e = np.column_stack([table[a] for a in ("ex", "ey", "ez")])[sl]
    return q, d, e


def test_params_protocol():
    m = rk.ErrorModel(space="js", seed=3)
    p = m.get_params()
    assert p["space"] == "js" and p["seed"] == 3 and p["corr"] == "auto"
    assert m.set_params(trend="linear") is m and m.trend == "linear"
    with pytest.raises(rk.RobokrigeError, match="no parameter 'bogus'"):
        m.set_params(bogus=1)
    assert "space='js'" in repr(m)


def test_sklearn_clone_works():
    base = need("sklearn.base")
    m = rk.ErrorModel(space="js", corr="gaussian")
    c = base.clone(m)
    assert c.get_params() == m.get_params() and c is not m


def test_predict_shapes_and_std(model, lhs):
    q, d, e = arrays(lhs, 25)
    mean = model.predict(q, d)
    assert mean.shape == (25, 3) and mean.dtype == np.float64
    mean2, std = model.predict(q, d, return_std=True)
    assert np.array_equal(mean, mean2)
    assert std.shape == (25, 3) and np.all(std > 0)
    # the fitted model is close to the training errors (nugget: not exact)
    assert np.mean(np.linalg.norm(mean - e, axis=1)) < 0.05
    assert rk.mean_3d_error(model, q, d, e) < 0.05


def test_fitted_attributes(model):
    assert model.space_ == "ejs" and model.n_joints_ == 6 and model.n_rows_ == 300
    assert len(model.families_) == 3 and len(model.reports_) == 3
    assert model.input_names_[:2] == ["q1", "q2"] and "dir1" in model.input_names_
    assert "ln_psi" in model.reports_[0] and model.reports_[0]["families"]
    assert model.robot_ is None and model.extras_ == []


def test_directions_derived_from_row_order_when_none(lhs):
    q, d, e = arrays(lhs, 60)
    derived = rk.as_data(q, None, e)
    assert derived.dir_source == "derived"
    assert derived.dirs.shape == q.shape and set(np.unique(derived.dirs)) <= {-1.0, 1.0}
    m = rk.ErrorModel(corr="gaussian").fit(q, errors=e)
    assert np.array_equal(m.predict(q, derived.dirs), m.predict(q, derived.dirs))
    with pytest.warns(rk.RobokrigeWarning, match="derived from the row order"):
        m.predict(q)


def test_save_load_pickle_round_trip(model, lhs, tmp_path):
    q, d, _ = arrays(lhs, 10)
    model.save(tmp_path / "m.json")
    back = rk.ErrorModel.load(tmp_path / "m.json")
    assert back == model
    assert np.array_equal(back.predict(q, d), model.predict(q, d))
    assert back.get_params()["space"] == "ejs" and back.get_params()["corr"] == "auto"
    again = pickle.loads(pickle.dumps(model))
    assert again == model and np.array_equal(again.predict(q, d), model.predict(q, d))
    assert rk.ErrorModel.from_json(model.to_json()) == model


def test_cross_validate_report(lhs):
    q, d, e = arrays(lhs, 60)
    res = rk.cross_validate(rk.ErrorModel(corr="gaussian"), q, d, e, folds=5)
    assert res["mode"] == "refit" and res["folds"] == 5 and res["seed"] == 1
    assert res["residuals"].shape == (60, 3) and res["fold"].shape == (60,)
    s = res["summary"]
    assert len(s["rms_mm"]) == 3 and s["mean_3d_mm"] > 0 and s["n"] == 60
    assert np.allclose(np.sqrt(np.mean(res["residuals"] ** 2, axis=0)), s["rms_mm"])


def test_cross_validate_as_frame(lhs):
    need("pandas")
    q, d, e = arrays(lhs, 60)
    df = rk.cross_validate({"corr": "gaussian"}, q, d, e, folds=5, mode="closed-form", as_frame=True)
    assert list(df.columns) == ["fold", "res_ex", "res_ey", "res_ez", "res_3d"]
    assert len(df) == 60 and df.attrs["mode"] == "closed-form"


def test_progress_callback_and_tqdm(lhs, capsys):
    q, d, e = arrays(lhs, 60)
    calls = []
    rk.cross_validate(
        rk.ErrorModel(corr="gaussian"), q, d, e, folds=4, progress=lambda *a: calls.append(a)
    )
    assert [c[0] for c in calls] == [1, 2, 3, 4]
    assert all(c[1] == 4 for c in calls) and calls[-1][2] == "fold 4 of 4"
    # progress=True: tqdm if installed, else lines on stderr; either works
    rk.cross_validate(rk.ErrorModel(corr="gaussian"), q, d, e, folds=3, progress=True)


def test_progress_callback_exception_is_raised_after_the_call(lhs):
    q, d, e = arrays(lhs, 40)

    def boom(done, total, message):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        rk.cross_validate(rk.ErrorModel(corr="gaussian"), q, d, e, folds=3, progress=boom)


def test_gil_is_released_during_a_fit(datasets):
    counter = {"n": 0}
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            counter["n"] += 1
            time.sleep(0.001)

    t = threading.Thread(target=spin)
    t.start()
    try:
        before = counter["n"]
        t0 = time.perf_counter()
        rk.ErrorModel().fit(datasets / "comau_lhs.csv")
        elapsed = time.perf_counter() - t0
        ticks = counter["n"] - before
    finally:
        stop.set()
        t.join()
    # a held GIL would let the thread run only at the fit's end
    assert ticks > 0.2 * elapsed / 0.001 * 0.1, (ticks, elapsed)


def test_compensate_circle_on_the_simulated_robot(model, datasets):
    out = rk.compensate(
        model,
        "comau-nj220",
        datasets / "comau_circle.csv",
        truth=datasets / "comau_circle.truth.json",
    )
    k = out["xyz"].shape[0]
    assert out["rpy"].shape == (k, 3) and out["joints"].shape == (k, 6)
    assert out["predicted"].shape == (k, 3) and out["history"]
    assert out["stop"] in ("converged", "stalled", "max-iterations")
    ev = out["evaluation"]
    assert ev["before"].shape == (k, 3) and ev["after"].shape == (k, 3)
    assert ev["summary"]["after"]["mean_abs_mm"] < 0.5 * ev["summary"]["before"]["mean_abs_mm"]


def test_compensate_arrays_and_frames(model, datasets):
    pd = need("pandas")
    circle = pd.read_csv(datasets / "comau_circle.csv")
    from_file = rk.compensate(model, "comau-nj220", datasets / "comau_circle.csv", iterative=False)
    from_frame = rk.compensate(model, "comau-nj220", circle, iterative=False)
    six = circle[["x", "y", "z", "roll_deg", "pitch_deg", "yaw_deg"]].to_numpy()
    from_array = rk.compensate(model, "comau-nj220", six, iterative=False)
    assert from_file["stop"] == "single-step"
    for other in (from_frame, from_array):
        assert np.array_equal(other["xyz"], from_file["xyz"])
    # position-only targets take the start pose's orientation
    pos = rk.compensate(model, "comau-nj220", six[:, :3], iterative=False)
    assert pos["xyz"].shape == (len(six), 3)
    # joint poses: their nominal TCP poses become the targets
    poses = rk.read_campaign(datasets / "comau_verify.csv")
    out = rk.compensate(model, "comau-nj220", poses[[f"q{j}" for j in range(1, 7)]])
    assert out["joints"].shape == (len(poses), 6)


def test_diagnose_finds_the_tracker_step(datasets):
    need("pandas")
    df = rk.read_campaign(datasets / "comau_tracker_step.csv")
    lines = []
    effects, improved, report = rk.diagnose(df, permutations=199, progress=lambda *a: lines.append(a[2]))
    accepted = effects[effects["accepted"]]
    assert len(accepted) >= 1
    assert "step" in accepted.iloc[0]["label"]  # "step in the measurement order (at row 150)"
    assert report["after"]["pooled_rmse_mm"] < 0.6 * report["before"]["pooled_rmse_mm"]
    assert improved.extras_ and report["before_residuals"].shape == (len(df), 3)
    assert lines and "cross-validating" in lines[0]
    # the improved model predicts the campaign (its effect columns from the frame)
    assert improved.predict(df).shape == (len(df), 3)


def test_diagnose_scans_a_subset_of_a_large_campaign(datasets):
    df = rk.read_campaign(datasets / "comau_tracker_step.csv")
    effects, improved, report = rk.diagnose(df, permutations=199, scan_rows=200, as_frame=False)
    assert report["scanned_rows"] == 200
    assert report["before_residuals"].shape == (len(df), 3)
    top = next(e for e in effects if e["accepted"])
    assert "step" in top["label"] and abs(top["params"]["row"] - 150) <= 2
    with pytest.raises(ValueError, match="scan_rows"):
        rk.diagnose(df, scan_rows=10)


def test_a_robot_calibrates_by_default(datasets, lhs):
    import json

    q, d, e = arrays(lhs, 120)
    opts = dict(robot="comau-nj220", corr="gaussian", optimizer="hj")
    cal = rk.ErrorModel(**opts).fit(q, d, e)
    raw = rk.ErrorModel(calibrate=False, **opts).fit(q, d, e)
    report = json.loads(cal.model_.calibration_json())
    assert 0 < report["directions_seen"] < report["parameters_total"]
    assert json.loads(raw.model_.calibration_json()) is None
    assert json.loads(cal.model_.to_json())["version"] == 4
    # the nugget's noise: positive (estimated) and below the errors' spread
    noise = np.asarray(cal.model_.noise_std())
    assert noise.shape == (3,) and np.all(noise > 0)
    assert np.all(noise < np.std(e, axis=0))
    with pytest.raises(rk.RobokrigeError, match="calibrate must be True or False"):
        rk.ErrorModel(calibrate="yes", **opts).fit(q, d, e)


def test_one_calibrated_model_fits_predicts_compensates_and_diagnoses(datasets, lhs, tmp_path):
    """fit -> save/load -> predict -> compensate (measured on the simulated
    robot's truth) -> diagnose(calibrate=True), from one calibrated model."""
    import json

    q, d, e = arrays(lhs)
    opts = dict(robot="comau-nj220", corr="gaussian", optimizer="hj")
    cal = rk.ErrorModel(**opts).fit(q, d, e)
    raw = rk.ErrorModel(calibrate=False, **opts).fit(q, d, e)
    path = tmp_path / "cal.json"
    cal.save(path)
    loaded = rk.ErrorModel.load(path)
    assert json.loads(loaded.model_.to_json())["version"] == 4
    verify = rk.read_campaign(datasets / "comau_verify.csv", as_frame=False)
    vq, vd, _ = arrays(verify)
    assert np.array_equal(loaded.predict(vq, vd), cal.predict(vq, vd))

    def reduction(m):
        out = rk.compensate(
            m,
            "comau-nj220",
            datasets / "comau_circle.csv",
            truth=datasets / "comau_circle.truth.json",
        )
        s = out["evaluation"]["summary"]
        return 1.0 - s["after"]["mean_abs_mm"] / s["before"]["mean_abs_mm"]

    r_cal, r_raw = reduction(loaded), reduction(raw)
    assert r_cal >= 0.85, r_cal
    assert r_cal >= r_raw - 0.02, (r_cal, r_raw)
    # with a robot, the diagnosis is of the calibration's residual (the
    # default) and keeps the calibration
    _, improved, report = rk.diagnose(
        datasets / "comau_lhs.csv",
        method="js-hj",
        robot="comau-nj220",
        max_effects=1,
        permutations=199,
        as_frame=False,
    )
    saved = json.loads(improved.model_.to_json())
    # 4, or 5 when the effect added is a harmonic (its phase reference)
    assert saved["version"] in (4, 5) and saved["calibration"]["parameters"]
    assert report["before_residuals"].shape == (len(lhs["q1"]), 3)
    with pytest.raises(rk.RobokrigeError, match="robot"):
        rk.diagnose(datasets / "comau_lhs.csv", method="js-hj", calibrate=True, permutations=199)


def test_plan_a_first_batch_and_write_a_program(tmp_path):
    """Without measurements or a prior: a space-filling first batch; the
    plan's table and a URScript program of it."""
    p = rk.plan("ur10", 12, candidates=300, region_points=100, output=tmp_path / "plan.script", format="urscript")
    assert p.summary["source"] == "spacefilling" and p.model is None
    k = len(p.q)
    assert p.q.shape == p.dirs.shape == (k, 6) and p.measure.dtype == bool and p.measure.sum() == 12
    assert set(np.unique(p.dirs)) <= {-1.0, 1.0}
    assert np.all((p.source >= 0) == p.measure)
    text = (tmp_path / "plan.script").read_text()
    assert text.count("movej") == k
    if need_pandas_or_none() is not None:
        frame = p.frame()
        assert list(frame.columns[:2]) == ["id", "q1"] and frame["measure"].sum() == 12
        assert frame["source"].isna().sum() == k - 12
    with pytest.raises(rk.RobokrigeError, match="budget"):
        rk.plan("ur10", 0)
    # in passes over the region: the same poses, each pass a run of them
    three = rk.plan("ur10", 12, candidates=300, region_points=100, passes=3)
    assert three.summary["passes"] == 3 and p.summary["passes"] == 1
    assert sorted(three.summary["chosen"]) == sorted(p.summary["chosen"])
    assert "order_correlation" in three.summary["order_in_joint_space"]
    with pytest.raises(rk.RobokrigeError, match=r"passes=\) must be at least 1"):
        rk.plan("ur10", 12, passes=0)


def test_plan_from_a_prior_model(datasets):
    prior = rk.ErrorModel(corr="gaussian", robot="comau-nj220", calibrate=False).fit(datasets / "comau_lhs.csv")
    p = rk.plan("comau-nj220", 5, prior=prior, candidates=200, region_points=80)
    assert p.summary["source"] == "prior" and len(p.summary["imse_curve_mm2"]) == 6
    curve = p.summary["imse_curve_mm2"]
    assert all(b <= a for a, b in zip(curve, curve[1:]))  # every chosen pose lowers the region's MSE


def need_pandas_or_none():
    try:
        import pandas
    except ImportError:
        return None
    return pandas


def test_the_calibration_finds_a_joint_harmonic_unless_told_geometric(datasets):
    """comau_harmonic.csv has a 7.5° harmonic planted on a joint: the
    default calibration adds it; joint_harmonics=False does not."""
    import json

    campaign = rk.read_campaign(datasets / "comau_harmonic.csv", as_frame=False)
    q, d, e = arrays(campaign)
    opts = dict(robot="comau-nj220", corr="gaussian", optimizer="hj")

    def harmonics(m):
        return json.loads(m.model_.to_json())["calibration"].get("harmonics", [])

    found = harmonics(rk.ErrorModel(**opts).fit(q, d, e))
    assert len(found) == 1 and abs(found[0]["period_deg"] / 7.5 - 1.0) < 0.02, found
    assert harmonics(rk.ErrorModel(joint_harmonics=False, **opts).fit(q, d, e)) == []
    with pytest.raises(rk.RobokrigeError, match="joint_harmonics must be True or False"):
        rk.ErrorModel(joint_harmonics="yes", **opts).fit(q, d, e)


def test_the_calibration_identifies_the_joints_backlash_when_asked(datasets):
    """comau_lhs.csv is simulated with play in every joint: backlash=True
    keeps the joints that move the tool most; the default does not look."""
    import json

    campaign = rk.read_campaign(datasets / "comau_lhs.csv", as_frame=False)
    q, d, e = arrays(campaign)
    opts = dict(robot="comau-nj220", corr="gaussian", optimizer="hj")

    def backlash(m):
        return json.loads(m.model_.to_json())["calibration"].get("backlash", [])

    assert backlash(rk.ErrorModel(**opts).fit(q, d, e)) == []
    joints = [b["joint"] for b in backlash(rk.ErrorModel(backlash=True, **opts).fit(q, d, e))]
    assert {1, 2, 3} <= set(joints), joints
    with pytest.raises(rk.RobokrigeError, match="backlash must be True or False"):
        rk.ErrorModel(backlash="yes", **opts).fit(q, d, e)
