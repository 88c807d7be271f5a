//! A robot that is not a preset, from its robot file alone:
//! simulate → fit → cv → compensate with `--robot FILE`, and a model refused
//! for another robot or tool.

mod common;

use common::rk;
use robokrige::kinematics::{self, RobotFile};

const ABB: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/examples/robots/abb-irb2600.toml"
);

#[test]
fn a_datasheet_robot_goes_from_simulation_to_compensation_from_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let ok = |args: &[&str]| {
        let (c, out, err) = rk(args);
        assert_eq!(c, 0, "{args:?}: {err}");
        out
    };
    let out = ok(&[
        "simulate",
        "--robot",
        ABB,
        "--poses",
        "120",
        "--seed",
        "3",
        "-o",
        &p("c.csv"),
    ]);
    assert!(out.contains("rows: 120"), "{out}");
    ok(&[
        "simulate",
        "--robot",
        ABB,
        "--kind",
        "circle",
        "--seed",
        "3",
        "-o",
        &p("circle.csv"),
    ]);
    ok(&["fit", &p("c.csv"), "--robot", ABB, "-o", &p("m.json")]);
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("m.json")).unwrap()).unwrap();
    assert_eq!(model["robot"]["name"], "abb-irb2600-12-165");
    assert_eq!(model["robot"]["tool"]["xyz_mm"][2], 150.0);
    assert!(
        model["software"]
            .as_str()
            .unwrap()
            .starts_with("robokrige ")
    );
    ok(&["cv", &p("c.csv"), "--folds", "4", "--json", &p("cv.json")]);
    let cv: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("cv.json")).unwrap()).unwrap();
    let rmse = cv["summary"]["rms_mm"][0].as_f64().unwrap();
    assert!(rmse > 0.0 && rmse < 0.1, "CV RMSE x {rmse} mm");
    ok(&[
        "compensate",
        "--model",
        &p("m.json"),
        "--robot",
        ABB,
        &p("circle.csv"),
        "-o",
        &p("comp.csv"),
        "--iterative",
        "--truth",
        &p("circle.truth.json"),
        "--json",
        &p("comp.json"),
    ]);
    let comp: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("comp.json")).unwrap()).unwrap();
    let reduction = comp["evaluation"]["reduction_mean_abs_pct"]
        .as_f64()
        .unwrap();
    assert!(reduction > 80.0, "mean |δ| reduced by {reduction} %");

    // the same model, another robot or another tool: refused before any work
    let (c, _, err) = rk(&[
        "compensate",
        "--model",
        &p("m.json"),
        "--robot",
        "comau-nj220",
        &p("circle.csv"),
        "-o",
        &p("x.csv"),
    ]);
    assert_eq!(c, 1);
    assert!(
        err.contains("fitted for robot 'abb-irb2600-12-165'") && err.contains("comau-nj220"),
        "{err}"
    );
    let (c, _, err) = rk(&[
        "compensate",
        "--model",
        &p("m.json"),
        "--robot",
        ABB,
        "--tool",
        "0,0,100",
        &p("circle.csv"),
        "-o",
        &p("x.csv"),
    ]);
    assert_eq!(c, 1);
    assert!(err.contains("tools differ"), "{err}");
    assert!(!dir.path().join("x.csv").exists());
}

#[test]
fn a_robot_file_round_trips_and_its_digest_ignores_the_name() {
    let abb = kinematics::load_robot(ABB).unwrap();
    assert_eq!(abb.dof(), 6);
    assert_eq!(abb.home, vec![0.0, 15.0, -15.0, 0.0, 50.0, 0.0]);
    let text = RobotFile::of(&abb).to_toml().unwrap();
    let back = RobotFile::from_toml(&text, "back")
        .unwrap()
        .robot("back")
        .unwrap();
    assert_eq!(back, abb);
    let mut renamed = abb.clone();
    renamed.name = "another name".into();
    assert_eq!(
        kinematics::table_digest(&renamed),
        kinematics::table_digest(&abb)
    );
    let mut moved = abb.clone();
    moved.links[1].a_mm += 0.001;
    assert_ne!(
        kinematics::table_digest(&moved),
        kinematics::table_digest(&abb)
    );
    // JSON is the same format
    let json = serde_json::to_string(&RobotFile::of(&abb)).unwrap();
    assert_eq!(
        RobotFile::from_json(&json, "j")
            .unwrap()
            .robot("j")
            .unwrap(),
        abb
    );
}

#[test]
fn an_unknown_robot_names_the_presets_and_the_file_format() {
    let e = kinematics::load_robot("abb-irb").unwrap_err().to_string();
    assert!(e.contains("comau-nj220") && e.contains("robot file"), "{e}");
}
