//! Which of a round's significant candidates joins the model, and what the
//! report says about the others.
//!
//! - **Compared** ([`compared`]): the best significant candidate of each
//!   kind (the order's drift apart from its step and block: [`group`]), at
//!   most [`COMPARED`], in their ranked order, the last place going to
//!   the round's strongest by evidence when its kind is not among them. The round
//!   orders them by what each adds on the refitted model
//!   ([`EffectReport::refit_gain`]), not by the scan's score, so that a
//!   step the data shows clearly is not crowded out by a harmonic whose
//!   scan promised more than the refitted model delivers.
//! - **Not separable** ([`mark_competitors`]): each compared candidate
//!   names the candidates it cannot be told apart from
//!   ([`super::confound`], and those of [`alike`]: nearly the same fit
//!   with nearly its score).
//! - **The measured column first** ([`prefer_measured`]): when the first
//!   is an anonymous order effect and a covariate candidate is not
//!   separable from it, the covariate goes first; both reports say so.
//! - **The cap** ([`left_out`]): at the cap of effects, the significant
//!   candidates left, with what each would add.
//! - **Intervals** ([`widen_intervals`]): those of an added effect with its
//!   competitors refitted ([`super::profile`]).

use super::confound::{self, SAME_RESIDUAL, competitor_text, not_separable};
use super::profile::{
    across_period, drift_columns, feature_columns, profile_period, widen_coefficients, widen_rows,
};
use super::rank::alike;
use super::regions::{NEIGHBOURS, region_overlap};
use super::report::{EffectReport, LeftOut};
use super::scan::{EffectKind, Family, Tested, step_rows};
use crate::calibration::Displacements;
use crate::dataset::Dataset;
use crate::features::Feature;

impl Family {
    /// Whether it is the drift over the order (it adds the row as an input).
    fn add_drift(&self) -> bool {
        self.grid.iter().any(|g| g.add.contains(&Feature::Row))
    }
}

/// Candidates a round compares for adding (one per kind).
pub const COMPARED: usize = 4;

/// A round's tested candidates in ranked order, their families, the CV
/// residuals at the scanned rows and the test of significance.
pub(super) struct Round<'a> {
    pub tested: &'a [Tested],
    pub fams: &'a [Family],
    pub residuals: &'a [[f64; 3]],
    pub significant: &'a dyn Fn(&Tested) -> bool,
}

impl Round<'_> {
    fn family(&self, k: usize) -> &Family {
        &self.fams[self.tested[k].family]
    }

    fn eligible(&self, k: usize) -> bool {
        (self.significant)(&self.tested[k]) && self.tested[k].score > 0.0
    }
}

/// The kind a candidate competes within: its kind, the order's drift
/// apart from its change points. A step and a block of rows (two steps)
/// are one explanation, a change of level, between which the scan's
/// evidence decides: it weighs the block's second edge (the mean of its
/// null over the two-edge grid), which the refitted model's CV does not.
fn group(f: &Family) -> (EffectKind, bool) {
    (f.kind, f.kind == EffectKind::Order && f.add_drift())
}

/// The candidates compared for adding: the first significant one (with a
/// positive score) of each kind ([`group`]), at most [`COMPARED`], the
/// last place going to the round's strongest by evidence when its kind is
/// not among them. The rank puts the kinds already added last, so that a
/// new kind is weighed; the strongest is weighed too, so that a kind
/// already added (a second harmonic of the campaign's own) is not left out
/// of the comparison by what the refitted model would gain, nor the loop
/// stopped while it would lower the CV.
pub(super) fn compared(r: &Round) -> Vec<usize> {
    let mut seen = Vec::new();
    let mut out = Vec::new();
    let eligible: Vec<usize> = (0..r.tested.len()).filter(|&k| r.eligible(k)).collect();
    for &k in &eligible {
        let g = group(r.family(k));
        if !seen.contains(&g) {
            seen.push(g);
            out.push(k);
            if out.len() == COMPARED {
                break;
            }
        }
    }
    let strongest = eligible
        .iter()
        .copied()
        .max_by(|&a, &b| r.tested[a].evidence.total_cmp(&r.tested[b].evidence));
    if let Some(k) = strongest.filter(|k| !seen.contains(&group(r.family(*k)))) {
        if out.len() == COMPARED {
            out.pop();
        }
        out.push(k);
    }
    out
}

/// The competitors of candidate `k`: [`not_separable`] and [`alike`], as
/// (index, correlation), most correlated first.
fn competitors_of(r: &Round, k: usize) -> Vec<(usize, f64)> {
    let mut out: Vec<(usize, f64)> = not_separable(r.tested, r.fams, r.residuals, k, r.significant)
        .into_iter()
        .map(|c| (c.index, c.correlation))
        .collect();
    for i in alike(r.tested, r.fams, r.residuals, k, r.significant) {
        if !out.iter().any(|(j, _)| *j == i) {
            let fit = |t: &Tested| super::rank::fitted(t.point(&r.fams[t.family]), r.residuals);
            let c = super::rank::similarity(&fit(&r.tested[k]), &fit(&r.tested[i]));
            out.push((i, c));
        }
    }
    out
}

/// Each compared candidate's report names its competitors
/// ([`EffectReport::confounded_with`]).
pub(super) fn mark_competitors(reports: &mut [EffectReport], r: &Round, compared: &[usize]) {
    for &k in compared {
        let named: Vec<String> = competitors_of(r, k)
            .into_iter()
            .map(|(i, c)| competitor_text(&reports[i], c))
            .collect();
        reports[k].confounded_with = named;
    }
}

/// The measured column before an anonymous order effect it is not
/// separable from: if `order[0]` is such an effect, the covariate candidate
/// [`confound::prefer_measured`] finds goes first, and both reports say so.
pub(super) fn prefer_measured(reports: &mut [EffectReport], r: &Round, order: &mut Vec<usize>) {
    let Some(&first) = order.first() else { return };
    let Some(j) = confound::prefer_measured(r.tested, r.fams, r.residuals, first, r.significant)
    else {
        return;
    };
    order.retain(|&i| i != j);
    order.insert(0, j);
    let (over, measured) = (reports[first].label.clone(), reports[j].label.clone());
    reports[j].add_note(format!(
        "tried before '{over}': not separable on this campaign, their evidence within noise; the measured column is preferred over an anonymous order effect"
    ));
    reports[first].add_note(format!(
        "'{measured}', a measured column, explains the same residual within noise and was tried first"
    ));
}

/// The significant candidates left at the cap, with what each would add:
/// those compared, in `order`, then the others in their ranked order.
pub(super) fn left_out(reports: &[EffectReport], r: &Round, order: &[usize]) -> Vec<LeftOut> {
    let rest = (0..reports.len()).filter(|k| r.eligible(*k) && !order.contains(k));
    order
        .iter()
        .copied()
        .chain(rest)
        .map(|k| LeftOut::of(&reports[k]))
        .collect()
}

/// The columns an added effect's intervals are computed with refitted, and
/// their names: `columns` on every axis, `calibration` (the displacements
/// of the directions the calibration saw) on its own axis, for the
/// coefficients only.
pub(super) struct Competitors {
    columns: Vec<Vec<f64>>,
    calibration: Option<Displacements>,
    names: Vec<String>,
}

/// The competitors of candidate `k` (its report `reports[k]`) on every row
/// of `data`: the drift over the order (but for the drift itself), the
/// features of the candidates of another source it is not separable from
/// (one of the same source, `temp_c` alone and lagged, a step and a block
/// of rows, is the same explanation), but those it adds itself, and, when
/// `data` is a calibration's residual, the `calibration`'s directions
/// ([`Competitors`]).
pub(super) fn competitor_columns(
    data: &Dataset,
    calibration: Option<&Displacements>,
    r: &Round,
    k: usize,
    reports: &[EffectReport],
) -> Competitors {
    let own = &reports[k].add;
    let mut c = Competitors {
        columns: Vec::new(),
        calibration: calibration.filter(|d| !d[0].is_empty()).cloned(),
        names: Vec::new(),
    };
    if !own.contains(&Feature::Row) {
        c.columns = drift_columns(data.len());
        c.names.push("the drift over the measurement order".into());
    }
    // one of the same source is the same explanation, not a competing one
    let source = &reports[k].source;
    for (i, _) in competitors_of(r, k) {
        if &reports[i].source == source {
            continue;
        }
        let add: Vec<Feature> = reports[i]
            .add
            .iter()
            .filter(|f| !own.contains(f) && **f != Feature::Row)
            .cloned()
            .collect();
        let cols = feature_columns(data, &add);
        if !cols.is_empty() {
            c.columns.extend(cols);
            c.names.push(format!("'{}'", reports[i].label));
        }
    }
    c
}

/// An added effect's row and coefficient intervals with its `competitors`
/// refitted on the CV `residuals` of the model it joined (all rows of
/// `data`), and, for a step or block of rows, the region of the joint
/// space its rows make up when they make one up.
pub(super) fn widen_intervals(
    report: &mut EffectReport,
    data: &Dataset,
    residuals: &[[f64; 3]],
    competitors: &Competitors,
) {
    let m = residuals.len();
    let rows = widen_rows(report, residuals, &competitors.columns, step_rows(m));
    let period = profile_period(
        report,
        data,
        residuals,
        (&competitors.columns, competitors.calibration.as_ref()),
    );
    let alternatives = across_period(report);
    let coefs = widen_coefficients(
        &mut report.size,
        data,
        residuals,
        (&report.add, &alternatives),
        (&competitors.columns, competitors.calibration.as_ref()),
    );
    let mut names = competitors.names.clone();
    if coefs && let Some(d) = &competitors.calibration {
        names.push(format!(
            "the {} directions the calibration saw (the coefficients)",
            d[0].len()
        ));
    }
    if period {
        report.add_note(format!(
            "the period's 95 % interval from the profile of the evidence over the period (±{:.0} %)",
            100.0 * super::profile::PERIOD_SPAN
        ));
    }
    if (rows || period || coefs) && !names.is_empty() {
        report.add_note(format!(
            "95 % intervals with {} refitted alongside it",
            names.join(", ")
        ));
    }
    let steps = report.change_point_rows();
    let inside: Vec<bool> = match steps[..] {
        [a] => (0..m).map(|i| i >= a).collect(),
        [a, b] => (0..m).map(|i| (a.min(b)..a.max(b)).contains(&i)).collect(),
        _ => return,
    };
    let overlap = region_overlap(&data.q, &inside);
    if overlap >= SAME_RESIDUAL {
        report.confounded_with.push(format!(
            "a region of the joint space: its rows were measured in a region of their own (correlation of the rows with their {} nearest poses' {overlap:.2}); a function of the pose explains the same",
            NEIGHBOURS
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::scan::GridPoint;
    use std::collections::BTreeMap;

    fn family(kind: EffectKind) -> Family {
        Family {
            kind,
            source: vec![kind.name().into()],
            label: kind.name().into(),
            grid: vec![GridPoint::new(
                BTreeMap::new(),
                vec![vec![1.0; 4]],
                Vec::new(),
            )],
            zoom: None,
        }
    }

    /// A kind already in the model is ranked after the new ones; when
    /// [`COMPARED`] new kinds would fill the comparison, its strongest
    /// candidate takes the last place, and it is not compared twice when it
    /// is there.
    #[test]
    fn the_strongest_candidate_is_compared_whatever_its_kind() {
        use EffectKind::*;
        let kinds = [
            Harmonic,
            Covariate,
            Order,
            Interaction,
            DirectionHistory,
            MotionHistory,
        ];
        let fams: Vec<Family> = kinds.iter().map(|&k| family(k)).collect();
        let residuals = vec![[0.0; 3]; 4];
        let all = |_: &Tested| true;
        // the harmonic (already added) has the most evidence
        let mut tested: Vec<Tested> = [0.05, 0.04, 0.03, 0.02, 0.015, 0.01]
            .iter()
            .enumerate()
            .map(|(f, &e)| Tested::for_test(f, e))
            .collect();
        crate::diagnose::rank::rank(&mut tested, &all, &|t: &Tested| t.family == 0);
        assert_eq!(tested.last().map(|t| t.family), Some(0));
        let r = Round {
            tested: &tested,
            fams: &fams,
            residuals: &residuals,
            significant: &all,
        };
        let families: Vec<usize> = compared(&r).iter().map(|&k| tested[k].family).collect();
        assert_eq!(families, vec![1, 2, 3, 0]);
        // ranked first, it is compared once
        let mut tested: Vec<Tested> = (0..6)
            .map(|f| Tested::for_test(f, 0.05 - 0.005 * f as f64))
            .collect();
        crate::diagnose::rank::rank(&mut tested, &all, &|_: &Tested| false);
        let r = Round {
            tested: &tested,
            ..r
        };
        let families: Vec<usize> = compared(&r).iter().map(|&k| tested[k].family).collect();
        assert_eq!(families, vec![0, 1, 2, 3]);
    }
}
