//! The test that scores the candidate families (step 3 of `diagnose`).
//!
//! Every grid point of a family joins the trend of the current model at
//! its ξ and nugget ([`gls`]); the family's statistic is the largest pooled
//! leave-one-out gain over its grid, `max_g [LOO(model) − LOO(model + g)]`.
//! Its p-value is a sequential sign-flip test against pseudo-campaigns of
//! the fitted model (its whitened residuals with random signs, the same
//! resamples for every family, the maximum over the same grid, so the scan
//! is paid for): `p = (1 + exceedances)/(1 + resamples)`, a family stopping
//! once [`SETTLED`] resamples reach its statistic (Besag & Clifford 1991).
//! Benjamini–Hochberg adjusts the p-values across families
//! ([`benjamini_hochberg`]). The strongest few families are tried again at
//! the ξ re-estimated with them ([`Refit`]), a lattice family is resolved on
//! its finer grid ([`Zoom`]), and each family's score is the
//! closed-form K-fold CV drop of its best point, its evidence the statistic
//! less its null mean, and its support set the points within `χ²₁(95 %)`
//! times the expected leave-one-out variance of the best.

use super::{Family, GridPoint, Zoom};
use crate::Result;
use crate::cancel::Cancel;
use crate::dataset::Dataset;
use crate::diagnose::gls::{self, AxisColumns, AxisSystem, FamilyTest};
use crate::diagnose::rows::ScanRows;
use crate::stats::rng_for;
use rand::RngExt;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Result of testing one family.
#[derive(Debug, Clone)]
pub struct Tested {
    /// Index of the family in the list tested.
    pub family: usize,
    /// Index of the best grid point in the family's grid.
    pub best: usize,
    /// Leave-one-out gain of the best grid point as a share of the model's
    /// leave-one-out SSE (the test statistic, relative).
    pub explained: f64,
    /// Sign-flip test p-value `(1 + exceedances) / (1 + resamples)`.
    pub p_value: f64,
    /// Benjamini–Hochberg adjusted p-value.
    pub q_value: f64,
    /// Out-of-sample score: relative drop of the closed-form K-fold CV SSE
    /// when the best grid point joins the trend.
    pub score: f64,
    /// Sign-flip resamples run before the family's p-value was settled.
    pub resamples: usize,
    /// Tested at the ξ the model would choose with it (else at the model's ξ).
    pub refit: bool,
    /// The closed-form K-fold CV SSE of the model as it is, pooled over the
    /// axes (mm²): `score` is relative to it.
    pub cv_sse_before: f64,
    /// Evidence: the statistic minus the mean of its null distribution (the
    /// best gain over the same grid in the pseudo-campaigns), as a share of
    /// the model's leave-one-out SSE — the gain beyond what scanning the
    /// family's grid finds by chance. A wide scan (a harmonic over hundreds
    /// of periods) pays for its width here, and unlike the p-value it does
    /// not saturate at `1/(1 + resamples)`.
    pub evidence: f64,
    /// Grid points whose leave-one-out gain is within `χ²₁(95 %) = 3.84`
    /// times the model's expected leave-one-out variance of the best (a 95 %
    /// support set of the scanned parameter, e.g. the rows a step may be at).
    pub support: Vec<usize>,
    /// For a family with a [`Family::zoom`](super::Family::zoom): its best point among the finer
    /// points around the lattice's best, on the data at the model's ξ (the
    /// p-value and score stay those of the lattice: the null distribution is
    /// the lattice's).
    pub refined: Option<Refined>,
}

/// A lattice point resolved on the finer grid around it.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The point reported and added.
    pub point: GridPoint,
    /// Parameters of the finer points within the support width of it.
    pub support: Vec<BTreeMap<String, f64>>,
}

impl Tested {
    /// A significant test result of `family` (its first grid point) whose
    /// score, share explained and evidence are all `evidence`: what the
    /// ranking and choosing tests build their rounds from.
    #[cfg(test)]
    pub(crate) fn for_test(family: usize, evidence: f64) -> Self {
        Tested {
            family,
            best: 0,
            explained: evidence,
            p_value: 0.001,
            q_value: 0.01,
            score: evidence,
            resamples: 999,
            refit: false,
            cv_sse_before: 1.0,
            evidence,
            support: Vec::new(),
            refined: None,
        }
    }

    /// The grid point to report and add: the refined one where there is one.
    pub fn point<'a>(&'a self, family: &'a Family) -> &'a GridPoint {
        self.refined
            .as_ref()
            .map_or(&family.grid[self.best], |r| &r.point)
    }
}

/// `χ²₁` quantile of 95 %: the drop of a likelihood-ratio statistic that
/// bounds a 95 % support interval of one scanned parameter.
const CHI2_1_95: f64 = 3.841_458_820_694_124;

/// Re-estimates ξ with a grid point's columns in the trend and returns the
/// model's systems there ([`gls::refit_systems`]); `None` keeps the first test.
pub type Refit<'a> = dyn Fn(&GridPoint) -> Option<Vec<AxisSystem>> + Sync + 'a;

/// Resamples per batch of the sequential test.
const BATCH: usize = 100;
/// Exceedances after which a family's p-value is settled (Besag & Clifford
/// 1991): a clearly null family stops after a batch or two.
const SETTLED: usize = 10;
/// Chance, at one look, that a family's upper confidence bound of its
/// exceedance probability is below the truth (one-sided Clopper–Pearson):
/// what it costs to stop a clearly significant family early
/// ([`exceedance_upper`], [`Null::decide`]).
const DECIDED_RISK: f64 = 1e-3;

/// A family as tested.
struct Trial {
    /// At the model's ξ: gives the null distribution.
    base: FamilyTest,
    /// Observed statistic (mm²): the best leave-one-out improvement over the
    /// model as it is, at its ξ or at the re-estimated one (score, evidence).
    stat: f64,
    /// The statistic at the model's ξ: what the null distribution tests.
    base_stat: f64,
    /// Reported grid point.
    best: usize,
    /// Scored at re-estimated ξ: its closed-form K-fold CV SSE and support
    /// set there (computed at once, so that the systems at that ξ — four
    /// m × m matrices per output — are not kept).
    refit: Option<(f64, Vec<usize>)>,
}

/// The support set's width at `systems`: `χ²₁(95 %)` times the expected
/// leave-one-out variance, pooled over the axes (mm²).
fn support_width(systems: &[AxisSystem]) -> f64 {
    CHI2_1_95
        * systems
            .iter()
            .map(|a| a.expected_loo_rmse().powi(2))
            .sum::<f64>()
        / systems.len() as f64
}

/// Test every family inside the current model (`systems`, one per output,
/// [`gls`], on the scanned rows `rows` the families were built on):
/// statistic, the pooled leave-one-out gain of the best
/// grid point at the model's ξ. Its null distribution is that of the same
/// statistic in pseudo-campaigns (sign-flipped whitened residuals, seeded,
/// the same for every family, sequential: a family stops once `SETTLED`
/// resamples reach its statistic, `p = (1 + exceed)/(1 + run)`, or once
/// Benjamini–Hochberg at `fdr` counts it on the upper Clopper–Pearson
/// bounds of the open families' exceedance probabilities, so that the
/// resamples left could not change it), so the p-value accounts for the
/// scan over the family's grid. Benjamini–Hochberg across families.
///
/// The `refine` families with the largest statistic are tried again at the
/// ξ the model would choose with their best grid point (`refit` returns the
/// systems there; `None` keeps the first test). Their score and reported
/// point become those of the new ξ when it gives more: the smaller of the
/// candidate's gain there and the improvement over the model as it is,
/// `LOO(model) − LOO(model + candidate at its ξ)`. A family of a
/// [`EffectKind::pose_function`](super::EffectKind::pose_function) kind is then also *tested* with that
/// statistic (the GP had partly soaked the effect up at the model's ξ). The
/// re-estimated statistic has no re-estimation in its null, so that p-value
/// is optimistic, and [`diagnose`](crate::diagnose::diagnose) counts such a candidate only once
/// the refit CV confirms it (pseudo-campaigns at the re-estimated ξ itself
/// were worse: controls reached p = 0.0005). Every other family keeps the
/// p-value of the model's ξ: in 160-row controls a step, and then a block
/// of rows, reached the smallest p-value the resamples allow at the
/// re-estimated ξ, and the GP cannot soak up an effect it has no input for.
/// Score, the closed-form K-fold CV drop at the partition the systems were
/// built for.
///
/// `cancel` is read between the re-estimations and between batches of
/// resamples: once it is cancelled the test ends with
/// [`Error::Interrupted`](crate::Error::Interrupted).
#[allow(clippy::too_many_arguments)]
pub fn test_families(
    families: &[Family],
    data: &Dataset,
    rows: &ScanRows,
    systems: Vec<AxisSystem>,
    permutations: usize,
    seed: u64,
    fdr: f64,
    refine: usize,
    refit: &Refit<'_>,
    cancel: &Cancel,
    progress: &dyn Fn(&str),
) -> Result<Vec<Tested>> {
    let grids: Vec<Vec<AxisColumns<'_>>> = families
        .iter()
        .map(|f| f.grid.iter().map(GridPoint::by_axis).collect())
        .collect();
    let base = Baseline::new(&systems);
    let mut trials: Vec<Trial> = grids.par_iter().map(|grid| base.trial(grid)).collect();
    refine_strongest(
        families,
        &grids,
        &mut trials,
        refine,
        refit,
        base.loo0,
        progress,
    );
    // a cancelled re-estimation gave no systems: the statistics are not final
    cancel.check()?;
    // the statistic each family's null distribution tests
    let observed: Vec<f64> = families
        .iter()
        .zip(&trials)
        .map(|(f, t)| {
            if f.kind.pose_function() {
                t.stat
            } else {
                t.base_stat
            }
        })
        .collect();
    let null = base.sign_flip(
        &trials,
        &observed,
        (permutations, fdr),
        seed,
        cancel,
        progress,
    );
    cancel.check()?;
    let p = null.p_values();
    let q = benjamini_hochberg(&p);
    let within = support_width(&systems);
    Ok((0..families.len())
        .into_par_iter()
        .map(|k| {
            let mut t = base.tested(k, &families[k], &trials[k], &null, within);
            t.p_value = p[k];
            t.q_value = q[k];
            if t.resamples > 0 && trials[k].stat.is_finite() && base.loo0 > 0.0 {
                t.evidence = (observed[k] - null.moments[k][0] / t.resamples as f64) / base.loo0;
            }
            if let Some(zoom) = families[k].zoom.filter(|_| trials[k].stat.is_finite()) {
                let start = &families[k].grid[trials[k].best];
                let on = (data, rows);
                t.refined = resolve(zoom, start, on, &systems, &base.data, within);
            }
            t
        })
        .collect())
}

/// The model as it is, at its own ξ, that every family is tested inside:
/// its systems, their observed responses, its leave-one-out SSE and its
/// closed-form K-fold CV SSE (score and share are against these).
struct Baseline<'a> {
    systems: &'a [AxisSystem],
    data: Vec<gls::Response>,
    loo0: f64,
    before: f64,
}

/// The sign-flip resamples of every family: exceedances of its observed
/// statistic, resamples run, and the sum and sum of squares of its null
/// statistics; the smallest upper bound of its exceedance probability so
/// far, and whether it was stopped as significant.
struct Null {
    exceed: Vec<usize>,
    run: Vec<usize>,
    moments: Vec<[f64; 2]>,
    upper: Vec<f64>,
    decided: Vec<bool>,
    /// Whether the family has a finite statistic (one without is never
    /// resampled; its p-value is 1).
    finite: Vec<bool>,
}

impl Null {
    fn new(finite: Vec<bool>) -> Self {
        let f = finite.len();
        Null {
            exceed: vec![0; f],
            run: vec![0; f],
            moments: vec![[0.0; 2]; f],
            upper: vec![1.0; f],
            decided: vec![false; f],
            finite,
        }
    }

    /// Whether family `k` still takes resamples.
    fn open(&self, k: usize) -> bool {
        self.exceed[k] < SETTLED && !self.decided[k] && self.finite[k]
    }

    /// Stop the open families that are significant at `fdr` whatever the
    /// resamples left would show (the idea of Gandy & Hahn's MMCTest, 2014):
    /// each open family's exceedance probability is bounded above by
    /// [`exceedance_upper`] (the smallest bound over the looks so far), the
    /// others keep their p-value, and an open family whose
    /// Benjamini–Hochberg q-value on these bounds is within `fdr` is
    /// decided. Its p-value stays `(1 + exceed)/(1 + run)`, below its
    /// bound, and Benjamini–Hochberg is monotone in the p-values, so with
    /// every bound holding it is significant in the end too. A clearly null
    /// family still stops at [`SETTLED`] exceedances; what only more
    /// resamples can tell runs on.
    fn decide(&mut self, fdr: f64) {
        let open: Vec<usize> = (0..self.finite.len()).filter(|&k| self.open(k)).collect();
        for &k in &open {
            let u = exceedance_upper(self.exceed[k], self.run[k], DECIDED_RISK);
            self.upper[k] = self.upper[k].min(u);
        }
        let mut v = self.p_values();
        for &k in &open {
            v[k] = self.upper[k];
        }
        let q = benjamini_hochberg(&v);
        for k in open {
            self.decided[k] = q[k] <= fdr;
        }
    }

    /// `(1 + exceedances) / (1 + resamples)`, 1 for a family without a
    /// finite statistic.
    fn p_values(&self) -> Vec<f64> {
        (0..self.finite.len())
            .map(|k| {
                if self.finite[k] {
                    (1 + self.exceed[k]) as f64 / (1 + self.run[k]) as f64
                } else {
                    1.0
                }
            })
            .collect()
    }
}

impl<'a> Baseline<'a> {
    fn new(systems: &'a [AxisSystem]) -> Self {
        Baseline {
            systems,
            data: gls::observed(systems),
            loo0: gls::loo_sse_before(systems),
            before: gls::kfold_sse_before(systems),
        }
    }

    /// A family's grid tested at the model's ξ: its best point and gain.
    fn trial(&self, grid: &[AxisColumns<'_>]) -> Trial {
        let base = FamilyTest::new(self.systems, grid);
        let (best, stat) = base.best(self.systems, &self.data);
        Trial {
            base,
            stat,
            base_stat: stat,
            best,
            refit: None,
        }
    }

    /// The sequential sign-flip test: pseudo-campaigns (sign-flipped
    /// whitened residuals, seeded, the same for every family) in batches,
    /// a family dropping out once [`SETTLED`] of them reach its `observed`
    /// statistic or once it is significant at `fdr` whatever more would
    /// show ([`Null::decide`]), at most `permutations` in all.
    fn sign_flip(
        &self,
        trials: &[Trial],
        observed: &[f64],
        (permutations, fdr): (usize, f64),
        seed: u64,
        cancel: &Cancel,
        progress: &dyn Fn(&str),
    ) -> Null {
        let (f, m) = (trials.len(), self.systems[0].rows());
        let mut null = Null::new(trials.iter().map(|t| t.stat.is_finite()).collect());
        let mut done = 0;
        while done < permutations && !cancel.is_cancelled() {
            let active: Vec<usize> = (0..f).filter(|&k| null.open(k)).collect();
            if active.is_empty() {
                break;
            }
            progress(&format!(
                "resamples {done}/{permutations}: {} candidate(s) still open",
                active.len()
            ));
            let batch = BATCH.min(permutations - done);
            let signs: Vec<Vec<f64>> = (done..done + batch)
                .map(|b| {
                    let mut rng = rng_for(seed.wrapping_add(b as u64), "diagnose-signs");
                    (0..m)
                        .map(|_| if rng.random_bool(0.5) { 1.0 } else { -1.0 })
                        .collect()
                })
                .collect();
            let pseudo = gls::flipped_batch(self.systems, &signs);
            // the best gain of every active family in every pseudo-campaign
            let hits: Vec<Vec<f64>> = active
                .par_iter()
                .map(|&k| trials[k].base.best_of_batch(self.systems, &pseudo))
                .collect();
            for (&k, h) in active.iter().zip(hits) {
                let o = observed[k];
                for g in h {
                    null.exceed[k] += usize::from(g >= o - 1e-12 * o.abs());
                    null.run[k] += 1;
                    if g.is_finite() {
                        null.moments[k][0] += g;
                        null.moments[k][1] += g * g;
                    }
                }
            }
            done += batch;
            null.decide(fdr);
        }
        null
    }

    /// Family `k` as tested (its p-value, q-value, evidence and refined
    /// point are set by the caller): share, score and support set at the ξ
    /// it was scored at.
    fn tested(&self, k: usize, family: &Family, t: &Trial, null: &Null, within: f64) -> Tested {
        let finite = t.stat.is_finite();
        let (kfold, support) = match &t.refit {
            Some((kfold, support)) => (*kfold, support.clone()),
            None if finite => (
                t.base.kfold_sse(self.systems, t.best),
                t.base.near_best(self.systems, &self.data, within),
            ),
            None => (self.before, Vec::new()),
        };
        Tested {
            family: k,
            best: t.best,
            explained: if finite && self.loo0 > 0.0 {
                t.stat / self.loo0
            } else {
                0.0
            },
            p_value: 1.0,
            q_value: 1.0,
            score: if finite && self.before > 0.0 {
                1.0 - kfold / self.before
            } else {
                0.0
            },
            resamples: null.run[k],
            refit: t.refit.is_some(),
            cv_sse_before: self.before,
            evidence: 0.0,
            support: if finite && family.grid.len() > 1 {
                support
            } else {
                Vec::new()
            },
            refined: None,
        }
    }
}

/// The `refine` families with the largest statistic tried again at the ξ
/// the model would choose with their best grid point (`refit`); a family's
/// statistic, best point, score and support become those of the new ξ when
/// its improvement over the model as it is (`loo0`) is larger there.
fn refine_strongest(
    families: &[Family],
    grids: &[Vec<AxisColumns<'_>>],
    trials: &mut [Trial],
    refine: usize,
    refit: &Refit<'_>,
    loo0: f64,
    progress: &dyn Fn(&str),
) {
    let mut order: Vec<usize> = (0..families.len())
        .filter(|&k| trials[k].stat.is_finite() && trials[k].stat > 0.0)
        .collect();
    order.sort_by(|&a, &b| trials[b].stat.total_cmp(&trials[a].stat));
    for (n, &k) in order.iter().take(refine).enumerate() {
        progress(&format!(
            "re-estimating ξ with '{}' ({}/{})",
            families[k].label,
            n + 1,
            refine.min(order.len())
        ));
        let Some(sys) = refit(&families[k].grid[trials[k].best]) else {
            continue;
        };
        let test = FamilyTest::new(&sys, &grids[k]);
        let (best, gain) = test.best(&sys, &gls::observed(&sys));
        // the candidate's own share: its gain at the new ξ, but no more than
        // the improvement over the model as it is (the new ξ may be worse for
        // the model without it, which inflates the first, or better, which
        // inflates the second)
        let improvement = gain.min(gain - (gls::loo_sse_before(&sys) - loo0));
        let t = &mut trials[k];
        if improvement > t.stat {
            t.stat = improvement;
            t.best = best;
            t.refit = Some((
                test.kfold_sse(&sys, best),
                test.near_best(&sys, &gls::observed(&sys), support_width(&sys)),
            ));
        }
    }
}

/// The best of the finer points around `start` ([`Zoom`]) on the data, the
/// zoom repeated around each new best (a block's edges move one at a time,
/// so both settle after a few passes; at most [`ZOOM_PASSES`]), and the
/// points of the last pass within the support width of it; `None` when none
/// is usable.
fn resolve(
    zoom: Zoom,
    start: &GridPoint,
    (campaign, rows): (&Dataset, &ScanRows),
    systems: &[AxisSystem],
    data: &[gls::Response],
    within: f64,
) -> Option<Refined> {
    let mut found: Option<Refined> = None;
    for _ in 0..ZOOM_PASSES {
        let centre = found.as_ref().map_or(start, |r| &r.point);
        let local = zoom(centre, rows, campaign);
        if local.is_empty() {
            break;
        }
        let grid: Vec<AxisColumns<'_>> = local.iter().map(GridPoint::by_axis).collect();
        let test = FamilyTest::new(systems, &grid);
        let (best, gain) = test.best(systems, data);
        if !gain.is_finite() {
            break;
        }
        let settled = local[best].params == centre.params;
        found = Some(Refined {
            support: test
                .near_best(systems, data, within)
                .into_iter()
                .map(|i| local[i].params.clone())
                .collect(),
            point: local[best].clone(),
        });
        if settled {
            break;
        }
    }
    found
}

/// Passes of a [`Zoom`] at most.
const ZOOM_PASSES: usize = 4;

/// Upper one-sided `1 − risk` Clopper–Pearson bound of an exceedance
/// probability from `exceed` exceedances in `run` resamples: the `p` at
/// which `P(Binomial(run, p) ≤ exceed) = risk` (bisection; 1 without
/// resamples).
fn exceedance_upper(exceed: usize, run: usize, risk: f64) -> f64 {
    if run == 0 || exceed >= run {
        return 1.0;
    }
    // ln P(Binomial(run, p) ≤ exceed), the terms summed in log space
    let ln_cdf = |p: f64| -> f64 {
        let (lp, lq) = (p.ln(), (1.0 - p).ln());
        let mut ln_choose = 0.0;
        let mut terms = Vec::with_capacity(exceed + 1);
        for i in 0..=exceed {
            if i > 0 {
                ln_choose += ((run - i + 1) as f64).ln() - (i as f64).ln();
            }
            terms.push(ln_choose + i as f64 * lp + (run - i) as f64 * lq);
        }
        let top = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        top + terms.iter().map(|t| (t - top).exp()).sum::<f64>().ln()
    };
    let target = risk.ln();
    let (mut lo, mut hi) = (exceed as f64 / run as f64, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if ln_cdf(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
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

    /// Without exceedances the bound is `1 − risk^(1/run)`; with some, the
    /// binomial CDF at the bound is the risk; more resamples tighten it.
    #[test]
    fn the_upper_bound_of_an_exceedance_probability_is_clopper_pearson() {
        let u = exceedance_upper(0, 100, 1e-3);
        assert!((u - (1.0 - 1e-3f64.powf(0.01))).abs() < 1e-9, "{u}");
        let (e, n) = (3usize, 500usize);
        let u = exceedance_upper(e, n, 1e-3);
        let mut cdf = 0.0;
        let mut choose = 1.0f64;
        for i in 0..=e {
            if i > 0 {
                choose *= (n - i + 1) as f64 / i as f64;
            }
            cdf += choose * u.powi(i as i32) * (1.0 - u).powi((n - i) as i32);
        }
        assert!((cdf - 1e-3).abs() < 1e-9, "{cdf}");
        assert!(u > (1 + e) as f64 / (1 + n) as f64);
        assert!(exceedance_upper(3, 1000, 1e-3) < u);
        assert_eq!(exceedance_upper(0, 0, 1e-3), 1.0);
    }

    /// A family no resample reaches stops once Benjamini–Hochberg on the
    /// bounds already counts it, the sooner the more such families there
    /// are (the bar is `rank × fdr / families`); one with a few
    /// exceedances, whose fate more resamples decide, and a null one do
    /// not; three clear families among 95 need every resample.
    #[test]
    fn a_clearly_significant_family_stops_before_the_last_resample() {
        // `clear` families without exceedances, one with three in every
        // 500, the rest null (settled at once); the resamples run when the
        // first clear one stopped
        let run_until_stop = |clear: usize| -> (Option<usize>, Null) {
            let mut null = Null::new(vec![true; 95]);
            let mut stopped = None;
            for run in (100..=1999).step_by(100) {
                for k in 0..95 {
                    if null.open(k) {
                        null.exceed[k] = match k {
                            k if k < clear => 0,
                            k if k == clear => 3 * run / 500,
                            _ => SETTLED,
                        };
                        null.run[k] = run;
                    }
                }
                null.decide(0.05);
                if stopped.is_none() && null.decided[0] {
                    stopped = Some(run);
                }
            }
            (stopped, null)
        };
        let (at, null) = run_until_stop(20);
        let at = at.expect("twenty clear families stop early");
        assert!(at < 1999 && (0..20).all(|k| null.decided[k]), "{at}");
        assert!((20..95).all(|k| !null.decided[k]));
        // their p-values stay below their bounds, and BH on the p-values
        // counts them
        let p = null.p_values();
        let q = benjamini_hochberg(&p);
        assert!((0..20).all(|k| p[k] <= null.upper[k] && q[k] <= 0.05));
        let (sooner, _) = run_until_stop(60);
        assert!(sooner.unwrap() < at, "{sooner:?} vs {at}");
        let (never, few) = run_until_stop(3);
        assert!(never.is_none() && few.run[0] == 1900, "{never:?}");
    }
}
