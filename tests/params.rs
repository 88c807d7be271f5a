//! `ErrorModelParams → check → fit`: one way to fit that reaches every
//! combination, gives the same models as the direct entry points, and
//! refuses what does not combine.

use robokrige::dataset::{Dataset, read_csv};
use robokrige::features::Feature;
use robokrige::kriging::{KrigingOptions, OptimizerKind};
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
fn without_times(mut m: ErrorModel) -> ErrorModel {
    for r in &mut m.reports {
        r.seconds = 0.0;
    }
    m
}

fn quick() -> KrigingOptions {
    KrigingOptions {
        optimizer: OptimizerKind::HookeJeeves,
        nugget: false,
        ..KrigingOptions::default()
    }
}

#[test]
fn the_params_path_gives_the_direct_entry_points_models() {
    let data = campaign(50);
    let opts = quick();
    let direct = ErrorModel::fit_pcc_pca(&data, Space::Js, &opts, 0.1, 0.99)
        .unwrap()
        .0;
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
    assert_eq!(without_times(via), without_times(direct.clone()));
    // fixed hyperparameters: the refit of the direct model
    let sub = campaign(40);
    let refit = ErrorModelParams::new()
        .space(Space::Js)
        .hyper(HyperSpec::FixedFrom(Box::new(direct.clone())))
        .check()
        .unwrap()
        .fit(&sub)
        .unwrap();
    let want = direct.refit_at_hyperparameters(&sub).unwrap();
    assert_eq!(without_times(refit), without_times(want));
    // a paper method's params hold its constants: EJS, Hooke–Jeeves, no nugget
    let hj = KrigingOptions {
        seed: 3,
        optimizer: OptimizerKind::HookeJeeves,
        starts: robokrige::methods::PAPER_GPS_STARTS,
        nugget: false,
        ..KrigingOptions::default()
    };
    let a = Method::EjsHj.fit(&data, 3).unwrap();
    let b = ErrorModel::fit(&data, Space::Ejs, &hj).unwrap();
    assert_eq!(without_times(a), without_times(b));
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
    assert_eq!(model.space, Space::Js);
    assert!(matches!(
        model.selection,
        Some(robokrige::basis::Selection::Ga { .. })
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
    refused(
        ErrorModelParams::new().hyper(HyperSpec::FixedFrom(Box::new(js))),
        "another space",
    );
}
