//! The binary: exit codes 0 / 1 / 2, one-line errors, files written.

use std::process::Command;

fn rk(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_robokrige"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn simulate_fit_predict_round_trip() {
    let dir = std::env::temp_dir().join(format!("robokrige-cli-{}", std::process::id()));
    let p = |f: &str| dir.join(f).display().to_string();
    let (c, out, _) = rk(&[
        "simulate",
        "--poses",
        "40",
        "--seed",
        "3",
        "-o",
        &p("c.csv"),
    ]);
    assert_eq!(c, 0);
    assert!(out.contains("rows: 40"), "{out}");
    assert!(dir.join("c.truth.json").exists());
    let (c, _, err) = rk(&["fit", &p("c.csv"), "--optimizer", "hj", "-o", &p("m.json")]);
    assert_eq!(c, 0, "{err}");
    let (c, out, err) = rk(&["predict", &p("m.json"), &p("c.csv"), "-o", &p("pred.csv")]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("40 poses"), "{out}");
    let header = std::fs::read_to_string(dir.join("pred.csv")).unwrap();
    assert!(header.starts_with("id,q1,"), "{header}");
    assert!(
        header
            .lines()
            .next()
            .unwrap()
            .contains("pred_ex,pred_ey,pred_ez,std_ex,std_ey,std_ez")
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bad_data_exits_1_with_one_line_bad_usage_exits_2() {
    let (c, _, err) = rk(&["fit", "/nonexistent/data.csv", "-o", "/tmp/x.json"]);
    assert_eq!(c, 1);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("/nonexistent/data.csv"));
    let (c, _, err) = rk(&["simulate", "--effect", "warp-drive", "-o", "/tmp/x.csv"]);
    assert_eq!(c, 1);
    assert!(err.contains("unknown effect 'warp-drive'"), "{err}");
    let (c, _, _) = rk(&["fit", "--trend", "cubic", "x.csv", "-o", "m.json"]);
    assert_eq!(c, 2);
    let (c, out, _) = rk(&["simulate", "--help"]);
    assert_eq!(c, 0);
    assert!(out.contains("Examples:"));
}
