//! Stress test of the kinematic-trend Kriging models on ISO 9283 cube
//! campaigns (`sim::iso_cubes`): random 10-fold CV (`holdout::holdout_cv`)
//! and leave-one-cube-out, with a diagnosis of the worst held-out pose of
//! the kinematic-trend models (trend columns, β, leverage, conditioning,
//! trend and Kriging parts).
//!
//! Run: `cargo run --release --example iso_cube_stress -- robot=ur10 seed=1
//! cubes=4 edge=300 per_cube=150 [random=1] [loco=1] [diag=1] [tilt=10]
//! [flips=1] [turns=1]`. `robot` is ur10 (with the public data's TCP),
//! comau, abb, or a robot file.

use robokrige::dataset::Dataset;
use robokrige::holdout::{CV_MODELS, calibrate, holdout_cv, residual};
use robokrige::kinematics::{JointKind, Robot, load_robot};
use robokrige::kriging::{TrendModel, trend_matrix};
use robokrige::model::ErrorModel;
use robokrige::params::{ErrorModelParams, TrendSpec};
use robokrige::physics::HybridModel;
use robokrige::sim::iso_cubes::{IsoCubeCampaign, IsoCubeSpec, iso_cubes, measure_cubes};
use robokrige::sim::{ErrorProfile, TrueRobot};
use robokrige::space::{Space, periodic_joints};
use robokrige::stats::kfold_partition;
use std::collections::HashMap;

type Res<T> = robokrige::Result<T>;

fn arg(a: &HashMap<String, String>, k: &str, d: f64) -> f64 {
    a.get(k).and_then(|v| v.parse().ok()).unwrap_or(d)
}

fn robot_and_spec(a: &HashMap<String, String>) -> Res<(Robot, IsoCubeSpec)> {
    let name = a.get("robot").map_or("ur10", String::as_str);
    let cubes = arg(a, "cubes", 4.0) as usize;
    let edge = arg(a, "edge", 300.0);
    let per = arg(a, "per_cube", 150.0) as usize;
    let (robot, flips, ranges) = match name {
        "ur10" => {
            let mut r = load_robot("ur10")?;
            r.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
            (r, vec![2, 4], None)
        }
        "comau" => (
            load_robot("comau-nj220")?,
            vec![4],
            Some(vec![
                (-90.0, 90.0),
                (-40.0, 20.0),
                (-150.0, -90.0),
                (-90.0, 90.0),
                (-60.0, 60.0),
                (-90.0, 90.0),
            ]),
        ),
        "abb" => (
            load_robot(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/examples/robots/abb-irb2600.toml"
            ))?,
            vec![4],
            Some(vec![
                (-90.0, 90.0),
                (-20.0, 60.0),
                (-60.0, 20.0),
                (-90.0, 90.0),
                (-90.0, 90.0),
                (-90.0, 90.0),
            ]),
        ),
        other => (load_robot(other)?, Vec::new(), None),
    };
    let mut spec = IsoCubeSpec::new(cubes, edge, per);
    spec.tilt_deg = arg(a, "tilt", spec.tilt_deg);
    spec.ranges = ranges;
    if arg(a, "flips", 1.0) > 0.0 {
        spec.flip_joints = flips;
    }
    if arg(a, "turns", 1.0) > 0.0 {
        spec.turn_joints = (0..robot.dof())
            .filter(|&j| robot.links[j].kind == JointKind::Revolute)
            .collect();
    }
    Ok((robot, spec))
}

/// The models of `holdout_cv`, refitted on one training fold.
struct FoldFits {
    dh: robokrige::physics::PhysicsModel,
    hybrid: [HybridModel; 2],
    uk: [ErrorModel; 2],
}

fn fit_fold(tr: &Dataset, robot: &Robot, hyb: &[ErrorModel], kin: &[ErrorModel]) -> Res<FoldFits> {
    let (dh, _) = calibrate(tr, robot)?;
    let resid = residual(tr, &dh)?;
    let refit =
        |m: &ErrorModel, d: &Dataset| ErrorModelParams::fixed_from(m.clone()).check()?.fit(d);
    Ok(FoldFits {
        hybrid: [
            HybridModel {
                physics: dh.clone(),
                residual: refit(&hyb[0], &resid)?,
            },
            HybridModel {
                physics: dh.clone(),
                residual: refit(&hyb[1], &resid)?,
            },
        ],
        uk: [refit(&kin[0], tr)?, refit(&kin[1], tr)?],
        dh,
    })
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// What a fold run reports beyond the fold maxima.
#[derive(Clone, Copy)]
struct Report {
    /// Diagnose the kinematic models' worst poses of a fold beyond 3× D-H.
    diag: bool,
    /// Prior σ (mm, degrees) of the Bayesian prototype, if run.
    prior: Option<(f64, f64)>,
    /// Diagnose a fold whose kinematic model exceeds this × the D-H max.
    ratio: f64,
}

/// Folds `fold` (label per row): per fold the max 3D error of the five
/// models (hybrids `hyb` and kinematic-trend `kin` refitted at their
/// hyperparameters).
fn run_folds(
    label: &str,
    data: &Dataset,
    robot: &Robot,
    fold: &[usize],
    (hyb, kin): (&[ErrorModel], &[ErrorModel]),
    Report { diag, prior, ratio }: Report,
) -> Res<Vec<[f64; 5]>> {
    let errors = data.errors_or_err()?;
    let k = fold.iter().max().map_or(0, |v| v + 1);
    let mut out = Vec::new();
    let mut prior_worst = [0.0f64; 2];
    println!(
        "{label}: fold | rows | max 3D error, mm: D-H | hyb JS | hyb EJS | UK-kin JS | UK-kin EJS"
    );
    for f in 0..k {
        let (test, train): (Vec<usize>, Vec<usize>) = (0..data.len()).partition(|&i| fold[i] == f);
        let (tr, held) = (data.select(&train), data.select(&test));
        let fits = fit_fold(&tr, robot, hyb, kin)?;
        let preds = [
            fits.dh.predict(&held.q, &held.dir)?,
            fits.hybrid[0].predict(&held.q, &held.dir)?,
            fits.hybrid[1].predict(&held.q, &held.dir)?,
            fits.uk[0].predict_mean(&held.q, &held.dir)?,
            fits.uk[1].predict_mean(&held.q, &held.dir)?,
        ];
        let mut worst = [0.0; 5];
        let mut arg_worst = [0usize; 5];
        for (s, p) in preds.iter().enumerate() {
            for (j, v) in p.iter().enumerate() {
                let e = dist(&errors[test[j]], v);
                if e > worst[s] {
                    worst[s] = e;
                    arg_worst[s] = j;
                }
            }
        }
        let mut line = format!(
            "{label}: {f:>2} | {:>4} | {}",
            test.len(),
            worst.map(|v| format!("{v:8.3}")).join(" | ")
        );
        // what `holdout_cv` calls covered: the rows the kinematic models
        // do not flag (ErrorModel::coverage with the predicted std)
        for s in 0..2 {
            let uk = &fits.uk[s];
            let p = uk.predict(&held.q, &held.dir)?;
            let flags: Vec<usize> = uk
                .coverage(&held.q, &held.dir, &p.mean, Some(&p.std))?
                .into_iter()
                .map(|w| w.index)
                .collect();
            let covered = (0..test.len())
                .filter(|j| !flags.contains(j))
                .map(|j| dist(&errors[test[j]], &p.mean[j]))
                .fold(0.0, f64::max);
            line += &format!(
                " | {} covered {covered:.3} ({} flagged{})",
                ["JS", "EJS"][s],
                flags.len(),
                if flags.contains(&arg_worst[3 + s]) {
                    ", worst among them"
                } else {
                    ""
                }
            );
        }
        if let Some(sig) = prior {
            // the Bayesian prototype (and the GLS it must reproduce)
            let check = prior_max(&fits.uk[0], &tr, &held, None)?;
            let js = prior_max(&fits.uk[0], &tr, &held, Some(sig))?;
            let ejs = prior_max(&fits.uk[1], &tr, &held, Some(sig))?;
            line += &format!(" || GLS re-run JS {check:.3}; prior JS {js:.3} EJS {ejs:.3}");
            prior_worst[0] = prior_worst[0].max(js);
            prior_worst[1] = prior_worst[1].max(ejs);
        }
        println!("{line}");
        if diag && (worst[3] > ratio * worst[0] || worst[4] > ratio * worst[0]) {
            for s in 0..2 {
                let j = arg_worst[3 + s];
                println!(
                    "  worst pose of UK-kin {}: row {}",
                    ["JS", "EJS"][s],
                    test[j]
                );
                diagnose(&fits.uk[s], &held, j, &errors[test[j]], &preds[0][j])?;
                if s == 0 {
                    stacked_vs_axis(&fits.uk[0], robot, &tr, &held.q[j])?;
                }
            }
        }
        out.push(worst);
    }
    let overall = out
        .iter()
        .fold([0.0f64; 5], |a, b| std::array::from_fn(|i| a[i].max(b[i])));
    println!(
        "{label}: max  | {} | ratio to D-H: {}",
        overall.map(|v| format!("{v:8.3}")).join(" | "),
        overall
            .map(|v| format!("{:.1}", v / overall[0]))
            .join(" / ")
    );
    if prior.is_some() {
        println!(
            "{label}: prior max JS {:.3} EJS {:.3} (ratio to D-H {:.1} / {:.1})",
            prior_worst[0],
            prior_worst[1],
            prior_worst[0] / overall[0],
            prior_worst[1] / overall[0]
        );
    }
    Ok(out)
}

/// Prior σ of a calibration parameter named in a trend term `dPx/d<name>`:
/// `angle_deg` for angles (θ offsets, α, β, base rotations), `length_mm`
/// for lengths; `None` for other terms (the constant: no prior).
fn prior_sigma(term: &str, length_mm: f64, angle_deg: f64) -> Option<f64> {
    let p = term.split_once("/d")?.1;
    let angle = ["theta_off", "alpha", "beta", "base_r"]
        .iter()
        .any(|a| p.starts_with(a));
    Some(if angle { angle_deg } else { length_mm })
}

/// Prototype of Bayesian universal Kriging on one output of a fitted
/// kinematic-trend model: β ~ N(0, Σβ) (Σβ from [`prior_sigma`], vague for
/// the constant), i.e. `F Σβ Fᵀ` added to the covariance; at the model's
/// own ξ, ν, σ². Returns the predicted means (original units) at `s`.
/// With an infinite prior it reproduces the GLS model's mean.
fn prior_predict(
    o: &robokrige::kriging::KrigingModel,
    names: &[String],
    y: &[f64],
    s: &[Vec<f64>],
    sigmas: Option<(f64, f64)>,
) -> Res<Vec<f64>> {
    use faer::Par;
    use faer::linalg::triangular_solve::{
        solve_lower_triangular_in_place, solve_upper_triangular_in_place,
    };
    let d = o.data();
    let (c, ft, _) = o.factors()?;
    let (m, p) = (ft.nrows(), ft.ncols());
    let mut yt = faer::Mat::from_fn(m, 1, |i, _| (y[i] - d.y_mean) / d.y_std);
    solve_lower_triangular_in_place(c.as_ref(), yt.as_mut(), Par::Seq);
    // (F̃ᵀF̃ + σ² Σβ⁻¹) β = F̃ᵀỹ
    let mut a = nalgebra::DMatrix::<f64>::zeros(p, p);
    let mut b = nalgebra::DVector::<f64>::zeros(p);
    for j in 0..p {
        for k in 0..p {
            a[(j, k)] = (0..m).map(|i| ft[(i, j)] * ft[(i, k)]).sum();
        }
        b[j] = (0..m).map(|i| ft[(i, j)] * yt[(i, 0)]).sum();
        if let Some((len, ang)) = sigmas
            && let Some(sp) = prior_sigma(&d.trend.term_name(j, names), len, ang)
        {
            a[(j, j)] += d.sigma2 / (sp / d.y_std).powi(2);
        }
    }
    let beta = a
        .svd(true, true)
        .solve(&b, 1e-14)
        .map_err(|e| robokrige::Error::Numerical(e.to_string()))?;
    // γ = R⁻¹(y − Fβ) = C⁻ᵀ(ỹ − F̃β)
    let mut g = faer::Mat::from_fn(m, 1, |i, _| {
        yt[(i, 0)] - (0..p).map(|j| ft[(i, j)] * beta[j]).sum::<f64>()
    });
    solve_upper_triangular_in_place(c.transpose(), g.as_mut(), Par::Seq);
    let mut f = vec![0.0; p];
    Ok(s.iter()
        .map(|x| {
            d.trend.eval_into(x, &mut f);
            let r: f64 = (0..m)
                .map(|i| {
                    let q: f64 = (0..x.len())
                        .map(|k| d.theta[k] * (d.x_train[i][k] - x[k]).powi(2))
                        .sum();
                    (-q).exp() * g[(i, 0)]
                })
                .sum();
            let t: f64 = (0..p).map(|j| f[j] * beta[j]).sum();
            d.y_mean + d.y_std * (t + r)
        })
        .collect())
}

/// Max 3D error on `held` of the kinematic-trend model `uk` (fitted on
/// `tr`) with the prior `sigmas` (None: the GLS, to check the prototype).
fn prior_max(
    uk: &ErrorModel,
    tr: &Dataset,
    held: &Dataset,
    sigmas: Option<(f64, f64)>,
) -> Res<f64> {
    let s = uk.input_map().encode(&held.q, &held.dir)?;
    let e = tr.errors_or_err()?;
    let mut p = vec![[0.0; 3]; held.len()];
    for (a, o) in uk.outputs().iter().enumerate() {
        let y: Vec<f64> = e.iter().map(|v| v[a]).collect();
        for (i, v) in prior_predict(o, uk.input_names(), &y, &s, sigmas)?
            .into_iter()
            .enumerate()
        {
            p[i][a] = v;
        }
    }
    let t = held.errors_or_err()?;
    Ok(p.iter().zip(t).map(|(x, y)| dist(x, y)).fold(0.0, f64::max))
}

/// Leverage `x*ᵀ(AᵀA)⁺x*` of the rows `xs` in the least-squares problem of
/// design `a` (columns scaled to unit norm, pseudo-inverse by SVD, relative
/// cut 1e-12), and the largest leverage of `a`'s own rows.
fn ols_leverage(a: &nalgebra::DMatrix<f64>, xs: &[Vec<f64>]) -> (Vec<f64>, f64) {
    let p = a.ncols();
    let norms: Vec<f64> = (0..p).map(|j| a.column(j).norm().max(1e-300)).collect();
    let mut b = a.clone();
    for (j, nj) in norms.iter().enumerate() {
        b.column_mut(j).scale_mut(1.0 / nj);
    }
    let svd = b.svd(false, true);
    let Some(vt) = svd.v_t.as_ref() else {
        return (vec![f64::NAN; xs.len()], f64::NAN);
    };
    let cut = svd.singular_values.max() * 1e-12;
    let lev = |x: &[f64]| -> f64 {
        (0..svd.singular_values.len())
            .filter(|&k| svd.singular_values[k] > cut)
            .map(|k| {
                let u: f64 = (0..p).map(|j| vt[(k, j)] * x[j] / norms[j]).sum();
                (u / svd.singular_values[k]).powi(2)
            })
            .sum()
    };
    let train = (0..a.nrows())
        .map(|i| lev(&a.row(i).iter().copied().collect::<Vec<_>>()))
        .fold(0.0, f64::max);
    (xs.iter().map(|x| lev(x)).collect(), train)
}

/// The held-out pose `q` in the stacked least squares of the D-H
/// calibration (one parameter vector for x, y, z: the identifiable columns
/// of the 3m-row Jacobian plus a constant per axis) and in the per-axis
/// least squares of the kinematic trend (each axis its own columns): the
/// pose's leverage against the training rows' largest (OLS, R ignored).
fn stacked_vs_axis(uk: &ErrorModel, robot: &Robot, tr: &Dataset, q: &[f64]) -> Res<()> {
    use robokrige::kinematics::{calib_len, identification_jacobian};
    use robokrige::kriging::{Trend, independent_columns};
    let np = calib_len(robot.dof());
    let m = tr.len();
    let rows: Vec<[Vec<f64>; 3]> =
        tr.q.iter()
            .map(|q| identification_jacobian(robot, q))
            .collect();
    let stacked = faer::Mat::from_fn(3 * m, np, |i, k| rows[i / 3][i % 3][k]);
    let (kept, _) = independent_columns(&stacked, 1e-7);
    let p = kept.len() + 3;
    let design = |r: &[Vec<f64>; 3], a: usize| -> Vec<f64> {
        let mut x: Vec<f64> = kept.iter().map(|&k| r[a][k]).collect();
        x.extend((0..3).map(|b| if a == b { 1.0 } else { 0.0 }));
        x
    };
    let a = nalgebra::DMatrix::from_fn(3 * m, p, |i, c| design(&rows[i / 3], i % 3)[c]);
    let here = identification_jacobian(robot, q);
    let (lev, train) = ols_leverage(&a, &(0..3).map(|ax| design(&here, ax)).collect::<Vec<_>>());
    println!(
        "    stacked (D-H) LS: {} columns; held-out pose leverage x/y/z {:.3e} / {:.3e} / {:.3e}, training max {train:.3e}",
        p, lev[0], lev[1], lev[2]
    );
    for (ax, o) in uk.outputs().iter().enumerate() {
        let Trend::Kinematic(k) = &o.data().trend else {
            continue;
        };
        let cols: Vec<usize> = k.params.clone();
        let row = |r: &[Vec<f64>; 3]| -> Vec<f64> {
            let mut x = vec![1.0];
            x.extend(cols.iter().map(|&c| r[ax][c]));
            x
        };
        let a = nalgebra::DMatrix::from_fn(m, cols.len() + 1, |i, c| row(&rows[i])[c]);
        let (lev, train) = ols_leverage(&a, &[row(&here)]);
        println!(
            "    per-axis LS, axis {ax}: {} columns; held-out pose leverage {:.3e}, training max {train:.3e}",
            cols.len() + 1,
            lev[0]
        );
    }
    Ok(())
}

/// Singular values of `a` with its columns scaled to unit norm.
fn scaled_singular_values(a: &faer::Mat<f64>) -> Vec<f64> {
    let norms: Vec<f64> = (0..a.ncols())
        .map(|j| {
            (0..a.nrows())
                .map(|i| a[(i, j)].powi(2))
                .sum::<f64>()
                .sqrt()
                .max(1e-300)
        })
        .collect();
    let b = faer::Mat::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)] / norms[j]);
    b.singular_values().unwrap_or_default()
}

/// `x` with `Gᵀ u = x` solved for u (G upper triangular).
fn solve_gt(g: &faer::Mat<f64>, x: &[f64]) -> Vec<f64> {
    let p = x.len();
    let mut u = vec![0.0; p];
    for i in 0..p {
        let s: f64 = (0..i).map(|k| g[(k, i)] * u[k]).sum();
        u[i] = (x[i] - s) / g[(i, i)];
    }
    u
}

/// One held-out pose `j` of `held` through the kinematic-trend model `uk`:
/// per axis the trend and Kriging parts, the largest trend terms there and
/// on the training rows, the pose's trend leverage against the training
/// rows', the conditioning of F̃ and the hyperparameters.
fn diagnose(uk: &ErrorModel, held: &Dataset, j: usize, truth: &[f64; 3], dh: &[f64; 3]) -> Res<()> {
    let s = uk.input_map().encode(&held.q[j..=j], &held.dir[j..=j])?;
    let pred = uk.predict_mean(&held.q[j..=j], &held.dir[j..=j])?[0];
    println!(
        "  diag {:?} q = [{}] measured [{}] UK [{}] D-H [{}]",
        uk.space(),
        held.q[j]
            .iter()
            .map(|v| format!("{v:.1}"))
            .collect::<Vec<_>>()
            .join(", "),
        truth.map(|v| format!("{v:.3}")).join(", "),
        pred.map(|v| format!("{v:.3}")).join(", "),
        dh.map(|v| format!("{v:.3}")).join(", "),
    );
    for (a, o) in uk.outputs().iter().enumerate() {
        let d = o.data();
        let trend_part = o.predict_trend(&s)[0];
        let mean = o.predict_mean(&s)[0];
        let p = d.trend.len();
        let mut f = vec![0.0; p];
        d.trend.eval_into(&s[0], &mut f);
        let ftr = trend_matrix(&d.trend, &d.x_train);
        let (_, ftilde, g) = o.factors()?;
        let sv = scaled_singular_values(ftilde);
        let cond = sv.first().copied().unwrap_or(0.0) / sv.last().copied().unwrap_or(1.0);
        let lev = solve_gt(g, &f).iter().map(|v| v * v).sum::<f64>();
        let lev_train: Vec<f64> = (0..ftr.nrows())
            .map(|i| {
                let row: Vec<f64> = (0..p).map(|c| ftr[(i, c)]).collect();
                solve_gt(g, &row).iter().map(|v| v * v).sum::<f64>()
            })
            .collect();
        let lev_max = lev_train.iter().copied().fold(0.0, f64::max);
        let lev_mean = lev_train.iter().sum::<f64>() / lev_train.len() as f64;
        let ys = d.y_std;
        let se = o.beta_std_errors();
        // the terms: value at the pose and largest value on the training rows, mm
        let mut terms: Vec<(f64, f64, String, f64, f64)> = (0..p)
            .map(|c| {
                let here = ys * d.beta[c] * f[c];
                let train = (0..ftr.nrows())
                    .map(|i| (ys * d.beta[c] * ftr[(i, c)]).abs())
                    .fold(0.0, f64::max);
                (
                    here,
                    train,
                    d.trend.term_name(c, uk.input_names()),
                    d.beta[c],
                    se[c],
                )
            })
            .collect();
        terms.sort_by(|x, y| y.0.abs().total_cmp(&x.0.abs()));
        let log_xi: Vec<f64> = d.theta.iter().map(|t| t.log10()).collect();
        println!(
            "    axis {a}: mean {mean:.3} = trend {trend_part:.3} + Kriging {:.3}; {p} trend terms; cond(F̃, cols scaled) {cond:.2e}; leverage f*ᵀ(F̃ᵀF̃)⁻¹f* {lev:.3e} (training max {lev_max:.3e}, mean {lev_mean:.3e}); trend std {:.3} mm; nugget {:.2e}, log10 ξ in [{:.1}, {:.1}], process std {:.3} mm",
            mean - trend_part,
            (d.sigma2 * lev).sqrt() * ys,
            d.nugget,
            log_xi.iter().copied().fold(f64::MAX, f64::min),
            log_xi.iter().copied().fold(f64::MIN, f64::max),
            o.process_std(),
        );
        for (here, train, name, b, se) in terms.iter().take(6) {
            println!(
                "      {name:<22} β {b:>11.4e} (± {se:.2e}, t {:>7.1}) term here {here:>10.3} mm, max on training {train:>9.3} mm",
                b / se
            );
        }
    }
    Ok(())
}

/// With `home=1`, the robot's home pose as the first row; with
/// `checks=N`, N poses drawn uniformly in the work ranges at random places
/// of the sequence: poses out of the cubes, as a real campaign has (one
/// extra group for leave-one-cube-out).
fn add_outliers(c: &mut IsoCubeCampaign, robot: &Robot, a: &HashMap<String, String>, seed: u64) {
    use rand::RngExt;
    let group = c.centres_mm.len();
    let mut rng = robokrige::sim::rng_for(seed, "stress-outliers");
    for _ in 0..arg(a, "checks", 0.0) as usize {
        let q: Vec<f64> = robot
            .work_ranges
            .iter()
            .map(|(lo, hi)| lo + (hi - lo) * rng.random::<f64>())
            .collect();
        let at = rng.random_range(0..=c.q.len());
        c.q.insert(at, q);
        c.cube.insert(at, group);
        c.iso_point.insert(at, None);
    }
    if arg(a, "home", 0.0) > 0.0 {
        c.q.insert(0, robot.home.clone());
        c.cube.insert(0, group);
        c.iso_point.insert(0, None);
    }
}

fn main() -> Res<()> {
    let a: HashMap<String, String> = std::env::args()
        .skip(1)
        .filter_map(|s| {
            s.split_once('=')
                .map(|(k, v)| (k.to_string(), v.to_string()))
        })
        .collect();
    let seed = arg(&a, "seed", 1.0) as u64;
    let (robot, spec) = robot_and_spec(&a)?;
    let mut camp: IsoCubeCampaign = iso_cubes(&robot, &spec, seed)?;
    add_outliers(&mut camp, &robot, &a, seed);
    let mut profile = ErrorProfile::for_robot(&robot);
    profile.harmonic_deg *= arg(&a, "harm", 1.0);
    profile.backlash_deg *= arg(&a, "backlash", 1.0);
    let truth = TrueRobot::draw(&robot, &profile, seed);
    let data = measure_cubes(&truth, camp.q.clone(), seed)?;
    let periodic = periodic_joints(&data.q);
    println!(
        "{} seed {seed}: {} cubes of {} mm, {} poses; joint spans [{}] deg; periodic {:?}",
        robot.name,
        spec.cubes,
        spec.edge_mm,
        data.len(),
        camp.joint_spans()
            .iter()
            .map(|v| format!("{v:.0}"))
            .collect::<Vec<_>>()
            .join(", "),
        periodic
    );
    let base = ErrorModelParams::new()
        .periodic(periodic)
        .kriging(robokrige::kriging::KrigingOptions::default().nugget(true));
    let diag = arg(&a, "diag", 1.0) > 0.0;
    // prior σ of the parameter errors (mm, degrees) for the Bayesian prototype
    let prior = (arg(&a, "prior", 0.0) > 0.0)
        .then(|| (arg(&a, "prior_mm", 1.0), arg(&a, "prior_deg", 0.1)));
    let report = Report {
        diag,
        prior,
        ratio: arg(&a, "diag_ratio", 3.0),
    };
    let out_rows: Vec<usize> = (0..camp.len())
        .filter(|&i| camp.cube[i] == spec.cubes)
        .collect();
    println!("rows out of the cubes (home, checks): {out_rows:?}");
    if arg(&a, "holdout", 0.0) > 0.0 {
        let t = std::time::Instant::now();
        let cv = holdout_cv(&data, &robot, &base, 10, seed, data.len(), &|_, _| {})?;
        for (f, w) in cv.fold_max_mm.iter().enumerate() {
            println!(
                "holdout_cv fold {f:>2}: {}",
                w.map(|v| format!("{v:8.3}")).join(" | ")
            );
        }
        for (n, r) in CV_MODELS.iter().zip(&cv.rows[1..]) {
            println!(
                "holdout_cv {n:<42} mean {:.3} max {:.3}",
                r.mean_mm, r.max_mm
            );
        }
        println!("holdout_cv: {:.0} s", t.elapsed().as_secs_f64());
    }
    // the hyperparameters as holdout_cv chooses them: on all rows
    let t = std::time::Instant::now();
    let (dh_all, _) = calibrate(&data, &robot)?;
    let resid = residual(&data, &dh_all)?;
    let mut hyb = Vec::new();
    let mut kin = Vec::new();
    for space in [Space::Js, Space::Ejs] {
        hyb.push(
            base.clone()
                .space(space)
                .trend(TrendSpec::Options)
                .check()?
                .fit(&resid)?,
        );
        kin.push(
            base.clone()
                .space(space)
                .trend(TrendSpec::Kinematic(Box::new(robot.clone())))
                .check()?
                .fit(&data)?,
        );
    }
    println!("hyperparameters: {:.0} s", t.elapsed().as_secs_f64());
    if arg(&a, "random", 1.0) > 0.0 {
        let fold = kfold_partition(data.len(), 10, seed)?;
        run_folds("random10", &data, &robot, &fold, (&hyb, &kin), report)?;
    }
    if arg(&a, "loco", 1.0) > 0.0 {
        run_folds("loco", &data, &robot, &camp.cube, (&hyb, &kin), report)?;
    }
    Ok(())
}
