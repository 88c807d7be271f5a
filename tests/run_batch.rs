//! `run CONFIG` does what the flags do; `batch` fits a folder of campaigns,
//! one robot each, and reports every campaign, failures included.

mod common;

use common::rk;

fn ds(f: &str) -> String {
    format!("{}/datasets/{f}", env!("CARGO_MANIFEST_DIR"))
}

/// A test's temporary folder.
struct Scratch(tempfile::TempDir);

impl Scratch {
    fn new() -> Self {
        Scratch(tempfile::tempdir().unwrap())
    }

    /// The path of `f` in the folder.
    fn path(&self, f: &str) -> String {
        self.0.path().join(f).display().to_string()
    }

    /// Write `text` to `f` in the folder; its path.
    fn write(&self, f: &str, text: &str) -> String {
        std::fs::write(self.path(f), text).unwrap();
        self.path(f)
    }

    /// A `fleet` folder of campaigns (name, text) and the path of an `out`
    /// folder beside it, for `batch`.
    fn fleet(&self, campaigns: &[(&str, &str)]) -> (String, String) {
        std::fs::create_dir(self.path("fleet")).unwrap();
        for (name, text) in campaigns {
            self.write(&format!("fleet/{name}"), text);
        }
        (self.path("fleet"), self.path("out"))
    }
}

/// The shipped COMAU campaign's text.
fn lhs() -> String {
    std::fs::read_to_string(ds("comau_lhs.csv")).unwrap()
}

#[test]
fn a_config_step_gives_the_same_model_as_its_flags() {
    let dir = Scratch::new();
    let p = |f: &str| dir.path(f);
    let config = format!(
        "data = \"{}\"\nrobot = \"comau-nj220\"\n\n[[step]]\ncommand = \"fit\"\noutput = \"a.json\"\noptimizer = \"hj\"\ncorr = \"gaussian\"\nno-nugget = true\n",
        ds("comau_lhs.csv")
    );
    let (c, out, err) = rk(&["run", &dir.write("robokrige.toml", &config)]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("robokrige fit"), "{out}");
    let (c, _, err) = rk(&[
        "fit",
        &ds("comau_lhs.csv"),
        "--robot",
        "comau-nj220",
        "--optimizer",
        "hj",
        "--corr",
        "gaussian",
        "--no-nugget",
        "-o",
        &p("b.json"),
    ]);
    assert_eq!(c, 0, "{err}");
    let read = |f: &str| -> serde_json::Value {
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p(f)).unwrap()).unwrap();
        for r in v["reports"].as_array_mut().unwrap() {
            r["seconds"] = 0.0.into();
        }
        v
    };
    // written relative to the config's folder, equal to the flags' model
    assert_eq!(read("a.json"), read("b.json"));
}

#[test]
fn a_config_plan_step_plans_what_its_flags_plan() {
    let dir = Scratch::new();
    let p = |f: &str| dir.path(f);
    let config = format!(
        "robot = \"comau-nj220\"\n\n[[step]]\ncommand = \"plan\"\ncampaign = \"{}\"\nbudget = 6\ncandidates = 400\nregion-points = 200\noutput = \"a.csv\"\n",
        ds("comau_lhs.csv")
    );
    let (c, out, err) = rk(&["run", &dir.write("robokrige.toml", &config)]);
    assert_eq!(c, 0, "{err}");
    assert!(out.contains("robokrige plan"), "{out}");
    let (c, _, err) = rk(&[
        "plan",
        "--robot",
        "comau-nj220",
        "--campaign",
        &ds("comau_lhs.csv"),
        "--budget",
        "6",
        "--candidates",
        "400",
        "--region-points",
        "200",
        "-o",
        &p("b.csv"),
    ]);
    assert_eq!(c, 0, "{err}");
    let a = std::fs::read_to_string(p("a.csv")).unwrap();
    assert_eq!(a, std::fs::read_to_string(p("b.csv")).unwrap());
    // six measured poses (measure = 1), and their pre-position moves
    let header: Vec<&str> = a.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "measure").unwrap();
    let measured = a
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(col) == Some("1"))
        .count();
    assert_eq!(measured, 6, "{a}");
}

#[test]
fn a_config_with_an_unknown_option_names_the_step_and_the_options() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("c.toml");
    std::fs::write(
        &cfg,
        "[[step]]\ncommand = \"fit\"\ndata = \"x.csv\"\nfolds = 3\n",
    )
    .unwrap();
    let (c, _, err) = rk(&["run", &cfg.display().to_string()]);
    assert_eq!(c, 1);
    assert!(
        err.contains("step 1: fit has no option 'folds'") && err.contains("optimizer"),
        "{err}"
    );
    std::fs::write(&cfg, "[[step]]\ncommand = \"fly\"\n").unwrap();
    let (c, _, err) = rk(&["run", &cfg.display().to_string()]);
    assert_eq!(c, 1);
    assert!(err.contains("no subcommand 'fly'"), "{err}");
}

/// A step that fails stops the run, and the `--json` log still says what
/// ran: the steps before it, and the failed one with its error.
#[test]
fn a_failed_step_is_in_the_run_log() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("c.toml");
    std::fs::write(
        &cfg,
        "[[step]]\ncommand = \"simulate\"\nposes = 20\noutput = \"s.csv\"\n\n\
         [[step]]\ncommand = \"fit\"\ndata = \"missing.csv\"\noutput = \"m.json\"\n\n\
         [[step]]\ncommand = \"simulate\"\nposes = 20\noutput = \"t.csv\"\n",
    )
    .unwrap();
    let log = dir.path().join("log.json");
    let (c, _, err) = rk(&[
        "run",
        &cfg.display().to_string(),
        "--json",
        &log.display().to_string(),
    ]);
    assert_eq!(c, 1, "{err}");
    assert!(err.contains("step 2 (fit) failed"), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&log).expect("the log")).unwrap();
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2, "{v}");
    assert!(steps[0]["error"].is_null(), "{v}");
    assert!(
        steps[1]["error"].as_str().unwrap().contains("missing.csv"),
        "{v}"
    );
    assert!(!dir.path().join("t.csv").exists(), "the run went on");
}

#[test]
fn a_batch_reports_every_campaign_with_its_own_robot_and_lists_failures() {
    let dir = tempfile::tempdir().unwrap();
    let fleet = dir.path().join("fleet");
    std::fs::create_dir(&fleet).unwrap();
    let text = std::fs::read_to_string(ds("comau_lhs.csv")).unwrap();
    let first: String = text.lines().take(81).collect::<Vec<_>>().join("\n") + "\n";
    std::fs::write(fleet.join("cell_a.csv"), &first).unwrap();
    std::fs::write(fleet.join("cell_b.csv"), &first).unwrap();
    // cell_b's own robot file wins over --robot
    let abb = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/robots/abb-irb2600.toml"
    );
    std::fs::copy(abb, fleet.join("cell_b.robot.toml")).unwrap();
    std::fs::write(fleet.join("empty.csv"), "q1,q2,ex,ey,ez\n").unwrap();
    let out = dir.path().join("out");
    let (c, stdout, err) = rk(&[
        "batch",
        &fleet.display().to_string(),
        "-o",
        &out.display().to_string(),
        "--robot",
        "comau-nj220",
        "--folds",
        "4",
    ]);
    assert_eq!(c, 1, "one campaign fails: {err}");
    assert!(err.contains("1 of 3 campaign(s) failed"), "{err}");
    assert!(
        stdout.contains("empty") && stdout.contains("failed"),
        "{stdout}"
    );
    let summary = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let lines: Vec<&str> = summary.lines().collect();
    assert_eq!(lines.len(), 4, "{summary}");
    assert!(lines[1].starts_with("cell_a,80,comau-nj220,") && lines[1].ends_with(",ok"));
    assert!(lines[2].starts_with("cell_b,80,abb-irb2600-12-165,"));
    assert!(lines[3].starts_with("empty,") && lines[3].contains("failed"));
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("cell_b.model.json")).unwrap())
            .unwrap();
    assert_eq!(model["robot"]["name"], "abb-irb2600-12-165");
    assert!(out.join("cell_a.report.json").exists());
    // the campaign folder is not an output folder
    let (c, _, err) = rk(&[
        "batch",
        &fleet.display().to_string(),
        "-o",
        &fleet.display().to_string(),
    ]);
    assert_eq!(c, 1);
    assert!(
        err.contains("output folder is the campaign folder"),
        "{err}"
    );
}

/// The batch's calibration flags are `fit`'s: with `--backlash` the
/// simulated COMAU's play is identified and kept in the campaign's model
/// file, and its report says what the calibration found.
#[test]
fn a_batch_calibrates_with_the_backlash_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let fleet = dir.path().join("fleet");
    std::fs::create_dir(&fleet).unwrap();
    std::fs::copy(ds("comau_lhs.csv"), fleet.join("cell.csv")).unwrap();
    let batch = |out: &str, extra: &[&str]| {
        let out = dir.path().join(out);
        let json = dir.path().join(format!("{}.json", out.display()));
        let mut args = vec![
            "batch".to_string(),
            fleet.display().to_string(),
            "-o".into(),
            out.display().to_string(),
            "--robot".into(),
            "comau-nj220".into(),
            "--folds".into(),
            "4".into(),
            "--json".into(),
            json.display().to_string(),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        let (c, _, err) = rk(&argv);
        assert_eq!(c, 0, "{err}");
        let model: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("cell.model.json")).unwrap())
                .unwrap();
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
        (model, report[0]["report"]["calibration"].clone())
    };
    let (plain, line) = batch("plain", &[]);
    assert!(plain["calibration"]["backlash"].is_null(), "{line}");
    assert!(line.as_str().unwrap().contains("directions seen"), "{line}");
    assert!(!line.as_str().unwrap().contains("backlash"), "{line}");
    let (with, line) = batch("backlash", &["--backlash"]);
    let found = with["calibration"]["backlash"].as_array().unwrap();
    assert!(!found.is_empty(), "{line}");
    assert!(line.as_str().unwrap().contains("half backlash"), "{line}");
    // no calibration, no backlash: refused rather than ignored
    let (c, _, err) = rk(&[
        "batch",
        &fleet.display().to_string(),
        "-o",
        &dir.path().join("x").display().to_string(),
        "--no-calibrate",
        "--backlash",
    ]);
    assert_eq!(c, 2, "{err}");
    assert!(err.contains("cannot be used with"), "{err}");
}

#[test]
fn no_step_and_no_log_of_a_run_writes_over_its_config() {
    let dir = Scratch::new();
    let config = format!(
        "data = \"{}\"\n\n[[step]]\ncommand = \"fit\"\noutput = \"run.toml\"\noptimizer = \"hj\"\n",
        ds("comau_lhs.csv")
    );
    let run = dir.write("run.toml", &config);
    let (c, _, err) = rk(&["run", &run]);
    assert_ne!(c, 0);
    assert!(err.contains("refusing to overwrite"), "{err}");
    assert_eq!(std::fs::read_to_string(&run).unwrap(), config);
    // the log, refused before any step runs
    let config = config.replace("output = \"run.toml\"", "output = \"m.json\"");
    dir.write("run.toml", &config);
    let (c, _, err) = rk(&["run", &run, "--json", &run]);
    assert_ne!(c, 0);
    assert!(err.contains("refusing to overwrite"), "{err}");
    assert!(!std::path::Path::new(&dir.path("m.json")).exists());
    assert_eq!(std::fs::read_to_string(&run).unwrap(), config);
}

#[test]
fn a_batch_refuses_two_campaigns_that_would_write_the_same_files() {
    let dir = Scratch::new();
    let (fleet, out) = dir.fleet(&[("a.csv", &lhs()), ("a.CSV", &lhs())]);
    let (c, _, err) = rk(&["batch", &fleet, "-o", &out]);
    assert_ne!(c, 0);
    assert!(err.contains("the same model and report files"), "{err}");
    assert!(!std::path::Path::new(&out).join("summary.csv").exists());
}

#[test]
fn a_top_level_key_no_step_has_is_refused() {
    let dir = Scratch::new();
    let config = format!(
        "data = \"{}\"\nrobt = \"comau-nj220\"\n\n[[step]]\ncommand = \"fit\"\noutput = \"m.json\"\n",
        ds("comau_lhs.csv")
    );
    let (c, _, err) = rk(&["run", &dir.write("run.toml", &config)]);
    assert_ne!(c, 0);
    assert!(err.contains("'robt'"), "{err}");
    assert!(!std::path::Path::new(&dir.path("m.json")).exists());
}

#[test]
fn a_batch_with_calibration_options_and_no_robot_is_refused() {
    let dir = Scratch::new();
    let (fleet, out) = dir.fleet(&[("a.csv", &lhs())]);
    let (c, _, err) = rk(&["batch", &fleet, "-o", &out, "--geometric"]);
    assert_ne!(c, 0);
    assert!(err.contains("need a robot"), "{err}");
    assert!(!std::path::Path::new(&out).join("summary.csv").exists());
}

#[test]
fn a_config_step_output_to_standard_output_is_refused_before_any_step() {
    let dir = Scratch::new();
    let config = format!(
        "data = \"{}\"\n\n[[step]]\ncommand = \"simulate\"\nposes = 10\noutput = \"s.csv\"\n\n[[step]]\ncommand = \"fit\"\noutput = \"-\"\n",
        ds("comau_lhs.csv")
    );
    let (c, _, err) = rk(&["run", &dir.write("run.toml", &config)]);
    assert_ne!(c, 0);
    assert!(
        err.contains("step 2: output = \"-\": '-' would be a file named '-'")
            && err.contains("give output a path"),
        "{err}"
    );
    assert!(
        !std::path::Path::new(&dir.path("s.csv")).exists(),
        "a step ran"
    );
}
