//! `diagnose`: an undeclared effect is found, ranked first and added; a
//! control campaign reports nothing significant; features and the statistics
//! behave.

mod common;

use robokrige::diagnose::{DiagnoseOptions, EffectKind, diagnose};
use robokrige::features::Feature;
use robokrige::kinematics;
use robokrige::kriging::{KrigingOptions, OptimizerKind};
use robokrige::model::ErrorModel;
use robokrige::params::ErrorModelParams;
use robokrige::sim::{CampaignKind, CampaignSpec, Effect, SimOutput, simulate};
use robokrige::space::Space;
use robokrige::{Error, dataset::Dataset};

fn campaign(rows: usize, seed: u64, effect: Option<&str>) -> Dataset {
    let robot = kinematics::preset("comau-nj220").unwrap();
    let mut spec = CampaignSpec::new(CampaignKind::Lhs, seed);
    spec.poses = rows;
    spec.effects = effect
        .map(|e| vec![Effect::parse(e).unwrap()])
        .unwrap_or_default();
    match simulate(&robot, &spec).unwrap().0 {
        SimOutput::Measurements(d) => d,
        SimOutput::Trajectory(_) => unreachable!(),
    }
}

fn quick() -> DiagnoseOptions {
    common::quick_diagnose()
}

#[test]
fn a_tracker_bump_is_found_at_its_row_added_and_removed_from_the_residual() {
    let data = campaign(160, 4, Some("tracker-step:row=80,dx=0.2,dy=-0.15,dz=0.15"));
    let d = diagnose(&data, &quick(), &|_| {}).unwrap();
    let top = &d.effects[0];
    assert_eq!(top.kind, EffectKind::Order, "{top:?}");
    let row = top.params["row"];
    assert!((row - 80.0).abs() <= 2.0, "step found at row {row}");
    assert!(top.significant && top.accepted && top.p_value < 0.01);
    assert_eq!(d.extras.len(), 1);
    assert!(matches!(d.extras[0], Feature::Step { .. }));
    assert!(
        d.after.pooled_rmse_mm < 0.7 * d.before.pooled_rmse_mm,
        "{:?} → {:?}",
        d.before.cv_rmse_mm,
        d.after.cv_rmse_mm
    );
    // the report is reproducible
    let again = diagnose(&data, &quick(), &|_| {}).unwrap();
    assert_eq!(
        serde_json::to_string(&again.effects).unwrap(),
        serde_json::to_string(&d.effects).unwrap()
    );
}

/// Above `refit_rows` (a whole campaign) every CV is closed-form and every
/// fit converges ξ on one seeded subset: the same step is found, at the
/// same row, and the report says which CV it used.
#[test]
fn a_campaign_above_refit_rows_is_diagnosed_with_closed_form_cv() {
    let data = campaign(160, 4, Some("tracker-step:row=80,dx=0.2,dy=-0.15,dz=0.15"));
    let o = quick()
        .kriging(KrigingOptions::default())
        .refit_rows(100)
        .max_effects(1);
    let d = diagnose(&data, &o, &|_| {}).unwrap();
    assert_eq!(d.cv_mode(), robokrige::cv::CvMode::ClosedForm);
    let top = &d.effects[0];
    assert_eq!(top.kind, EffectKind::Order, "{top:?}");
    assert!((top.params["row"] - 80.0).abs() <= 2.0, "{top:?}");
    assert!(top.accepted);
    assert!(d.after.pooled_rmse_mm < 0.7 * d.before.pooled_rmse_mm);
    // below it, the same campaign is refitted per fold
    let refit = diagnose(&data, &o.clone().refit_rows(1000), &|_| {}).unwrap();
    assert_eq!(refit.cv_mode(), robokrige::cv::CvMode::Refit);
    assert_eq!(refit.effects[0].params["row"], top.params["row"]);
}

#[test]
fn a_gear_harmonic_absorbed_by_the_gp_is_still_found_and_added_as_trend_terms() {
    // the GP shortens its q2 length scale to soak the harmonic up; tested at
    // the ξ it would have with the harmonic, the effect stands out
    let data = campaign(
        200,
        2,
        Some("harmonic:joint=2,period_deg=7.5,amp_deg=0.004"),
    );
    let d = diagnose(&data, &quick(), &|_| {}).unwrap();
    let top = &d.effects[0];
    assert_eq!(top.kind, EffectKind::Harmonic, "{top:?}");
    assert_eq!(top.source, ["q2"]);
    let p = top.params["period_deg"];
    assert!((p / 7.5 - 1.0).abs() < 0.05, "period {p}");
    assert!(top.significant && top.accepted && top.refit_xi, "{top:?}");
    assert!(matches!(d.extras[0], Feature::Harmonic { joint: 2, .. }));
    assert!(d.extras[0].trend_only());
    assert!(
        d.after.pooled_rmse_mm < 0.75 * d.before.pooled_rmse_mm,
        "{:?} → {:?}",
        d.before.cv_rmse_mm,
        d.after.cv_rmse_mm
    );
}

/// A gear harmonic is a deviation of the joint: at the TCP it is the
/// harmonic times the Jacobian, which varies over the campaign. With the
/// robot, the harmonic through the Jacobian is a candidate of its own, at
/// the same periods, and it finds the gear's period too; its columns are
/// the Jacobian's times sin/cos.
#[test]
fn a_gear_harmonic_is_a_candidate_through_the_jacobian_with_the_robot() {
    let robot = kinematics::preset("comau-nj220").unwrap();
    let data = campaign(
        200,
        2,
        Some("harmonic:joint=2,period_deg=7.5,amp_deg=0.004"),
    );
    let o = quick().robot(Some(robot.clone()));
    let d = diagnose(&data, &o, &|_| {}).unwrap();
    let top = &d.effects[0];
    assert_eq!(top.kind, EffectKind::Harmonic, "{top:?}");
    assert_eq!(top.source, ["q2"]);
    assert!(
        (top.params["period_deg"] / 7.5 - 1.0).abs() < 0.05,
        "{top:?}"
    );
    assert!(top.accepted, "{top:?}");
    let jacobian = d
        .effects
        .iter()
        .find(|e| e.label == "harmonic of q2 (via the Jacobian)")
        .expect("the Jacobian harmonic of q2 is reported");
    let p = jacobian.params["period_deg"];
    assert!((p / 7.5 - 1.0).abs() < 0.05, "{jacobian:?}");
    assert!(jacobian.p_value < 0.01, "{jacobian:?}");
    // the period is resolved between the scanned ones: its interval holds
    // the planted period
    let [lo, hi] = jacobian.params_ci["period_deg"];
    assert!(lo <= 7.5 && 7.5 <= hi, "{jacobian:?}");
    // its phase is counted from q2's mean on the campaign
    let mean = data.q.iter().map(|r| r[1]).sum::<f64>() / data.len() as f64;
    match &jacobian.add[..] {
        [Feature::HarmonicJacobian { centre_deg, .. }] => {
            assert!((centre_deg - mean).abs() <= 0.005, "{centre_deg} {mean}")
        }
        other => panic!("{other:?}"),
    }
    // its columns: ∂P/∂θ₂ times sin and cos of 2π (θ₂ − c) / P
    let c = 12.5;
    let f = Feature::HarmonicJacobian {
        robot: Box::new(robot.clone()),
        joint: 2,
        period_deg: p,
        centre_deg: c,
    };
    assert!(f.trend_only());
    let f_names = f.names();
    let cols = f.columns_from_poses(&data.q, &data.dir).unwrap();
    assert_eq!(cols.len(), 6);
    for i in [0, 77, 199] {
        let jac = robot.position_jacobian(&data.q[i]).unwrap();
        let th = std::f64::consts::TAU * (data.q[i][1] - c) / p;
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * (1.0 + y.abs());
        for a in 0..3 {
            assert!(close(cols[a][i], jac[(a, 1)] * th.sin()), "row {i}");
            assert!(close(cols[3 + a][i], jac[(a, 1)] * th.cos()), "row {i}");
        }
    }
    assert!(d.after.pooled_rmse_mm < 0.75 * d.before.pooled_rmse_mm);
    // a model with it is saved with its robot and predicts the same back
    let m = ErrorModelParams::new()
        .space(Space::Ejs)
        .kriging(
            KrigingOptions::default()
                .optimizer(OptimizerKind::HookeJeeves)
                .max_evals(100),
        )
        .extras(vec![f])
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap();
    // each axis's trend has its own row of the Jacobian only
    for (name, axis) in f_names.iter().zip([0, 1, 2, 0, 1, 2]) {
        let c = m.trend_coefficient(name).unwrap();
        for (a, (b, se)) in c.iter().enumerate() {
            assert_eq!(a == axis, *se > 0.0, "{name} on axis {a}: {c:?}");
            assert_eq!(a == axis, *b != 0.0, "{name} on axis {a}: {c:?}");
        }
    }
    let back = ErrorModel::from_json(&serde_json::to_string(&m).unwrap(), "m.json").unwrap();
    assert_eq!(back.extras(), m.extras());
    assert_eq!(
        back.predict_mean(&data.q, &data.dir).unwrap(),
        m.predict_mean(&data.q, &data.dir).unwrap()
    );
}

#[test]
fn hysteresis_after_reversals_is_traced_to_the_travel_since_the_reversal() {
    let data = campaign(
        200,
        3,
        Some("hysteresis:joint=2,amp_deg=0.01,travel_deg=20"),
    );
    let d = diagnose(&data, &quick(), &|_| {}).unwrap();
    let top = &d.effects[0];
    assert_eq!(top.kind, EffectKind::DirectionHistory, "{top:?}");
    assert_eq!(top.source, ["dir2"]);
    assert!(top.significant && top.accepted, "{top:?}");
    assert!(matches!(d.extras[0], Feature::SinceReversal { joint: 2 }));
    assert!(d.after.pooled_rmse_mm < 0.8 * d.before.pooled_rmse_mm);
}

#[test]
fn a_control_campaign_reports_no_significant_effect() {
    let data = campaign(160, 4, None);
    let d = diagnose(&data, &quick(), &|_| {}).unwrap();
    let sig: Vec<_> = d.effects.iter().filter(|e| e.significant).collect();
    assert!(sig.is_empty(), "{sig:?}");
    assert!(d.steps.is_empty() && d.extras.is_empty());
    assert_eq!(d.before, d.after);
    // every family was tested once, with p-values in (0, 1]; the motion
    // history and the generic search are among them, and the resamples
    // were raised so that a lone effect could have been significant
    assert!(d.effects.len() > 30);
    assert_eq!(d.candidates[0], d.effects.len());
    assert!(
        d.effects
            .iter()
            .any(|e| e.kind == EffectKind::MotionHistory)
    );
    assert!(d.permutations >= robokrige::diagnose::min_resamples(d.candidates[0], 0.05));
    assert!(d.candidates[1] > d.candidates[0]);
    assert!(
        d.effects
            .iter()
            .all(|e| e.p_value > 0.0 && e.p_value <= 1.0 && e.round == 1)
    );
}

/// A campaign measured in a random order has no note on its order; the
/// same poses measured joint by joint (sorted by q1, so that the order
/// follows the joint space) have one, in the report as in the JSON.
#[test]
fn a_campaign_measured_region_by_region_says_its_order_effects_are_pose_effects() {
    use robokrige::report::diagnose::{Names, summary};
    let data = campaign(160, 4, None);
    let names = Names {
        data: "c.csv".as_ref(),
        method: "ejs",
    };
    let d = diagnose(&data, &quick(), &|_| {}).unwrap();
    let o = d.order_in_joint_space.as_ref().unwrap();
    assert!(!o.matters(), "{o:?}");
    assert!(!summary(&d, names).contains("not separable on this campaign: a step"));
    let mut by_q1: Vec<usize> = (0..data.len()).collect();
    by_q1.sort_by(|&a, &b| data.q[a][0].total_cmp(&data.q[b][0]));
    let d = diagnose(&data.select(&by_q1), &quick(), &|_| {}).unwrap();
    let o = d.order_in_joint_space.as_ref().unwrap();
    assert!(
        o.order_correlation > 0.8 && o.regional_steps() > o.scanned / 2,
        "{o:?}"
    );
    let text = summary(&d, names);
    assert!(
        text.contains("not separable on this campaign: a step at rows")
            && text.contains("measuring in a random order separates them"),
        "{text}"
    );
    let json = serde_json::to_value(&d).unwrap();
    assert!(
        json["order_in_joint_space"]["step_rows"].is_array(),
        "{json}"
    );
}

#[test]
fn a_model_with_extra_inputs_round_trips_and_predicts_from_poses() {
    let data = campaign(80, 5, Some("payload:kg=0/60/120"));
    let extras = vec![
        Feature::Covariate {
            name: "payload_kg".into(),
            reference: Some(0.0),
        },
        Feature::Harmonic {
            joint: 2,
            period_deg: 7.5,
            centre_deg: 0.0,
        },
        Feature::SinceReversal { joint: 3 },
    ];
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(200);
    let m = ErrorModelParams::new()
        .space(Space::Ejs)
        .kriging(opts.clone())
        .extras(extras.clone())
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap();
    assert_eq!(m.input_names().len(), 12 + 4);
    // correlation inputs first; the harmonic is trend-only (ξ = 0 on its two columns)
    let stored = vec![extras[0].clone(), extras[2].clone(), extras[1].clone()];
    assert_eq!(m.extras(), stored);
    assert_eq!(m.correlation_dims(), 14);
    for o in m.outputs() {
        assert_eq!(o.data().theta().len(), 16);
        assert!(o.data().theta()[14..].iter().all(|t| *t == 0.0));
        assert!(o.data().theta()[..14].iter().all(|t| *t > 0.0));
    }
    let back = ErrorModel::from_json(&serde_json::to_string(&m).unwrap(), "m.json").unwrap();
    assert_eq!(back.extras(), stored);
    // from the dataset the payload column is used; from poses its reference 0
    let a = m.predict_dataset(&data).unwrap().mean;
    let b = m.predict(&data.q, &data.dir).unwrap().mean;
    let first_block = data
        .covariate("payload_kg")
        .unwrap()
        .values
        .iter()
        .take_while(|v| **v == 0.0)
        .count();
    assert!(first_block > 0);
    for k in 0..first_block {
        for ax in 0..3 {
            assert!((a[k][ax] - b[k][ax]).abs() < 1e-9);
        }
    }
    // a missing covariate without a reference is a clear error
    let no_ref = vec![Feature::Covariate {
        name: "payload_kg".into(),
        reference: None,
    }];
    let m2 = ErrorModelParams::new()
        .space(Space::Ejs)
        .kriging(opts.clone())
        .extras(no_ref)
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap();
    let err = m2.predict(&data.q, &data.dir).unwrap_err();
    assert!(err.to_string().contains("payload_kg"), "{err}");
    // a joint out of range is rejected
    let bad = vec![Feature::Harmonic {
        joint: 9,
        period_deg: 5.0,
        centre_deg: 0.0,
    }];
    assert!(matches!(
        ErrorModelParams::new()
            .space(Space::Ejs)
            .kriging(opts.clone())
            .extras(bad)
            .check()
            .and_then(|p| p.fit(&data)),
        Err(Error::InvalidParameter(_))
    ));
}

#[test]
fn direction_history_features_follow_the_sequence() {
    let q = vec![
        vec![0.0],
        vec![1.0],
        vec![3.0],
        vec![2.0],
        vec![2.0],
        vec![5.0],
    ];
    let dir = robokrige::space::derive_directions(&q, None);
    let prev = Feature::PreviousDirection { joint: 1 }
        .columns_from_poses(&q, &dir)
        .unwrap();
    assert_eq!(prev[0], vec![1.0, 1.0, 1.0, 1.0, -1.0, -1.0]);
    let travel = Feature::SinceReversal { joint: 1 }
        .columns_from_poses(&q, &dir)
        .unwrap();
    // reversal at row 3 (3 → 2) and again at row 5 (2 → 5); row 4 did not move
    assert_eq!(travel[0], vec![0.0, 1.0, 3.0, 1.0, 1.0, 3.0]);
}

/// Servo lag: an error that depends on how the robot moved into
/// the pose is traced to the joint's moves with the right memory, added as
/// an input, and modelled to the level of the same campaign without it;
/// the improved model predicts along a pose sequence from its order alone.
#[test]
fn a_servo_lag_is_traced_to_the_joints_moves_and_modelled_end_to_end() {
    let data = campaign(200, 1, Some("lag:joint=2,gain=0.0005,tau_poses=0"));
    let o = quick();
    let d = diagnose(&data, &o, &|_| {}).unwrap();
    let top = &d.effects[0];
    assert_eq!(top.kind, EffectKind::MotionHistory, "{top:?}");
    assert_eq!(top.source, ["move2"]);
    assert_eq!(top.params.get("tau_poses"), Some(&0.0), "{top:?}");
    assert!(top.significant && top.accepted, "{top:?}");
    let lag = Feature::Moves {
        joint: 2,
        tau_poses: 0.0,
        clock: None,
    };
    assert_eq!(d.extras[0], lag);
    let check = top.after_check.as_ref().expect("after check");
    assert!(!check.partly, "{check:?}");
    // the same true robot and poses without the lag
    let clean = campaign(200, 1, None);
    let c = diagnose(&clean, &quick().max_effects(0), &|_| {}).unwrap();
    assert!(
        d.before.pooled_rmse_mm > 2.0 * c.before.pooled_rmse_mm,
        "the lag is large: {} vs {}",
        d.before.pooled_rmse_mm,
        c.before.pooled_rmse_mm
    );
    assert!(
        d.after.pooled_rmse_mm < 1.3 * c.before.pooled_rmse_mm,
        "after {} vs without the lag {}",
        d.after.pooled_rmse_mm,
        c.before.pooled_rmse_mm
    );
    // end to end: the improved model, saved and loaded, predicts from the
    // pose order what it predicts from the campaign
    let m = robokrige::diagnose::fit_with_effects(&data, &o, &d.extras).unwrap();
    let back = ErrorModel::from_json(&serde_json::to_string(&m).unwrap(), "m.json").unwrap();
    assert_eq!(back.extras(), d.extras);
    let a = m.predict_dataset(&data).unwrap().mean;
    let b = back.predict(&data.q, &data.dir).unwrap().mean;
    for (x, y) in a.iter().zip(&b) {
        for ax in 0..3 {
            assert!((x[ax] - y[ax]).abs() < 1e-9);
        }
    }
    // and the lag changes the prediction: the same poses in reverse order
    let rq: Vec<Vec<f64>> = data.q.iter().rev().cloned().collect();
    let rd = robokrige::space::derive_directions(&rq, None);
    let r = back.predict(&rq, &rd).unwrap().mean;
    let moved = (1..rq.len())
        .map(|k| (r[k][2] - b[rq.len() - 1 - k][2]).abs())
        .fold(0.0, f64::max);
    assert!(moved > 0.05, "largest change {moved} mm");
}

#[test]
fn motion_history_features_follow_the_sequence() {
    let q: Vec<Vec<f64>> = [0.0, 1.0, 3.0, 2.0, 2.0, 5.0]
        .iter()
        .map(|v| vec![*v, 90.0])
        .collect();
    let dir = robokrige::space::derive_directions(&q, None);
    let col = |f: Feature| f.columns_from_poses(&q, &dir).unwrap();
    let last = Feature::Moves {
        joint: 1,
        tau_poses: 0.0,
        clock: None,
    };
    assert_eq!(col(last.clone())[0], vec![0.0, 1.0, 2.0, -1.0, 0.0, 3.0]);
    let k = (-1.0f64).exp();
    let decayed = col(Feature::Moves {
        joint: 1,
        tau_poses: 1.0,
        clock: None,
    });
    assert!((decayed[0][2] - (2.0 + k)).abs() < 1e-15);
    assert!((decayed[0][3] - (-1.0 + k * (2.0 + k))).abs() < 1e-15);
    assert_eq!(
        col(Feature::MoveSize { joint: 1 })[0],
        vec![0.0, 1.0, 2.0, 1.0, 0.0, 3.0]
    );
    assert_eq!(
        col(Feature::Lagged {
            of: Box::new(last.clone()),
            lag: 1
        })[0],
        vec![0.0, 0.0, 1.0, 2.0, -1.0, 0.0]
    );
    // × joint 2's angle (90°): θ, sin θ = 1, cos θ ≈ 0
    let t = col(Feature::Times {
        of: Box::new(last.clone()),
        joint: 2,
        centre: 0.0,
    });
    assert_eq!(t.len(), 3);
    assert_eq!(t[0][2], 180.0);
    assert!((t[1][2] - 2.0).abs() < 1e-12 && t[2][2].abs() < 1e-12);
    // less a centre: (2 − 0.5)·90°
    let t = col(Feature::Times {
        of: Box::new(last.clone()),
        joint: 2,
        centre: 0.5,
    });
    assert_eq!(t[0][2], 135.0);
    // the TCP move through the robot is 0 for the first row
    let robot = kinematics::preset("comau-nj220").unwrap();
    let q6: Vec<Vec<f64>> = (0..4).map(|i| vec![i as f64 * 5.0; 6]).collect();
    let d6 = robokrige::space::derive_directions(&q6, None);
    let tcp = Feature::TcpMove {
        robot: Box::new(robot.clone()),
    }
    .columns_from_poses(&q6, &d6)
    .unwrap();
    assert_eq!(tcp.len(), 3);
    assert!(tcp.iter().all(|c| c[0] == 0.0) && tcp.iter().any(|c| c[1].abs() > 1.0));
    // the interval of a time column; from poses alone its reference
    let mut data = campaign(30, 2, None);
    let iv = Feature::Interval {
        column: "time_s".into(),
        reference: Some(4.0),
    };
    let t = data.covariate("time_s").unwrap().values.clone();
    let v = iv.columns(&data).unwrap();
    assert_eq!(v[0][0], 4.0);
    assert!((v[0][5] - (t[5] - t[4])).abs() < 1e-12);
    assert_eq!(
        iv.columns_from_poses(&data.q, &data.dir).unwrap()[0],
        vec![4.0; 30]
    );
    data.covariates.retain(|c| c.name != "time_s");
    assert!(iv.columns(&data).is_err());
    // bad features are clear errors
    for bad in [
        Feature::Lagged {
            of: Box::new(last.clone()),
            lag: 0,
        },
        Feature::Times {
            of: Box::new(Feature::Harmonic {
                joint: 1,
                period_deg: 5.0,
                centre_deg: 0.0,
            }),
            joint: 1,
            centre: 0.0,
        },
        Feature::Times {
            of: Box::new(last.clone()),
            joint: 1,
            centre: f64::NAN,
        },
        Feature::Moves {
            joint: 1,
            tau_poses: -1.0,
            clock: None,
        },
        Feature::MoveSize { joint: 3 },
    ] {
        assert!(
            matches!(bad.validate(2), Err(Error::InvalidParameter(_))),
            "{bad:?}"
        );
    }
}

#[test]
fn bad_options_are_errors() {
    let data = campaign(40, 1, None);
    for o in [
        quick().permutations(5),
        quick().fdr(0.0),
        quick().folds(100),
        quick().refit_rows(99),
    ] {
        assert!(diagnose(&data, &o, &|_| {}).is_err());
    }
}

/// A covariate that does not vary over the rows used is left out of the
/// candidates and reported: "temp_c × joint angles" with a
/// constant temp_c is only a joint-angle trend under a wrong name.
#[test]
fn constant_covariates_are_left_out_and_reported() {
    use robokrige::diagnose::scan::{dropped_covariates, families};
    let mut data = campaign(60, 3, None);
    let k = data
        .covariates
        .iter()
        .position(|c| c.name == "temp_c")
        .expect("temp_c column");
    let varying = families(&data, &[], None);
    assert!(varying.iter().any(|f| f.source == ["temp_c"]));
    assert!(dropped_covariates(&data, &[]).is_empty());
    // constant, as in the first 600 rows of UR10 series C
    data.covariates[k].values = vec![21.68; 60];
    let fams = families(&data, &[], None);
    assert!(!fams.iter().any(|f| f.source == ["temp_c"]));
    let dropped = dropped_covariates(&data, &[]);
    assert_eq!(dropped.len(), 1);
    assert!(
        dropped[0].reason.contains("constant (21.68)"),
        "{dropped:?}"
    );
    // nearly constant: an indicator of 3 rows is not a covariate either
    for i in [5, 17, 40] {
        data.covariates[k].values[i] = 22.5;
    }
    assert!(
        !families(&data, &[], None)
            .iter()
            .any(|f| f.source == ["temp_c"])
    );
    assert!(
        dropped_covariates(&data, &[])[0]
            .reason
            .contains("all but 3")
    );
}

/// An effect counts when it lowers the CV RMSE by `min_gain`, or the CV
/// mean square by what that is worth at the model's noise (so that a
/// clear effect does not hide behind an under-fitted base model).
#[test]
fn an_effect_is_worth_adding_by_its_share_or_by_its_size_against_the_noise() {
    use robokrige::diagnose::{Worth, min_resamples};
    let w = Worth::new(0.02, &[0.1, 0.1, 0.1]);
    let floor = w.floor_mse();
    assert!((floor - (1.0 - 0.98f64.powi(2)) * 0.01).abs() < 1e-15);
    // a base far above the noise: 1.5 % of its RMSE is below the share
    // rule, but above the noise floor's worth
    let before = 0.3f64.powi(2);
    let after = (0.3 * 0.985f64).powi(2);
    assert!(before - after < (1.0 - 0.98f64.powi(2)) * before);
    assert!(w.counts(before, after));
    // a tiny drop counts by neither rule, a rise never
    assert!(!w.counts(before, before - 0.5 * floor));
    assert!(!w.counts(before, before + 1.0));
    // at the noise floor the two rules agree
    let at_floor = 0.01;
    assert!(w.counts(at_floor, at_floor * 0.98f64.powi(2) - 1e-12));
    assert!(!w.counts(at_floor, at_floor * 0.985f64.powi(2)));
    // an interpolating model (no nugget) has only the share rule
    let interp = Worth::new(0.02, &[0.0; 3]);
    assert!(!interp.counts(before, after));
    // BH among F candidates: a lone p = 1/(1 + P) must reach q ≤ fdr
    for f in [10usize, 64, 95, 400] {
        let p = min_resamples(f, 0.05);
        assert!(f as f64 / (1.0 + p as f64) <= 0.05);
    }
}

#[test]
fn a_covariate_times_a_joint_angle_does_not_depend_on_the_covariate_offset() {
    // temperature near 22 °C times θ is mostly θ: the candidate must test
    // (and add) the interaction, the same as for the temperature less 22 °C
    let mut data = campaign(80, 3, None);
    data.covariates.retain(|c| c.name != "temp_c");
    let temp: Vec<f64> = (0..80).map(|i| 0.01 * i as f64).collect();
    data.covariates.push(robokrige::dataset::Covariate {
        name: "temp_c".into(),
        values: temp.clone(),
        missing: 0,
    });
    let times_columns = |data: &Dataset| -> Vec<Vec<Vec<f64>>> {
        robokrige::diagnose::scan::families(data, &[], None)
            .into_iter()
            .filter(|f| f.label.starts_with("temp_c × one joint"))
            .flat_map(|f| f.grid.into_iter().map(|g| g.columns))
            .collect()
    };
    let at_zero = times_columns(&data);
    assert_eq!(at_zero.len(), data.n_joints());
    let c = data
        .covariates
        .iter_mut()
        .find(|c| c.name == "temp_c")
        .unwrap();
    c.values = temp.iter().map(|t| t + 22.0).collect();
    let at_22 = times_columns(&data);
    for (a, b) in at_zero.iter().flatten().zip(at_22.iter().flatten()) {
        let worst = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "columns moved by {worst} with the offset");
    }
}

/// A bump that returns (a tracker knocked and put back) is one effect: the
/// block of rows is found with both edges, and added as two steps.
#[test]
fn a_tracker_bump_is_found_as_a_block_with_both_edges() {
    // neither edge on the lattice of edges (every 6 rows from row 10)
    let (from, to) = (73, 141);
    let data = campaign(
        200,
        6,
        Some("tracker-step:row=73,until=141,dx=0.15,dy=-0.12,dz=0.12"),
    );
    let d = diagnose(&data, &quick(), &|_| {}).unwrap();
    let top = d.effects.iter().find(|e| e.accepted).unwrap();
    assert_eq!(
        top.label, "block of rows (a bump, back at its end)",
        "{top:?}"
    );
    assert_eq!(top.round, 1);
    let (a, b) = (top.params["from_row"], top.params["to_row"]);
    assert!(
        (a - from as f64).abs() <= 2.0 && (b - to as f64).abs() <= 2.0,
        "block found at rows {a}–{b}"
    );
    assert!(top.params_ci["from_row"][0] <= a && a <= top.params_ci["from_row"][1]);
    assert_eq!(
        d.extras[..2],
        [
            Feature::Step { row: a as usize },
            Feature::Step { row: b as usize }
        ]
    );
    // each edge's height, with its interval, is the planted 0.15 mm on x
    let up = &top.size[0].estimate;
    assert!((up[0] - 0.15).abs() < 0.04, "rising edge {up:?}");
    assert!((top.size[1].estimate[0] + 0.15).abs() < 0.04);
}

/// A joint's moves with a memory in time: each earlier move
/// decays over the measured interval, a pause lets the robot settle, and a
/// pose sequence without times takes the reference interval.
#[test]
fn a_memory_in_time_decays_over_the_interval_between_poses() {
    use robokrige::features::Clock;
    let mut data = campaign(6, 3, None);
    for (row, v) in data.q.iter_mut().zip([0.0, 1.0, 3.0, 2.0, 2.0, 5.0]) {
        row[0] = v;
    }
    let time = data
        .covariates
        .iter_mut()
        .find(|c| c.name == "time_s")
        .expect("the simulator writes time_s");
    // 2 s between poses, and a 60 s pause before the fourth
    time.values = vec![0.0, 2.0, 4.0, 64.0, 66.0, 68.0];
    let clock = Clock {
        column: "time_s".into(),
        tau_s: 2.0,
        interval_s: Some(2.0),
    };
    let f = Feature::Moves {
        joint: 1,
        tau_poses: 0.0,
        clock: Some(clock.clone()),
    };
    let h = f.columns(&data).unwrap().remove(0);
    let k = (-1.0f64).exp();
    let expect = [0.0, 1.0, 2.0 + k, -1.0 + (-30.0f64).exp() * (2.0 + k)];
    for (a, b) in h.iter().zip(expect) {
        assert!((a - b).abs() < 1e-12, "{h:?}");
    }
    // from poses alone: every interval is the reference 2 s, as τ = 1 pose
    let in_poses = Feature::Moves {
        joint: 1,
        tau_poses: 1.0,
        clock: None,
    };
    assert_eq!(
        f.columns_from_poses(&data.q, &data.dir).unwrap(),
        in_poses.columns_from_poses(&data.q, &data.dir).unwrap()
    );
    // saved and loaded with its clock; a file without one loads as before
    let json = serde_json::to_string(&f).unwrap();
    assert_eq!(serde_json::from_str::<Feature>(&json).unwrap(), f);
    let old: Feature =
        serde_json::from_str(r#"{"feature":"moves","joint":1,"tau_poses":1.0}"#).unwrap();
    assert_eq!(old, in_poses);
    // both memories at once, or a memory of zero seconds, are errors
    for bad in [
        Feature::Moves {
            joint: 1,
            tau_poses: 1.0,
            clock: Some(clock.clone()),
        },
        Feature::Moves {
            joint: 1,
            tau_poses: 0.0,
            clock: Some(Clock {
                tau_s: 0.0,
                ..clock.clone()
            }),
        },
    ] {
        assert!(bad.columns(&data).is_err(), "{bad:?}");
    }
    // the scan offers memories in seconds beside those in poses
    let moves = robokrige::diagnose::scan::families(&data, &[], None)
        .into_iter()
        .find(|f| f.label == "moves of q1 into the pose (lag)")
        .unwrap();
    assert!(moves.grid.iter().any(|g| g.params.contains_key("tau_s")));
    assert!(
        moves
            .grid
            .iter()
            .any(|g| g.params.contains_key("tau_poses"))
    );
}

/// The memory a diagnosis needs is estimated before it allocates: it grows
/// with rows × scanned values, and the number of rows it names for a
/// smaller limit does fit that limit.
#[test]
fn the_diagnosis_memory_plan_names_a_row_count_that_fits() {
    use robokrige::diagnose::DiagnosePlan;
    let data = campaign(240, 2, None);
    let o = DiagnoseOptions::default();
    let plan = DiagnosePlan::new(&data, &o);
    let half = DiagnosePlan::new(&data.select(&(0..120).collect::<Vec<_>>()), &o);
    assert!(plan.values() > half.values() && plan.bytes() > 2 * half.bytes());
    // the campaign fits its own estimate, nothing fits in no memory
    assert_eq!(plan.max_rows(plan.bytes()), 240);
    assert_eq!(plan.max_rows(0), 0);
    let limit = plan.bytes() / 3;
    let n = plan.max_rows(limit);
    assert!(n > 10 && n < 240, "{n} rows");
    let fits = DiagnosePlan::new(&data.select(&(0..n).collect::<Vec<_>>()), &o);
    assert!(fits.bytes() <= limit, "{fits} over {limit} bytes");
    // scanning a subset: the candidate test's share stops growing with the
    // rows, and the plan names how many rows to scan for a smaller limit
    let scan = o.clone().scan_rows(200);
    let plan = DiagnosePlan::new(&data, &scan);
    assert_eq!(plan.scanned_rows(), 200);
    assert!(plan.bytes() < DiagnosePlan::new(&data, &o).bytes());
    assert_eq!(plan.max_scanned_rows(plan.bytes()), 200);
    let s = plan.max_scanned_rows(plan.bytes() * 9 / 10);
    assert!((1..200).contains(&s), "{s} rows scanned");
    let fits = DiagnosePlan::new(&data, &scan.clone().scan_rows(s));
    assert!(fits.bytes() <= plan.bytes() * 9 / 10, "{fits}");
}

/// Above `scan_rows` the candidates are scanned on an evenly spread subset
/// of the rows (so that a whole campaign of thousands of rows can be
/// diagnosed): a step is still found, placed to within the spacing of the
/// scanned rows, and the models compared are fitted and cross-validated on
/// every row.
#[test]
fn a_campaign_above_scan_rows_is_scanned_on_a_subset_and_compared_on_all_rows() {
    let data = campaign(400, 4, Some("tracker-step:row=201,dx=0.2,dy=-0.15,dz=0.15"));
    let o = quick()
        .kriging(KrigingOptions::default())
        .refit_rows(100)
        .max_effects(1)
        .scan_rows(200);
    let d = diagnose(&data, &o, &|_| {}).unwrap();
    assert_eq!(d.scanned_rows, 200);
    assert_eq!(d.before.residuals.len(), 400);
    assert_eq!(d.after.residuals.len(), 400);
    let top = &d.effects[0];
    assert_eq!(top.label, "step in the measurement order", "{top:?}");
    // every second row is scanned: the step shows from the first scanned
    // row at or after it, and is placed at its row by the residuals of all
    let row = top.params["row"];
    assert_eq!(row, 201.0, "{top:?}");
    let ci = top.params_ci["row"];
    assert!(ci[0] <= 201.0 && 201.0 <= ci[1], "{ci:?}");
    assert!(top.accepted);
    assert_eq!(d.extras, [Feature::Step { row: 201 }]);
    assert!(
        d.after.pooled_rmse_mm < 0.7 * d.before.pooled_rmse_mm,
        "{:?} → {:?}",
        d.before.cv_rmse_mm,
        d.after.cv_rmse_mm
    );
    // too few rows to scan is an error
    let few = diagnose(&data, &o.clone().scan_rows(100), &|_| {});
    assert!(matches!(few, Err(Error::InvalidParameter(_))), "{few:?}");
}

/// The scanned rows keep the history of the whole campaign: a joint's moves
/// into a pose are those from the pose measured before it, not from the
/// scanned row before it; the order families scan the scanned rows and
/// name campaign rows.
#[test]
fn scanned_rows_keep_the_history_of_the_whole_campaign() {
    use robokrige::diagnose::ScanRows;
    use robokrige::diagnose::scan::{Family, families, families_on, step_rows};
    let data = campaign(300, 3, None);
    let rows = ScanRows::spread(300, 100);
    let find = |f: &[Family], label: &str| f.iter().find(|x| x.label == label).unwrap().clone();
    let label = "moves of q1 into the pose (lag)";
    let full = find(&families(&data, &[], None), label);
    let scanned = find(&families_on(&data, &[], None, &rows), label);
    let alone = find(&families(&data.select(rows.indices()), &[], None), label);
    let zscore = |v: &[f64]| {
        let n = v.len() as f64;
        let mu = v.iter().sum::<f64>() / n;
        let sd = (v.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / n).sqrt();
        v.iter().map(|x| (x - mu) / sd).collect::<Vec<f64>>()
    };
    let gap = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    assert!(!full.grid.is_empty());
    assert_eq!(full.grid.len(), scanned.grid.len());
    assert_eq!(full.grid.len(), alone.grid.len());
    for ((f, s), a) in full.grid.iter().zip(&scanned.grid).zip(&alone.grid) {
        assert_eq!(s.columns[0].len(), 100);
        let picked = zscore(&rows.pick(&f.columns[0]));
        assert!(gap(&picked, &s.columns[0]) < 1e-9, "{:?}", f.params);
        // computed on the scanned rows alone, the moves would be others
        assert!(gap(&picked, &a.columns[0]) > 0.1, "{:?}", f.params);
    }
    let step = find(
        &families_on(&data, &[], None, &rows),
        "step in the measurement order",
    );
    assert_eq!(step.grid.len(), step_rows(100).len());
    for g in &step.grid {
        let row = g.params["row"] as usize;
        assert!(rows.indices().contains(&row));
        assert_eq!(g.add, [Feature::Step { row }]);
    }
}

#[test]
fn a_lag_the_calibration_took_up_part_of_is_covered_by_its_interval() {
    // diagnosed on the calibration's residual (the default with a robot):
    // the calibration, identified with the lag in the errors, took up
    // part of it, and the interval of what is left must still hold the
    // planted gain on each axis's own row of the Jacobian
    let robot = kinematics::preset("comau-nj220").unwrap();
    let data = campaign(200, 1, Some("lag:joint=2,gain=0.0005,tau_poses=0"));
    let o = quick().robot(Some(robot));
    let base = robokrige::study::diagnosis::DiagnosisBase::new(data, &o, None).unwrap();
    assert!(base.calibration.is_some());
    let d = base.diagnose(&o, &|_| {}).unwrap();
    let lag = d
        .effects
        .iter()
        .find(|e| e.accepted && e.source == ["move2"])
        .expect("the lag is added");
    let planted = -0.0005f64.to_radians();
    assert_eq!(lag.size.len(), 3, "{lag:?}");
    for c in &lag.size {
        let a = c.axis.expect("a row of the Jacobian");
        assert!(
            (c.estimate[a] - planted).abs() <= c.ci95[a],
            "{} on axis {a}: {} ± {} for a planted {planted}",
            c.column,
            c.estimate[a],
            c.ci95[a]
        );
    }
    let note = lag.note.as_deref().unwrap_or("");
    assert!(note.contains("directions the calibration saw"), "{note}");
}
