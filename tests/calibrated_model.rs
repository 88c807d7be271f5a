//! The calibrated model: a kinematic calibration plus Kriging of what it
//! leaves, in one model file that every consumer reads — fitted, saved,
//! loaded, predicted, compensated (measured on the simulator's truth),
//! refitted per fold, diagnosed and written back as a robot file.

mod common;

use common::rk;
use robokrige::calibration::CalibrationOptions;
use robokrige::dataset::read_csv;
use robokrige::kinematics::preset;
use robokrige::kriging::{KrigingOptions, OptimizerKind};
use robokrige::model::ErrorModel;
use robokrige::params::ErrorModelParams;
use robokrige::space::Space;

fn ds(f: &str) -> String {
    format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"))
}

/// `robokrige fit DATA --robot comau-nj220` with quick options, writing
/// `out`, with `extra` arguments.
fn quick_fit(data: &str, out: &str, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        "fit",
        data,
        "--robot",
        "comau-nj220",
        "--optimizer",
        "hj",
        "--corr",
        "gaussian",
        "-o",
        out,
    ];
    args.extend_from_slice(extra);
    rk(&args)
}

/// [`quick_fit`] with `--json -`: the list `key` of its JSON report.
fn fit_list(data: &str, out: &str, extra: &[&str], key: &str) -> Vec<serde_json::Value> {
    let extra: Vec<&str> = ["--json", "-"].iter().chain(extra).copied().collect();
    let (c, out, err) = quick_fit(data, out, &extra);
    assert_eq!(c, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    v[key].as_array().unwrap().clone()
}

fn quick() -> KrigingOptions {
    KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(400)
        .starts(2)
}

#[test]
fn one_file_holds_the_calibration_and_predicts_their_sum() {
    let data = read_csv(ds("comau_lhs.csv").as_ref()).unwrap();
    let robot = preset("comau-nj220").unwrap();
    let params = ErrorModelParams::new()
        .space(Space::Ejs)
        .kriging(quick())
        .robot(robot.clone())
        .calibrate(Some(CalibrationOptions::default()));
    let model = params.clone().check().unwrap().fit(&data).unwrap();
    let cal = model.calibration().expect("a calibration");
    assert_eq!(model.version(), 4);
    // the calibration explains most of the simulated robot's geometric error
    let (before, after) = cal.rms_mm();
    assert!(after < 0.6 * before, "{}", cal.summary_line());
    let id = cal.identifiability();
    assert!(id.directions_seen > 10 && id.directions_seen < id.parameters_total);
    // the model predicts calibration + Kriging of its residual
    let q = &data.q[..5];
    let dir = &data.dir[..5];
    let sum = model.predict_mean(q, dir).unwrap();
    let kin = cal.predict(q, dir).unwrap();
    let plain = ErrorModel::from_json(
        &{
            let mut v: serde_json::Value = serde_json::from_str(&model.to_json().unwrap()).unwrap();
            v.as_object_mut().unwrap().remove("calibration");
            v["version"] = 3.into();
            v.to_string()
        },
        "<no calibration>",
    )
    .unwrap();
    let krig = plain.predict_mean(q, dir).unwrap();
    for k in 0..5 {
        for a in 0..3 {
            assert!((sum[k][a] - kin[k][a] - krig[k][a]).abs() < 1e-12);
        }
    }
    // the file round-trips, and loads back to the same predictions
    let text = model.to_json().unwrap();
    let back = ErrorModel::from_json(&text, "<memory>").unwrap();
    assert_eq!(back.predict_mean(q, dir).unwrap(), sum);
    assert_eq!(back.to_json().unwrap(), text);
    // a model without a calibration is still a version-3 file
    assert_eq!(plain.version(), 3);
    // a calibration whose parameters do not give its robot is refused
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["calibration"]["parameters"][2] = 3.0.into();
    let err = ErrorModel::from_json(&v.to_string(), "bad.json").unwrap_err();
    assert!(err.to_string().contains("identified robot"), "{err}");
    // a refit at fixed hyperparameters identifies the calibration anew
    let half = data.select(&(0..150).collect::<Vec<_>>());
    let refit = model.refit(&half).unwrap();
    let c2 = refit.calibration().unwrap();
    assert_eq!(c2.rows(), 150);
    assert_ne!(c2.parameters(), cal.parameters());
    // rules: a calibration needs the robot, and not with the kinematic trend
    let no_robot = ErrorModelParams::new().calibrate(Some(CalibrationOptions::default()));
    assert!(no_robot.check().unwrap_err().to_string().contains("robot"));
    let kin = params.trend(robokrige::params::TrendSpec::Kinematic(Box::new(robot)));
    assert!(kin.check().is_err());
}

/// `fit --robot` (calibrated by default) → `predict` → `compensate` on the
/// simulated robot's truth → `diagnose --robot --model-out` →
/// `robot calibrated`, through the binary.
#[test]
fn fit_predict_compensate_diagnose_from_one_calibrated_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let ds_lhs = ds("comau_lhs.csv");
    let fit = |out: &str, extra: &[&str]| quick_fit(&ds_lhs, &p(out), extra);
    let (c, out, err) = fit("cal.json", &[]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("calibration:"), "{out}");
    let (c, _, err) = fit("raw.json", &["--no-calibrate"]);
    assert_eq!(c, 0, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("cal.json")).unwrap())
            .unwrap();
    assert_eq!(v["version"], 4);
    let raw: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("raw.json")).unwrap())
            .unwrap();
    assert!(raw.get("calibration").is_none());
    // predict reads it
    let (c, _, err) = rk(&[
        "predict",
        &p("cal.json"),
        &ds("comau_verify.csv"),
        "-o",
        &p("pred.csv"),
    ]);
    assert_eq!(c, 0, "{err}");
    // compensation of the circle, measured on the simulated robot
    let compensate = |model: &str| {
        let json = format!("{model}.comp.json");
        let (c, _, err) = rk(&[
            "compensate",
            "--model",
            &p(model),
            "--robot",
            "comau-nj220",
            &ds("comau_circle.csv"),
            "-o",
            &p(&format!("{model}.csv")),
            "--iterative",
            "--truth",
            &ds("comau_circle.truth.json"),
            "--json",
            &p(&json),
        ]);
        assert_eq!(c, 0, "{err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join(&json)).unwrap())
                .unwrap();
        let (b, a) = (
            v["before"]["mean_abs_mm"].as_f64().unwrap(),
            v["after"]["mean_abs_mm"].as_f64().unwrap(),
        );
        1.0 - a / b
    };
    let (cal, raw) = (compensate("cal.json"), compensate("raw.json"));
    eprintln!("circle mean reduction: calibrated {cal:.3}, raw Kriging {raw:.3}");
    assert!(cal >= 0.85, "calibrated model: reduction {cal:.3}");
    assert!(cal >= raw - 0.02, "calibrated {cal:.3} vs raw {raw:.3}");
    // with a robot, diagnose works on the calibration's residual and writes
    // a calibrated model; --no-calibrate diagnoses the raw error
    for (flag, out, calibrated) in [
        (None, "diag.json", true),
        (Some("--no-calibrate"), "diag_raw.json", false),
    ] {
        let mut args = vec![
            "diagnose".to_string(),
            ds("comau_lhs.csv"),
            "--robot".into(),
            "comau-nj220".into(),
            "--method".into(),
            "js-hj".into(),
            "--max-effects".into(),
            "1".into(),
            "--model-out".into(),
            p(out),
        ];
        args.extend(flag.map(String::from));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (c, stdout, err) = rk(&args);
        assert_eq!(c, 0, "{err}");
        assert_eq!(stdout.contains("calibrated base:"), calibrated, "{stdout}");
        let d: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join(out)).unwrap()).unwrap();
        assert_eq!(
            d["calibration"]["parameters"].is_array(),
            calibrated,
            "{flag:?}: calibration in the model written"
        );
    }
    // the identified kinematics as a robot file, usable as --robot
    let (c, out, err) = rk(&[
        "robot",
        "calibrated",
        &p("cal.json"),
        "-o",
        &p("calibrated.toml"),
    ]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("directions seen"), "{out}");
    let (c, out, err) = rk(&["robot", "show", &p("calibrated.toml")]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("comau-nj220-calibrated"), "{out}");
    // a model without a calibration has no robot file to give
    let (c, _, err) = rk(&["robot", "calibrated", &p("raw.json"), "-o", &p("x.toml")]);
    assert_eq!(c, 1, "{err}");
    assert!(err.contains("no calibration"), "{err}");
}

#[test]
fn fit_finds_the_planted_gear_harmonic_and_robot_calibrated_says_it_is_not_in_the_table() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let data = ds("comau_harmonic.csv");
    let fit = |out: &str, extra: &[&str]| fit_list(&data, &p(out), extra, "joint_harmonics");
    // the 7.5° harmonic the campaign was simulated with, and nothing else
    let found = fit("h.json", &[]);
    assert_eq!(found.len(), 1, "{found:?}");
    let period = found[0]["period_deg"].as_f64().unwrap();
    assert!((period / 7.5 - 1.0).abs() < 0.02, "{period}");
    assert!(fit("g.json", &["--geometric"]).is_empty());
    let (c, out, err) = rk(&["robot", "calibrated", &p("h.json"), "-o", &p("h.toml")]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("1 joint harmonics"), "{out}");
    assert!(
        err.contains("joint harmonics stay in the model file"),
        "{err}"
    );
    let (_, _, err) = rk(&["robot", "calibrated", &p("g.json"), "-o", &p("g.toml")]);
    assert!(!err.contains("joint harmonics"), "{err}");
}

/// `fit --backlash` on a simulated COMAU campaign whose joints have play:
/// the joints it keeps are the simulator's, each half backlash near the
/// truth's; off by default; `robot calibrated` says the table leaves it
/// out.
#[test]
fn fit_with_backlash_finds_the_simulated_play_and_keeps_it_in_the_model_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let data = ds("comau_lhs.csv");
    let fit = |out: &str, extra: &[&str]| fit_list(&data, &p(out), extra, "backlash");
    assert!(fit("d.json", &[]).is_empty());
    let found = fit("b.json", &["--backlash"]);
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(ds("comau_lhs.truth.json")).unwrap())
            .unwrap();
    let planted = |j: usize| {
        truth["robot"]["deviation"][j - 1]["backlash_deg"]
            .as_f64()
            .unwrap()
    };
    let joints: Vec<usize> = found
        .iter()
        .map(|b| b["joint"].as_u64().unwrap() as usize)
        .collect();
    // the joints that move the TCP most (a wrist joint's play may hide
    // under the noise)
    for j in [1, 2, 3] {
        assert!(joints.contains(&j), "{found:?}");
    }
    for b in &found {
        let j = b["joint"].as_u64().unwrap() as usize;
        let half = b["half_deg"].as_f64().unwrap();
        assert!(
            (half / planted(j) - 1.0).abs() < 0.35,
            "q{j}: {half} against {}",
            planted(j)
        );
    }
    // a build before the backlash would ignore it: the file says so
    let head: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("b.json")).unwrap()).unwrap();
    assert_eq!(head["version"], robokrige::model::MODEL_VERSION);
    let head: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("d.json")).unwrap()).unwrap();
    assert_eq!(head["version"], robokrige::model::MODEL_VERSION_CALIBRATED);
    let (c, _, err) = rk(&["robot", "calibrated", &p("b.json"), "-o", &p("b.toml")]);
    assert_eq!(c, 0, "{err}");
    assert!(err.contains("backlash of"), "{err}");
    let (c, _, err) = rk(&["predict", &p("b.json"), &data, "-o", &p("b.csv")]);
    assert_eq!(c, 0, "{err}");
    let rows = std::fs::read_to_string(p("b.csv")).unwrap().lines().count();
    assert_eq!(rows, 301);
}

#[test]
fn a_calibration_on_a_few_poses_keeps_coordinates_for_its_noise_and_refuses_too_few() {
    let robot = preset("comau-nj220").unwrap();
    let data = read_csv(ds("comau_lhs.csv").as_ref()).unwrap();
    // 8 poses, 24 coordinates: a first fit on every direction interpolated
    // them (noise 0, every direction "seen")
    let cal = robokrige::calibration::calibrate(
        &data.clone().head(8),
        &robot,
        &CalibrationOptions::geometric(),
    )
    .unwrap();
    let id = cal.identifiability();
    assert!(id.noise_mm > 0.01, "noise {}", id.noise_mm);
    assert!(
        id.directions_seen <= 24 - robokrige::calibration::MIN_NOISE_DOF,
        "{} directions seen on 24 coordinates",
        id.directions_seen
    );
    // 3 poses leave nothing for the noise: refused, naming the ways out
    let err = robokrige::calibration::calibrate(
        &data.clone().head(3),
        &robot,
        &CalibrationOptions::geometric(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("--calibration-noise") && err.contains("--no-calibrate"),
        "{err}"
    );
    // with the noise given, they are calibrated along what they see
    let given = CalibrationOptions::new(false, Some(0.05));
    assert!(robokrige::calibration::calibrate(&data.head(3), &robot, &given).is_ok());
}

#[test]
fn a_calibration_that_sees_no_direction_is_written_and_loads_back() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.json");
    let out = out.to_str().unwrap();
    let (c, text, err) = quick_fit(&ds("comau_lhs.csv"), out, &["--calibration-noise", "1000"]);
    assert_eq!(c, 0, "{err}");
    assert!(text.contains("0 of 39 directions"), "{text}");
    let m = ErrorModel::load(out.as_ref()).unwrap();
    let id = m.calibration().unwrap().identifiability();
    assert_eq!(id.directions_seen, 0);
    assert!(id.condition_number.is_infinite());
}
