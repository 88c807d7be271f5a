//! One round of the [`diagnose`](super::diagnose) loop: test the candidate
//! families inside the current model, rank and report them, give the
//! effect added last round its "after" check, and add the best candidate
//! the refit CV confirms.

use super::accept::{CONFIRMATIONS, Worth, after_check};
use super::choose::{self, Round};
use super::confound;
use super::fit::{closed_form_rmse, cross_validated, refit_closed_form};
use super::gls;
use super::options::{DiagnoseOptions, min_resamples};
use super::rank::{prefer_simpler, rank};
use super::report::{
    AfterCheck, CvStats, Diagnosis, EffectReport, LeftOut, coefficients, support_interval,
};
use super::rows::{ScanRows, place_steps};
use super::scan::{self, EffectKind, Family, Tested};
use crate::Result;
use crate::calibration::Displacements;
use crate::dataset::Dataset;
use crate::features::Feature;
use crate::model::ErrorModel;

/// The campaign as the loop sees it: all rows for the fits and CVs, the
/// scanned rows ([`ScanRows`]) with their fold partition and errors for
/// the candidate test.
pub(super) struct Campaign<'a> {
    pub data: &'a Dataset,
    pub errors: &'a [[f64; 3]],
    pub rows: &'a ScanRows,
    pub fold: &'a [usize],
    pub scan_errors: &'a [[f64; 3]],
    /// The displacements of the directions the calibration whose residual
    /// is diagnosed saw, per axis, on every row
    /// ([`crate::calibration::Calibration::seen_displacements`]).
    pub calibration: Option<&'a Displacements>,
    pub o: &'a DiagnoseOptions,
}

/// The effect accepted in the last round, awaiting its "after" check.
struct Pending {
    /// Its index in [`Rounds::effects`].
    index: usize,
    /// The pooled CV RMSE drop its test promised.
    promised: f64,
    /// The drop the refit CV measured.
    achieved: f64,
    /// The CV with it.
    after: CvStats,
    /// The candidates of its round whose fit its columns take
    /// ([`confound::sharing`]).
    shared: Vec<confound::Shared>,
}

/// What the loop carries from round to round.
pub(super) struct Rounds {
    model: ErrorModel,
    before: CvStats,
    current: CvStats,
    extras: Vec<Feature>,
    steps: Vec<CvStats>,
    effects: Vec<EffectReport>,
    permutations: usize,
    candidates: [usize; 2],
    pending: Option<Pending>,
    added_kinds: Vec<EffectKind>,
    left_by_cap: Vec<LeftOut>,
}

/// How a round judges a tested candidate: its closed-form CV mean squared
/// error before and with it, and whether the drop counts.
struct Judge {
    fdr: f64,
    min_gain: f64,
    worth: Worth,
    /// Values the closed-form CV squared error is summed over (3 × rows).
    values: f64,
}

impl Judge {
    fn new(o: &DiagnoseOptions, current: &CvStats, rows: usize) -> Self {
        Judge {
            fdr: o.fdr,
            min_gain: o.min_gain,
            worth: Worth::new(o.min_gain, &current.noise_mm),
            values: 3.0 * rows as f64,
        }
    }

    /// The closed-form CV mean squared error before and with `t`.
    fn mse(&self, t: &Tested) -> (f64, f64) {
        let before = t.cv_sse_before / self.values;
        (before, before * (1.0 - t.score))
    }

    /// A discovery: q within the FDR and a drop worth an effect.
    fn significant(&self, t: &Tested) -> bool {
        let (b, a) = self.mse(t);
        t.q_value <= self.fdr && self.worth.counts(b, a)
    }

    /// Why a candidate with q within the FDR does not count, if so.
    fn note(&self, t: &Tested) -> Option<String> {
        let (b, a) = self.mse(t);
        (t.q_value <= self.fdr && !self.worth.counts(b, a)).then(|| {
            format!(
                "q within the FDR, but it would lower the CV RMSE by only {:.1} % (closed form) and its mean square by {:.2e} mm², under the {:.0} % and the {:.2e} mm² (its worth at the noise floor) that count",
                100.0 * (1.0 - (1.0 - t.score.max(0.0)).sqrt()),
                (b - a).max(0.0),
                100.0 * self.min_gain,
                self.worth.floor_mse()
            )
        })
    }
}

impl Rounds {
    /// The loop before its first round: the current model and its CV.
    pub(super) fn new(model: ErrorModel, before: CvStats, permutations: usize) -> Self {
        Rounds {
            model,
            current: before.clone(),
            before,
            extras: Vec::new(),
            steps: Vec::new(),
            effects: Vec::new(),
            permutations,
            candidates: [0; 2],
            pending: None,
            added_kinds: Vec::new(),
            left_by_cap: Vec::new(),
        }
    }

    /// Round `round`: test, rank and report the candidates, check the
    /// effect added last, add the best one the refit CV confirms. Returns
    /// whether one was added (the loop goes on).
    pub(super) fn round(
        &mut self,
        c: &Campaign,
        round: usize,
        progress: &dyn Fn(&str),
    ) -> Result<bool> {
        let o = c.o;
        let fams = scan::families_on(c.data, &self.used_covariates(), o.robot.as_ref(), c.rows);
        let resamples = o.permutations.max(min_resamples(fams.len(), o.fdr));
        self.permutations = self.permutations.max(resamples);
        if round == 1 {
            self.candidates = [fams.len(), fams.iter().map(|f| f.grid.len()).sum()];
        }
        progress(&format!(
            "round {round}: testing {} candidate effects with up to {resamples} resamples",
            fams.len(),
        ));
        let (mut tested, level) = self.test_candidates(c, &fams, resamples, progress)?;
        // the CV residuals at the scanned rows (what a candidate's columns
        // are compared with)
        let residuals = c.rows.pick(&self.current.residuals);
        let judge = Judge::new(o, &self.current, c.rows.len());
        let significant = |t: &Tested| judge.significant(t);
        rank(&mut tested, &significant, &|t: &Tested| {
            self.added_kinds.contains(&fams[t.family].kind)
        });
        let preferred = prefer_simpler(&mut tested, &fams, &residuals, &significant);
        let mut reports = report_candidates(&tested, &fams, &judge, round);
        if let Some((k, over)) = preferred {
            reports[k].add_note(format!(
                "ranked before '{over}': it explains the same with fewer model columns"
            ));
        }
        let r = Round {
            tested: &tested,
            fams: &fams,
            residuals: &residuals,
            significant: &significant,
        };
        let compared = choose::compared(&r);
        choose::mark_competitors(&mut reports, &r, &compared);
        self.name_explained_away(&reports, round);
        self.check_last_effect(&reports, level, round);
        let added =
            self.add_confirmed(c, &mut reports, &r, compared, round, &judge.worth, progress)?;
        self.effects.extend(reports);
        Ok(added)
    }

    /// The covariates the model already holds as inputs (not candidates).
    fn used_covariates(&self) -> Vec<String> {
        self.extras
            .iter()
            .filter_map(|f| match f {
                Feature::Covariate { name, .. } => Some(name.clone()),
                _ => None,
            })
            .collect()
    }

    /// Every family tried inside the current model on the scanned rows (at
    /// its hyperparameters, refactorised on them when they are a subset),
    /// and the level of the after check: the model's own leave-one-out
    /// expectation per axis — on all rows (from the closed-form CV) when
    /// only some are scanned, for on every fourth row its interpolation
    /// error is larger.
    fn test_candidates(
        &self,
        c: &Campaign,
        fams: &[Family],
        resamples: usize,
        progress: &dyn Fn(&str),
    ) -> Result<(Vec<Tested>, [f64; 3])> {
        let o = c.o;
        let mut restricted = if c.rows.is_all() {
            None
        } else {
            Some(self.model.restricted(c.rows.indices(), c.errors)?)
        };
        let systems: Vec<gls::AxisSystem> = restricted
            .as_ref()
            .unwrap_or(&self.model)
            .outputs
            .iter()
            .map(|km| gls::AxisSystem::new(km, c.fold))
            .collect::<Result<_>>()?;
        // the systems hold what the test needs of the subset's factors
        if let Some(r) = restricted.as_mut() {
            r.release_factors();
        }
        let scanned = restricted.as_ref().unwrap_or(&self.model);
        let level: [f64; 3] = match self.current.expected_loo_rmse_mm {
            Some(all) if !c.rows.is_all() => all,
            _ => std::array::from_fn(|a| systems[a].expected_loo_rmse()),
        };
        let refit = |point: &scan::GridPoint| {
            gls::refit_systems(
                scanned,
                c.scan_errors,
                &o.kriging,
                &point.columns,
                &point.axes,
                c.fold,
            )
            .ok()
        };
        let tested = scan::test_families(
            fams,
            c.data,
            c.rows,
            systems,
            resamples,
            o.seed,
            o.fdr,
            o.refine,
            &refit,
            &o.kriging.cancel,
            progress,
        )?;
        Ok((tested, level))
    }

    /// The effect added last round names the candidates it explained away
    /// ([`confound::explained_away`]), now that this round's `reports`
    /// tested them inside the model with it.
    fn name_explained_away(&mut self, reports: &[EffectReport], round: usize) {
        let Some(p) = &self.pending else { return };
        let before: Vec<&EffectReport> = self
            .effects
            .iter()
            .filter(|e| e.round + 1 == round)
            .collect();
        let named = confound::explained_away(&self.effects[p.index], (&before, reports), &p.shared);
        self.effects[p.index].confounded_with.extend(named);
    }

    /// The "after" check of the effect added last round, now that this
    /// round's reports say whether its source is still significant.
    fn check_last_effect(&mut self, reports: &[EffectReport], level: [f64; 3], round: usize) {
        let Some(p) = self.pending.take() else { return };
        let source = &self.effects[p.index].source;
        let again = reports
            .iter()
            .find(|r| r.significant && &r.source == source)
            .map(|r| r.label.clone());
        let check: AfterCheck = after_check(p.promised, p.achieved, &p.after, level, again, round);
        self.effects[p.index].after_check = Some(check);
    }

    /// The candidates `compared` (the best significant one of each kind),
    /// ordered by what each adds on the refitted model ([`Self::refit_gains`]),
    /// a measured column first when an order effect ahead of it is not
    /// separable from it ([`choose::prefer_measured`]); then tried in turn
    /// until the refit CV confirms one (at most [`CONFIRMATIONS`] per
    /// round): it joins the model. At the cap, the significant candidates
    /// left are recorded instead. Returns whether one joined.
    #[allow(clippy::too_many_arguments)]
    fn add_confirmed(
        &mut self,
        c: &Campaign,
        reports: &mut [EffectReport],
        r: &Round,
        mut order: Vec<usize>,
        round: usize,
        worth: &Worth,
        progress: &dyn Fn(&str),
    ) -> Result<bool> {
        let o = c.o;
        if order.is_empty() {
            return Ok(false);
        }
        if !c.rows.is_all() {
            for &k in &order {
                place_steps(&mut reports[k], c.rows, &self.current.residuals);
            }
        }
        if order.len() > 1 {
            self.refit_gains(c, reports, &order, progress)?;
            // stable: ties keep the rank
            order.sort_by(|&a, &b| gain(&reports[b]).total_cmp(&gain(&reports[a])));
        }
        choose::prefer_measured(reports, r, &mut order);
        if round > o.max_effects {
            self.left_by_cap = choose::left_out(reports, r, &order);
            confound::steps_left_by_cap(&mut self.effects, &mut self.left_by_cap);
            reports[order[0]].add_note(format!("not added: the cap of {} effects", o.max_effects));
            return Ok(false);
        }
        for k in order.into_iter().take(CONFIRMATIONS) {
            let trial = self.trial(&reports[k]);
            progress(&format!(
                "adding '{}' and cross-validating again",
                reports[k].label
            ));
            let (after, trial_model) = cross_validated(c.data, &trial, o, Some(&self.model))?;
            let (now, then) = (self.current.pooled_rmse_mm, after.pooled_rmse_mm);
            if worth.counts(now.powi(2), then.powi(2)) {
                progress(&format!(
                    "'{}' confirmed: naming its competitors and its intervals",
                    reports[k].label
                ));
                let competitors = choose::competitor_columns(c.data, c.calibration, r, k, reports);
                let shared = confound::sharing(r.tested, r.fams, r.residuals, k, r.significant);
                let index = self.effects.len() + k;
                self.accept(
                    c,
                    &mut reports[k],
                    index,
                    (trial, trial_model),
                    after,
                    (&competitors, shared),
                );
                return Ok(true);
            }
            refuse(&mut reports[k], now, then, o.min_gain, worth);
        }
        Ok(false)
    }

    /// The model's extras with those of `report` after them.
    fn trial(&self, report: &EffectReport) -> Vec<Feature> {
        let mut trial = self.extras.clone();
        for f in &report.add {
            if !trial.contains(f) {
                trial.push(f.clone());
            }
        }
        trial
    }

    /// [`EffectReport::refit_gain`] of each candidate `order` names: the
    /// drop of the pooled closed-form CV RMSE with it in the model
    /// refitted, against the current model's closed-form CV.
    fn refit_gains(
        &self,
        c: &Campaign,
        reports: &mut [EffectReport],
        order: &[usize],
        progress: &dyn Fn(&str),
    ) -> Result<()> {
        let now = closed_form_rmse(c.data, &self.extras, &self.model, c.o)?;
        for &k in order {
            progress(&format!(
                "refitting with '{}' to measure what it adds",
                reports[k].label
            ));
            let then = refit_closed_form(c.data, &self.trial(&reports[k]), c.o, &self.model)?;
            reports[k].refit_gain = Some(1.0 - then / now.max(f64::MIN_POSITIVE));
        }
        Ok(())
    }

    /// `report`, at `index` among the effects once this round's are in,
    /// joins the model: `extras` and their refit `model` with CV `after`.
    /// Its row and coefficient intervals are those with the `competitors`
    /// refitted ([`choose::widen_intervals`]).
    fn accept(
        &mut self,
        c: &Campaign,
        report: &mut EffectReport,
        index: usize,
        (extras, model): (Vec<Feature>, ErrorModel),
        after: CvStats,
        (competitors, shared): (&choose::Competitors, Vec<confound::Shared>),
    ) {
        report.accepted = true;
        self.added_kinds.push(report.kind);
        report.size = coefficients(&model, &report.add);
        choose::widen_intervals(report, c.data, &self.current.residuals, competitors);
        self.pending = Some(Pending {
            index,
            promised: 1.0 - (1.0 - report.score.clamp(0.0, 1.0)).sqrt(),
            achieved: 1.0 - after.pooled_rmse_mm / self.current.pooled_rmse_mm,
            after: after.clone(),
            shared,
        });
        self.extras = extras;
        self.model = model;
        self.current = after.clone();
        self.steps.push(after);
    }

    /// The report of the loop on `data` (`scanned` rows), after `seconds`.
    pub(super) fn into_diagnosis(
        self,
        o: &DiagnoseOptions,
        data: &Dataset,
        rows: &ScanRows,
        seconds: f64,
    ) -> Diagnosis {
        Diagnosis {
            space: o.space,
            folds: o.folds,
            seed: o.seed,
            permutations: self.permutations,
            candidates: self.candidates,
            fdr: o.fdr,
            before: self.before,
            after: self.current,
            steps: self.steps,
            effects: self.effects,
            extras: self.extras,
            rows: data.len(),
            scanned_rows: rows.len(),
            dropped_covariates: scan::dropped_covariates_on(data, &[], rows),
            left_by_cap: self.left_by_cap,
            order_in_joint_space: super::OrderInJointSpace::measure_at(&rows.pick(&data.q), |t| {
                rows.row(t)
            }),
            seconds,
        }
    }
}

/// One report per tested candidate of round `round`, in the order of
/// `tested`: nothing accepted yet.
fn report_candidates(
    tested: &[Tested],
    fams: &[Family],
    judge: &Judge,
    round: usize,
) -> Vec<EffectReport> {
    tested
        .iter()
        .map(|t| {
            let f = &fams[t.family];
            let g = t.point(f);
            EffectReport {
                round,
                kind: f.kind,
                source: f.source.clone(),
                label: f.label.clone(),
                params: g.params.clone(),
                params_ci: match &t.refined {
                    Some(r) => support_interval(&r.support),
                    None => support_interval(t.support.iter().map(|&i| &f.grid[i].params)),
                },
                score: t.score,
                explained: t.explained,
                p_value: t.p_value,
                q_value: t.q_value,
                evidence: t.evidence,
                significant: judge.significant(t),
                accepted: false,
                confounded_with: Vec::new(),
                refit_gain: None,
                note: judge.note(t),
                refit_xi: t.refit,
                resamples: t.resamples,
                size: Vec::new(),
                after_check: None,
                add: g.add.clone(),
            }
        })
        .collect()
}

/// The note of a significant candidate the refit CV did not confirm (CV
/// RMSE `now` → `then`, mm). Tested at ξ re-estimated on these data, whose
/// null is optimistic, a pose function loses its significance without
/// that confirmation.
fn refuse(report: &mut EffectReport, now: f64, then: f64, min_gain: f64, worth: &Worth) {
    let drop = format!(
        "CV RMSE {now:.4} → {then:.4} mm, less than the required {:.0} % drop or its worth at the noise floor ({:.2e} mm² of mean square)",
        100.0 * min_gain,
        worth.floor_mse()
    );
    if report.refit_xi && report.kind.pose_function() {
        report.significant = false;
        report.add_note(format!(
            "significant only at the ξ re-estimated with it, and the refit CV does not confirm it: {drop}"
        ));
    } else {
        report.add_note(format!("not added: {drop}"));
    }
}

/// A candidate's refit gain, or −∞ when it was not measured.
fn gain(r: &EffectReport) -> f64 {
    r.refit_gain.unwrap_or(f64::NEG_INFINITY)
}
