//! The analytic gradient of the concentrated likelihood ln ψ
//! against central differences, for constant, linear, kinematic and fused
//! (PCC+PCA) trends, at several ξ, with and without a nugget, for every
//! correlation family.

use robokrige::dataset::Dataset;
use robokrige::kinematics;
use robokrige::kriging::{
    Correlation, KrigingModel, KrigingOptions, KrigingProblem, OptimizerKind, TrainingInputs,
    Workspace, fit_columns, trend_matrix,
};
use robokrige::model::ErrorModel;
use robokrige::params::{ErrorModelParams, TrendSpec};
use robokrige::space::Space;

mod common;

fn campaign(rows: usize) -> Dataset {
    common::comau_lhs(rows)
}

/// A quick fit whose only purpose is to produce each kind of trend.
fn quick() -> KrigingOptions {
    KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(30)
}

/// ln ψ at `z` = (log10 ξ, [log10 ν]).
fn ln_psi(prob: &KrigingProblem, z: &[f64], d: usize, ws: &mut Workspace) -> f64 {
    let theta: Vec<f64> = z[..d].iter().map(|v| 10f64.powf(*v)).collect();
    let nu = if z.len() > d { 10f64.powf(z[d]) } else { 0.0 };
    prob.psi(&theta, nu, ws).unwrap().ln_psi
}

/// Checks every component of the analytic gradient of one output's problem
/// against central differences at three ξ, with and without a nugget.
fn check(out: &KrigingModel, y: &[f64], what: &str) {
    let data = &out.data();
    let x = data.x_train();
    let d = data.theta().len();
    let inputs = TrainingInputs::new(x);
    // the columns a fit keeps (a shared trend is stored whole)
    let (kept, _) = fit_columns(data.trend(), &trend_matrix(data.trend(), x));
    let f = trend_matrix(&data.trend().subset(&kept), x);
    let yn: Vec<f64> = y
        .iter()
        .map(|v| (v - data.y_mean()) / data.y_std())
        .collect();
    let corr = data.corr();
    let prob = KrigingProblem {
        min_jitter: None,
        corr: &corr,
        inputs: &inputs,
        f: &f,
        y: &yn,
        prior: &[],
    };
    let mut ws = Workspace::new(x.len(), f.ncols());
    let mut ws_fd = Workspace::new(x.len(), f.ncols());
    let points: [(f64, Option<f64>); 4] = [
        (-1.5, None),
        (-0.7, None),
        (-1.0, Some(-2.5)),
        (-0.3, Some(-1.2)),
    ];
    for (k0, (base, nugget)) in points.into_iter().enumerate() {
        // a different ξ per dimension, so that every component is exercised
        let mut z: Vec<f64> = (0..d)
            .map(|k| base + 0.35 * (((k + k0) * 7 % 5) as f64 - 2.0) / 2.0)
            .collect();
        if let Some(nu) = nugget {
            z.push(nu);
        }
        let theta: Vec<f64> = z[..d].iter().map(|v| 10f64.powf(*v)).collect();
        let nu = nugget.map_or(0.0, |v| 10f64.powf(v));
        let mut grad = vec![0.0; z.len()];
        let v = prob.psi_grad(&theta, nu, &mut ws, &mut grad).unwrap();
        assert_eq!(v.ln_psi, prob.psi(&theta, nu, &mut ws_fd).unwrap().ln_psi);
        let h = 1e-5;
        let scale = grad.iter().map(|g| g.abs()).fold(0.0, f64::max);
        assert!(scale > 1e-4, "{what}: a gradient of zero tests nothing");
        for k in 0..z.len() {
            let mut zp = z.clone();
            zp[k] += h;
            let mut zm = z.clone();
            zm[k] -= h;
            let fd =
                (ln_psi(&prob, &zp, d, &mut ws_fd) - ln_psi(&prob, &zm, d, &mut ws_fd)) / (2.0 * h);
            assert!(
                (grad[k] - fd).abs() <= 1e-6 + 1e-5 * scale,
                "{what}, point {k0}, component {k}: analytic {} vs central difference {fd}",
                grad[k]
            );
        }
    }
}

fn check_model(model: &ErrorModel, data: &Dataset, what: &str) {
    let errors = data.errors.as_ref().unwrap();
    for (a, out) in model.outputs().iter().enumerate() {
        let y: Vec<f64> = errors.iter().map(|e| e[a]).collect();
        check(out, &y, &format!("{what} output {a}"));
    }
}

#[test]
fn gradient_matches_central_differences_constant_and_linear_trends() {
    let data = campaign(70);
    for trend in [
        robokrige::kriging::TrendKind::Constant,
        robokrige::kriging::TrendKind::Linear,
    ] {
        let opts = quick().trend(trend);
        let model = ErrorModel::fit(&data, Space::Ejs, &opts).unwrap();
        check_model(&model, &data, &format!("{trend:?}"));
    }
}

#[test]
fn gradient_matches_central_differences_every_correlation_family() {
    let data = campaign(60);
    for corr in Correlation::ALL {
        let opts = quick()
            .corr(corr)
            .trend(robokrige::kriging::TrendKind::Linear);
        let model = ErrorModel::fit(&data, Space::Ejs, &opts).unwrap();
        assert!(model.outputs().iter().all(|o| o.corr() == corr));
        check_model(&model, &data, corr.name());
    }
}

#[test]
fn gradient_matches_central_differences_kinematic_trend() {
    let data = campaign(90);
    let robot = kinematics::preset("comau-nj220").unwrap();
    let model = ErrorModelParams::new()
        .kriging(quick())
        .trend(TrendSpec::Kinematic(Box::new(robot)))
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap();
    assert!(matches!(
        model.outputs()[0].data().trend(),
        robokrige::kriging::Trend::Kinematic(_)
    ));
    check_model(&model, &data, "kinematic");
}

#[test]
fn gradient_matches_central_differences_fused_trend() {
    let data = campaign(80);
    let (model, _) = common::fit_pcc_pca(&data, &quick(), None);
    assert!(matches!(
        model.outputs()[0].data().trend(),
        robokrige::kriging::Trend::Fused(_)
    ));
    check_model(&model, &data, "fused");
}

/// The path of ARCHITECTURE.md's "Add a correlation family" (a family of
/// one's own): the rational quadratic `R = 1/(1 + h²)`, whose
/// `q = R′(h)/(2h) = −R²`, implemented as a `CorrelationModel` from its
/// scalar `corr` and `gradient_weights` alone and registered by name. The
/// likelihood and its analytic gradient take it as they take the built-in
/// families; `KrigingParams::fit` and `ErrorModel::fit` fit with it; the
/// model file names it, and reads back to the same predictions.
#[test]
fn a_users_correlation_family_reaches_the_likelihood_the_fit_and_the_model_file() {
    use robokrige::kriging::{CorrelationModel, KrigingParams, Monomials, Trend};
    /// (The field gives two statics distinct addresses: two models.)
    struct RationalQuadratic(#[allow(dead_code)] u8);
    impl CorrelationModel for RationalQuadratic {
        fn corr(&self, theta: &[f64], a: &[f64], b: &[f64]) -> f64 {
            let h2: f64 = theta
                .iter()
                .zip(a.iter().zip(b))
                .map(|(t, (x, y))| t * (x - y) * (x - y))
                .sum();
            1.0 / (1.0 + h2)
        }
        fn gradient_weights(
            &self,
            _theta: &[f64],
            _x: &TrainingInputs,
            _i: usize,
            r: &[f64],
            w: &mut [f64],
        ) {
            // w ← −q·w with −q = R²
            for (v, rv) in w.iter_mut().zip(r) {
                *v *= rv * rv;
            }
        }
    }
    static RQ: RationalQuadratic = RationalQuadratic(0);
    let rq = Correlation::register("rational-quadratic", &RQ).unwrap();
    assert_eq!(
        Correlation::register("rational-quadratic", &RQ).unwrap(),
        rq
    );
    static OTHER: RationalQuadratic = RationalQuadratic(1);
    assert!(Correlation::register("rational-quadratic", &OTHER).is_err());
    assert!(Correlation::register("matern52", &RQ).is_err());
    assert!(Correlation::register("Auto Family", &RQ).is_err());

    let data = campaign(60);
    let model = ErrorModel::fit(&data, Space::Js, &quick()).unwrap();
    let out = &model.outputs()[0];
    let x = out.data().x_train();
    let d = x[0].len();
    let inputs = TrainingInputs::new(x);
    let f = trend_matrix(out.data().trend(), x);
    let y: Vec<f64> = data.errors.as_ref().unwrap().iter().map(|e| e[0]).collect();
    let prob = KrigingProblem {
        min_jitter: None,
        corr: &rq,
        inputs: &inputs,
        f: &f,
        y: &y,
        prior: &[],
    };
    let mut ws = Workspace::new(x.len(), f.ncols());
    let z: Vec<f64> = (0..d)
        .map(|k| -1.0 + 0.1 * k as f64)
        .chain([-2.0])
        .collect();
    let theta: Vec<f64> = z[..d].iter().map(|v| 10f64.powf(*v)).collect();
    let mut grad = vec![0.0; d + 1];
    let v = prob.psi_grad(&theta, 1e-2, &mut ws, &mut grad).unwrap();
    let h = 1e-5;
    let scale = grad.iter().map(|g| g.abs()).fold(0.0, f64::max);
    assert!(scale > 1e-4);
    for k in 0..=d {
        let (mut zp, mut zm) = (z.clone(), z.clone());
        zp[k] += h;
        zm[k] -= h;
        let fd = (ln_psi(&prob, &zp, d, &mut ws) - ln_psi(&prob, &zm, d, &mut ws)) / (2.0 * h);
        assert!((grad[k] - fd).abs() <= 1e-6 + 1e-5 * scale, "component {k}");
    }
    // the solve at ξ reproduces ψ
    let sol = prob.solve(&theta, 1e-2).unwrap();
    assert_eq!(sol.value.ln_psi, v.ln_psi);
    assert_eq!(sol.gamma.len(), x.len());

    // one output's fit with the family, searched: it is the model's family,
    // and differs from the Gaussian's fit of the same data
    let params = KrigingParams::new(Trend::from(Monomials::constant(d)))
        .corr(rq)
        .options(quick().corr(rq));
    let (fitted, report) = params.check().unwrap().fit(x, &y).unwrap();
    assert_eq!(fitted.corr(), rq);
    assert!(report.ln_psi.is_finite() && report.evals > 0);
    let (gauss, _) = KrigingParams::new(Trend::from(Monomials::constant(d)))
        .options(quick())
        .corr(Correlation::Gaussian)
        .check()
        .unwrap()
        .fit(x, &y)
        .unwrap();
    let probe = vec![vec![0.1; d]];
    let (pr, pg) = (
        fitted.predict(&probe).unwrap(),
        gauss.predict(&probe).unwrap(),
    );
    assert_ne!(pr[0].mean, pg[0].mean);

    // the error model: fitted with it, saved by name, read back the same
    let em = ErrorModel::fit(&data, Space::Js, &quick().corr(rq)).unwrap();
    assert!(em.outputs().iter().all(|o| o.corr() == rq));
    let dir = std::env::temp_dir().join(format!("rk_custom_corr_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("rq.json");
    em.save(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("\"rational-quadratic\""));
    let back = ErrorModel::load(&path).unwrap();
    let (a, b) = (
        em.predict_dataset(&data).unwrap(),
        back.predict_dataset(&data).unwrap(),
    );
    assert_eq!(a.mean, b.mean);
    // a file naming a family nobody registered is refused with its name
    std::fs::write(&path, text.replace("rational-quadratic", "no-such-family")).unwrap();
    let err = ErrorModel::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("no-such-family") && err.contains("register"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
