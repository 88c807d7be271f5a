//! The genetic-algorithm trend selection of seed 004 (EJS&GA+GPS), with the
//! closed-form K-fold CV RMSE as fitness.

use super::screen::screen_candidates;
use super::selector::{BasisSelector, GaSelection, Selection, SelectionProblem};
use crate::Result;
use crate::kriging::{
    Hyperparameters, KrigingParams, Trend, TrendKind, TrendModel, Tuning, ValidKrigingParams,
};
use crate::optim::{GaOptions, ga};
use crate::stats::{fold_blocks, kfold_partition};

/// Progress of a GA selection: `(output axis, generation, best CV RMSE mm)`.
pub type GaProgress<'a> = &'a (dyn Fn(usize, usize, f64) + Sync);

/// The GA selector of seed 004: per output, ξ from a constant-trend fit
/// with the problem's options; the candidates screened for linear
/// dependence ([`screen_candidates`]); a GA over the survivors (the constant
/// always kept) minimising the closed-form `folds`-fold CV RMSE (eq 17) at
/// that ξ, with the size cap C ≤ (K−1)m/K. Each output's [`GaSelection`]
/// holds its fitness history (seed 004 Fig 10); `progress` is called after
/// every generation.
#[derive(Clone, Copy)]
pub struct Ga<'a> {
    /// Folds K of the CV fitness (seed 004: 10).
    pub folds: usize,
    /// Seed of the fold partition and of the GA (output `a` uses `seed + a`).
    pub seed: u64,
    /// Called after every generation.
    pub progress: GaProgress<'a>,
}

impl std::fmt::Debug for Ga<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ga")
            .field("folds", &self.folds)
            .field("seed", &self.seed)
            .finish_non_exhaustive()
    }
}

impl BasisSelector for Ga<'_> {
    fn select(&self, p: &SelectionProblem) -> Result<([Trend; 3], Selection)> {
        let (k, m) = (self.folds, p.x.len());
        let d = p.names.len();
        let fold = kfold_partition(m, k, self.seed)?;
        let blocks = fold_blocks(&fold);
        let cap = (k - 1) * m / k;
        let constant = TrendKind::Constant.trend(d);
        let mut trends = Vec::with_capacity(3);
        let mut reports = Vec::with_capacity(3);
        for a in 0..3 {
            let screen = screen_candidates(&p.candidates[a], p.x, p.names);
            let cand = p.candidates[a].subset(&screen.kept);
            let y = &p.y[a];
            // every candidate is scored at one family: the options' fixed
            // one, the Gaussian when they choose it by CV
            let params = |trend: Trend, tuning: Tuning| -> Result<ValidKrigingParams> {
                KrigingParams::new(trend)
                    .options(p.options.clone())
                    .corr(p.options.get_corr().fixed().unwrap_or_default())
                    .tuning(tuning)
                    .correlation_inputs(p.inputs.d)
                    .names(p.names.to_vec())
                    .check()
            };
            let (_, base) = params(constant.clone(), Tuning::Search)?.fit(p.x, y)?;
            let at = Tuning::Fixed(Hyperparameters::of(&base, p.inputs.d));
            let rmse = |bits: &[bool]| {
                if p.options.cancel.is_cancelled() {
                    return f64::INFINITY;
                }
                let keep: Vec<usize> = (0..cand.len()).filter(|&j| j == 0 || bits[j]).collect();
                params(cand.subset(&keep), at.clone())
                    .and_then(|fit| fit.fit(p.x, y))
                    .and_then(|(model, _)| model.held_out_residuals(&blocks))
                    .map_or(f64::INFINITY, |e| {
                        (e.iter().map(|v| v * v).sum::<f64>() / m as f64).sqrt()
                    })
            };
            let ga_opts = GaOptions {
                max_ones: cap.saturating_sub(1),
                seed: self.seed.wrapping_add(a as u64),
                ..GaOptions::default()
            };
            let best = ga(cand.len(), rmse, &ga_opts, |g, f| (self.progress)(a, g, f));
            // once cancelled, every fitness is ∞ and the GA stalls out
            p.options.cancel.check()?;
            let keep: Vec<usize> = (0..cand.len())
                .filter(|&j| j == 0 || best.best[j])
                .collect();
            let trend = cand.subset(&keep);
            reports.push(GaSelection {
                candidates: screen.total,
                dropped: screen.dropped.clone(),
                size_cap: cap,
                selected: (0..trend.len())
                    .map(|j| trend.term_name(j, p.names))
                    .collect(),
                cv_rmse_mm: best.fitness,
                history: best.history,
                generations: best.generations,
                evaluations: best.evaluations,
            });
            trends.push(trend);
        }
        let trends: [Trend; 3] = trends.try_into().expect("three outputs");
        Ok((trends, Selection::Ga { outputs: reports }))
    }
}
