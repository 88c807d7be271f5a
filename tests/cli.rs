//! The binary: exit codes 0 / 1 / 2, one-line errors, files written.

mod common;

use common::rk;

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

#[test]
fn compensate_and_evaluate_report_before_and_after() {
    let dir = std::env::temp_dir().join(format!("robokrige-cli-comp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |f: &str| dir.join(f).display().to_string();
    let ds = |f: &str| format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"));
    let (c, _, err) = rk(&[
        "fit",
        &ds("comau_lhs.csv"),
        "--optimizer",
        "hj",
        "-o",
        &p("m.json"),
    ]);
    assert_eq!(c, 0, "{err}");
    let (c, out, err) = rk(&[
        "compensate",
        "--model",
        &p("m.json"),
        "--robot",
        "comau-nj220",
        &ds("comau_circle.csv"),
        "-o",
        &p("comp.csv"),
        "--iterative",
        "--truth",
        &ds("comau_circle.truth.json"),
        "--json",
        &p("comp.json"),
        "--plot",
        &p("comp.svg"),
    ]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("reduction"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("comp.json")).unwrap()).unwrap();
    let (b, a) = (&v["before"], &v["after"]);
    for key in ["mean_abs_mm", "max_abs_mm", "std_abs_mm"] {
        assert!(
            b[key].as_f64().unwrap() > a[key].as_f64().unwrap(),
            "{key}: {v}"
        );
    }
    assert_eq!(a["mean_mm"].as_array().unwrap().len(), 3);
    assert!(v["iterations"].as_array().unwrap().len() >= 2);
    assert!(
        std::fs::read_to_string(dir.join("comp.svg"))
            .unwrap()
            .contains("<svg")
    );
    // the same commands through `evaluate`
    let (c, _, err) = rk(&[
        "evaluate",
        "--truth",
        &ds("comau_circle.truth.json"),
        &ds("comau_circle.csv"),
        &p("comp.csv"),
        "--json",
        &p("eval.json"),
    ]);
    assert_eq!(c, 0, "{err}");
    let e: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("eval.json")).unwrap()).unwrap();
    // same noise seed; the commands went through a CSV (round-off only)
    for run in ["before", "after"] {
        for key in ["mean_abs_mm", "max_abs_mm", "std_abs_mm"] {
            let (x, y) = (e[run][key].as_f64().unwrap(), v[run][key].as_f64().unwrap());
            assert!((x - y).abs() < 1e-9, "{run}.{key}: {x} vs {y}");
        }
    }
    // a plot without measurements to draw, and a truth for another robot
    let (c, _, err) = rk(&[
        "compensate",
        "--model",
        &p("m.json"),
        "--robot",
        "comau-nj220",
        &ds("comau_circle.csv"),
        "-o",
        &p("x.csv"),
        "--plot",
        &p("x.svg"),
    ]);
    assert_eq!(c, 2, "{err}");
    assert!(err.contains("--truth <TRUTH>"), "{err}");
    assert!(!dir.join("x.csv").exists(), "refused before any work");
    let (c, _, err) = rk(&[
        "evaluate",
        "--robot",
        "ur10",
        "--truth",
        &ds("comau_circle.truth.json"),
        &ds("comau_circle.csv"),
        &p("comp.csv"),
    ]);
    assert_eq!(c, 1);
    assert!(err.contains("not 'ur10'"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `compensate --format`: the commands' joints as a robot program, read
/// back (URScript in radians against the joint CSV in degrees); a KRL file
/// whose name cannot be its program's is refused before any work.
#[test]
fn compensate_writes_the_commands_as_a_robot_program() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let ds = |f: &str| format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"));
    let (c, _, err) = rk(&[
        "fit",
        &ds("comau_lhs.csv"),
        "--optimizer",
        "hj",
        "-o",
        &p("m.json"),
    ]);
    assert_eq!(c, 0, "{err}");
    let comp = |out: &str, format: &str| {
        rk(&[
            "compensate",
            "--model",
            &p("m.json"),
            "--robot",
            "comau-nj220",
            &ds("comau_circle.csv"),
            "-o",
            &p(out),
            "--format",
            format,
        ])
    };
    let (c, out, err) = comp("circle.script", "urscript");
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("circle.script"), "{out}");
    let script = std::fs::read_to_string(dir.path().join("circle.script")).unwrap();
    let lines: Vec<&str> = script.lines().map(str::trim).collect();
    assert_eq!(lines[0], "def circle():");
    assert_eq!(*lines.last().unwrap(), "end");
    let moves: Vec<Vec<f64>> = lines
        .iter()
        .filter_map(|l| l.strip_prefix("movej([")?.split_once(']'))
        .map(|(list, _)| list.split(", ").map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(moves.len(), 72, "one move per point of the circle");
    assert!(moves.iter().all(|q| q.len() == 6));
    assert_eq!(lines.iter().filter(|l| **l == "# via (path)").count(), 72);
    assert!(!script.contains("sleep("), "a path has no measured poses");
    let (c, _, err) = comp("circle_joints.csv", "csv");
    assert_eq!(c, 0, "{err}");
    let csv = std::fs::read_to_string(dir.path().join("circle_joints.csv")).unwrap();
    let mut rows = csv.lines();
    assert_eq!(rows.next().unwrap(), "id,q1,q2,q3,q4,q5,q6,measure,label");
    for (k, (row, rad)) in rows.zip(&moves).enumerate() {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(
            (cells[0], cells[7], cells[8]),
            (k.to_string().as_str(), "0", "path")
        );
        for (deg, r) in cells[1..7].iter().zip(rad) {
            let d: f64 = deg.parse().unwrap();
            assert!(
                (d.to_radians() - r).abs() < 1e-9,
                "row {k}: {d} deg vs {r} rad"
            );
        }
    }
    let (c, _, err) = comp("circle-comp.src", "krl");
    assert_eq!(c, 1);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("a KRL program is called as its file"), "{err}");
    assert!(!dir.path().join("circle-comp.src").exists());
    let (c, _, err) = comp("circle.gcode", "gcode");
    assert_eq!(c, 2, "{err}");
}

#[test]
fn diagnose_writes_json_report_and_plots() {
    let dir = std::env::temp_dir().join(format!("robokrige-cli-diag-{}", std::process::id()));
    let p = |f: &str| dir.join(f).display().to_string();
    let (c, _, err) = rk(&[
        "simulate",
        "--poses",
        "120",
        "--seed",
        "6",
        "--effect",
        "tracker-step:row=60,dx=0.2,dy=-0.2,dz=0.2",
        "-o",
        &p("c.csv"),
    ]);
    assert_eq!(c, 0, "{err}");
    let (c, out, err) = rk(&[
        "diagnose",
        &p("c.csv"),
        "--folds",
        "5",
        "--permutations",
        "199",
        "--max-effects",
        "1",
        "--json",
        &p("d.json"),
        "--report",
        &p("d.md"),
        "--plots",
        &p("plots"),
    ]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("ADDED"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("d.json")).unwrap()).unwrap();
    assert_eq!(v["before"]["cv_rmse_mm"].as_array().unwrap().len(), 3);
    assert_eq!(v["after"]["cv_rmse_mm"].as_array().unwrap().len(), 3);
    let top = &v["effects"][0];
    assert_eq!(top["kind"], "order");
    assert_eq!(top["source"], serde_json::json!(["row"]));
    assert_eq!(top["accepted"], true);
    for key in ["params", "score", "p_value"] {
        assert!(!top[key].is_null(), "{key} missing: {top}");
    }
    let report = std::fs::read_to_string(dir.join("d.md")).unwrap();
    assert!(report.contains("**added**"), "{report}");
    assert!(dir.join("plots/effect1_order.svg").exists());
    let (c, _, err) = rk(&["diagnose", &p("c.csv"), "--method", "ejs-ga"]);
    assert_eq!(c, 1);
    assert!(err.contains("js-hj, ejs-hj or ejs-gps"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn physics_identify_then_compensate_with_the_physics_model() {
    let dir = std::env::temp_dir().join(format!("robokrige-cli-phys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |f: &str| dir.join(f).display().to_string();
    let ds = |f: &str| format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"));
    let (c, out, err) = rk(&[
        "physics",
        "identify",
        &ds("scara_indexing.csv"),
        "--robot",
        "scara-rh3frh5515",
        "-o",
        &p("phys.json"),
        "--dh-output",
        &p("dh.json"),
        "--truth",
        &ds("scara_indexing.truth.json"),
        "--json",
        &p("id.json"),
    ]);
    assert_eq!(c, 0, "{err}");
    assert!(
        out.contains("ΔL1") && out.contains("identified vs simulator truth"),
        "{out}"
    );
    assert!(!err.contains("repeat an earlier pose"), "{err}");
    // random poses of the same true robot (seed 1), elbow bent (|q2| > 15°)
    let (c, _, err) = rk(&[
        "simulate",
        "--robot",
        "scara-rh3frh5515",
        "--kind",
        "verify",
        "--poses",
        "20",
        "--seed",
        "1",
        "--ranges",
        "-165:165,20:143,50:100,-90:90",
        "-o",
        &p("v.csv"),
    ]);
    assert_eq!(c, 0, "{err}");
    let mut after = Vec::new();
    for m in ["phys.json", "dh.json"] {
        let (c, out, err) = rk(&[
            "compensate",
            "--model",
            &p(m),
            "--robot",
            "scara-rh3frh5515",
            &p("v.csv"),
            "-o",
            &p("comp.csv"),
            "--truth",
            &p("v.truth.json"),
            "--json",
            &p("comp.json"),
        ]);
        assert_eq!(c, 0, "{err}");
        assert!(out.contains("physics model"), "{out}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("comp.json")).unwrap()).unwrap();
        let (b, a) = (
            v["before"]["mean_abs_mm"].as_f64().unwrap(),
            v["after"]["mean_abs_mm"].as_f64().unwrap(),
        );
        assert!(a < b, "{m}: {b} -> {a}");
        assert_eq!(v["space"], "physics");
        after.push(a);
    }
    assert!(
        after[0] < after[1],
        "D-H + APD {} vs D-H {}",
        after[0],
        after[1]
    );
    std::fs::remove_dir_all(dir).ok();
}

/// One rule, one message: a refused combination of model options gives the
/// library's message (`methods::params_with`), which Python prints too
/// (python/tests/test_bad_input.py compares the two front ends).
#[test]
fn refused_combinations_give_the_library_message() {
    use robokrige::methods::{Method, Overrides, params_with};
    use robokrige::space::Space;
    let lhs = format!("{}/datasets/comau_lhs.csv", env!("CARGO_MANIFEST_DIR"));
    let data = robokrige::dataset::read_csv(lhs.as_ref()).unwrap();
    let robot = robokrige::kinematics::load_robot("comau-nj220").unwrap();
    let cases: [(&[&str], Option<Method>, Overrides); 4] = [
        (
            &["--method", "ejs-gps", "--space", "js", "--starts", "2"],
            Some(Method::EjsGps),
            Overrides::new().space(Space::Js).starts(2),
        ),
        (
            &["--optimizer", "hj", "--starts", "3"],
            None,
            Overrides::new()
                .optimizer(robokrige::kriging::OptimizerKind::HookeJeeves)
                .starts(3),
        ),
        (&["--kinematic"], None, Overrides::new().kinematic(true)),
        (
            &["--method", "js-hj", "--robot", "comau-nj220", "--kinematic"],
            Some(Method::JsHj),
            Overrides::new().robot(robot).kinematic(true),
        ),
    ];
    let out = std::env::temp_dir().join(format!("rk-rules-{}.json", std::process::id()));
    for (flags, method, overrides) in cases {
        let expected = params_with(method, &overrides, &data)
            .unwrap_err()
            .to_string();
        let mut args = vec!["fit", lhs.as_str(), "-o", out.to_str().unwrap()];
        args.extend_from_slice(flags);
        let (c, _, err) = rk(&args);
        assert_eq!(c, 1, "{flags:?}: {err}");
        assert_eq!(err.trim(), format!("error: {expected}"), "{flags:?}");
    }
    assert!(!out.exists());
}

#[test]
fn kinematic_and_periodic_options_are_checked() {
    let ds = |f: &str| format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"));
    let out = std::env::temp_dir().join(format!("rk-kin-{}.json", std::process::id()));
    let o = out.display().to_string();
    let (c, _, err) = rk(&["fit", &ds("comau_lhs.csv"), "--kinematic", "-o", &o]);
    assert_eq!(c, 1, "{err}");
    assert!(err.contains("kinematic needs robot"), "{err}");
    let (c, _, err) = rk(&["fit", &ds("comau_lhs.csv"), "--periodic", "9", "-o", &o]);
    assert_eq!(c, 1, "{err}");
    assert!(err.contains("joint numbers 1..6"), "{err}");
    let (c, _, err) = rk(&[
        "fit",
        &ds("comau_lhs.csv"),
        "--robot",
        "ur10",
        "--tool",
        "1,2",
        "--kinematic",
        "-o",
        &o,
    ]);
    assert_eq!(c, 1, "{err}");
    assert!(err.contains("expected x,y,z"), "{err}");
    // a working kinematic fit on the COMAU campaign, quick optimiser
    let (c, stdout, err) = rk(&[
        "fit",
        &ds("comau_lhs.csv"),
        "--robot",
        "comau-nj220",
        "--kinematic",
        "--optimizer",
        "hj",
        "--space",
        "js",
        "-o",
        &o,
    ]);
    assert_eq!(c, 0, "{err}");
    assert!(stdout.contains("fitted 300 rows"), "{stdout}");
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(
        model["outputs"][0]["trend"]["kind"], "kinematic",
        "{}",
        model["outputs"][0]["trend"]
    );
    std::fs::remove_file(out).ok();
}

/// An output that is an input (by path, through `..`, or a
/// hard link) or another output is refused before any work, and the input
/// is left as it was.
#[test]
fn outputs_never_overwrite_inputs() {
    let dir = std::env::temp_dir().join(format!("robokrige-guard-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let p = |f: &str| dir.join(f).display().to_string();
    let (c, _, err) = rk(&[
        "simulate",
        "--poses",
        "30",
        "--seed",
        "5",
        "-o",
        &p("d.csv"),
    ]);
    assert_eq!(c, 0, "{err}");
    let before = std::fs::read(dir.join("d.csv")).unwrap();
    std::fs::hard_link(dir.join("d.csv"), dir.join("link.csv")).unwrap();
    for out in [p("d.csv"), p("sub/../d.csv"), p("link.csv")] {
        let (c, _, err) = rk(&["fit", &p("d.csv"), "--optimizer", "hj", "-o", &out]);
        assert_eq!(c, 1, "{out}: {err}");
        assert!(err.contains("refusing to overwrite"), "{err}");
    }
    assert_eq!(std::fs::read(dir.join("d.csv")).unwrap(), before);
    let (c, _, err) = rk(&["fit", &p("d.csv"), "--optimizer", "hj", "-o", &p("m.json")]);
    assert_eq!(c, 0, "{err}");
    let (c, _, err) = rk(&["predict", &p("m.json"), &p("d.csv"), "-o", &p("m.json")]);
    assert_eq!(c, 1, "{err}");
    let (c, _, err) = rk(&[
        "predict",
        &p("m.json"),
        &p("d.csv"),
        "-o",
        &p("o.csv"),
        "--json",
        &p("o.csv"),
    ]);
    assert_eq!(c, 1, "{err}");
    assert!(err.contains("same file"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The default (a nugget estimated) cross-validates better than
/// the papers' interpolator on a noisy simulated campaign (by > 5 %), and
/// both stay above the simulator's noise floor (the RMS of the noise
/// alone, from the truth file).
#[test]
fn default_nugget_cross_validates_no_worse_than_the_interpolator() {
    let scratch = common::Scratch::new("robokrige-cli-nugget");
    let dir = scratch.path();
    let src = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
    let text = std::fs::read_to_string(src).unwrap();
    let head: Vec<&str> = text.lines().take(151).collect();
    let data = dir.join("lhs150.csv");
    std::fs::write(&data, head.join("\n") + "\n").unwrap();
    let cv = |extra: &[&str], name: &str| -> [f64; 3] {
        let json = dir.join(name);
        let mut args = vec![
            "cv",
            data.to_str().unwrap(),
            "--mode",
            "closed-form",
            "--json",
            json.to_str().unwrap(),
        ];
        args.extend(extra);
        let (c, _, err) = rk(&args);
        assert_eq!(c, 0, "{err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let r = &v["summary"]["rms_mm"];
        [0, 1, 2].map(|k| r[k].as_f64().unwrap())
    };
    let default = cv(&[], "default.json");
    let interp = cv(&["--no-nugget"], "interp.json");
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/datasets/comau_lhs.truth.json"
        ))
        .unwrap(),
    )
    .unwrap();
    let floor = &truth["noise_floor_mm"];
    let norm = |r: [f64; 3]| r.iter().map(|v| v * v).sum::<f64>().sqrt();
    let floor3 = norm([0, 1, 2].map(|k| floor[k].as_f64().unwrap()));
    assert!(
        norm(default) < 0.95 * norm(interp),
        "default {default:?} vs interpolator {interp:?}"
    );
    assert!(
        norm(default) > floor3,
        "{default:?} below the noise floor {floor3}"
    );
}

/// `predict` says when it assumed the first pose's λ, and
/// `cv --methods` refuses the model options it would not honour.
#[test]
fn predict_warns_about_derived_directions_and_cv_methods_refuses_unused_options() {
    let dir = std::env::temp_dir().join(format!("robokrige-cli-dir-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |f: &str| dir.join(f).display().to_string();
    let root = env!("CARGO_MANIFEST_DIR");
    let lhs = format!("{root}/datasets/comau_lhs.csv");
    let (c, _, err) = rk(&["fit", &lhs, "--corr", "gaussian", "-o", &p("m.json")]);
    assert_eq!(c, 0, "{err}");
    // the verification poses without their dir columns
    let text = std::fs::read_to_string(format!("{root}/datasets/comau_verify.csv")).unwrap();
    let cut: String = text
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            [&f[..7], &f[13..16]].concat().join(",") + "\n"
        })
        .collect();
    std::fs::write(dir.join("nodir.csv"), cut).unwrap();
    let (c, _, err) = rk(&["predict", &p("m.json"), &p("nodir.csv"), "-o", &p("a.csv")]);
    assert_eq!(c, 0, "{err}");
    assert!(
        err.contains("no dir1..dir6 columns") && err.contains("λ = +1"),
        "{err}"
    );
    let verify = format!("{root}/datasets/comau_verify.csv");
    let (c, _, err) = rk(&["predict", &p("m.json"), &verify, "-o", &p("b.csv")]);
    assert_eq!(c, 0, "{err}");
    assert!(!err.contains("dir1..dir6"), "{err}");
    for extra in [
        &["--mode", "closed-form"][..],
        &["--no-nugget"],
        &["--space", "js"],
        &["--hyper-rows", "100"],
    ] {
        let mut args = vec!["cv", lhs.as_str(), "--methods", "js-hj"];
        args.extend_from_slice(extra);
        let (c, _, err) = rk(&args);
        assert_eq!(c, 2, "{extra:?}: {err}");
        assert!(err.contains("cannot be used with"), "{err}");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// Every subcommand has an example and every option a help text.
#[test]
fn every_subcommand_has_an_example_and_every_option_a_help_text() {
    let subcommands = |args: &[&str]| -> Vec<String> {
        let mut a = args.to_vec();
        a.push("--help");
        let (_, out, _) = rk(&a);
        out.lines()
            .skip_while(|l| !l.starts_with("Commands:"))
            .skip(1)
            .take_while(|l| l.starts_with("  "))
            .filter_map(|l| l.split_whitespace().next())
            .filter(|c| *c != "help")
            .map(String::from)
            .collect()
    };
    let mut checked = 0;
    let mut missing = Vec::new();
    for top in subcommands(&[]) {
        let subs = subcommands(&[&top]);
        let paths: Vec<Vec<String>> = if subs.is_empty() {
            vec![vec![top.clone()]]
        } else {
            subs.into_iter().map(|s| vec![top.clone(), s]).collect()
        };
        for path in paths {
            let mut args: Vec<&str> = path.iter().map(String::as_str).collect();
            args.push("--help");
            let (c, out, _) = rk(&args);
            assert_eq!(c, 0, "{path:?}");
            assert!(out.contains("Example"), "{path:?} has no example:\n{out}");
            assert!(
                out.contains("--json <FILE>"),
                "{path:?} has no --json FILE:\n{out}"
            );
            // the Options section only (the examples after it are not options)
            let lines: Vec<&str> = out
                .lines()
                .skip_while(|l| !l.starts_with("Options:"))
                .skip(1)
                .take_while(|l| l.is_empty() || l.starts_with(' '))
                .collect();
            assert!(!lines.is_empty(), "{path:?}: no options section");
            for (i, l) in lines.iter().enumerate() {
                let t = l.trim_start();
                // (a "- name: text" line is a possible value, not an option)
                if !(l.starts_with("  ") && t.starts_with('-'))
                    || t.starts_with("- ")
                    || t.starts_with("-h, --help")
                {
                    continue;
                }
                // the text follows on the same line after two spaces, or on
                // the next, indented further
                let same = t.split_once("  ").is_some_and(|(_, r)| {
                    !r.trim().is_empty() && !r.trim().starts_with("[default")
                });
                let next = lines
                    .get(i + 1)
                    .is_some_and(|n| n.starts_with("          ") && !n.trim().is_empty());
                if !(same || next) {
                    missing.push(format!("{path:?} {t}"));
                }
            }
            checked += 1;
        }
    }
    assert!(
        missing.is_empty(),
        "options without help:\n{}",
        missing.join("\n")
    );
    assert!(checked >= 14, "{checked} subcommands checked");
}

/// One grammar: every subcommand has `--json FILE`, and `--json -` puts the
/// JSON, and only the JSON, on standard output (the text report goes to
/// standard error). Run on every subcommand but the two slow ones (`demo`,
/// `physics compare`), whose help is checked.
#[test]
fn json_dash_writes_only_json_to_stdout_on_every_subcommand() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let ds = |f: &str| format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"));
    let export = p("export.csv");
    std::fs::write(&export, "J1;J2;T\n0,5;1;20\n0,25;1,5;21\n0,75;2;22\n").unwrap();
    let setup: [&[&str]; 5] = [
        &[
            "simulate",
            "--poses",
            "40",
            "--seed",
            "3",
            "-o",
            &p("s.csv"),
        ],
        &[
            "simulate",
            "--kind",
            "circle",
            "--seed",
            "3",
            "-o",
            &p("circle.csv"),
        ],
        &["fit", &p("s.csv"), "--optimizer", "hj", "-o", &p("m.json")],
        &[
            "compensate",
            "--model",
            &p("m.json"),
            "--robot",
            "comau-nj220",
            &p("circle.csv"),
            "-o",
            &p("comp.csv"),
        ],
        &[
            "simulate",
            "--robot",
            "scara-rh3frh5515",
            "--kind",
            "crosstalk",
            "--seed",
            "1",
            "-o",
            &p("xt.csv"),
        ],
    ];
    for args in setup {
        let (c, _, err) = rk(args);
        assert_eq!(c, 0, "{args:?}: {err}");
    }
    let runs: Vec<Vec<String>> = [
        vec![
            "simulate",
            "--poses",
            "20",
            "--seed",
            "4",
            "-o",
            &p("s2.csv"),
        ],
        vec!["fit", &p("s.csv"), "--optimizer", "hj", "-o", &p("m2.json")],
        vec!["predict", &p("m.json"), &p("s.csv"), "-o", &p("pred.csv")],
        vec!["cv", &p("s.csv"), "--folds", "4", "--optimizer", "hj"],
        vec![
            "compensate",
            "--model",
            &p("m.json"),
            "--robot",
            "comau-nj220",
            &p("circle.csv"),
            "-o",
            &p("comp2.csv"),
        ],
        vec![
            "evaluate",
            "--truth",
            &p("circle.truth.json"),
            &p("circle.csv"),
            &p("comp.csv"),
        ],
        vec!["diagnose", &p("s.csv"), "--permutations", "19"],
        vec![
            "physics",
            "register",
            &p("s.csv"),
            "--robot",
            "comau-nj220",
            "-o",
            &p("reg.csv"),
        ],
        vec![
            "physics",
            "probing",
            "--robot",
            "kuka-kr30ha",
            "--seed",
            "1",
        ],
        vec![
            "physics",
            "identify",
            &ds("scara_indexing.csv"),
            "-o",
            &p("sp.json"),
        ],
        vec![
            "physics",
            "crosstalk",
            &p("xt.csv"),
            "--model",
            &p("sp.json"),
        ],
        vec![
            "holdout",
            &p("s.csv"),
            "--robot",
            "comau-nj220",
            "--train",
            "30",
            "--test",
            "10",
        ],
        vec![
            "import",
            &export,
            "--map",
            "q1=J1,q2=J2,temp_c=T",
            "-o",
            &p("imp.csv"),
        ],
        vec!["robot", "show", "ur10"],
        vec![
            "plan",
            "--robot",
            "ur10",
            "--budget",
            "6",
            "--candidates",
            "200",
            "-o",
            &p("plan.csv"),
        ],
    ]
    .into_iter()
    .map(|v| v.into_iter().map(String::from).collect())
    .collect();
    for mut args in runs {
        args.extend(["--json".to_string(), "-".to_string()]);
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (c, out, err) = rk(&a);
        assert_eq!(c, 0, "{args:?}: {err}");
        let v: Result<serde_json::Value, _> = serde_json::from_str(&out);
        assert!(
            v.is_ok(),
            "{args:?}: stdout is not one JSON document:\n{out}"
        );
        assert!(
            !err.is_empty() || args[0] == "robot",
            "{args:?}: the text report is gone"
        );
    }
    for path in [&["demo"][..], &["physics", "compare"]] {
        let mut a = path.to_vec();
        a.push("--help");
        let (_, out, _) = rk(&a);
        assert!(out.contains("--json <FILE>"), "{path:?}");
    }
}

/// Options a mode does not use are refused, not silently ignored: each
/// case exits 1 or 2 with a message naming the option.
#[test]
fn options_a_mode_does_not_use_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let ds = |f: &str| format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"));
    let (c, _, err) = rk(&[
        "simulate",
        "--poses",
        "40",
        "--seed",
        "3",
        "-o",
        &p("s.csv"),
    ]);
    assert_eq!(c, 0, "{err}");
    let (c, _, err) = rk(&[
        "fit",
        &p("s.csv"),
        "--optimizer",
        "hj",
        "--robot",
        "comau-nj220",
        "-o",
        &p("m.json"),
    ]);
    assert_eq!(c, 0, "{err}");
    let export = p("e.csv");
    std::fs::write(&export, "a,b\n1,2\n2,3\n").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "simulate",
                "--robot",
                "scara-rh3frh5515",
                "--kind",
                "indexing",
                "--poses",
                "5",
            ],
            "--poses",
        ),
        (
            vec!["simulate", "--poses", "20", "--diameter", "7"],
            "--diameter",
        ),
        (
            vec!["simulate", "--poses", "20", "--cycles", "2"],
            "--cycles",
        ),
        (
            vec![
                "simulate",
                "--kind",
                "circle",
                "--ranges=-1:1,-1:1,-1:1,-1:1,-1:1,-1:1",
            ],
            "--ranges",
        ),
        (
            vec!["simulate", "--kind", "circle", "--effect", "temperature"],
            "--effect temperature",
        ),
        (
            vec!["fit", &p("s.csv"), "--method", "ejs-hj", "--space", "js"],
            "leave space at the defaults",
        ),
        (vec!["fit", &p("s.csv"), "--tool", "1,2,3"], "--robot"),
        (
            vec!["fit", &p("s.csv"), "--optimizer", "hj", "--starts", "3"],
            "starts is for optimizer",
        ),
        (
            vec![
                "compensate",
                "--model",
                &p("m.json"),
                "--robot",
                "comau-nj220",
                &ds("comau_circle.csv"),
                "--tol",
                "5",
            ],
            "--iterative",
        ),
        (
            vec![
                "compensate",
                "--model",
                &p("m.json"),
                "--robot",
                "comau-nj220",
                &ds("comau_circle.csv"),
                "--seed",
                "5",
            ],
            "--truth",
        ),
        (
            vec![
                "compensate",
                "--model",
                &p("m.json"),
                "--robot",
                "comau-nj220",
                &ds("comau_circle.csv"),
                "--orientation=1,2,3",
            ],
            "--orientation",
        ),
        (
            vec![
                "diagnose",
                &p("s.csv"),
                "--robot",
                "comau-nj220",
                "--traj",
                &ds("comau_circle.csv"),
            ],
            "--truth",
        ),
        (
            vec![
                "holdout",
                &p("s.csv"),
                "--robot",
                "comau-nj220",
                "--cv",
                "3",
                "--ga",
            ],
            "--ga",
        ),
        (
            vec![
                "holdout",
                &p("s.csv"),
                "--robot",
                "comau-nj220",
                "--cv",
                "3",
                "--test",
                "5",
            ],
            "--test",
        ),
        (
            vec![
                "physics",
                "identify",
                &ds("scara_indexing.csv"),
                "--train",
                &p("s.csv"),
            ],
            "--train",
        ),
        (
            vec![
                "physics",
                "compare",
                "--js",
                "recommended",
                "--ejs",
                "recommended",
                "--nugget",
            ],
            "--nugget",
        ),
        (
            vec![
                "cv",
                &p("s.csv"),
                "--mode",
                "closed-form",
                "--hyper-rows",
                "500",
            ],
            "--hyper-rows",
        ),
        (vec!["import", &export, "--map", "q1=a,q1=b"], "given twice"),
        (
            vec!["import", &export, "--map", "q1=a", "--decimal", ","],
            "decimal comma",
        ),
    ]
    .into_iter()
    .map(|(v, w)| (v.into_iter().map(String::from).collect(), w))
    .collect();
    for (mut args, word) in cases {
        if !args.iter().any(|a| a == "-o")
            && args[0] != "cv"
            && args[0] != "holdout"
            && args[0] != "diagnose"
            && args[1] != "compare"
        {
            args.extend(["-o".to_string(), p("out.csv")]);
        }
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (c, _, err) = rk(&a);
        assert!(c == 1 || c == 2, "{args:?} was accepted");
        assert!(err.contains(word), "{args:?}: {err}");
        assert!(
            !dir.path().join("out.csv").exists(),
            "{args:?} wrote its output"
        );
    }
}

/// A model with `temp_c` as an input, compensated at a temperature given
/// with `--covariate`; without it, at the campaign's start value with a
/// warning that says so (and that the trajectory's own column is not read).
#[test]
fn compensate_holds_a_covariate_at_the_value_given_and_warns_without_one() {
    use robokrige::features::Feature;
    use robokrige::kriging::{KrigingOptions, OptimizerKind};
    use robokrige::params::ErrorModelParams;
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let ds = |f: &str| format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"));
    let data = robokrige::dataset::read_csv(ds("comau_temperature.csv").as_ref())
        .unwrap()
        .head(120);
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(200);
    let m = ErrorModelParams::new()
        .kriging(opts)
        .extras(vec![Feature::Covariate {
            name: "temp_c".into(),
            reference: Some(21.0),
        }])
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap();
    m.save(p("m.json").as_ref()).unwrap();
    let comp = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "compensate",
            ds("comau_circle.csv").leak(),
            "--model",
            p("m.json").leak(),
            "--robot",
            "comau-nj220",
            "-o",
            p(out).leak(),
        ];
        args.extend_from_slice(extra);
        rk(&args)
    };
    let (c, _, err) = comp("a.csv", &[]);
    assert_eq!(c, 0, "{err}");
    assert!(
        err.contains("covariate 'temp_c': compensating at 21")
            && err.contains("--covariate temp_c=VALUE"),
        "{err}"
    );
    let (c, _, err) = comp("b.csv", &["--covariate", "temp_c=21"]);
    assert_eq!(c, 0, "{err}");
    assert!(!err.contains("warning: the model uses covariate"), "{err}");
    let (c, _, err) = comp("c.csv", &["--covariate", "temp_c=35"]);
    assert_eq!(c, 0, "{err}");
    let read = |f: &str| std::fs::read_to_string(p(f)).unwrap();
    assert_eq!(read("a.csv"), read("b.csv"));
    assert_ne!(read("a.csv"), read("c.csv"));
    let (c, _, err) = comp("d.csv", &["--covariate", "payload=3"]);
    assert_eq!(c, 1);
    assert!(err.contains("does not use covariate 'payload'"), "{err}");
    let (c, _, err) = comp("d.csv", &["--covariate", "temp_c"]);
    assert_eq!(c, 2, "{err}");
}
