"""The same numbers as the Rust API: the command line's model files,
predictions and CV residuals, on the shipped campaigns."""

import json

import numpy as np
import pytest

import robokrige as rk

TOL = 1e-12


def read_pred_csv(path):
    """pred_ex.., std_ex.. of `robokrige predict`'s CSV (NumPy only)."""
    head = open(path).readline().strip().split(",")
    body = np.genfromtxt(path, delimiter=",", skip_header=1, dtype=np.float64)
    col = {n: i for i, n in enumerate(head)}
    mean = body[:, [col["pred_ex"], col["pred_ey"], col["pred_ez"]]]
    std = body[:, [col["std_ex"], col["std_ey"], col["std_ez"]]]
    return mean, std


@pytest.mark.parametrize(
    "flags,params",
    [
        ([], {}),
        (["--space", "js", "--corr", "gaussian", "--optimizer", "hj"], dict(space="js", corr="gaussian", optimizer="hj")),
        (["--trend", "linear", "--no-nugget", "--corr", "matern52"], dict(trend="linear", nugget=False, corr="matern52")),
    ],
    ids=["defaults", "js-gaussian-hj", "linear-interpolating-matern52"],
)
def test_fit_gives_the_cli_model_file_byte_for_byte(cli, datasets, tmp_path, flags, params):
    lhs = datasets / "comau_lhs.csv"
    cli("fit", lhs, *flags, "-o", tmp_path / "cli.json")
    py = rk.ErrorModel(**params).fit(lhs)
    py.save(tmp_path / "py.json")
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "cli.json").read_bytes()


def test_dataframe_and_arrays_give_the_same_model_as_the_file(datasets):
    lhs = datasets / "comau_lhs.csv"
    from_file = rk.ErrorModel(corr="gaussian").fit(lhs)
    table = rk.read_campaign(lhs, as_frame=False)
    q = np.column_stack([table[f"q{j}"] for j in range(1, 7)])
    d = np.column_stack([table[f"dir{j}"] for j in range(1, 7)])
    e = np.column_stack([table[a] for a in ("ex", "ey", "ez")])
    cov = {"time_s": table["time_s"], "temp_c": table["temp_c"]}
    from_arrays = rk.ErrorModel(corr="gaussian").fit(q, d, e, cov)
    assert from_arrays.to_json() == from_file.to_json()
    from_table = rk.ErrorModel(corr="gaussian").fit(table)
    assert from_table.to_json() == from_file.to_json()


def test_cli_model_predicts_here_as_cli_predict(cli, datasets, tmp_path):
    cli("fit", datasets / "comau_lhs.csv", "-o", tmp_path / "m.json")
    cli("predict", tmp_path / "m.json", datasets / "comau_verify.csv", "-o", tmp_path / "p.csv")
    model = rk.ErrorModel.load(tmp_path / "m.json")
    mean, std = model.predict(datasets / "comau_verify.csv", return_std=True)
    cmean, cstd = read_pred_csv(tmp_path / "p.csv")
    assert np.max(np.abs(mean - cmean)) <= TOL
    assert np.max(np.abs(std - cstd)) <= TOL
    # the mean-only path (no m × m factor) gives the same means
    assert np.max(np.abs(model.predict(datasets / "comau_verify.csv") - cmean)) <= TOL


def test_python_model_file_predicts_in_the_cli(cli, datasets, tmp_path):
    model = rk.ErrorModel(space="js", corr="gaussian").fit(datasets / "comau_lhs.csv")
    model.save(tmp_path / "py.json")
    cli("predict", tmp_path / "py.json", datasets / "comau_verify.csv", "-o", tmp_path / "p.csv")
    verify = rk.read_campaign(datasets / "comau_verify.csv", as_frame=False)
    q = np.column_stack([verify[f"q{j}"] for j in range(1, 7)])
    d = np.column_stack([verify[f"dir{j}"] for j in range(1, 7)])
    mean, std = model.predict(q, d, return_std=True)
    cmean, cstd = read_pred_csv(tmp_path / "p.csv")
    assert np.max(np.abs(mean - cmean)) <= TOL
    assert np.max(np.abs(std - cstd)) <= TOL


def test_cross_validation_equals_cli_cv(cli, datasets, tmp_path):
    lhs = datasets / "comau_lhs.csv"
    cli("cv", lhs, "--mode", "closed-form", "--folds", "10", "--json", tmp_path / "cv.json")
    ref = json.loads((tmp_path / "cv.json").read_text())
    res = rk.cross_validate(rk.ErrorModel(), lhs, mode="closed-form", folds=10)
    assert res["mode"] == ref["mode"] == "closed-form"
    assert list(res["fold"]) == ref["fold"]
    assert np.max(np.abs(res["residuals"] - np.asarray(ref["residuals"]))) <= TOL
    for key in ("rms_mm", "mean_3d_mm", "max_3d_mm"):
        assert np.allclose(res["summary"][key], ref["summary"][key], rtol=0, atol=TOL)


def test_refit_cross_validation_equals_cli_cv(cli, datasets, tmp_path):
    # refit CV on 80 rows written by NumPy (shortest round-trip floats)
    table = rk.read_campaign(datasets / "comau_lhs.csv", as_frame=False)
    names = [f"q{j}" for j in range(1, 7)] + [f"dir{j}" for j in range(1, 7)] + ["ex", "ey", "ez"]
    rows = np.column_stack([table[n] for n in names])[:80]
    path = tmp_path / "sub.csv"
    with open(path, "w") as f:
        f.write(",".join(names) + "\n")
        for r in rows:
            f.write(",".join(repr(float(v)) for v in r) + "\n")
    cli("cv", path, "--folds", "5", "--corr", "gaussian", "--json", tmp_path / "cv.json")
    ref = json.loads((tmp_path / "cv.json").read_text())
    res = rk.cross_validate(rk.ErrorModel(corr="gaussian"), path, folds=5)
    assert res["mode"] == "refit"
    assert np.max(np.abs(res["residuals"] - np.asarray(ref["residuals"]))) <= TOL


def test_compensation_equals_cli_compensate(cli, datasets, tmp_path):
    lhs, circle = datasets / "comau_lhs.csv", datasets / "comau_circle.csv"
    cli("fit", lhs, "--robot", "comau-nj220", "-o", tmp_path / "m.json")
    cli("compensate", "--model", tmp_path / "m.json", "--robot", "comau-nj220", circle,
        "--iterative", "-o", tmp_path / "c.csv")
    model = rk.ErrorModel(robot="comau-nj220").fit(lhs)
    model.save(tmp_path / "py.json")
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "m.json").read_bytes()
    out = rk.compensate(model, "comau-nj220", circle)
    ref = np.genfromtxt(tmp_path / "c.csv", delimiter=",", skip_header=1)
    assert np.max(np.abs(out["xyz"] - ref[:, 1:4])) <= TOL
    assert np.max(np.abs(out["rpy"] - ref[:, 4:7])) <= TOL


def test_diagnosis_equals_cli_diagnose(cli, datasets, tmp_path):
    step = datasets / "comau_tracker_step.csv"
    cli("diagnose", step, "--permutations", "199", "--json", tmp_path / "d.json",
        "--model-out", tmp_path / "m.json")
    ref = json.loads((tmp_path / "d.json").read_text())
    effects, improved, report = rk.diagnose(step, permutations=199, as_frame=False)
    improved.save(tmp_path / "py.json")
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "m.json").read_bytes()
    assert [e["label"] for e in effects] == [e["label"] for e in ref["effects"]]
    assert [e["accepted"] for e in effects] == [e["accepted"] for e in ref["effects"]]
    assert np.allclose([e["p_value"] for e in effects], [e["p_value"] for e in ref["effects"]], rtol=0, atol=TOL)
    assert np.allclose(report["after"]["cv_rmse_mm"], ref["after"]["cv_rmse_mm"], rtol=0, atol=TOL)


def test_tool_is_applied_by_the_library_as_in_the_cli(cli, datasets, tmp_path):
    """tool=(x, y, z) and --tool x,y,z both go through the library's
    Robot::with_tool_translation: the same model file."""
    lhs = datasets / "comau_lhs.csv"
    cli("fit", lhs, "--robot", "comau-nj220", "--tool", "1.5,-2,250", "--corr", "gaussian", "-o", tmp_path / "cli.json")
    py = rk.ErrorModel(robot="comau-nj220", tool=(1.5, -2, 250), corr="gaussian").fit(lhs)
    py.save(tmp_path / "py.json")
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "cli.json").read_bytes()
    default = rk.ErrorModel(robot="comau-nj220", corr="gaussian").fit(lhs)
    assert py.robot_ != default.robot_  # the tool is part of the robot recorded
    with pytest.raises(rk.RobokrigeError, match=r"tool \(NaN, 0, 250\): expected finite x, y, z in mm"):
        rk.ErrorModel(robot="comau-nj220", tool=(np.nan, 0, 250)).fit(lhs)


def test_compensation_with_a_physics_model_equals_cli_compensate(cli, datasets, tmp_path):
    """A lookup-table model of `robokrige physics identify` compensates in
    Python as `robokrige compensate --model` does, given as a PhysicsModel
    or as its file."""
    robot = "scara-rh3frh5515"
    cli("physics", "identify", datasets / "scara_indexing.csv", "--robot", robot, "-o", tmp_path / "phys.json")
    cli("simulate", "--robot", robot, "--kind", "verify", "--poses", "20", "--seed", "1",
        "--ranges", "-165:165,20:143,50:100,-90:90", "-o", tmp_path / "v.csv")
    cli("compensate", "--model", tmp_path / "phys.json", "--robot", robot, tmp_path / "v.csv",
        "-o", tmp_path / "c.csv", "--truth", tmp_path / "v.truth.json", "--json", tmp_path / "c.json")
    ref = np.genfromtxt(tmp_path / "c.csv", delimiter=",", names=True)
    report = json.loads((tmp_path / "c.json").read_text())
    phys = rk.PhysicsModel.load(tmp_path / "phys.json")
    assert phys.has_tables and phys.n_joints == 4 and "physics" in repr(phys).lower()
    for model in (phys, tmp_path / "phys.json"):
        out = rk.compensate(model, robot, tmp_path / "v.csv", iterative=False, truth=tmp_path / "v.truth.json")
        assert out["model"] == "physics" and out["stop"] == "single-step"
        xyz = np.column_stack([ref["x"], ref["y"], ref["z"]])
        assert np.max(np.abs(out["xyz"] - xyz)) <= TOL
        ev = out["evaluation"]["summary"]
        assert ev["after"]["mean_abs_mm"] == pytest.approx(report["after"]["mean_abs_mm"], abs=TOL)
        assert ev["after"]["mean_abs_mm"] < ev["before"]["mean_abs_mm"]
    # its predictions at the verification poses, from the library
    v = rk.read_campaign(tmp_path / "v.csv", as_frame=False)
    data = rk.as_data({k: v[k] for k in v if k.startswith(("q", "dir"))})
    assert phys.predict(data).shape == (20, 3)
    with pytest.raises(rk.RobokrigeError, match="robot"):
        rk.compensate(phys, "comau-nj220", tmp_path / "v.csv")


def test_plan_equals_cli_plan(cli, datasets, tmp_path):
    """rk.plan gives the command line's plan: the same moves (joints,
    directions, measure flags, sources) and summary."""
    lhs = datasets / "comau_lhs.csv"
    args = ["--robot", "comau-nj220", "--budget", "15", "--campaign", lhs, "--candidates", "400",
            "--region-points", "150", "--target-mm", "0.03"]
    cli("plan", *args, "-o", tmp_path / "plan.csv", "--json", tmp_path / "plan.json")
    ref = np.genfromtxt(tmp_path / "plan.csv", delimiter=",", names=True)
    summary = json.loads((tmp_path / "plan.json").read_text())
    p = rk.plan("comau-nj220", 15, campaign=lhs, candidates=400, region_points=150, target_mm=0.03,
                output=tmp_path / "py.csv")
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "plan.csv").read_bytes()
    assert np.max(np.abs(p.q - np.column_stack([ref[f"q{j}"] for j in range(1, 7)]))) <= TOL
    assert np.array_equal(p.dirs, np.column_stack([ref[f"dir{j}"] for j in range(1, 7)]))
    assert np.array_equal(p.measure, ref["measure"] == 1) and p.measure.sum() == 15
    assert np.array_equal(p.source[p.measure], ref["source"][p.measure].astype(np.int64))
    assert np.all(p.source[~p.measure] == -1)
    for key in ("source", "candidates", "chosen", "measure", "unrealised", "notes"):
        assert p.summary[key] == summary[key], key
    assert np.allclose(p.summary["imse_curve_mm2"], summary["imse_curve_mm2"], rtol=0, atol=TOL)
    f, g = p.summary["forecast"], summary["forecast"]
    assert np.allclose(f["mean_3d_mm"], g["mean_3d_mm"], rtol=0, atol=TOL)
    assert "target 0.03 mm" in p.summary["text"] and p.model is not None and p.model.n_rows_ == 300
