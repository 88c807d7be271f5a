//! Pool-based score of the campaign planner on real UR10 campaigns (the
//! standard way to score a design): the measured campaign is the pool; a
//! chosen pose is "measured" by revealing its recorded error; the model is
//! trained on the chosen poses and scored (mean 3D error, mm) on all the
//! others.
//!
//! - **planned**: a space-filling first batch, then batches chosen by the
//!   integrated-MSE reduction over the pool's poses not measured yet, the hyperparameters
//!   re-estimated (the default model, calibrated) after every batch;
//! - **random**: uniform subsets of the pool, mean and spread over seeds;
//! - **maximin**: a greedy space-filling subset of the pool.
//!
//! Run: `cargo bench --bench plan_pool -- [c|b] [--sizes 100,200,400,800]
//! [--seeds 10] [--batch 50] [--svg FILE] [--forecast-only]`
//! (`--forecast-only`: the default planner and its forecast table alone).
//! The forecast table scores the held-out error twice: on every pose not
//! chosen, and on the new poses only (none within 0.1° of a chosen pose on
//! every joint; series B repeats configurations). Needs
//! `../shared/data/ipa-ur10/` (skips cleanly without it).
//!
//! `-- --timing` instead times one batch of 50 from 10 000 drawn
//! candidates with 400 simulated poses measured (UR10), fit included, and
//! then its forecast (the stopping rule's CV).
//!
//! `-- --circle` instead plans a campaign for a task (the shipped COMAU
//! circle as `--region`; 50 + 50 poses, the second batch planned on the
//! first's measurements), measures it on the circle's true robot, and
//! compensates the circle with the default model; then the same with Latin
//! hypercubes of 100 and 300 poses (three seeds each). Mean 3D error of the
//! compensated circle on the true robot, mm, averaged over five runs.

use robokrige::cancel::Cancel;
use robokrige::dataset::{Dataset, read_csv};
use robokrige::kinematics::{self, Robot};
use robokrige::methods::default_params;
use robokrige::model::ErrorModel;
use robokrige::plan::stop::Forecast;
use robokrige::plan::{PlanInputs, PlanParams, PoseSet, Region, candidates};
use std::path::Path;
use std::time::Instant;

fn robot() -> Robot {
    kinematics::load_robot_with_tool("ur10", Some("-0.14,0.30,92.82")).unwrap()
}

fn default_model(robot: &Robot, data: &Dataset) -> ErrorModel {
    default_params(robot, data)
        .unwrap()
        .check()
        .unwrap()
        .fit(data)
        .unwrap()
}

/// Mean 3D error of `model` on the pool rows `rows`.
fn mean_3d_on(model: &ErrorModel, pool: &Dataset, rows: &[usize]) -> f64 {
    let test = pool.select(rows);
    let p = model.predict_dataset(&test).unwrap();
    let e = test.errors.as_ref().unwrap();
    p.mean
        .iter()
        .zip(e)
        .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt())
        .sum::<f64>()
        / rows.len() as f64
}

/// Mean 3D error of `model` on the pool rows not in `train`.
fn score(model: &ErrorModel, pool: &Dataset, train: &[usize]) -> f64 {
    let mut held = vec![true; pool.len()];
    for &i in train {
        held[i] = false;
    }
    let rows: Vec<usize> = (0..pool.len()).filter(|&i| held[i]).collect();
    mean_3d_on(model, pool, &rows)
}

/// A held-out row within this many degrees of a chosen pose on every
/// joint repeats that configuration (586 of series B's 1 495 rows have
/// another row within 0.1°).
const REPEAT_DEG: f64 = 0.1;

/// Mean 3D error of `model` on the pool rows not in `train` that repeat
/// no configuration of `train` ([`REPEAT_DEG`]): new poses only.
fn score_new(model: &ErrorModel, pool: &Dataset, train: &[usize]) -> f64 {
    let repeats = |i: usize| {
        train.iter().any(|&t| {
            pool.q[i]
                .iter()
                .zip(&pool.q[t])
                .all(|(a, b)| (a - b).abs() < REPEAT_DEG)
        })
    };
    let rows: Vec<usize> = (0..pool.len()).filter(|&i| !repeats(i)).collect();
    mean_3d_on(model, pool, &rows)
}

fn pool_poses(pool: &Dataset) -> PoseSet {
    PoseSet::from(pool)
}

/// The planned sequence: scores at `sizes` (and the plan's seconds per batch).
fn planned(
    robot: &Robot,
    pool: &Dataset,
    sizes: &[usize],
    batch: usize,
    share: bool,
) -> Vec<(usize, f64)> {
    let mut chosen: Vec<usize> = Vec::new();
    let mut out = Vec::new();
    let max = *sizes.iter().max().unwrap();
    // (measured, forecast at measured + batch, measured there, the same
    // on new poses only, CV now)
    let mut forecasts: Vec<(usize, f64, f64, f64, f64)> = Vec::new();
    while chosen.len() < max {
        let campaign = (!chosen.is_empty()).then(|| pool.select(&chosen));
        // the region is what the score is taken on: the pool's poses not
        // measured yet (a measured pose's error is the noise, and it is
        // not scored). It still holds the batch about to be measured,
        // which the score one batch later leaves out: the forecast there
        // reads a little low (the batch is 50 of the 700–2 700 poses left)
        let rest: Vec<usize> = (0..pool.len()).filter(|i| !chosen.contains(i)).collect();
        let region = Region::Poses(pool_poses(&pool.select(&rest)));
        let t0 = Instant::now();
        let params = PlanParams::new(batch)
            .first_batch(batch)
            .calibration_share(share)
            .check()
            .unwrap();
        let plan = params
            .plan(&PlanInputs {
                robot,
                campaign: campaign.as_ref(),
                prior: None,
                pool: Some(pool),
                region: &region,
            })
            .unwrap();
        eprintln!(
            "  {} measured: batch of {} in {:.1} s ({:?})",
            chosen.len(),
            plan.chosen.len(),
            t0.elapsed().as_secs_f64(),
            plan.source
        );
        if let Some(model) = plan.model.as_ref() {
            let now = score(model, pool, &chosen);
            if sizes.contains(&chosen.len()) {
                out.push((chosen.len(), now));
            }
            let f =
                Forecast::new(&plan, robot, campaign.as_ref().unwrap(), &Cancel::new()).unwrap();
            if let Some(prev) = forecasts.last_mut() {
                prev.2 = now;
                prev.3 = score_new(model, pool, &chosen);
            }
            forecasts.push((
                chosen.len(),
                f.mean_3d[plan.chosen.len()],
                f64::NAN,
                f64::NAN,
                f.cv_mean_3d,
            ));
        }
        chosen.extend(&plan.chosen);
    }
    let model = default_model(robot, &pool.select(&chosen));
    let last = score(&model, pool, &chosen);
    if sizes.contains(&chosen.len()) {
        out.push((chosen.len(), last));
    }
    if let Some(prev) = forecasts.last_mut() {
        prev.2 = last;
        prev.3 = score_new(&model, pool, &chosen);
    }
    let what = if share {
        "IMSE of the Kriging outputs and the calibration"
    } else {
        "IMSE of the Kriging outputs alone"
    };
    println!("\nplanned by the {what}:\n");
    println!(
        "| measured m | CV mean 3D at m | forecast at m + {batch} | held-out at m + {batch} | forecast / held-out | held-out, new poses | forecast / new |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (m, f, h, hn, cv) in &forecasts {
        println!(
            "| {m} | {cv:.4} | {f:.4} | {h:.4} | {:.3} | {hn:.4} | {:.3} |",
            f / h,
            f / hn
        );
    }
    out
}

fn random(robot: &Robot, pool: &Dataset, n: usize, seed: u64) -> f64 {
    let mut rng = robokrige::stats::rng_for(seed, "plan-pool-random");
    let mut rows: Vec<usize> = (0..pool.len()).collect();
    for i in (1..rows.len()).rev() {
        let j = rand::RngExt::random_range(&mut rng, 0..=i);
        rows.swap(i, j);
    }
    rows.truncate(n);
    let model = default_model(robot, &pool.select(&rows));
    score(&model, pool, &rows)
}

fn mean_sd(v: &[f64]) -> (f64, f64) {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    let s = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len().max(2) - 1) as f64).sqrt();
    (m, s)
}

fn arg<'a>(args: &'a [String], name: &str) -> Option<&'a str> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(String::as_str)
}

fn timing() {
    use robokrige::sim::{CampaignKind, CampaignSpec, ErrorProfile, TrueRobot};
    let nominal = kinematics::preset("ur10").unwrap();
    let truth = TrueRobot::draw(&nominal, &ErrorProfile::for_robot(&nominal), 7);
    let mut spec = CampaignSpec::new(CampaignKind::Lhs, 7);
    spec.poses = 400;
    let campaign = robokrige::sim::campaign::measurements(&truth, &spec).unwrap();
    let t0 = Instant::now();
    let plan = PlanParams::new(50)
        .candidates(10_000)
        .check()
        .unwrap()
        .plan(&PlanInputs {
            robot: &nominal,
            campaign: Some(&campaign),
            prior: None,
            pool: None,
            region: &Region::WorkRange,
        })
        .unwrap();
    let planned = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let f = Forecast::new(&plan, &nominal, &campaign, &Cancel::new()).unwrap();
    println!(
        "one batch of {} from {} candidates, 400 measured, 1000 region points: {planned:.2} s \
         (fit included); its forecast {:.2} s ({:.4} mm now over the region); {:.2} s in all",
        plan.chosen.len(),
        plan.candidates,
        t1.elapsed().as_secs_f64(),
        f.now_mean_3d(),
        t0.elapsed().as_secs_f64()
    );
}

/// Mean 3D error (mm) of the circle run on the true robot with its
/// commands compensated by `model` (the library's compensation and
/// evaluation, as `robokrige evaluate`: from home), averaged over the noise
/// seeds 1–5 of the run: a single run's tracker noise moves it by a few µm.
/// The compensation is computed once; only the runs differ.
fn circle_error(
    truth: &robokrige::sim::Truth,
    model: &ErrorModel,
    circle: &robokrige::trajectory::Trajectory,
) -> f64 {
    let robot = &truth.robot.nominal;
    let targets = robokrige::study::Targets::from_trajectory(circle.clone());
    let opts = targets.compensation_options(&robot.home);
    let commands = robokrige::compensate::compensate(robot, model, circle, &opts)
        .unwrap()
        .commands;
    let truth_path = Path::new("comau_circle.truth.json");
    let errors: Vec<f64> = (1..=5)
        .map(|seed| {
            let (evaluation, _) = robokrige::study::evaluate(
                truth_path,
                truth,
                &targets,
                &commands,
                &robot.home,
                seed,
            )
            .unwrap();
            evaluation.after.mean_abs_mm
        })
        .collect();
    errors.iter().sum::<f64>() / errors.len() as f64
}

fn circle() {
    use robokrige::sim::{CampaignKind, CampaignSpec, Truth};
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets");
    let truth: Truth =
        serde_json::from_str(&std::fs::read_to_string(d.join("comau_circle.truth.json")).unwrap())
            .unwrap();
    let robot = truth.robot.nominal.clone();
    let task = robokrige::trajectory::Trajectory::read_csv(&d.join("comau_circle.csv")).unwrap();
    let region = Region::from_file(&d.join("comau_circle.csv"), &robot).unwrap();
    let plan = |campaign: Option<&Dataset>, n: usize| {
        PlanParams::new(n)
            .first_batch(n)
            .check()
            .unwrap()
            .plan(&PlanInputs {
                robot: &robot,
                campaign,
                prior: None,
                pool: None,
                region: &region,
            })
            .unwrap()
    };
    let measure = |moves: &[robokrige::plan::PlannedMove]| {
        let q: Vec<Vec<f64>> = moves.iter().map(|m| m.q.clone()).collect();
        let flags: Vec<bool> = moves.iter().map(|m| m.measure).collect();
        robokrige::sim::iso_cubes::measure_sequence(&truth.robot, &q, &flags, "<plan>", 21).unwrap()
    };
    let first = plan(None, 50);
    let second = plan(Some(&measure(&first.moves)), 50);
    let all: Vec<_> = first.moves.iter().chain(&second.moves).cloned().collect();
    let campaign = measure(&all);
    let planned = circle_error(&truth, &default_model(&robot, &campaign), &task);
    println!(
        "planned 50 + 50 ({} poses measured): compensated circle {planned:.4} mm",
        campaign.len()
    );
    for size in [100, 300] {
        let errors: Vec<String> = (33..36)
            .map(|seed| {
                let mut spec = CampaignSpec::new(CampaignKind::Lhs, seed);
                spec.poses = size;
                let lhs = robokrige::sim::campaign::measurements(&truth.robot, &spec).unwrap();
                format!(
                    "{:.4}",
                    circle_error(&truth, &default_model(&robot, &lhs), &task)
                )
            })
            .collect();
        println!(
            "Latin hypercube {size} (seeds 33, 34, 35): compensated circle {} mm",
            errors.join(" / ")
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--timing") {
        timing();
        return;
    }
    if args.iter().any(|a| a == "--circle") {
        circle();
        return;
    }
    let which = if args.iter().any(|a| a == "b") {
        "b_joint_configurations"
    } else {
        "c_random_poses"
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("../shared/data/ipa-ur10/series_{which}.csv"));
    if !path.exists() {
        eprintln!("skipped: {} not found", path.display());
        return;
    }
    let sizes: Vec<usize> = arg(&args, "--sizes")
        .unwrap_or("100,200,400,800")
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect();
    let seeds: u64 = arg(&args, "--seeds").map_or(10, |s| s.parse().unwrap());
    let batch: usize = arg(&args, "--batch").map_or(50, |s| s.parse().unwrap());
    let pool = read_csv(&path).unwrap();
    let robot = robot();
    println!(
        "pool: series {which} ({} poses), batches of {batch}",
        pool.len()
    );
    let plan = planned(&robot, &pool, &sizes, batch, true);
    if args.iter().any(|a| a == "--forecast-only") {
        return;
    }
    let plan_k = planned(&robot, &pool, &sizes, batch, false);
    let ranges: Vec<(f64, f64)> = (0..robot.dof())
        .map(|j| {
            let col = pool.q.iter().map(|q| q[j]);
            (
                col.clone().fold(f64::INFINITY, f64::min),
                col.fold(f64::NEG_INFINITY, f64::max),
            )
        })
        .collect();
    let mm = candidates::maximin(
        &pool_poses(&pool),
        &PoseSet::default(),
        &ranges,
        *sizes.iter().max().unwrap(),
    );
    println!(
        "\n| N | planned | planned, Kriging IMSE alone | random N (mean ± sd, {seeds} seeds) | random 2N | maximin |"
    );
    println!("|---|---|---|---|---|---|");
    let mut curves: [Vec<(f64, f64)>; 5] = Default::default();
    for ((n, p), (_, pk)) in plan.into_iter().zip(plan_k) {
        let r: Vec<f64> = (0..seeds).map(|s| random(&robot, &pool, n, s)).collect();
        let r2: Vec<f64> = if 2 * n < pool.len() {
            (0..seeds)
                .map(|s| random(&robot, &pool, 2 * n, s))
                .collect()
        } else {
            Vec::new()
        };
        let m = default_model(&robot, &pool.select(&mm[..n]));
        let (rm, rs) = mean_sd(&r);
        let r2s = if r2.is_empty() {
            "-".into()
        } else {
            let (a, b) = mean_sd(&r2);
            curves[3].push(((2 * n) as f64, a));
            format!("{a:.4} ± {b:.4}")
        };
        let mx = score(&m, &pool, &mm[..n]);
        println!("| {n} | {p:.4} | {pk:.4} | {rm:.4} ± {rs:.4} | {r2s} | {mx:.4} |");
        curves[0].push((n as f64, p));
        curves[1].push((n as f64, pk));
        curves[2].push((n as f64, rm));
        curves[4].push((n as f64, mx));
    }
    if let Some(svg) = arg(&args, "--svg") {
        learning_curves(Path::new(svg), which, curves);
    }
}

/// The learning curves as an SVG: held-out error against poses measured.
fn learning_curves(path: &Path, which: &str, curves: [Vec<(f64, f64)>; 5]) {
    use robokrige::plot::{Labels, Series, xy_plot};
    let [planned, kriging, random, random2, maximin] = curves;
    let mut random_all = random;
    random_all.extend(random2);
    random_all.sort_by(|a, b| a.0.total_cmp(&b.0));
    random_all.dedup_by(|a, b| a.0 == b.0);
    let series = [
        Series::line("planned (IMSE, Kriging + calibration)", planned),
        Series::line("planned (IMSE, Kriging alone)", kriging),
        Series::line("random subsets (mean over seeds)", random_all),
        Series::line("maximin subset", maximin),
    ];
    let title = format!(
        "UR10 series {}: held-out error of the calibrated model",
        &which[..1].to_uppercase()
    );
    let labels = Labels {
        title: &title,
        x: "poses measured",
        y: "mean 3D error on the rest of the pool (mm)",
    };
    xy_plot(path, &labels, &series, false).unwrap();
    eprintln!("learning curves: {}", path.display());
}
