//! Which candidates a campaign cannot tell apart: "not separable on this
//! campaign" ([`not_separable`]), the measured column preferred over an
//! anonymous order effect among them ([`prefer_measured`]). A step or
//! block of rows that is also a region of the joint space:
//! [`super::regions`].
//!
//! **The measure.** A candidate's *fitted contribution* is the
//! least-squares fit of the centred CV residuals of the current model (at
//! the scanned rows, per axis) on its centred columns ([`fitted`]). Two
//! candidates of different families explain the same residual when
//! 1. the correlation of their fitted contributions (the cosine of the two
//!    centred fits, pooled over the axes: [`similarity`]) is at least
//!    [`SAME_RESIDUAL`]; and
//! 2. their evidence is within noise: with `σ²_a` the mean square of the
//!    residuals of axis `a`, a candidate of `p` columns explains
//!    `E = Σ_a (‖f_a‖² − p·σ²_a)/σ²_a` (its fitted sum of squares in noise
//!    units, less what `p` columns fit of pure noise), and two are within
//!    noise when `|E₁ − E₂| ≤ 1.96 · 2·√(Σ_a ‖f₁,a − f₂,a‖²/σ²_a)`: the
//!    standard deviation of the difference of the two fits' residual sums
//!    of squares under noise `e` is that of `2·e·(f₁ − f₂)`.
//!
//! A step and a drift over the order (a mid-campaign step and a linear
//! ramp correlate at `√(3p(1−p))`, 0.87 at the middle), a covariate and a
//! step at its jump, an order effect and a smooth function of the pose
//! measured region by region are such pairs. The residual `σ²_a` holds
//! whatever the model still misses, so "within noise" errs towards naming
//! a competitor.
//!
//! **Explained away.** Two candidates can also explain the same residual
//! when one is clearly ahead: the one added then takes the other's
//! evidence. An effect explained a candidate away when
//! 1. its columns take what the candidate fits: on the residuals of the
//!    round it was added in, of the candidate's least-squares fitted sum of
//!    squares (noise units, pooled over the axes) at most
//!    [`EXPLAINED_AWAY`] is left once the effect's columns are fitted
//!    first ([`Taken::share_left`]); and
//! 2. the model with it says so: the next round tests every candidate
//!    again inside the model with the effect, and the candidate, significant
//!    before, is no longer (q over the FDR, or a drop no longer worth an
//!    effect), with at most [`EXPLAINED_AWAY`] of its evidence left
//!    ([`explained_away`]).
//!
//! The effect's report then names it, "explained away by it". When only
//! the second holds (the effect's columns leave more than
//! [`EXPLAINED_AWAY`] of the candidate's least-squares fit, yet the model
//! refitted with the effect no longer needs the candidate: the columns
//! with the refitted process take it, which least squares on the round's
//! residuals does not see), the report names it too, after those, as
//! "taken up by it": on this campaign the data could not say which of
//! the two the residual is.
//!
//! **Two steps, one block.** When the cap of effects leaves out a
//! significant step of rows and a step was added, their two columns span
//! a block of rows between them (a bump, back at its end, when their
//! sizes are opposite): a step and a block are then explanations of the
//! same residual that the cap, not the data, told apart. Each one's
//! report names the other ([`steps_left_by_cap`]).
//!
//! **Region of the joint space.** A step or block of rows is a region of
//! the joint space when the poses were measured region by region
//! ([`super::regions`]).

use super::rank::{extend_orthonormal, fitted, orthonormal, similarity};
use super::report::{EffectReport, LeftOut, params_text};
use super::scan::{EffectKind, Family, GridPoint, Tested, is_time_column};

/// Correlation of two fitted contributions from which they explain the
/// same residual (and of a step or block with its region of the joint
/// space).
pub const SAME_RESIDUAL: f64 = 0.7;

/// Share of its least-squares fit, and of its evidence, a candidate keeps
/// at most once an effect is added for that effect to have explained it
/// away ([`Taken::share_left`], [`explained_away`]).
pub const EXPLAINED_AWAY: f64 = 0.5;

/// What a candidate explains: its fitted contribution, and its explained
/// sum of squares in noise units less the columns' share of noise.
struct Explained {
    fit: Vec<[f64; 3]>,
    e: f64,
}

/// The per-axis mean square of the centred residuals (the noise unit).
fn noise(residuals: &[[f64; 3]]) -> [f64; 3] {
    let m = residuals.len().max(1) as f64;
    std::array::from_fn(|a| {
        let mu = residuals.iter().map(|r| r[a]).sum::<f64>() / m;
        let v = residuals.iter().map(|r| (r[a] - mu).powi(2)).sum::<f64>() / m;
        v.max(f64::MIN_POSITIVE)
    })
}

fn explained(t: &Tested, fams: &[Family], residuals: &[[f64; 3]], s2: &[f64; 3]) -> Explained {
    let point = t.point(&fams[t.family]);
    let fit = fitted(point, residuals);
    let e = (0..3)
        .map(|a| {
            let p = point.on_axis(a).len() as f64;
            fit.iter().map(|f| f[a] * f[a]).sum::<f64>() / s2[a] - p
        })
        .sum();
    Explained { fit, e }
}

/// A competitor of a candidate: its index among the tested, the
/// correlation of their fitted contributions, and both explained sums of
/// squares in noise units ([`Explained`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Competitor {
    pub index: usize,
    pub correlation: f64,
    pub explained: [f64; 2],
}

/// The significant candidates of other families that candidate `k` of
/// `tested` cannot be told apart from on these residuals (the measure of
/// this module), most correlated first.
pub(super) fn not_separable(
    tested: &[Tested],
    fams: &[Family],
    residuals: &[[f64; 3]],
    k: usize,
    significant: &dyn Fn(&Tested) -> bool,
) -> Vec<Competitor> {
    let s2 = noise(residuals);
    let top = explained(&tested[k], fams, residuals, &s2);
    let label = &fams[tested[k].family].label;
    let mut out: Vec<Competitor> = (0..tested.len())
        .filter(|&i| i != k && significant(&tested[i]))
        .filter(|&i| &fams[tested[i].family].label != label)
        .filter_map(|i| {
            let other = explained(&tested[i], fams, residuals, &s2);
            let correlation = similarity(&top.fit, &other.fit);
            let d2: f64 = top
                .fit
                .iter()
                .zip(&other.fit)
                .map(|(x, y)| (0..3).map(|a| (x[a] - y[a]).powi(2) / s2[a]).sum::<f64>())
                .sum();
            let within = (top.e - other.e).abs() <= crate::stats::Z95 * 2.0 * d2.sqrt();
            (correlation >= SAME_RESIDUAL && within).then_some(Competitor {
                index: i,
                correlation,
                explained: [top.e, other.e],
            })
        })
        .collect();
    out.sort_by(|a, b| b.correlation.total_cmp(&a.correlation));
    out
}

/// A competitor as the report names it: label (with its parameters),
/// score, evidence and the correlation of the fitted contributions.
pub(super) fn competitor_text(r: &EffectReport, correlation: f64) -> String {
    format!(
        "{}{} (score {:.3}, evidence {:.3}, within noise; correlation of the fitted contributions {:.2})",
        r.label,
        params_text(&r.params),
        r.score,
        r.evidence,
        correlation
    )
}

/// An added effect's columns on one round's residuals, for
/// [`Taken::share_left`]: per axis, the residual and an orthonormal basis
/// of the effect's centred columns, and the noise.
pub(super) struct Taken {
    s2: [f64; 3],
    r: [Vec<f64>; 3],
    qa: [Vec<Vec<f64>>; 3],
}

impl Taken {
    /// Effect `a`'s columns against the `residuals`.
    pub(super) fn new(a: &GridPoint, residuals: &[[f64; 3]]) -> Self {
        Taken {
            s2: noise(residuals),
            r: std::array::from_fn(|axis| residuals.iter().map(|x| x[axis]).collect()),
            qa: std::array::from_fn(|axis| orthonormal(&a.on_axis(axis))),
        }
    }

    /// What is left of candidate `b`'s fit of the residuals once the
    /// effect's columns are fitted first: per axis, with `Q` an orthonormal
    /// basis of the centred columns on that axis,
    /// `(‖Q_{ab}ᵀr‖² − ‖Q_aᵀr‖²)/‖Q_bᵀr‖²` (the numerator is the fit of the
    /// part of `b`'s columns orthogonal to the effect's), the sums in noise
    /// units and pooled over the axes. 0: the effect's columns fit all that
    /// `b`'s do; 1: none of it (above 1 when `b`'s columns fit more once
    /// the effect's are in: their overlap had cancelled part of it). `None`
    /// when `b` fits nothing.
    pub(super) fn share_left(&self, b: &GridPoint) -> Option<f64> {
        let fit = |q: &[Vec<f64>], r: &[f64]| -> f64 {
            q.iter()
                .map(|v| v.iter().zip(r).map(|(x, y)| x * y).sum::<f64>().powi(2))
                .sum()
        };
        let (mut after, mut alone) = (0.0, 0.0);
        for axis in 0..3 {
            let (r, qa) = (&self.r[axis], &self.qa[axis]);
            let cb = b.on_axis(axis);
            let qab = extend_orthonormal(qa.clone(), &cb);
            after += fit(&qab[qa.len()..], r) / self.s2[axis];
            alone += fit(&orthonormal(&cb), r) / self.s2[axis];
        }
        (alone > 0.0).then(|| after / alone)
    }
}

/// A significant candidate of another source than an added effect, with
/// the share of its fit the effect's columns leave
/// ([`Taken::share_left`]; condition 1 of the module docs holds at most
/// [`EXPLAINED_AWAY`]): its family's label and source, and the share left.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Shared {
    pub label: String,
    pub source: Vec<String>,
    pub left: f64,
}

/// The significant candidates of another source and label than candidate
/// `k` of `tested`, each with the share of its fit of the `residuals`
/// that `k`'s columns leave.
pub(super) fn sharing(
    tested: &[Tested],
    fams: &[Family],
    residuals: &[[f64; 3]],
    k: usize,
    significant: &dyn Fn(&Tested) -> bool,
) -> Vec<Shared> {
    let top = &fams[tested[k].family];
    let taken = Taken::new(tested[k].point(top), residuals);
    (0..tested.len())
        .filter(|&i| i != k && significant(&tested[i]))
        .filter_map(|i| {
            let f = &fams[tested[i].family];
            if f.source == top.source || f.label == top.label {
                return None;
            }
            let left = taken.share_left(tested[i].point(f))?;
            Some(Shared {
                label: f.label.clone(),
                source: f.source.clone(),
                left,
            })
        })
        .collect()
}

/// The candidates the effect `added` explained away or took up (module
/// docs): of `before` (the reports of the round it was added in) those of
/// another source (`shared`, [`sharing`]), significant and not added; in
/// `after` (the next round's reports, inside the model with it) the same
/// family, not significant (q over the FDR, or a drop no longer worth an
/// effect), with at most [`EXPLAINED_AWAY`] of its evidence. Those
/// `added` already names as a competitor are not named twice. Each is
/// named with its evidence and q before and after and the share of its
/// fit the effect's columns leave: those explained away (a share of at
/// most [`EXPLAINED_AWAY`]) first, then those taken up, each most
/// evidence lost first.
pub(super) fn explained_away(
    added: &EffectReport,
    (before, after): (&[&EffectReport], &[EffectReport]),
    shared: &[Shared],
) -> Vec<String> {
    let named = |b: &EffectReport| {
        let head = format!("{}{} (", b.label, params_text(&b.params));
        added.confounded_with.iter().any(|c| c.starts_with(&head))
    };
    let mut out: Vec<(bool, f64, String)> = before
        .iter()
        .filter(|b| b.significant && !b.accepted && !named(b))
        .filter_map(|b| {
            let s = shared
                .iter()
                .find(|s| s.label == b.label && s.source == b.source)?;
            let a = after
                .iter()
                .find(|a| a.label == b.label && a.source == b.source)?;
            (!a.significant && a.evidence <= EXPLAINED_AWAY * b.evidence).then(|| {
                let taken_up = s.left > EXPLAINED_AWAY;
                let how = if taken_up {
                    "; the model refitted with this one takes the rest: taken up by it"
                } else {
                    ": explained away by it"
                };
                // fitted after the effect's columns, a candidate's can fit
                // more than alone (their overlap had cancelled part of it)
                let share = if s.left >= 1.0 {
                    "its columns take none of what this one fits".to_string()
                } else {
                    format!("its columns leave {:.0} % of what this one fits", 100.0 * s.left)
                };
                let text = format!(
                    "{}{} (evidence {:.3}, q {:.4} before it was added; {:.3}, q {:.4} after; {share}{how})",
                    b.label,
                    params_text(&b.params),
                    b.evidence,
                    b.q_value,
                    a.evidence,
                    a.q_value,
                );
                (taken_up, b.evidence - a.evidence, text)
            })
        })
        .collect();
    out.sort_by(|x, y| x.0.cmp(&y.0).then(y.1.total_cmp(&x.1)));
    out.into_iter().map(|(_, _, t)| t).collect()
}

/// The row of a step in the measurement order (an order effect with a
/// single change point), if `kind` and `params` are one's.
fn step_row(kind: EffectKind, params: &std::collections::BTreeMap<String, f64>) -> Option<f64> {
    (kind == EffectKind::Order && params.len() == 1)
        .then(|| params.get("row").copied())
        .flatten()
}

/// Each step of rows the cap `left` out and each step among the `added`
/// effects name each other (module docs, "two steps, one block"): the
/// left one in the added one's `confounded_with` with its evidence, and
/// the other way round.
pub(super) fn steps_left_by_cap(added: &mut [EffectReport], left: &mut [LeftOut]) {
    for l in left.iter_mut() {
        let Some(r2) = step_row(l.kind, &l.params) else {
            continue;
        };
        for e in added.iter_mut().filter(|e| e.accepted) {
            let Some(r1) = step_row(e.kind, &e.params) else {
                continue;
            };
            let (a, b) = (r1.min(r2), r1.max(r2));
            let block = format!(
                "with the other, a block of rows {a:.0}–{b:.0} (a bump, back at its end, when their sizes are opposite)"
            );
            e.confounded_with.push(format!(
                "{}{} (evidence {:.3}, significant when the cap of effects was reached, not added: {block})",
                l.label,
                params_text(&l.params),
                l.evidence
            ));
            l.confounded_with.push(format!(
                "{}{} (added in round {}: {block})",
                e.label,
                params_text(&e.params),
                e.round
            ));
        }
    }
}

/// Whether a candidate is an anonymous order effect (a drift, a step or a
/// block of rows: nothing measured names it).
fn anonymous(f: &Family) -> bool {
    f.kind == EffectKind::Order
}

/// Whether a candidate is a measured column (a covariate: `temp_c`, a
/// payload), alone or with the joints. A time column (`time_s`, …) is not:
/// it is the measurement order in seconds, as anonymous as the row.
fn measured(f: &Family) -> bool {
    f.kind == EffectKind::Covariate && !f.source.iter().any(|s| is_time_column(s))
}

/// Between explanations that cannot be told apart, the measured column
/// goes before an anonymous order effect: if `tested[first]` is an order
/// effect and a significant covariate candidate is not separable from it
/// (evidence within noise, [`not_separable`]), that candidate (the one of
/// fewest columns, then the most evidence) is returned, to go first.
pub(super) fn prefer_measured(
    tested: &[Tested],
    fams: &[Family],
    residuals: &[[f64; 3]],
    first: usize,
    significant: &dyn Fn(&Tested) -> bool,
) -> Option<usize> {
    if !anonymous(&fams[tested[first].family]) {
        return None;
    }
    let width = |i: usize| tested[i].point(&fams[tested[i].family]).columns.len();
    not_separable(tested, fams, residuals, first, significant)
        .into_iter()
        .filter(|c| measured(&fams[tested[c.index].family]))
        .min_by(|a, b| {
            width(a.index).cmp(&width(b.index)).then(
                tested[b.index]
                    .evidence
                    .total_cmp(&tested[a.index].evidence),
            )
        })
        .map(|c| c.index)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A report of `label` from `source`, its evidence and significance.
    fn report(label: &str, source: &str, evidence: f64, significant: bool) -> EffectReport {
        serde_json::from_str(&format!(
            r#"{{"round": 1, "kind": "order", "source": ["{source}"], "label": "{label}",
                "params": {{}}, "score": 0.1, "explained": 0.1, "p_value": 0.01,
                "q_value": 0.02, "evidence": {evidence}, "significant": {significant},
                "accepted": false}}"#
        ))
        .unwrap()
    }

    /// An effect names the candidates it took the evidence of, those whose
    /// fit its columns take first ("explained away") and then those whose
    /// fit they do not ("taken up"); not one that kept its evidence, one
    /// that was not significant before, one of its own source, or one it
    /// already names as a competitor.
    #[test]
    fn an_added_effect_names_the_candidates_it_explained_away() {
        let mut added = report("q4's last move", "q4", 0.08, true);
        added.accepted = true;
        added
            .confounded_with
            .push("harmonic of q1 (score 0.1, evidence 0.03, within noise)".into());
        let before = [
            added.clone(),
            report("step in the measurement order", "row", 0.047, true),
            report("drift over the measurement order", "row", 0.030, true),
            report("moves of q3 into the pose", "q3", 0.010, false),
            report("harmonic of q2", "q2", 0.020, true),
            report("q5 × q6", "q5", 0.040, true),
            report("harmonic of q1", "q1", 0.030, true),
        ];
        let after = vec![
            report("step in the measurement order", "row", 0.011, false),
            // lost significance, but kept most of its evidence
            report("drift over the measurement order", "row", 0.020, false),
            report("moves of q3 into the pose", "q3", 0.001, false),
            // still significant
            report("harmonic of q2", "q2", 0.005, true),
            // its fit is not the added effect's columns' (taken up)
            report("q5 × q6", "q5", 0.001, false),
            report("harmonic of q1", "q1", 0.001, false),
        ];
        let shared: Vec<Shared> = [
            "step in the measurement order",
            "drift over the measurement order",
            "moves of q3 into the pose",
            "harmonic of q2",
            "harmonic of q1",
            "q5 × q6",
        ]
        .iter()
        .zip(["row", "row", "q3", "q2", "q1", "q5"])
        .map(|(l, s)| Shared {
            label: l.to_string(),
            source: vec![s.to_string()],
            left: if s == "q5" { 0.8 } else { 0.2 },
        })
        .collect();
        let before: Vec<&EffectReport> = before.iter().collect();
        let named = explained_away(&added, (&before, &after), &shared);
        assert_eq!(named.len(), 2, "{named:?}");
        assert!(named[0].starts_with("step in the measurement order (evidence 0.047"));
        assert!(named[0].contains("0.011") && named[0].contains("leave 20 %"));
        assert!(named[0].ends_with("explained away by it)"));
        // taken up: listed after, though it lost more evidence
        assert!(named[1].starts_with("q5 × q6 (evidence 0.040"), "{named:?}");
        assert!(named[1].contains("leave 80 %") && named[1].ends_with("taken up by it)"));
        // a share left of 100 % or more: the columns take none of it
        let shared: Vec<Shared> = shared
            .into_iter()
            .map(|s| Shared {
                left: if s.label == "q5 × q6" { 1.3 } else { s.left },
                ..s
            })
            .collect();
        let named = explained_away(&added, (&before, &after), &shared);
        assert!(
            named[1].contains("its columns take none of what this one fits; the model refitted")
        );
    }

    /// A step left out by the cap and a step added name each other, with
    /// the block their columns span; a block, a drift or a step not added
    /// are not named.
    #[test]
    fn a_step_left_by_the_cap_and_a_step_added_name_the_block() {
        let step = |row: f64, accepted: bool| {
            let mut r = report("step in the measurement order", "row", 0.05, true);
            r.kind = EffectKind::Order;
            r.params.insert("row".into(), row);
            r.accepted = accepted;
            r
        };
        let mut block = report("block of rows (a bump, back at its end)", "row", 0.04, true);
        block.kind = EffectKind::Order;
        block.params.insert("from_row".into(), 10.0);
        block.params.insert("to_row".into(), 20.0);
        block.accepted = true;
        let mut added = vec![step(229.0, true), step(100.0, false), block.clone()];
        let mut left = vec![
            LeftOut::of(&step(491.0, false)),
            LeftOut::of(&report(
                "drift over the measurement order",
                "row",
                0.03,
                true,
            )),
            LeftOut::of(&block),
        ];
        steps_left_by_cap(&mut added, &mut left);
        assert_eq!(
            added[0].confounded_with.len(),
            1,
            "{:?}",
            added[0].confounded_with
        );
        let named = &added[0].confounded_with[0];
        assert!(named.starts_with("step in the measurement order (row 491.000) (evidence 0.050"));
        assert!(named.contains("a block of rows 229–491"), "{named}");
        assert!(added[1].confounded_with.is_empty() && added[2].confounded_with.is_empty());
        assert_eq!(left[0].confounded_with.len(), 1);
        assert!(left[0].confounded_with[0].contains("(row 229.000) (added in round"));
        assert!(left[1].confounded_with.is_empty() && left[2].confounded_with.is_empty());
    }

    /// What a candidate fits is left in full by columns orthogonal to its
    /// own, and taken by columns that span them.
    #[test]
    fn the_share_left_is_what_the_added_columns_do_not_fit() {
        let m = 200;
        let x: Vec<f64> = (0..m)
            .map(|i| ((i * 37) % 101) as f64 / 101.0 - 0.5)
            .collect();
        let y: Vec<f64> = (0..m)
            .map(|i| if (i / 10) % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let residuals: Vec<[f64; 3]> = (0..m).map(|i| [x[i], 0.5 * x[i], y[i] * 0.01]).collect();
        let point = |cols: Vec<Vec<f64>>| GridPoint::new(Default::default(), cols, Vec::new());
        let b = point(vec![x.clone()]);
        // a spans b's column (and more): nothing left
        let spans = point(vec![x.iter().map(|v| 2.0 * v + 1.0).collect(), y.clone()]);
        assert!(Taken::new(&spans, &residuals).share_left(&b).unwrap() < 1e-9);
        // a is (nearly) orthogonal to b: all of it left
        let other = point(vec![y.clone()]);
        let left = Taken::new(&other, &residuals).share_left(&b).unwrap();
        assert!(left > 0.9, "{left}");
    }
}
