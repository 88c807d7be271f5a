//! The bad-input catalogue: every entry goes through the `robokrige` binary
//! and asserts its outcome — a clear one-line error (exit 1, naming the file,
//! line and column where there is one) or a documented graceful result
//! (exit 0, with what the user is told). Bad usage exits 2.

use std::path::{Path, PathBuf};
mod common;

use common::rk;

thread_local! {
    /// This test's files, removed when it ends.
    static DIR: common::Scratch = common::Scratch::new("robokrige-bad");
    /// The compensation entries' JS model, fitted once by each test that
    /// needs it.
    static JS_MODEL: String = fit_js_model();
}

fn dir() -> PathBuf {
    DIR.with(|d| d.path().to_path_buf())
}

fn write(name: &str, text: &str) -> String {
    let p = dir().join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

fn shipped(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("datasets")
        .join(name)
        .display()
        .to_string()
}

/// 24 rows of a smooth synthetic campaign (degrees), with a header.
fn campaign(rows: usize, f: impl Fn(usize) -> String) -> String {
    let mut s = String::from("q1,q2,q3,q4,q5,q6,ex,ey,ez\n");
    for i in 0..rows {
        s += &f(i);
        s.push('\n');
    }
    s
}

fn row(i: usize) -> String {
    common::synthetic_row(i)
}

/// Exit 1 with `needle` in the one-line error.
fn fails(args: &[&str], needle: &str) {
    let (c, _, err) = rk(args);
    assert_eq!(c, 1, "{args:?}: {err}");
    // warnings may come first; the error itself is one line, the last
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(errors.len(), 1, "one error line: {err}");
    assert!(
        err.trim_end()
            .lines()
            .last()
            .unwrap()
            .starts_with("error: "),
        "{err}"
    );
    assert!(
        err.contains(needle),
        "{args:?}: expected '{needle}' in: {err}"
    );
}

/// Exit 0; returns (stdout, stderr).
fn succeeds(args: &[&str]) -> (String, String) {
    let (c, out, err) = rk(args);
    assert_eq!(c, 0, "{args:?}: {err}");
    (out, err)
}

/// A saved model has no NaN/∞ (JSON writes them as null); the only null
/// allowed is the unset option `min_jitter`.
fn no_non_finite(path: &str) -> bool {
    let text = std::fs::read_to_string(path).unwrap();
    !text.replace("\"min_jitter\":null", "").contains("null")
}

/// A JS model of the shipped campaign, for the compensation entries.
fn js_model() -> String {
    JS_MODEL.with(|m| m.clone())
}

fn fit_js_model() -> String {
    let m = model_out("js_shared.json");
    succeeds(&[
        "fit",
        &shipped("comau_lhs.csv"),
        "--space",
        "js",
        "--optimizer",
        "hj",
        "-o",
        &m,
    ]);
    m
}

fn model_out(name: &str) -> String {
    dir().join(name).display().to_string()
}

#[test]
fn c01_empty_file() {
    fails(
        &["fit", &write("empty.csv", ""), "-o", &model_out("m.json")],
        "empty",
    );
}

#[test]
fn c02_header_only() {
    let f = write("header.csv", "q1,q2,q3,q4,q5,q6,ex,ey,ez\n");
    fails(&["fit", &f, "-o", &model_out("m.json")], "no data rows");
}

#[test]
fn c03_missing_joint_columns() {
    let f = write("noq.csv", "a,b,ex,ey,ez\n1,2,0.1,0.2,0.3\n");
    fails(&["fit", &f, "-o", &model_out("m.json")], "q1");
}

#[test]
fn c04_missing_error_columns_for_fit() {
    let f = write("noe.csv", "q1,q2\n10,20\n30,40\n50,60\n");
    fails(&["fit", &f, "-o", &model_out("m.json")], "ex");
}

#[test]
fn c05_non_numeric_cell_names_line_and_column() {
    let text = campaign(10, row);
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<&str> = lines[3].split(',').collect();
    cells[1] = "abc";
    lines[3] = cells.join(",");
    let f = write("nonnum.csv", &(lines.join("\n") + "\n"));
    fails(
        &["fit", &f, "-o", &model_out("m.json")],
        "nonnum.csv:4: column 'q2'",
    );
}

#[test]
fn c06_nan_and_inf() {
    for (name, bad) in [("nan.csv", "NaN"), ("inf.csv", "inf")] {
        let mut lines: Vec<String> = campaign(10, row).lines().map(String::from).collect();
        let mut cells: Vec<String> = lines[5].split(',').map(String::from).collect();
        cells[7] = bad.into();
        lines[5] = cells.join(",");
        let f = write(name, &(lines.join("\n") + "\n"));
        fails(&["fit", &f, "-o", &model_out("m.json")], ":6: column 'ey'");
    }
}

#[test]
fn c07_ragged_row() {
    let mut text = campaign(10, row);
    text.push_str("1,2,3\n");
    let f = write("ragged.csv", &text);
    fails(&["fit", &f, "-o", &model_out("m.json")], ":12");
}

#[test]
fn c08_duplicate_header() {
    let f = write("dup.csv", "q1,q1,ex,ey,ez\n1,2,0.1,0.2,0.3\n");
    fails(
        &["fit", &f, "-o", &model_out("m.json")],
        "dup.csv:1: column 'q1': column name appears twice",
    );
}

#[test]
fn c09_direction_not_plus_minus_one() {
    let f = write(
        "dir.csv",
        "q1,q2,dir1,dir2,ex,ey,ez\n1,2,1,0.5,0.1,0.2,0.3\n2,3,1,1,0.1,0.2,0.3\n4,5,-1,1,0.1,0.2,0.3\n",
    );
    fails(&["fit", &f, "-o", &model_out("m.json")], "column 'dir2'");
}

#[test]
fn c10_radians_are_detected_and_warned_about() {
    let text = campaign(24, |i| {
        let r = row(i);
        let mut c: Vec<String> = r.split(',').map(String::from).collect();
        for v in c.iter_mut().take(6) {
            *v = format!("{:.5}", v.parse::<f64>().unwrap().to_radians());
        }
        c.join(",")
    });
    let f = write("rad.csv", &text);
    let (_, err) = succeeds(&["fit", &f, "--optimizer", "hj", "-o", &model_out("rad.json")]);
    assert!(err.contains("warning:") && err.contains("radians"), "{err}");
    // degrees do not warn
    let f = write("deg.csv", &campaign(24, row));
    let (_, err) = succeeds(&["fit", &f, "--optimizer", "hj", "-o", &model_out("deg.json")]);
    assert!(!err.contains("radians"), "{err}");
}

#[test]
fn c11_duplicate_poses_still_fit() {
    // every pose twice with different measurements: R is singular; jitter
    // makes it factorisable and the model is saved with finite numbers
    let text = campaign(24, |i| {
        let mut cells: Vec<String> = row(i / 2).split(',').map(String::from).collect();
        if i % 2 == 1 {
            cells[8] = "0.5".into(); // same pose, another measurement
        }
        cells.join(",")
    });
    let f = write("dupposes.csv", &text);
    let m = model_out("dup.json");
    let (_, err) = succeeds(&["fit", &f, "--optimizer", "hj", "-o", &m]);
    assert!(
        err.contains("12 pose(s) repeat an earlier pose exactly"),
        "{err}"
    );
    assert!(no_non_finite(&m));
    succeeds(&["predict", &m, &f, "-o", &model_out("dup_pred.csv")]);
}

#[test]
fn c12_constant_response_fits_and_predicts_the_constant() {
    let text = campaign(20, |i| {
        let r = row(i);
        let c: Vec<&str> = r.split(',').take(6).collect();
        format!("{},0.1,0.2,0.3", c.join(","))
    });
    let f = write("const.csv", &text);
    let m = model_out("const.json");
    succeeds(&["fit", &f, "-o", &m]);
    assert!(no_non_finite(&m), "a saved model has only finite numbers");
    let (out, _) = succeeds(&["predict", &m, &f, "-o", &model_out("const_pred.csv")]);
    assert!(
        out.contains("after subtracting the prediction 0.0000 mm"),
        "{out}"
    );
}

#[test]
fn c13_fewer_rows_than_trend_terms() {
    let f = write("few.csv", &campaign(20, row));
    fails(
        &[
            "fit",
            &f,
            "--trend",
            "quadratic",
            "-o",
            &model_out("m.json"),
        ],
        "need more than 20 rows",
    );
}

#[test]
fn c14_more_folds_than_rows() {
    let f = write("k.csv", &campaign(12, row));
    fails(&["cv", &f, "--folds", "50"], "K-fold needs 2 ≤ K ≤ rows");
}

#[test]
fn c15_model_of_another_format_or_version() {
    let f = write(
        "v2.json",
        r#"{"format":"robokrige-error-model","version":99}"#,
    );
    fails(
        &[
            "predict",
            &f,
            &shipped("comau_verify.csv"),
            "-o",
            &model_out("p.csv"),
        ],
        "version",
    );
    let g = write("other.json", r#"{"format":"something-else","version":1}"#);
    fails(
        &[
            "predict",
            &g,
            &shipped("comau_verify.csv"),
            "-o",
            &model_out("p.csv"),
        ],
        "not a robokrige error model",
    );
    let h = write("garbage.json", "{ not json");
    fails(
        &[
            "predict",
            &h,
            &shipped("comau_verify.csv"),
            "-o",
            &model_out("p.csv"),
        ],
        "garbage.json",
    );
}

#[test]
fn c16_model_for_another_joint_count() {
    let m = model_out("six.json");
    succeeds(&[
        "fit",
        &write("six.csv", &campaign(24, row)),
        "--optimizer",
        "hj",
        "-o",
        &m,
    ]);
    fails(
        &[
            "predict",
            &m,
            &shipped("scara_indexing.csv"),
            "-o",
            &model_out("p.csv"),
        ],
        "has 4 joints but the model was fitted on 6",
    );
}

#[test]
fn c17_unreachable_trajectory_points_are_listed() {
    let m = js_model();
    let t = write(
        "far.csv",
        "x,y,z,roll_deg,pitch_deg,yaw_deg\n1890,0,1024,180,-55,0\n9000,0,0,180,-55,0\n1890,10,1024,180,-55,0\n",
    );
    fails(
        &[
            "compensate",
            "--model",
            &m,
            "--robot",
            "comau-nj220",
            &t,
            "-o",
            &model_out("c.csv"),
        ],
        "unreachable (0-based indices 1)",
    );
}

#[test]
fn c18_single_point_trajectory_is_compensated() {
    let m = js_model();
    let t = write(
        "one.csv",
        "x,y,z,roll_deg,pitch_deg,yaw_deg\n1890,0,1024,180,-55,0\n",
    );
    let (out, _) = succeeds(&[
        "compensate",
        "--model",
        &m,
        "--robot",
        "comau-nj220",
        &t,
        "-o",
        &model_out("one_c.csv"),
        "--iterative",
    ]);
    assert!(out.contains("1 points"), "{out}");
}

#[test]
fn c19_covariate_with_missing_values_is_carried_and_skipped_by_diagnose() {
    let mut text = String::from("q1,q2,q3,q4,q5,q6,ex,ey,ez,temp_c\n");
    for i in 0..40 {
        let t = if i % 7 == 3 {
            String::new()
        } else {
            format!("{:.2}", 20.0 + i as f64 * 0.01)
        };
        text += &format!("{},{t}\n", row(i));
    }
    let f = write("missing_cov.csv", &text);
    succeeds(&["fit", &f, "--optimizer", "hj", "-o", &model_out("mc.json")]);
    let j = model_out("mc_diag.json");
    succeeds(&[
        "diagnose",
        &f,
        "--folds",
        "4",
        "--permutations",
        "99",
        "--max-effects",
        "1",
        "--json",
        &j,
    ]);
    let v = std::fs::read_to_string(&j).unwrap();
    assert!(
        !v.contains("\"temp_c\""),
        "a column with missing values is not a candidate"
    );
}

#[test]
fn c20_unknown_robot_and_unknown_method() {
    let f = shipped("comau_circle.csv");
    fails(
        &[
            "compensate",
            "--model",
            "x.json",
            "--robot",
            "abb-irb",
            &f,
            "-o",
            &model_out("c.csv"),
        ],
        "unknown robot 'abb-irb'",
    );
    fails(
        &[
            "fit",
            &shipped("comau_lhs.csv"),
            "--method",
            "ejs-xx",
            "-o",
            &model_out("m.json"),
        ],
        "unknown method 'ejs-xx'",
    );
}

#[test]
fn c21_bad_usage_exits_2() {
    let (c, _, err) = rk(&["fit", "--no-such-flag"]);
    assert_eq!(c, 2, "{err}");
    let (c, _, _) = rk(&["no-such-command"]);
    assert_eq!(c, 2);
}

#[test]
fn c22_trajectory_with_a_bad_cell() {
    let t = write("badtraj.csv", "x,y,z\n1890,0,1024\n1890,zz,1024\n");
    let m = js_model();
    fails(
        &[
            "compensate",
            "--model",
            &m,
            "--robot",
            "comau-nj220",
            &t,
            "-o",
            &model_out("c.csv"),
        ],
        "badtraj.csv:3: column 'y'",
    );
}

#[test]
fn c23_missing_file() {
    fails(
        &["fit", "/no/such/file.csv", "-o", &model_out("m.json")],
        "/no/such/file.csv",
    );
}

#[test]
fn c24_same_command_twice_gives_byte_identical_json() {
    // model files are byte-identical; reports differ only in wall-clock `seconds`
    let f = shipped("comau_lhs.csv");
    let (a, b) = (model_out("det_a.json"), model_out("det_b.json"));
    succeeds(&["fit", &f, "--optimizer", "hj", "-o", &a]);
    succeeds(&["fit", &f, "--optimizer", "hj", "-o", &b]);
    let (ta, tb) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert!(ta == tb, "model files differ");
    // reports: identical once the wall-clock `seconds` fields are removed
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.remove("seconds");
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let load = |p: &str| {
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
        strip(&mut v);
        v.to_string()
    };
    let (ja, jb) = (model_out("det_a.cv.json"), model_out("det_b.cv.json"));
    for j in [&ja, &jb] {
        succeeds(&[
            "cv",
            &f,
            "--mode",
            "closed-form",
            "--space",
            "js",
            "--optimizer",
            "hj",
            "--json",
            j,
        ]);
    }
    assert_eq!(load(&ja), load(&jb));
    let d = write("det.csv", &campaign(60, row));
    let (da, db) = (model_out("det_a.diag.json"), model_out("det_b.diag.json"));
    for j in [&da, &db] {
        succeeds(&[
            "diagnose",
            &d,
            "--folds",
            "4",
            "--permutations",
            "99",
            "--json",
            j,
        ]);
    }
    assert_eq!(load(&da), load(&db));
}

/// A failure in one output keeps its cause's variant under the axis
/// (errors keep their variant through the layers).
#[test]
fn a_per_axis_failure_keeps_its_cause() {
    use robokrige::Error;
    use robokrige::dataset::Dataset;
    use robokrige::kriging::{Correlation, KrigingOptions, OptimizerKind};
    use robokrige::space::Space;
    // a warm start of the wrong length fails in every output's fit
    let q: Vec<Vec<f64>> = (0..12)
        .map(|i| vec![i as f64, (i * 7 % 5) as f64])
        .collect();
    let mut d = Dataset::from_poses("t", q, None).unwrap();
    d.errors = Some((0..12).map(|i| [i as f64 * 0.01, 0.0, 0.0]).collect());
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .corr(Correlation::Gaussian);
    let e = robokrige::params::ErrorModelParams::new()
        .space(Space::Ejs)
        .kriging(opts)
        .hyper(robokrige::params::HyperSpec::Warm(vec![
            robokrige::kriging::Hyperparameters::new(vec![1.0; 1], 0.0);
            3
        ]))
        .check()
        .and_then(|p| p.fit(&d))
        .unwrap_err();
    match &e {
        Error::Axis { axis, source } => {
            assert_eq!(*axis, "ex");
            assert!(!matches!(**source, Error::Axis { .. }), "{e}");
        }
        other => panic!("expected an Axis error, got {other:?}"),
    }
    assert!(e.to_string().starts_with("output ex: "), "{e}");
}
