//! Candidate effects and their significance (step 2–3 of `diagnose`).
//!
//! A *family* is one named effect scanned over a parameter grid (a step over
//! the split row, a harmonic over the period, …); each grid point is a set of
//! regressors. On residuals `R` (m × 3, centred per axis) the statistic of a
//! grid point with orthonormal regressor basis `Q` is the share of residual
//! variance it explains, pooled over the axes,
//! `T = Σ_a ‖Qᵀ r_a‖² / Σ_a ‖r_a‖²`, and a family's statistic is its maximum
//! over the grid. Significance is a permutation test of that maximum (the rows
//! of `R` permuted jointly across axes, the same permutations for every
//! family, so the scan over the grid is paid for), with the
//! Benjamini–Hochberg correction across families. The score used for ranking
//! is out of sample: `1 − SSE_cv / SSE0_cv`, K-fold least squares of the
//! residuals on the best grid point's regressors against the intercept alone.

use crate::dataset::Dataset;
use crate::features::Feature;
use crate::sim::rng_for;
use rand::RngExt;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What kind of effect a family is (the JSON `kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EffectKind {
    Covariate,
    Order,
    Harmonic,
    Interaction,
    DirectionHistory,
}

/// One parameter value of a family.
#[derive(Debug, Clone)]
pub struct GridPoint {
    pub params: BTreeMap<String, f64>,
    /// Regressors, one column per entry (row order).
    pub columns: Vec<Vec<f64>>,
    /// What to add to the model if this is accepted.
    pub add: Vec<Feature>,
}

/// A candidate effect: a name and a grid of regressor sets.
#[derive(Debug, Clone)]
pub struct Family {
    pub kind: EffectKind,
    /// Column(s) / joint(s) it comes from, e.g. `["temp_c"]`, `["q2"]`, `["row"]`.
    pub source: Vec<String>,
    /// Short description, e.g. "temp_c × joint angles".
    pub label: String,
    pub grid: Vec<GridPoint>,
}

fn zscore(v: &[f64]) -> Vec<f64> {
    let n = v.len() as f64;
    let mu = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / n).sqrt();
    v.iter()
        .map(|x| if sd > 0.0 { (x - mu) / sd } else { 0.0 })
        .collect()
}

fn params(kv: &[(&str, f64)]) -> BTreeMap<String, f64> {
    kv.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}

/// The candidate families a campaign supports. Covariates named in
/// `exclude` (already in the model) and columns with missing values are left
/// out; the harmonic periods run from 2° to half the joint's range, in steps
/// of a quarter cycle over the range. With a robot preset (`robot`), joint
/// cross-talk candidates mapped through its Jacobian are added.
pub fn families(data: &Dataset, exclude: &[String], robot: Option<&str>) -> Vec<Family> {
    let m = data.len();
    let n = data.n_joints();
    let u: Vec<Vec<f64>> = (0..n)
        .map(|j| zscore(&data.q.iter().map(|r| r[j]).collect::<Vec<_>>()))
        .collect();
    let single = |params: BTreeMap<String, f64>, col: Vec<f64>, add: Feature| GridPoint {
        params,
        columns: vec![col],
        add: vec![add],
    };
    let mut out = Vec::new();
    for c in &data.covariates {
        if exclude.contains(&c.name) || c.missing > 0 || c.name.starts_with('@') {
            continue;
        }
        let z = zscore(&c.values);
        if z.iter().all(|v| *v == 0.0) {
            continue;
        }
        let add = Feature::Covariate {
            name: c.name.clone(),
            reference: Some(c.values[0]),
        };
        out.push(Family {
            kind: EffectKind::Covariate,
            source: vec![c.name.clone()],
            label: format!("{} (alone)", c.name),
            grid: vec![single(BTreeMap::new(), z.clone(), add.clone())],
        });
        let mut cols = vec![z.clone()];
        cols.extend(
            u.iter()
                .map(|uj| z.iter().zip(uj).map(|(a, b)| a * b).collect()),
        );
        out.push(Family {
            kind: EffectKind::Covariate,
            source: vec![c.name.clone()],
            label: format!("{} × joint angles", c.name),
            grid: vec![GridPoint {
                params: BTreeMap::new(),
                columns: cols,
                add: vec![add],
            }],
        });
    }
    // measurement order: slow drift and a change point
    let row = zscore(&(0..m).map(|i| i as f64).collect::<Vec<_>>());
    out.push(Family {
        kind: EffectKind::Order,
        source: vec!["row".into()],
        label: "drift over the measurement order".into(),
        grid: vec![GridPoint {
            params: BTreeMap::new(),
            columns: vec![
                row.clone(),
                zscore(&row.iter().map(|r| r * r).collect::<Vec<_>>()),
            ],
            add: vec![Feature::Row],
        }],
    });
    let margin = (m / 20).max(5);
    if m > 2 * margin {
        out.push(Family {
            kind: EffectKind::Order,
            source: vec!["row".into()],
            label: "step in the measurement order".into(),
            grid: (margin..m - margin)
                .map(|t| {
                    let col = (0..m).map(|i| if i >= t { 1.0 } else { 0.0 }).collect();
                    single(params(&[("row", t as f64)]), col, Feature::Step { row: t })
                })
                .collect(),
        });
    }
    // periodic terms per joint
    for j in 0..n {
        let (lo, hi) = data
            .q
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                (a.min(r[j]), b.max(r[j]))
            });
        let range = hi - lo;
        let mut grid = Vec::new();
        let mut cycles = 2.0;
        while range / cycles >= 2.0 && grid.len() < 160 {
            let period = range / cycles;
            let w = std::f64::consts::TAU / period;
            let s: Vec<f64> = data.q.iter().map(|r| (w * r[j]).sin()).collect();
            let c: Vec<f64> = data.q.iter().map(|r| (w * r[j]).cos()).collect();
            grid.push(GridPoint {
                params: params(&[("period_deg", period)]),
                columns: vec![zscore(&s), zscore(&c)],
                add: vec![Feature::Harmonic {
                    joint: j + 1,
                    period_deg: period,
                }],
            });
            cycles += 0.25;
        }
        if !grid.is_empty() {
            out.push(Family {
                kind: EffectKind::Harmonic,
                source: vec![format!("q{}", j + 1)],
                label: format!("harmonic of q{}", j + 1),
                grid,
            });
        }
    }
    // cross-joint interactions
    for a in 0..n {
        for b in a + 1..n {
            let col = zscore(
                &u[a]
                    .iter()
                    .zip(&u[b])
                    .map(|(x, y)| x * y)
                    .collect::<Vec<_>>(),
            );
            out.push(Family {
                kind: EffectKind::Interaction,
                source: vec![format!("q{}", a + 1), format!("q{}", b + 1)],
                label: format!("q{} × q{}", a + 1, b + 1),
                grid: vec![single(
                    BTreeMap::new(),
                    col,
                    Feature::Interaction { a: a + 1, b: b + 1 },
                )],
            });
        }
    }
    // joint cross-talk through the Jacobian (needs the robot)
    if let Some(name) = robot {
        for j in 1..=n {
            for k in (1..=n).filter(|&k| k != j) {
                let f = Feature::Crosstalk {
                    robot: name.to_string(),
                    joint: j,
                    from: k,
                };
                let Ok(cols) = f.columns_from_poses(&data.q, &data.dir) else {
                    continue;
                };
                out.push(Family {
                    kind: EffectKind::Interaction,
                    source: vec![format!("q{j}"), format!("q{k}")],
                    label: format!("q{j} deviating with sin/cos q{k} (via the Jacobian)"),
                    grid: vec![GridPoint {
                        params: BTreeMap::new(),
                        columns: cols.iter().map(|c| zscore(c)).collect(),
                        add: vec![f],
                    }],
                });
            }
        }
    }
    // direction history
    for j in 0..n {
        for f in [
            Feature::PreviousDirection { joint: j + 1 },
            Feature::SinceReversal { joint: j + 1 },
        ] {
            let col = zscore(
                &f.columns_from_poses(&data.q, &data.dir)
                    .expect("pose feature")[0],
            );
            if col.iter().all(|v| *v == 0.0) {
                continue;
            }
            let label = match f {
                Feature::PreviousDirection { .. } => format!("previous direction of q{}", j + 1),
                _ => format!("travel of q{} since its last reversal", j + 1),
            };
            out.push(Family {
                kind: EffectKind::DirectionHistory,
                source: vec![format!("dir{}", j + 1)],
                label,
                grid: vec![single(BTreeMap::new(), col, f)],
            });
        }
    }
    out
}

/// Orthonormal basis (modified Gram–Schmidt, twice) of centred columns;
/// dependent columns are dropped.
fn orthonormal(columns: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for c in columns {
        let mu = c.iter().sum::<f64>() / c.len() as f64;
        let mut v: Vec<f64> = c.iter().map(|x| x - mu).collect();
        let n0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        for _ in 0..2 {
            for b in &basis {
                let d: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
                v.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
            }
        }
        let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n0 > 0.0 && nv > 1e-8 * n0 {
            v.iter_mut().for_each(|x| *x /= nv);
            basis.push(v);
        }
    }
    basis
}

/// Result of testing one family.
#[derive(Debug, Clone)]
pub struct Tested {
    pub family: usize,
    /// Best grid point (index) and its in-sample explained share T.
    pub best: usize,
    pub explained: f64,
    pub p_value: f64,
    /// Benjamini–Hochberg adjusted p-value.
    pub q_value: f64,
    /// Out-of-sample explained share (the ranking score).
    pub score: f64,
}

fn explained(q: &[Vec<f64>], r: &[[f64; 3]], perm: Option<&[usize]>) -> f64 {
    let mut num = 0.0;
    for b in q {
        let mut d = [0.0; 3];
        match perm {
            None => {
                for (bi, ri) in b.iter().zip(r) {
                    for a in 0..3 {
                        d[a] += bi * ri[a];
                    }
                }
            }
            Some(p) => {
                for (bi, &pi) in b.iter().zip(p) {
                    for a in 0..3 {
                        d[a] += bi * r[pi][a];
                    }
                }
            }
        }
        num += d.iter().map(|x| x * x).sum::<f64>();
    }
    num
}

/// Test every family on residuals `resid` (m × 3) with `permutations`
/// permutations (seeded), and score the best grid point of each by `folds`-fold
/// CV of least squares (fold of every row in `fold`).
pub fn test_families(
    families: &[Family],
    resid: &[[f64; 3]],
    permutations: usize,
    seed: u64,
    fold: &[usize],
    folds: usize,
) -> Vec<Tested> {
    let m = resid.len();
    let mean: [f64; 3] =
        std::array::from_fn(|a| resid.iter().map(|r| r[a]).sum::<f64>() / m as f64);
    let r: Vec<[f64; 3]> = resid
        .iter()
        .map(|x| [x[0] - mean[0], x[1] - mean[1], x[2] - mean[2]])
        .collect();
    let total: f64 = r
        .iter()
        .map(|x| x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        .sum();
    let bases: Vec<Vec<Vec<Vec<f64>>>> = families
        .par_iter()
        .map(|f| f.grid.iter().map(|g| orthonormal(&g.columns)).collect())
        .collect();
    let family_max = |perm: Option<&[usize]>| -> Vec<(usize, f64)> {
        bases
            .iter()
            .map(|grid| {
                grid.iter()
                    .enumerate()
                    .map(|(g, q)| (g, explained(q, &r, perm)))
                    .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a })
            })
            .collect()
    };
    let observed = family_max(None);
    let exceed: Vec<usize> = (0..permutations)
        .into_par_iter()
        .map(|b| {
            let mut rng = rng_for(seed.wrapping_add(b as u64), "diagnose-permutation");
            let mut p: Vec<usize> = (0..m).collect();
            for i in (1..m).rev() {
                p.swap(i, rng.random_range(0..=i));
            }
            family_max(Some(&p))
                .iter()
                .zip(&observed)
                .map(|(t, o)| usize::from(t.1 >= o.1 * (1.0 - 1e-12)))
                .collect::<Vec<usize>>()
        })
        .reduce(
            || vec![0; families.len()],
            |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect(),
        );
    let p: Vec<f64> = exceed
        .iter()
        .map(|e| (1 + e) as f64 / (permutations + 1) as f64)
        .collect();
    let q = benjamini_hochberg(&p);
    families
        .par_iter()
        .enumerate()
        .map(|(k, f)| {
            let best = observed[k].0;
            Tested {
                family: k,
                best,
                explained: if total > 0.0 {
                    observed[k].1 / total
                } else {
                    0.0
                },
                p_value: p[k],
                q_value: q[k],
                score: cv_score(&f.grid[best].columns, resid, fold, folds),
            }
        })
        .collect()
}

/// The least-squares fit of the centred residuals on the centred `columns`
/// (m × 3), for comparing what two candidates explain.
pub fn fitted(columns: &[Vec<f64>], resid: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let m = resid.len();
    let mean: [f64; 3] =
        std::array::from_fn(|a| resid.iter().map(|r| r[a]).sum::<f64>() / m as f64);
    let mut out = vec![[0.0; 3]; m];
    for b in orthonormal(columns) {
        for a in 0..3 {
            let d: f64 = b.iter().zip(resid).map(|(x, r)| x * (r[a] - mean[a])).sum();
            for (o, x) in out.iter_mut().zip(&b) {
                o[a] += d * x;
            }
        }
    }
    out
}

/// Cosine similarity of two fitted components (pooled over the axes).
pub fn similarity(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let dot = |u: &[[f64; 3]], v: &[[f64; 3]]| -> f64 {
        u.iter()
            .zip(v)
            .map(|(x, y)| x[0] * y[0] + x[1] * y[1] + x[2] * y[2])
            .sum()
    };
    let d = (dot(a, a) * dot(b, b)).sqrt();
    if d > 0.0 { dot(a, b) / d } else { 0.0 }
}

/// Benjamini–Hochberg adjusted p-values (step-up, monotone).
pub fn benjamini_hochberg(p: &[f64]) -> Vec<f64> {
    let n = p.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|a, b| p[*a].total_cmp(&p[*b]));
    let mut q = vec![0.0; n];
    let mut running = 1.0f64;
    for (rank, &i) in order.iter().enumerate().rev() {
        running = running.min(p[i] * n as f64 / (rank + 1) as f64);
        q[i] = running;
    }
    q
}

/// `1 − SSE_cv / SSE0_cv`: K-fold least squares of the residuals on
/// `[1, columns]` against the intercept alone, pooled over the three axes.
#[allow(clippy::needless_range_loop)] // `ax` indexes the axis of every residual row
pub fn cv_score(columns: &[Vec<f64>], resid: &[[f64; 3]], fold: &[usize], folds: usize) -> f64 {
    let m = resid.len();
    let (mut sse, mut sse0) = (0.0, 0.0);
    for f in 0..folds {
        let train: Vec<usize> = (0..m).filter(|&i| fold[i] != f).collect();
        let test: Vec<usize> = (0..m).filter(|&i| fold[i] == f).collect();
        if train.is_empty() || test.is_empty() {
            continue;
        }
        // centre on the training rows, orthonormalise, project
        let cmean: Vec<f64> = columns
            .iter()
            .map(|c| train.iter().map(|&i| c[i]).sum::<f64>() / train.len() as f64)
            .collect();
        let tr_cols: Vec<Vec<f64>> = columns
            .iter()
            .zip(&cmean)
            .map(|(c, mu)| train.iter().map(|&i| c[i] - mu).collect())
            .collect();
        // least squares via normal equations on the (small) orthonormalised set
        let k = tr_cols.len();
        let mut g = vec![vec![0.0; k]; k];
        for a in 0..k {
            for b in 0..k {
                g[a][b] = tr_cols[a].iter().zip(&tr_cols[b]).map(|(x, y)| x * y).sum();
            }
            g[a][a] += 1e-9 * (1.0 + g[a][a]);
        }
        for ax in 0..3 {
            let ymu = train.iter().map(|&i| resid[i][ax]).sum::<f64>() / train.len() as f64;
            let rhs: Vec<f64> = tr_cols
                .iter()
                .map(|c| {
                    c.iter()
                        .zip(&train)
                        .map(|(x, &i)| x * (resid[i][ax] - ymu))
                        .sum()
                })
                .collect();
            let beta = solve_small(&g, &rhs);
            for &i in &test {
                let pred: f64 = ymu
                    + (0..k)
                        .map(|a| beta[a] * (columns[a][i] - cmean[a]))
                        .sum::<f64>();
                sse += (resid[i][ax] - pred).powi(2);
                sse0 += (resid[i][ax] - ymu).powi(2);
            }
        }
    }
    if sse0 > 0.0 { 1.0 - sse / sse0 } else { 0.0 }
}

/// Solve a small symmetric positive definite system by Cholesky.
fn solve_small(g: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let k = b.len();
    let mut l = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..=i {
            let s: f64 = g[i][j] - (0..j).map(|t| l[i][t] * l[j][t]).sum::<f64>();
            l[i][j] = if i == j {
                s.max(1e-300).sqrt()
            } else {
                s / l[j][j]
            };
        }
    }
    let mut y = vec![0.0; k];
    for i in 0..k {
        y[i] = (b[i] - (0..i).map(|t| l[i][t] * y[t]).sum::<f64>()) / l[i][i];
    }
    let mut x = vec![0.0; k];
    for i in (0..k).rev() {
        x[i] = (y[i] - (i + 1..k).map(|t| l[t][i] * x[t]).sum::<f64>()) / l[i][i];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bh_adjustment_is_monotone_and_matches_hand_values() {
        let q = benjamini_hochberg(&[0.01, 0.04, 0.03, 0.5]);
        assert!((q[0] - 0.04).abs() < 1e-12);
        assert!((q[2] - 0.0533333333333).abs() < 1e-9);
        assert!((q[1] - 0.0533333333333).abs() < 1e-9);
        assert!((q[3] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn cv_score_of_a_perfect_regressor_is_near_one_and_of_noise_near_zero() {
        let m = 200;
        let x: Vec<f64> = (0..m).map(|i| ((i * 37) % 101) as f64 / 101.0).collect();
        let fold: Vec<usize> = (0..m).map(|i| i % 10).collect();
        let r: Vec<[f64; 3]> = x.iter().map(|v| [2.0 * v, -v, 0.5 * v]).collect();
        assert!(cv_score(std::slice::from_ref(&x), &r, &fold, 10) > 0.999);
        let noise: Vec<[f64; 3]> = (0..m)
            .map(|i| {
                let t = (i as f64 * 12.9898).sin() * 43758.5453;
                let u = t - t.floor() - 0.5;
                [u, -u, u]
            })
            .collect();
        assert!(cv_score(&[x], &noise, &fold, 10) < 0.05);
    }
}
