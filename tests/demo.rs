//! The demo's job as a library call ([`run_demo`]), on a small campaign:
//! every method is cross-validated, EJS compensates better than JS, and the
//! diagnosis finds the tracker bump.

use robokrige::demo::{DemoOptions, STEPS, run_demo};
use robokrige::methods::Method;
use std::sync::Mutex;

#[test]
fn a_small_demo_runs_every_step_and_finds_the_bump() {
    let options = DemoOptions {
        poses: 60,
        folds: 3,
    };
    assert_eq!(options.step_row(), 30);
    let seen = Mutex::new(Vec::new());
    let demo = run_demo(&options, &|done, _| seen.lock().unwrap().push(done)).unwrap();
    let seen = seen.into_inner().unwrap();
    assert!(seen.windows(2).all(|w| w[0] <= w[1]), "{seen:?}");
    assert_eq!((seen[0], seen.last().copied()), (0, Some(STEPS)));

    assert_eq!((demo.lhs.len(), demo.tracker_step.len()), (60, 60));
    assert_eq!((demo.verify.len(), demo.circle.len()), (30, 72));
    let methods: Vec<(Method, &str)> = demo
        .methods
        .iter()
        .map(|m| (m.method, m.cv.mode.name()))
        .collect();
    assert_eq!(
        methods,
        [
            (Method::Recommended, "refit"),
            (Method::JsHj, "refit"),
            (Method::EjsHj, "refit"),
            (Method::EjsGps, "closed-form"),
            (Method::EjsPca, "closed-form"),
            (Method::EjsGa, "closed-form"),
        ]
    );
    assert!(demo.methods.iter().all(|m| m.cv.folds == 3));

    // JS and EJS on the circle, then on the poses; the same nominal run each
    let rows: Vec<(&str, &str)> = demo
        .compensation
        .iter()
        .map(|c| (c.target, c.model))
        .collect();
    assert_eq!(
        rows,
        [
            ("circle", "JS"),
            ("circle", "EJS"),
            ("verification poses", "JS"),
            ("verification poses", "EJS"),
        ]
    );
    for pair in demo.compensation.chunks(2) {
        let (js, ejs) = (&pair[0], &pair[1]);
        assert_eq!(js.nominal, ejs.nominal);
        assert!(
            ejs.after.mean_abs_mm < js.after.mean_abs_mm
                && ejs.reduction_pct().0 > 50.0
                && ejs.iterations >= 1,
            "{}: EJS {:?} vs JS {:?}",
            ejs.target,
            ejs.after,
            js.after
        );
    }
    let names: Vec<&str> = demo.circle_runs.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(names, ["nominal", "JS compensated", "EJS compensated"]);
    assert!(demo.circle_runs.iter().all(|r| r.1.len() == 72));

    // the bump before row 30 is found and added, and it lowers the CV error
    let d = &demo.diagnosis;
    let added: Vec<String> = d
        .effects
        .iter()
        .filter(|e| e.accepted)
        .map(|e| e.describe())
        .collect();
    assert!(
        added
            .first()
            .is_some_and(|e| e.starts_with("step in the measurement order")),
        "{added:?}"
    );
    let sum = |v: [f64; 3]| v.iter().sum::<f64>();
    assert!(sum(d.after.cv_rmse_mm) < sum(d.before.cv_rmse_mm));
}

#[test]
fn a_demo_too_small_for_its_cross_validation_is_refused() {
    for (poses, folds) in [(10, 3), (60, 1), (60, 61)] {
        let options = DemoOptions { poses, folds };
        assert!(options.validate().is_err(), "{options:?}");
        assert!(run_demo(&options, &|_, _| {}).is_err());
    }
    assert!(DemoOptions::default().validate().is_ok());
}
