//! `ErrorModelParams → check → fit`: one way to fit that reaches every
//! combination, gives the same models as its parts composed by hand (a
//! selector's trends fitted as per-axis trends), and refuses what does not
//! combine.

use robokrige::dataset::{Dataset, read_csv};
use robokrige::features::Feature;
use robokrige::kriging::{KrigingOptions, OptimizerKind, Trend};
use robokrige::methods::Method;
use robokrige::model::ErrorModel;
use robokrige::params::{ErrorModelParams, HyperSpec, TrendSpec};
use robokrige::space::Space;

fn campaign(rows: usize) -> Dataset {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
    read_csv(path.as_ref())
        .unwrap()
        .select(&(0..rows).collect::<Vec<_>>())
}

/// Fit times differ run to run; everything else must not.
fn assert_same(a: &ErrorModel, b: &ErrorModel) {
    assert_eq!(a.outputs(), b.outputs());
    let untimed = |m: &ErrorModel| {
        let mut r = m.reports().to_vec();
        r.iter_mut().for_each(|r| r.seconds = 0.0);
        r
    };
    assert_eq!(untimed(a), untimed(b));
}

fn quick() -> KrigingOptions {
    KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .nugget(false)
}

#[test]
fn the_params_path_gives_the_models_of_its_parts() {
    let data = campaign(50);
    let opts = quick();
    let via = ErrorModelParams::new()
        .space(Space::Js)
        .kriging(opts.clone())
        .trend(TrendSpec::PccPca {
            threshold: 0.1,
            variance_share: 0.99,
            kinematic: None,
        })
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    // the selector's trends, given as per-axis trends, give the same model
    let trends: [Trend; 3] = std::array::from_fn(|a| via.outputs()[a].data().trend().clone());
    let by_hand = ErrorModelParams::new()
        .space(Space::Js)
        .kriging(opts.clone())
        .trend(TrendSpec::PerAxis(Box::new(trends)))
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert_same(&by_hand, &via);
    // fixed hyperparameters: a refit on the model's own rows reproduces it
    let refit = via.refit(&data).unwrap();
    for a in 0..3 {
        let (x, y) = (refit.outputs()[a].data(), via.outputs()[a].data());
        assert_eq!(
            (x.theta(), x.nugget(), x.trend()),
            (y.theta(), y.nugget(), y.trend())
        );
        let db = x.beta().iter().zip(y.beta()).map(|(p, q)| (p - q).abs());
        assert!(db.fold(0.0, f64::max) < 1e-9);
    }
    // a paper method's params hold its constants: EJS, Hooke–Jeeves, no nugget
    let hj = KrigingOptions::default()
        .seed(3)
        .optimizer(OptimizerKind::HookeJeeves)
        .starts(robokrige::methods::PAPER_GPS_STARTS)
        .nugget(false);
    let a = Method::EjsHj
        .params(3, false)
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    let b = ErrorModel::fit(&data, Space::Ejs, &hj).unwrap();
    assert_same(&a, &b);
}

#[test]
fn the_ga_selection_is_reachable_in_js() {
    let data = campaign(40);
    let model = ErrorModelParams::new()
        .space(Space::Js)
        .kriging(quick())
        .trend(TrendSpec::Ga {
            folds: 4,
            kinematic: None,
        })
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert_eq!(model.space(), Space::Js);
    assert!(matches!(
        model.selection(),
        Some(robokrige::selection::Selection::Ga { .. })
    ));
}

#[test]
fn combinations_that_do_not_fit_together_are_refused_at_check() {
    let refused = |p: ErrorModelParams, word: &str| {
        let e = p.check().unwrap_err().to_string();
        assert!(e.contains(word), "{e}");
    };
    refused(
        ErrorModelParams::new()
            .extras(vec![Feature::Row])
            .trend(TrendSpec::Ga {
                folds: 10,
                kinematic: None,
            }),
        "extra inputs",
    );
    refused(
        ErrorModelParams::new().trend(TrendSpec::Ga {
            folds: 1,
            kinematic: None,
        }),
        "2 folds",
    );
    refused(
        ErrorModelParams::new().trend(TrendSpec::PccPca {
            threshold: 1.5,
            variance_share: 0.99,
            kinematic: None,
        }),
        "threshold",
    );
    let js = ErrorModel::fit(&campaign(30), Space::Js, &quick()).unwrap();
    let mut two = js.warm_starts();
    two.pop();
    refused(
        ErrorModelParams::new().hyper(HyperSpec::Warm(two)),
        "one per output",
    );
}

/// Periodic joints are an input of the fit (the model's input map), not a
/// Kriging option: the model keeps them, and so does a refit at its fixed
/// hyperparameters.
#[test]
fn periodic_joints_are_part_of_the_inputs() {
    let data = campaign(40);
    let model = ErrorModelParams::new()
        .periodic(vec![0, 5])
        .kriging(quick())
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap();
    assert_eq!(model.periodic(), &[0, 5]);
    assert_eq!(model.input_names()[..2], ["sin q1", "cos q1"]);
    assert_eq!(model.input_map().dim(), 12 + 2);
    let refit = model.refit(&data).unwrap();
    assert_eq!(refit.input_map(), model.input_map());
    assert_eq!(refit.outputs(), model.outputs());
    // a joint the data does not have
    let e = ErrorModelParams::new()
        .periodic(vec![6])
        .kriging(quick())
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap_err()
        .to_string();
    assert!(e.contains("periodic joint 7"), "{e}");
}
