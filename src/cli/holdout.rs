//! `robokrige holdout`: train on the first rows of a campaign, score on the
//! next ones — nominal, D-H calibration, two-stage hybrid, universal Kriging
//! with the kinematic trend, in JS and EJS (issue 10's real-data table).

use super::progress::bar;
use super::{read_data, to_json};
use clap::Args;
use nalgebra::{Isometry3, Translation3};
use robokrige::compensate::ErrorPredictor;
use robokrige::dataset::Dataset;
use robokrige::kinematics::{self, Robot};
use robokrige::kriging::{KrigingOptions, OptimizerKind};
use robokrige::model::ErrorModel;
use robokrige::physics::{Geometry, HybridModel, PhysicsModel, identify_mdh};
use robokrige::space::Space;
use robokrige::stats::spread;
use robokrige::{Error, Result};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// Hold-out comparison of calibration models on a measured campaign.
#[derive(Debug, Args)]
#[command(after_help = "\
Rows 1..TRAIN train every model; rows TRAIN+1..TRAIN+TEST are predicted.
Models: nominal (no correction); D-H calibration (Levenberg–Marquardt on the
5n + 9 MD-H, tool and base errors; redundant ones frozen); hybrid (D-H
calibration, then Kriging JS or EJS on its residual); universal Kriging with
the kinematic trend (constant + identification-Jacobian rows; the GLS does the
calibration), JS and EJS. Kriging hyperparameters by Hooke–Jeeves.

Example (the public UR10 data, series C):
  robokrige holdout ../shared/data/ipa-ur10/series_c_random_poses.csv \\
      --robot ur10 --tool=-0.14,0.30,92.82 --train 600 --test 300")]
pub struct HoldoutArgs {
    /// Measurement CSV with ex,ey,ez.
    data: PathBuf,
    #[arg(long)]
    robot: String,
    /// TCP offset in the flange frame, mm ("x,y,z"), if the errors were
    /// computed with one.
    #[arg(long)]
    tool: Option<String>,
    #[arg(long, default_value_t = 600)]
    train: usize,
    #[arg(long, default_value_t = 300)]
    test: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Kriging hyperparameter search: hj (Hooke–Jeeves, fast) or gps.
    #[arg(long, default_value = "hj")]
    optimizer: String,
    /// Estimate a nugget in the Kriging fits (real data has noise).
    #[arg(long)]
    nugget: bool,
    /// Joints entered as (sin θ, cos θ): "auto" (range > 180° in the training
    /// rows), "none", or a list like "1,4,6".
    #[arg(long, default_value = "auto")]
    periodic: String,
    /// Instead: K-fold CV on all rows of the nominal and the D-H calibration
    /// (Levenberg–Marquardt refitted on every training fold).
    #[arg(long)]
    cv: Option<usize>,
    #[arg(long)]
    json: Option<PathBuf>,
}

#[derive(Debug, Serialize)]
struct Row {
    model: String,
    mean_mm: f64,
    max_mm: f64,
    rms_xyz_mm: [f64; 3],
    seconds: f64,
}

/// `--periodic auto|none|1,4,6` → 0-based joints.
pub fn parse_periodic(spec: &str, q: &[Vec<f64>]) -> Result<Vec<usize>> {
    let n = q.first().map_or(0, Vec::len);
    match spec.trim() {
        "auto" => Ok(robokrige::space::periodic_joints(q)),
        "none" | "" => Ok(Vec::new()),
        list => list
            .split(',')
            .map(|t| match t.trim().parse::<usize>() {
                Ok(j) if (1..=n).contains(&j) => Ok(j - 1),
                _ => Err(Error::InvalidParameter(format!(
                    "--periodic '{spec}': expected auto, none or joint numbers 1..{n}"
                ))),
            })
            .collect(),
    }
}

/// `--tool "x,y,z"` on top of a preset.
pub fn robot_with_tool(name: &str, tool: Option<&str>) -> Result<Robot> {
    let mut robot = kinematics::preset(name)?;
    if let Some(t) = tool {
        let v: Vec<f64> = t
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| Error::InvalidParameter(format!("--tool '{t}': expected x,y,z in mm")))?;
        if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
            return Err(Error::InvalidParameter(format!(
                "--tool '{t}': expected x,y,z in mm"
            )));
        }
        robot.tool =
            Isometry3::from_parts(Translation3::new(v[0], v[1], v[2]), robot.tool.rotation);
    }
    Ok(robot)
}

fn score(name: &str, truth: &[[f64; 3]], pred: &[[f64; 3]], seconds: f64) -> Row {
    let r: Vec<[f64; 3]> = truth
        .iter()
        .zip(pred)
        .map(|(t, p)| [t[0] - p[0], t[1] - p[1], t[2] - p[2]])
        .collect();
    let d: Vec<f64> = r
        .iter()
        .map(|e| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt())
        .collect();
    let s = spread(&d);
    let rms = |a: usize| (r.iter().map(|e| e[a] * e[a]).sum::<f64>() / r.len() as f64).sqrt();
    Row {
        model: name.into(),
        mean_mm: s.mean,
        max_mm: s.max,
        rms_xyz_mm: [rms(0), rms(1), rms(2)],
        seconds,
    }
}

fn run_cv(a: &HoldoutArgs, data: &Dataset, robot: &Robot, k: usize) -> Result<()> {
    let fold = robokrige::cv::kfold_partition(data.len(), k, a.seed)?;
    let errors = data.errors_or_err()?;
    let mut pred = vec![[0.0; 3]; data.len()];
    let t0 = Instant::now();
    let pb = bar(k as u64, "folds");
    for f in 0..k {
        let (test, train): (Vec<usize>, Vec<usize>) = (0..data.len()).partition(|&i| fold[i] == f);
        let (cal, _) = identify_mdh(&data.select(&train), robot, &vec![None; robot.dof()])?;
        let dh = PhysicsModel::new(
            "D-H calibration",
            robot.clone(),
            Geometry::Mdh { robot: cal },
        );
        let held = data.select(&test);
        for (j, p) in dh.predict(&held.q, &held.dir)?.into_iter().enumerate() {
            pred[test[j]] = p;
        }
        pb.inc(1);
    }
    pb.finish_and_clear();
    let rows = vec![
        score("nominal", errors, &vec![[0.0; 3]; errors.len()], 0.0),
        score(
            "D-H calibration (LM, refit per fold)",
            errors,
            &pred,
            t0.elapsed().as_secs_f64(),
        ),
    ];
    println!(
        "{}: {k}-fold CV (fold seed {}) on all {} rows",
        a.data.display(),
        a.seed,
        data.len()
    );
    print_rows(&rows);
    if let Some(p) = &a.json {
        std::fs::write(p, to_json(&rows, "cv table")?).map_err(|e| Error::io(p, e))?;
    }
    Ok(())
}

fn print_rows(rows: &[Row]) {
    println!("| model | mean 3D (mm) | max 3D (mm) | RMS x / y / z (mm) | time |");
    println!("|---|---|---|---|---|");
    for r in rows {
        println!(
            "| {} | {:.4} | {:.4} | {:.4} / {:.4} / {:.4} | {:.1} s |",
            r.model,
            r.mean_mm,
            r.max_mm,
            r.rms_xyz_mm[0],
            r.rms_xyz_mm[1],
            r.rms_xyz_mm[2],
            r.seconds
        );
    }
}

pub fn run(a: HoldoutArgs) -> Result<()> {
    let data = read_data(&a.data)?;
    let robot = robot_with_tool(&a.robot, a.tool.as_deref())?;
    if let Some(k) = a.cv {
        return run_cv(&a, &data, &robot, k);
    }
    if a.train < 10 || a.test < 1 || a.train + a.test > data.len() {
        return Err(Error::InvalidParameter(format!(
            "--train {} --test {} need at least 10 + 1 and at most {} rows",
            a.train,
            a.test,
            data.len()
        )));
    }
    let train = data.select(&(0..a.train).collect::<Vec<_>>());
    let test = data.select(&(a.train..a.train + a.test).collect::<Vec<_>>());
    let truth = test.errors_or_err()?.to_vec();
    let periodic = parse_periodic(&a.periodic, &train.q)?;
    let opts = KrigingOptions {
        optimizer: match a.optimizer.as_str() {
            "hj" => OptimizerKind::HookeJeeves,
            "gps" => OptimizerKind::Gps,
            o => {
                return Err(Error::InvalidParameter(format!(
                    "--optimizer '{o}': expected hj or gps"
                )));
            }
        },
        seed: a.seed,
        nugget: a.nugget,
        periodic: periodic.clone(),
        ..KrigingOptions::default()
    };
    let pb = bar(6, "holdout");
    let mut rows = Vec::new();
    rows.push(score("nominal", &truth, &vec![[0.0; 3]; truth.len()], 0.0));
    pb.set_message("D-H calibration");
    let t0 = Instant::now();
    let (cal, lm) = identify_mdh(&train, &robot, &vec![None; robot.dof()])?;
    let dh = PhysicsModel::new(
        "D-H calibration",
        robot.clone(),
        Geometry::Mdh { robot: cal },
    );
    let dh_secs = t0.elapsed().as_secs_f64();
    rows.push(score(
        "D-H calibration (LM)",
        &truth,
        &dh.predict_errors(&test.q, &test.dir)?,
        dh_secs,
    ));
    pb.inc(1);
    let mut resid: Dataset = train.clone();
    let pred_tr = dh.predict(&train.q, &train.dir)?;
    resid.errors = Some(
        train
            .errors_or_err()?
            .iter()
            .zip(&pred_tr)
            .map(|(e, p)| [e[0] - p[0], e[1] - p[1], e[2] - p[2]])
            .collect(),
    );
    for space in [Space::Js, Space::Ejs] {
        let label = format!("{space:?}").to_uppercase();
        pb.set_message(format!("hybrid {label}"));
        let t0 = Instant::now();
        let h = HybridModel {
            physics: dh.clone(),
            residual: ErrorModel::fit(&resid, space, &opts)?,
        };
        let secs = dh_secs + t0.elapsed().as_secs_f64();
        rows.push(score(
            &format!("hybrid: D-H calibration + Kriging {label}"),
            &truth,
            &h.predict(&test.q, &test.dir)?,
            secs,
        ));
        pb.inc(1);
        pb.set_message(format!("UK kinematic trend {label}"));
        let t0 = Instant::now();
        let m = ErrorModel::fit_kinematic(&train, space, &opts, &robot)?;
        let secs = t0.elapsed().as_secs_f64();
        rows.push(score(
            &format!("universal Kriging {label}, kinematic trend"),
            &truth,
            &m.predict_mean(&test.q, &test.dir)?,
            secs,
        ));
        pb.inc(1);
    }
    pb.finish_and_clear();
    println!(
        "{}: train rows 1–{}, test rows {}–{}; Kriging by {}{}; periodic joints (sin/cos): {}",
        a.data.display(),
        a.train,
        a.train + 1,
        a.train + a.test,
        if a.optimizer == "gps" {
            "GPS"
        } else {
            "Hooke–Jeeves"
        },
        if a.nugget { ", nugget estimated" } else { "" },
        if periodic.is_empty() {
            "none".to_string()
        } else {
            periodic
                .iter()
                .map(|j| format!("q{}", j + 1))
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    println!(
        "D-H calibration: {} parameters fitted ({} frozen as unidentifiable), rms {:.4} → {:.4} mm on the training rows",
        lm.parameters,
        lm.frozen.len(),
        lm.rms_before_mm,
        lm.rms_after_mm
    );
    print_rows(&rows);
    if let Some(p) = &a.json {
        std::fs::write(p, to_json(&rows, "hold-out table")?).map_err(|e| Error::io(p, e))?;
    }
    Ok(())
}
