//! The campaign planner end to end on a simulated robot: plan → measure the
//! plan on the true robot → fit → compensate a task, against a Latin
//! hypercube campaign of the same size.

use robokrige::compensate::{CompensationOptions, compensate};
use robokrige::dataset::Dataset;
use robokrige::kinematics::Robot;
use robokrige::methods::default_params;
use robokrige::model::ErrorModel;
use robokrige::plan::{PlanInputs, PlanParams, Region};
use robokrige::sim::iso_cubes::measure_sequence;
use robokrige::sim::{CampaignKind, CampaignSpec, Truth, execute, rng_for};
use robokrige::stats::position_error_table;
use robokrige::trajectory::Trajectory;
use std::path::{Path, PathBuf};

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("datasets")
        .join(name)
}

/// `params`' plan for `robot` and `region`, continuing `campaign`, choosing
/// among `pool`'s poses when given (no prior).
fn plan_with(
    params: PlanParams,
    robot: &Robot,
    campaign: Option<&Dataset>,
    pool: Option<&Dataset>,
    region: &Region,
) -> robokrige::plan::Plan {
    params
        .check()
        .unwrap()
        .plan(&PlanInputs {
            robot,
            campaign,
            prior: None,
            pool,
            region,
        })
        .unwrap()
}

fn default_model(robot: &Robot, data: &Dataset) -> ErrorModel {
    default_params(robot, data)
        .unwrap()
        .check()
        .unwrap()
        .fit(data)
        .unwrap()
}

/// Mean 3D error of the circle run on the true robot with the commands
/// compensated by `model`.
fn circle_error(truth: &Truth, model: &ErrorModel, circle: &Trajectory) -> f64 {
    let robot = &truth.robot.nominal;
    let commands = compensate(robot, model, circle, &CompensationOptions::default())
        .unwrap()
        .commands;
    let mut rng = rng_for(5, "plan-test");
    let ex = execute(
        &truth.robot,
        &commands,
        &robot.home,
        None,
        &truth.spec.effects,
        &mut rng,
    )
    .unwrap();
    let e: Vec<[f64; 3]> = ex
        .measured
        .iter()
        .zip(&circle.poses)
        .map(|(m, p)| std::array::from_fn(|a| m[a] - p.translation.vector[a]))
        .collect();
    position_error_table(&e).mean_abs_mm
}

#[test]
fn a_planned_campaign_for_the_task_beats_a_latin_hypercube_of_the_same_size() {
    let truth: Truth =
        serde_json::from_str(&std::fs::read_to_string(shipped("comau_circle.truth.json")).unwrap())
            .unwrap();
    let robot = truth.robot.nominal.clone();
    let circle = Trajectory::read_csv(&shipped("comau_circle.csv")).unwrap();
    let region = Region::from_file(&shipped("comau_circle.csv"), &robot).unwrap();
    let plan = |campaign: Option<&Dataset>, n: usize| {
        plan_with(
            PlanParams::new(n)
                .first_batch(n)
                .candidates(1500)
                .region_points(72),
            &robot,
            campaign,
            None,
            &region,
        )
    };
    let measure = |moves: &[robokrige::plan::PlannedMove]| {
        let q: Vec<Vec<f64>> = moves.iter().map(|m| m.q.clone()).collect();
        let flags: Vec<bool> = moves.iter().map(|m| m.measure).collect();
        measure_sequence(&truth.robot, &q, &flags, "<plan>", 21).unwrap()
    };
    // a first batch covering the task, measured; then a batch by the model
    let first = plan(None, 40);
    assert_eq!(first.measured_moves().count(), 40);
    let measured = measure(&first.moves);
    let second = plan(Some(&measured), 40);
    assert!(second.imse_curve.len() == 41 && second.imse_curve[40] < second.imse_curve[0]);
    // every measured pose of the plan arrives from its planned side
    let all: Vec<_> = first.moves.iter().chain(&second.moves).cloned().collect();
    let campaign = measure(&all);
    assert_eq!(campaign.len(), 80);
    for (m, d) in all.iter().filter(|m| m.measure).zip(&campaign.dir) {
        assert_eq!(&m.dir, d);
    }
    for p in [&first, &second] {
        assert_eq!(p.unrealised, 0);
        for m in p.measured_moves() {
            assert_eq!(m.dir, p.poses.dir[m.pose.unwrap()]);
        }
    }

    let mut spec = CampaignSpec::new(CampaignKind::Lhs, 33);
    spec.poses = 80;
    let lhs = robokrige::sim::campaign::measurements(&truth.robot, &spec).unwrap();
    let planned = circle_error(&truth, &default_model(&robot, &campaign), &circle);
    let latin = circle_error(&truth, &default_model(&robot, &lhs), &circle);
    eprintln!("circle mean 3D error: planned 80 {planned:.4} mm, LHS 80 {latin:.4} mm");
    assert!(planned <= latin, "planned {planned:.4} vs LHS {latin:.4}");
}

/// The stopping rule on a simulated UR10: 60 Latin-hypercube poses
/// measured, 300 random poses as the region (and the pool). Its error over
/// the region *now* (the forecast before any planned pose) must meet the
/// calibrated model's error on those 300 poses. On such campaigns (seeds
/// 1–4, 400 fresh poses) a CV that holds the calibration and ξ across its
/// folds was 0.57–0.80 of that error; the forecast's CV (everything
/// refitted per fold, then carried to the region by the model's own MSE)
/// 0.85–1.23. Here, seeds 2 and 3: 0.90 and 0.98.
#[test]
fn the_forecast_now_meets_the_error_on_new_poses_and_falls_with_the_plan() {
    use robokrige::plan::stop::{Forecast, Verdict};
    use robokrige::plan::{PoseSet, Region};
    use robokrige::sim::{ErrorProfile, TrueRobot};
    let nominal = robokrige::kinematics::preset("ur10").unwrap();
    for seed in [2, 3] {
        let truth = TrueRobot::draw(&nominal, &ErrorProfile::for_robot(&nominal), seed);
        let mut spec = CampaignSpec::new(CampaignKind::Lhs, seed);
        spec.poses = 60;
        let data = robokrige::sim::campaign::measurements(&truth, &spec).unwrap();
        let mut vs = CampaignSpec::new(CampaignKind::Verify, seed + 100);
        vs.poses = 300;
        let fresh = robokrige::sim::campaign::measurements(&truth, &vs).unwrap();
        let region = Region::Poses(PoseSet::from(&fresh));
        let plan = plan_with(
            PlanParams::new(20),
            &nominal,
            Some(&data),
            Some(&fresh),
            &region,
        );
        let cancel = robokrige::cancel::Cancel::new();
        let f = Forecast::new(&plan, &nominal, &data, &cancel).unwrap();
        // a campaign the plan's model was not fitted on is refused
        let other = fresh.select(&(0..data.len()).collect::<Vec<_>>());
        assert!(Forecast::new(&plan, &nominal, &other, &cancel).is_err());
        let model = plan.model.as_ref().unwrap();
        let p = model.predict_dataset(&fresh).unwrap();
        let residuals: Vec<[f64; 3]> = p
            .mean
            .iter()
            .zip(fresh.errors.as_ref().unwrap())
            .map(|(a, b)| std::array::from_fn(|k| b[k] - a[k]))
            .collect();
        let held = position_error_table(&residuals).mean_abs_mm;
        let now = f.now_mean_3d();
        eprintln!(
            "seed {seed}: forecast now {now:.4} mm (CV {:.4}, ρ {:.3}), new poses {held:.4} mm",
            f.cv_mean_3d, f.region_ratio
        );
        assert!(
            (0.75..1.35).contains(&(now / held)),
            "forecast {now:.4} vs {held:.4}"
        );
        // it falls with the plan's poses and stays above the floor
        assert_eq!(f.mean_3d.len(), plan.imse_curve.len());
        assert!(f.mean_3d.windows(2).all(|w| w[1] <= w[0]));
        let after = *f.mean_3d.last().unwrap();
        assert!(after < now && after > f.floor_mean_3d);
        // the verdicts
        assert_eq!(f.verdict(now * 1.01), Verdict::Met);
        // below the floor: unreachable, unless the model did not measure
        // its noise (a floor of about 0), when no target is called so
        eprintln!(
            "floor {:.5} mm, measured: {}",
            f.floor_mean_3d, f.floor_identified
        );
        let below = if f.floor_identified {
            Verdict::Unreachable
        } else {
            Verdict::BeyondPlan
        };
        assert_eq!(f.verdict(f.floor_mean_3d * 0.99), below);
        let k = f.mean_3d.iter().position(|v| *v <= after).unwrap();
        assert_eq!(f.verdict(after), Verdict::After(k));
        assert_eq!(
            f.verdict((after + f.floor_mean_3d) / 2.0),
            Verdict::BeyondPlan
        );
    }
}

/// A pool's poses the plan cannot use, and a budget it cannot fill, are
/// said in its notes (they were left out silently).
#[test]
fn a_plan_says_which_pool_poses_it_left_out_and_when_it_plans_fewer() {
    let robot = robokrige::kinematics::preset("comau-nj220").unwrap();
    let mut pool = robokrige::dataset::read_csv(&shipped("comau_verify.csv"))
        .unwrap()
        .head(20);
    // three poses beyond q2's upper limit
    let hi = robot.limits[1].1;
    for q in pool.q.iter_mut().take(3) {
        q[1] = hi + 5.0;
    }
    let region = Region::from_options(None, Some(&pool), &robot).unwrap();
    let plan = plan_with(PlanParams::new(50), &robot, None, Some(&pool), &region);
    let notes = plan.notes.join("\n");
    assert!(
        notes.contains("3 of the pool's poses outside the robot's joint limits"),
        "{notes}"
    );
    assert!(notes.contains("planned 17 of 50 poses"), "{notes}");
    assert_eq!(plan.chosen.len(), 17);
}

#[test]
fn a_plan_says_when_its_pre_position_moves_go_to_a_hard_limit() {
    let robot = robokrige::kinematics::preset("comau-nj220").unwrap();
    let region = Region::from_options(None, None, &robot).unwrap();
    let notes_with = |step: f64| {
        plan_with(
            PlanParams::new(12)
                .via_step(step)
                .candidates(300)
                .region_points(100),
            &robot,
            None,
            None,
            &region,
        )
        .notes
        .join("\n")
    };
    let limit = "go to a joint's hard limit";
    assert!(!notes_with(5.0).contains(limit), "{}", notes_with(5.0));
    let wide = notes_with(500.0);
    assert!(
        wide.contains(limit) && wide.contains("--via-step 500°"),
        "{wide}"
    );
}

/// In passes over the region the order of a plan follows the joint space
/// less than in one tour of the same poses, each pass a run of the poses
/// in the order chosen; the plan says how far it does, and a plan whose
/// tour follows it says so with the way out.
#[test]
fn a_plan_in_passes_keeps_its_order_from_following_the_joint_space() {
    let robot = robokrige::kinematics::preset("ur10").unwrap();
    let region = Region::from_options(None, None, &robot).unwrap();
    let plan = |passes: usize| {
        plan_with(
            PlanParams::new(150)
                .first_batch(150)
                .candidates(1500)
                .region_points(300)
                .passes(passes),
            &robot,
            None,
            None,
            &region,
        )
    };
    let (one, three) = (plan(1), plan(3));
    assert_eq!((one.passes, three.passes), (1, 3));
    assert_eq!(one.chosen, three.chosen);
    let (o1, o3) = (
        one.order_in_joint_space.clone().unwrap(),
        three.order_in_joint_space.clone().unwrap(),
    );
    assert!(
        o1.order_correlation > o3.order_correlation + 0.2,
        "{o1:?} {o3:?}"
    );
    // the passes are the runs 0..50, 50..100, 100..150 of the poses chosen
    let runs: Vec<usize> = three
        .moves
        .iter()
        .filter_map(|m| m.pose)
        .map(|i| i / 50)
        .collect();
    assert!(runs.windows(2).all(|w| w[0] <= w[1]) && runs.len() == 150);
    let note = |p: &robokrige::plan::Plan| {
        p.notes
            .iter()
            .any(|n| n.contains("the order planned follows"))
    };
    assert_eq!(note(&one), o1.matters());
    assert_eq!(note(&three), o3.matters());
    assert!(o1.matters(), "{o1:?}");
    assert!(
        one.notes
            .iter()
            .any(|n| n.contains("--passes K") && n.contains("from measured pose")),
        "{:?}",
        one.notes
    );
    assert!(
        PlanParams::new(10).passes(0).check().is_err(),
        "no pass is refused"
    );
}
