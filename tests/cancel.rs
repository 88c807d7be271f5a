//! Cancellation ([`robokrige::cancel::Cancel`]): a cancelled token stops a
//! fit (every optimiser, the family choice, a GA selection), a refit CV, a
//! diagnosis and a plan with `Error::Interrupted`, soon after it is set from
//! another thread; a token that is never set changes nothing, bit for bit.

mod common;

use common::comau_lhs;
use robokrige::Error;
use robokrige::cancel::Cancel;
use robokrige::cv::{CvMode, CvPlan, Folds};
use robokrige::diagnose::{DiagnoseOptions, diagnose};
use robokrige::kinematics::load_robot;
use robokrige::kriging::{Correlation, KrigingOptions, OptimizerKind};
use robokrige::methods::{Method, default_params};
use robokrige::params::ErrorModelParams;
use robokrige::plan::{PlanInputs, PlanParams, Region};
use std::time::{Duration, Instant};

fn cancelled() -> Cancel {
    let c = Cancel::new();
    c.cancel();
    c
}

fn interrupted<T: std::fmt::Debug>(r: robokrige::Result<T>) -> bool {
    matches!(r, Err(Error::Interrupted))
}

/// Every way to search the hyperparameters returns `Interrupted` (not an
/// axis failure, not a numerical one) when the token is already set, and
/// without doing the work.
#[test]
fn a_cancelled_token_stops_every_search_at_once() {
    let data = comau_lhs(120);
    let base = KrigingOptions::default();
    let cases = [
        ("bfgs", base.clone()),
        ("auto", KrigingOptions::recommended()),
        (
            "gps",
            base.clone()
                .optimizer(OptimizerKind::Gps)
                .starts(4)
                .nugget(false),
        ),
        ("hj", base.clone().optimizer(OptimizerKind::HookeJeeves)),
        ("matern32", base.clone().corr(Correlation::Matern32)),
    ];
    for (name, opts) in cases {
        let t0 = Instant::now();
        let r = ErrorModelParams::new()
            .kriging(opts)
            .cancel(cancelled())
            .check()
            .unwrap()
            .fit(&data);
        assert!(interrupted(r), "{name}");
        assert!(
            t0.elapsed() < Duration::from_millis(500),
            "{name}: {:?}",
            t0.elapsed()
        );
    }
    // a GA selection (the papers' ejs-ga) and a calibrated fit
    let ga = Method::EjsGa.params(1, false).cancel(cancelled());
    assert!(interrupted(ga.check().unwrap().fit(&data)));
    let robot = load_robot("comau-nj220").unwrap();
    let cal = default_params(&robot, &data).unwrap().cancel(cancelled());
    assert!(interrupted(cal.check().unwrap().fit(&data)));
}

/// A fit that would take seconds (the GA selection of seed 004) stops soon
/// after the token is set from another thread.
#[test]
fn a_token_set_from_another_thread_stops_a_long_fit_within_a_second() {
    let data = comau_lhs(300);
    let token = Cancel::new();
    let params = Method::EjsGa
        .params(1, false)
        .cancel(token.clone())
        .check()
        .unwrap();
    let setter = {
        let token = token.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(300));
            token.cancel();
            Instant::now()
        })
    };
    let r = params.fit(&data);
    let stopped = Instant::now();
    let set_at = setter.join().unwrap();
    assert!(
        interrupted(r),
        "the GA fit finished before it was cancelled"
    );
    let latency = stopped.saturating_duration_since(set_at);
    assert!(
        latency < Duration::from_secs(1),
        "stopped {latency:?} after the token was set"
    );
}

/// A token that is never set gives the model file of a fit without one,
/// byte for byte, and the model keeps no token.
#[test]
fn a_token_never_set_changes_nothing() {
    let data = comau_lhs(150);
    let plain = ErrorModelParams::new().check().unwrap().fit(&data).unwrap();
    let token = Cancel::new();
    let with = ErrorModelParams::new()
        .cancel(token.clone())
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert_eq!(with.to_json().unwrap(), plain.to_json().unwrap());
    // the model's options hold the never-set default, not the caller's token
    token.cancel();
    assert!(!with.options().get_cancel().is_cancelled());
    assert!(with.refit(&data).is_ok());
}

/// The studies: a refit CV, a diagnosis and a plan with a campaign.
#[test]
fn cv_diagnose_and_plan_stop_with_interrupted() {
    let data = comau_lhs(80);
    let params = ErrorModelParams::new().cancel(cancelled()).check().unwrap();
    let plan = CvPlan {
        mode: CvMode::Refit,
        folds: Folds::Random { k: 4, seed: 1 },
        hyper_rows: None,
    };
    assert!(interrupted(plan.run(&data, &params, &|_, _| {})));

    let o = DiagnoseOptions::default()
        .permutations(199)
        .cancel(cancelled());
    assert!(interrupted(diagnose(&data, &o, &|_| {})));

    let robot = load_robot("comau-nj220").unwrap();
    let inputs = PlanInputs {
        robot: &robot,
        campaign: Some(&data),
        prior: None,
        pool: None,
        region: &Region::WorkRange,
    };
    let p = PlanParams::new(10).candidates(300).region_points(100);
    assert!(interrupted(
        p.clone().cancel(cancelled()).check().unwrap().plan(&inputs)
    ));
    // the same plan without a cancelled token runs
    assert!(
        p.cancel(Cancel::new())
            .check()
            .unwrap()
            .plan(&inputs)
            .is_ok()
    );
}
