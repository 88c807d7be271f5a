//! Scoring one plant against the control (the same campaign without it).
//!
//! - **right**: an effect added to the planted campaign is of the planted
//!   kind, at the planted place, and is not one the control added too:
//!   a step whose row is within `tol` rows of the planted row; a block whose
//!   two edges are each within `tol`; `temp_c` (any covariate family of it)
//!   for a drift; the moves of the planted joint into the pose (the lag
//!   family) for a lag; a harmonic of the planted joint with its period
//!   within 3 % for a harmonic. `tol` = max(5, 2 % of the rows).
//! - **proxy**: not right, but something the control did not add was added
//!   (an effect is "the same" as a control's when its label matches and its
//!   parameters are within `tol` rows / 3 %). **named**: the
//!   `confounded_with` of an effect the control did not add names the
//!   planted family (the text of its label; a block's also a step in the
//!   measurement order, at an edge) at the planted place (a step's row
//!   within `tol` of the planted one or of a planted block's edge, a
//!   block's two edges each within `tol`, a harmonic's period within 3 %).
//!   Also **named** (counted apart, "by the order note"): a step or block
//!   whose row (each edge) is within `tol` of a row where the report's note
//!   on the order says a step is a region of the joint space, so that a
//!   step or block there and an effect of the pose can stand for each
//!   other ([`Diagnosis::order_in_joint_space`]).
//!   **seen**: the planted family was significant, at its place, in some
//!   round (a proxy whose family never was cannot be named by a rule that
//!   names significant candidates).
//!   **own only**: a proxy whose every new effect the control also found
//!   significant (in some round, at a compatible place: each parameter
//!   within the tolerances above, or either one's 95 % interval of it
//!   holding the other's value). The control
//!   gave its places to others; the plant only reordered the campaign's
//!   own effects, and nothing is a proxy of it in the sense of explaining
//!   its residual.
//! - **missed**: nothing new added.
//! - A block added as two steps, one at each edge (within `tol`), is
//!   right: the two step columns span the block's (its coverage: each
//!   step's row interval covers its edge, and its coefficient the planted
//!   offset, + at the first edge and − at the second).
//! - **left by the cap**: for a proxy or a miss, the planted family is
//!   among the significant candidates the report lists as left out by the
//!   cap of effects ([`Diagnosis::left_by_cap`]), with what it would add
//!   (a block's family includes the step at an edge; at the planted place).
//!
//! Coverage (for the right ones): the 95 % support interval of a step's
//! row (a block's two edges, a harmonic's period) covers the planted value;
//! the 95 % intervals of the size coefficients cover the planted ones,
//! counted per plant (all three axes, and both edges of a block) and per
//! coefficient and axis (step: `step@row`; block: `step@from` = +offset and `step@to`
//! = −offset; drift: the `temp_c` coefficient, mm/K; lag: its memory τ
//! (planted 0) and the coefficient of each axis's `J·move` column, −g·π/180).
//! A harmonic through the Jacobian: the coefficients of each axis's own
//! `J·sin` and `J·cos` columns, A·cos φ' and A·sin φ' radians with
//! φ' = φ + 2π c/P at the effect's phase reference c. A plain
//! harmonic's coefficients are per-axis sin/cos trend terms, not the
//! joint's amplitude: only its period is scored.

use crate::plant::{Planted, Shape};
use robokrige::diagnose::{Diagnosis, EffectKind, EffectReport};
use robokrige::features::Feature;

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    Right,
    ProxyNamed,
    Proxy,
    Missed,
}

/// The score of one plant.
pub struct Score {
    pub outcome: Outcome,
    /// Does the row / period interval cover the planted value (`None`: not scored).
    pub row_covered: Option<bool>,
    /// Per coefficient and axis: does its interval cover the planted value.
    pub coef_covered: Option<Vec<bool>>,
    /// The same, against the planted value plus the campaign's own: the
    /// coefficient of the same column when the unplanted campaign is
    /// fitted with the same final effects (a real campaign may already
    /// hold a component of that shape: its own temperature drift, or the
    /// projection of its order drift on a step).
    pub own_covered: Option<Vec<bool>>,
    /// Labels of what was added, beyond the control.
    pub added: Vec<String>,
    /// For a right one: what it found (parameters, their intervals, sizes).
    pub detail: String,
    /// Not right, and the planted family is listed as left by the cap.
    pub left_by_cap: bool,
    /// The planted family was significant, at its place, in some round.
    pub seen: bool,
    /// A proxy whose every new effect the control found significant too, in
    /// some round, at a compatible place ([`significant_in`]): the campaign's own
    /// effects, taking the places the control gave to others.
    pub own_only: bool,
    /// A proxy named by the report's note on the order against the joint
    /// space alone ([`named_by_order`]), not by an effect's competitors.
    pub by_order_note: bool,
}

pub fn tolerance(m: usize) -> usize {
    (m / 50).max(5)
}

fn param(e: &EffectReport, k: &str) -> Option<f64> {
    e.params.get(k).copied()
}

fn near_rows(a: Option<f64>, b: usize, tol: usize) -> bool {
    a.is_some_and(|a| (a - b as f64).abs() <= tol as f64)
}

/// Two values of parameter `k` at the same place: rows within `tol`,
/// others within 3 %.
fn near(k: &str, v: f64, w: f64, tol: usize) -> bool {
    if k.ends_with("row") {
        (v - w).abs() <= tol as f64
    } else {
        (v - w).abs() <= 0.03 * v.abs().max(w.abs())
    }
}

fn same(a: &EffectReport, b: &EffectReport, tol: usize) -> bool {
    a.label == b.label
        && a.params.len() == b.params.len()
        && a.params
            .iter()
            .all(|(k, v)| near(k, *v, b.params.get(k).copied().unwrap_or(f64::NAN), tol))
}

/// Whether `d` found `e` significant in some round: a report of the same
/// label whose every parameter is compatible with `e`'s: [`near`], or
/// either one's 95 % interval of it (when it has one) holds the other's
/// value.
fn significant_in(e: &EffectReport, d: &Diagnosis, tol: usize) -> bool {
    d.effects.iter().filter(|b| b.significant).any(|b| {
        b.label == e.label
            && b.params.len() == e.params.len()
            && e.params.iter().all(|(k, v)| {
                let w = b.params.get(k).copied().unwrap_or(f64::NAN);
                near(k, *v, w, tol)
                    || within(b.params_ci.get(k), *v) == Some(true)
                    || within(e.params_ci.get(k), w) == Some(true)
            })
    })
}

fn is_right(e: &EffectReport, shape: &Shape, tol: usize) -> bool {
    match shape {
        Shape::Step { .. } => {
            e.kind == EffectKind::Order
                && e.label.starts_with("step")
                && at_place(&e.params, shape, tol)
        }
        Shape::Block { from, to, .. } => {
            e.kind == EffectKind::Order
                && near_rows(param(e, "from_row"), *from, tol)
                && near_rows(param(e, "to_row"), *to, tol)
        }
        Shape::Drift { .. } => {
            e.kind == EffectKind::Covariate && e.source.iter().any(|s| s == "temp_c")
        }
        Shape::Lag { joint } => e.label.starts_with(&format!("moves of q{joint} ")),
        Shape::Harmonic { joint, .. } => {
            e.kind == EffectKind::Harmonic
                && e.source == [format!("q{joint}")]
                && at_place(&e.params, shape, tol)
        }
    }
}

/// Where the planted family stood in each round of `d`: its best candidate's
/// rank among the round's reports (by evidence, 1 = first), evidence, q
/// value and status (with its rows or period, [`place`]), and whether the
/// cap left it out at the planted place; "-" when the family was not among the reported candidates.
pub fn trace(d: &Diagnosis, shape: &Shape, m: usize) -> String {
    let tol = tolerance(m);
    let texts = family_texts(shape);
    let also = texts.len() > 1;
    let mut out = Vec::new();
    let rounds = d.effects.iter().map(|e| e.round).max().unwrap_or(0);
    for round in 1..=rounds {
        let mut of_round: Vec<&EffectReport> =
            d.effects.iter().filter(|e| e.round == round).collect();
        of_round.sort_by(|a, b| b.evidence.total_cmp(&a.evidence));
        let found = of_round
            .iter()
            .enumerate()
            .find(|(_, e)| of_family(&e.label, &texts));
        out.push(match found {
            Some((k, e)) => format!(
                "r{round} {}#{} ev {:.3} q {:.4}{}{}{}",
                if also {
                    format!("{} ", e.label.split(' ').next().unwrap_or(""))
                } else {
                    String::new()
                },
                k + 1,
                e.evidence,
                e.q_value,
                if e.accepted {
                    " ADDED"
                } else if e.significant {
                    " sig"
                } else {
                    ""
                },
                e.refit_gain
                    .map(|g| format!(" refit {:+.1} %", -100.0 * g))
                    .unwrap_or_default(),
                place(&e.params, shape, tol)
            ),
            None => format!("r{round} -"),
        });
    }
    if let Some(l) = d
        .left_by_cap
        .iter()
        .find(|l| is_plant(&l.label, &l.params, &texts, shape, tol))
    {
        out.push(format!("left by the cap (evidence {:.3})", l.evidence));
    }
    out.join("; ")
}

/// The texts that name the planted family in a label or a
/// `confounded_with` entry: a block is also found as a step at an edge.
fn family_texts(shape: &Shape) -> Vec<String> {
    match shape {
        Shape::Step { .. } => vec!["step in the measurement order".into()],
        Shape::Block { .. } => vec![
            "block of rows".into(),
            "step in the measurement order".into(),
        ],
        Shape::Drift { .. } => vec!["temp_c".into()],
        Shape::Lag { joint } => vec![format!("moves of q{joint} ")],
        Shape::Harmonic { joint, .. } => vec![format!("harmonic of q{joint}")],
    }
}

/// Does `text` name one of the family's `texts`.
fn of_family(text: &str, texts: &[String]) -> bool {
    texts.iter().any(|t| text.contains(t.as_str()))
}

type Params = std::collections::BTreeMap<String, f64>;

/// Is a candidate with parameters `params` at the planted place: a step
/// candidate's row within `tol` of the planted step or of a planted block's
/// edge; a block candidate's two edges each within `tol` of the planted
/// block's; a harmonic's period within 3 % of the planted one. A drift or
/// lag has no place beyond its family.
fn at_place(params: &Params, shape: &Shape, tol: usize) -> bool {
    let near = |k: &str, v: usize| {
        params
            .get(k)
            .is_some_and(|r| (r - v as f64).abs() <= tol as f64)
    };
    match shape {
        Shape::Step { row, .. } => near("row", *row),
        Shape::Block { from, to, .. } => {
            (near("from_row", *from) && near("to_row", *to))
                || near("row", *from)
                || near("row", *to)
        }
        Shape::Harmonic { period_deg, .. } => params
            .get("period_deg")
            .is_some_and(|p| (p - period_deg).abs() <= 0.03 * period_deg),
        _ => true,
    }
}

/// A step or block candidate's rows in a trace, " @r" or " @a–b" (a
/// harmonic's period, " @P°"), and " (elsewhere)" when not at the planted
/// place.
fn place(params: &Params, shape: &Shape, tol: usize) -> String {
    let shown: Vec<String> = params
        .iter()
        .filter(|(k, _)| k.ends_with("row"))
        .map(|(_, v)| format!("{v:.0}"))
        .chain(params.get("period_deg").map(|p| format!("{p:.2}°")))
        .collect();
    if shown.is_empty() {
        return String::new();
    }
    format!(
        " @{}{}",
        shown.join("–"),
        if at_place(params, shape, tol) {
            ""
        } else {
            " (elsewhere)"
        }
    )
}

/// The parameters written in a `confounded_with` entry's first parentheses
/// ("(row 373.000)", "(from_row 229.000, to_row 491.000)", "(period_deg
/// 21.500)"): the place parameters only.
fn params_in_text(text: &str) -> Params {
    let mut out = Params::new();
    for key in ["from_row", "to_row", "row", "period_deg"] {
        let pattern = format!("{key} ");
        for (i, _) in text.match_indices(&pattern) {
            // "row" must not be the end of "from_row" or "to_row"
            if i > 0 && !matches!(text.as_bytes()[i - 1], b'(' | b' ') {
                continue;
            }
            let rest = &text[i + pattern.len()..];
            let end = rest
                .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
                .unwrap_or(rest.len());
            if let Ok(v) = rest[..end].parse() {
                out.entry(key.to_string()).or_insert(v);
            }
        }
    }
    out
}

/// Is a candidate labelled `label` with `params` the planted family at
/// its place.
fn is_plant(label: &str, params: &Params, texts: &[String], shape: &Shape, tol: usize) -> bool {
    of_family(label, texts) && at_place(params, shape, tol)
}

/// Does `entry` (a `confounded_with` text) name the planted family at its
/// place.
fn names_plant(entry: &str, texts: &[String], shape: &Shape, tol: usize) -> bool {
    is_plant(entry, &params_in_text(entry), texts, shape, tol)
}

fn within(ci: Option<&[f64; 2]>, v: f64) -> Option<bool> {
    ci.map(|c| c[0] <= v && v <= c[1])
}

/// One planted coefficient: the model's column, the axis, the value.
pub type Target = (String, usize, f64);

/// Per axis of each of `columns`: the planted value `value` (× sign).
fn per_axis(columns: &[(String, f64)], value: [f64; 3]) -> Vec<Target> {
    columns
        .iter()
        .flat_map(|(c, sign)| (0..3).map(move |a| (c.clone(), a, sign * value[a])))
        .collect()
}

/// Do the 95 % intervals of `e` cover `targets`, each shifted by `own`
/// (`None`: a column is not in its sizes).
pub fn covers(e: &EffectReport, targets: &[Target], own: &[f64]) -> Option<Vec<bool>> {
    targets
        .iter()
        .zip(own.iter().chain(std::iter::repeat(&0.0)))
        .map(|((column, a, v), o)| {
            let c = e.size.iter().find(|c| &c.column == column)?;
            Some((c.estimate[*a] - v - o).abs() <= c.ci95[*a])
        })
        .collect()
}

/// Does the row / period / τ interval cover the planted value, and the
/// planted coefficients to check.
fn coverage(e: &EffectReport, shape: &Shape, p: &Planted) -> (Option<bool>, Vec<Target>) {
    match shape {
        Shape::Step { row, .. } => {
            let found = param(e, "row").unwrap_or(f64::NAN) as usize;
            let ci = e.params_ci.get("row").copied().unwrap_or([found as f64; 2]);
            (
                within(Some(&ci), *row as f64),
                per_axis(&[(format!("step@{found}"), 1.0)], p.value),
            )
        }
        Shape::Block { from, to, .. } => {
            let (a, b) = (
                param(e, "from_row").unwrap_or(f64::NAN) as usize,
                param(e, "to_row").unwrap_or(f64::NAN) as usize,
            );
            let ca = e
                .params_ci
                .get("from_row")
                .copied()
                .unwrap_or([a as f64; 2]);
            let cb = e.params_ci.get("to_row").copied().unwrap_or([b as f64; 2]);
            let rows = within(Some(&ca), *from as f64).zip(within(Some(&cb), *to as f64));
            let cols = [(format!("step@{a}"), 1.0), (format!("step@{b}"), -1.0)];
            (rows.map(|(x, y)| x && y), per_axis(&cols, p.value))
        }
        Shape::Drift { .. } => (None, per_axis(&[("temp_c".into(), 1.0)], p.value)),
        Shape::Lag { joint } => {
            // the trend column of axis a is `J_a,j(q)·h` (J per radian, the
            // move h in degrees): a planted gain g is −g·π/180 on each axis's
            // own column; the memory τ planted is 0
            let tau = param(e, "tau_poses").unwrap_or(f64::NAN);
            let tau_covered = within(e.params_ci.get("tau_poses"), 0.0).or(Some(tau == 0.0));
            let g = -p.value[0].to_radians();
            let targets = ["x", "y", "z"]
                .iter()
                .enumerate()
                .map(|(a, axis)| (format!("J{axis}{joint}·move{joint}"), a, g))
                .collect();
            (tau_covered, targets)
        }
        Shape::Harmonic {
            period_deg,
            phase_rad,
            ..
        } => {
            // through the Jacobian, the trend columns of axis a are
            // `J_a,j(q)·sin(2π (θ_j − c)/P)` and `·cos` (J per radian, c
            // the effect's phase reference): a planted `A sin(2π θ_j/P + φ)`
            // (A in degrees) is `A sin(2π (θ_j − c)/P + φ')` with
            // φ' = φ + 2π c/P, i.e. A·cos φ' and A·sin φ' radians on each
            // axis's own columns (named as the effect names them). An axis
            // the joint cannot move (q1's z: its Jacobian row is zero, and
            // the engine drops the column) has no coefficient to check. A
            // plain harmonic's per-axis coefficients have no planted value.
            let targets = match e.add.first() {
                Some(f @ Feature::HarmonicJacobian { centre_deg, .. }) => {
                    let a = p.value[0].to_radians();
                    let phi = phase_rad + std::f64::consts::TAU * centre_deg / period_deg;
                    let names = f.names();
                    (0..3)
                        .flat_map(|k| {
                            [
                                (names[k].clone(), k, a * phi.cos()),
                                (names[3 + k].clone(), k, a * phi.sin()),
                            ]
                        })
                        .filter(|(column, ..)| e.size.iter().any(|c| &c.column == column))
                        .collect()
                }
                _ => Vec::new(),
            };
            (within(e.params_ci.get("period_deg"), *period_deg), targets)
        }
    }
}

/// Score the diagnosis `d` of the planted campaign against `control`.
/// `own`: the unplanted campaign's coefficients of the planted targets
/// (fitted with the planted diagnosis's final effects).
pub fn score(
    d: &Diagnosis,
    control: &Diagnosis,
    (shape, p): (&Shape, &Planted),
    m: usize,
    own: &dyn Fn(&[Target]) -> Option<Vec<f64>>,
) -> Score {
    let tol = tolerance(m);
    let accepted = |x: &Diagnosis| {
        x.effects
            .iter()
            .filter(|e| e.accepted)
            .cloned()
            .collect::<Vec<_>>()
    };
    let base = accepted(control);
    let new: Vec<EffectReport> = accepted(d)
        .into_iter()
        .filter(|e| !base.iter().any(|b| same(e, b, tol)))
        .collect();
    let added = new.iter().map(with_params).collect();
    if let Some(e) = new.iter().find(|e| is_right(e, shape, tol)) {
        let (row_covered, targets) = coverage(e, shape, p);
        let own_values = own(&targets);
        let nonempty = |v: Option<Vec<bool>>| v.filter(|v| !v.is_empty());
        return Score {
            outcome: Outcome::Right,
            row_covered,
            coef_covered: nonempty(covers(e, &targets, &[])),
            own_covered: nonempty(own_values.as_ref().and_then(|o| covers(e, &targets, o))),
            added,
            detail: detail(e, p, &targets, own_values.as_deref()),
            left_by_cap: false,
            seen: true,
            own_only: false,
            by_order_note: false,
        };
    }
    if let Some(sc) = block_as_steps(&new, shape, p, tol, own) {
        return Score { added, ..sc };
    }
    let texts = family_texts(shape);
    // the effects the control added too name the campaign's own
    let named = new.iter().any(|e| {
        e.confounded_with
            .iter()
            .any(|c| names_plant(c, &texts, shape, tol))
    });
    let seen = d
        .effects
        .iter()
        .any(|e| e.significant && is_plant(&e.label, &e.params, &texts, shape, tol));
    let by_order_note = !named && named_by_order(d, shape, tol);
    let named = named || by_order_note;
    let outcome = match (new.is_empty(), named) {
        (true, _) => Outcome::Missed,
        (false, true) => Outcome::ProxyNamed,
        (false, false) => Outcome::Proxy,
    };
    Score {
        outcome,
        row_covered: None,
        coef_covered: None,
        own_covered: None,
        added,
        detail: String::new(),
        left_by_cap: d
            .left_by_cap
            .iter()
            .any(|l| is_plant(&l.label, &l.params, &texts, shape, tol)),
        seen,
        own_only: !new.is_empty() && new.iter().all(|e| significant_in(e, control, tol)),
        by_order_note: by_order_note && !new.is_empty(),
    }
}

/// Whether the report's note on the order against the joint space
/// ([`Diagnosis::order_in_joint_space`]) names the planted step or block:
/// a step is regional within `tol` rows of the planted row (of each of a
/// block's two edges). The note says that there a step or block of the
/// rows and an effect of the pose can stand for each other.
fn named_by_order(d: &Diagnosis, shape: &Shape, tol: usize) -> bool {
    let Some(o) = d.order_in_joint_space.as_ref().filter(|o| o.matters()) else {
        return false;
    };
    let near = |row: usize| (row.saturating_sub(tol)..=row + tol).any(|r| o.step_is_regional(r));
    match *shape {
        Shape::Step { row, .. } => near(row),
        Shape::Block { from, to, .. } => near(from) && near(to),
        _ => false,
    }
}

/// A planted block that `new` holds as two steps, one at each edge: right,
/// scored edge by edge (module docs). `None` for any other plant or when
/// an edge has no step.
fn block_as_steps(
    new: &[EffectReport],
    shape: &Shape,
    p: &Planted,
    tol: usize,
    own: &dyn Fn(&[Target]) -> Option<Vec<f64>>,
) -> Option<Score> {
    let Shape::Block { from, to, dir } = shape else {
        return None;
    };
    let step = |row: usize| Shape::Step { row, dir: *dir };
    let first = new.iter().position(|e| is_right(e, &step(*from), tol))?;
    // the other edge's step is another effect
    let second = new
        .iter()
        .enumerate()
        .position(|(k, e)| k != first && is_right(e, &step(*to), tol))?;
    let edges = [(&new[first], *from, 1.0), (&new[second], *to, -1.0)];
    // each edge's targets (the planted offset, + then −) and row coverage
    let scored: Vec<(&EffectReport, Option<bool>, Vec<Target>)> = edges
        .iter()
        .map(|&(e, row, sign)| {
            let (covered, targets) = coverage(e, &step(row), p);
            let targets = targets
                .into_iter()
                .map(|(c, a, v)| (c, a, sign * v))
                .collect();
            (e, covered, targets)
        })
        .collect();
    let rows = scored.iter().all(|(_, c, _)| *c == Some(true));
    let all: Vec<Target> = scored.iter().flat_map(|(_, _, t)| t.clone()).collect();
    // one refit of the unplanted campaign for both edges' coefficients
    let own_all = own(&all);
    let mut offset = 0;
    let (mut coef, mut own_cov) = (Some(Vec::new()), Some(Vec::new()));
    for (e, _, targets) in &scored {
        let own_values = own_all
            .as_ref()
            .map(|o| o[offset..offset + targets.len()].to_vec());
        offset += targets.len();
        let join = |acc: Option<Vec<bool>>, got: Option<Vec<bool>>| {
            acc.zip(got).map(|(mut a, b)| {
                a.extend(b);
                a
            })
        };
        coef = join(coef, covers(e, targets, &[]));
        own_cov = join(own_cov, own_values.and_then(|o| covers(e, targets, &o)));
    }
    let nonempty = |v: Option<Vec<bool>>| v.filter(|v| !v.is_empty());
    let details: Vec<String> = scored
        .iter()
        .map(|(e, _, _)| detail(e, p, &[], None))
        .collect();
    Some(Score {
        outcome: Outcome::Right,
        row_covered: Some(rows),
        coef_covered: nonempty(coef),
        own_covered: nonempty(own_cov),
        added: Vec::new(),
        detail: format!("as two steps: {}", details.join(" | ")),
        left_by_cap: false,
        seen: true,
        own_only: false,
        by_order_note: false,
    })
}

/// Its label and parameters, e.g. "harmonic of q1 (period_deg 6.3)".
pub fn with_params(e: &EffectReport) -> String {
    if e.params.is_empty() {
        return e.label.clone();
    }
    let p: Vec<String> = e
        .params
        .iter()
        .map(|(k, v)| format!("{k} {v:.1}"))
        .collect();
    format!("{} ({})", e.label, p.join(", "))
}

/// The found parameters with their intervals, and the size coefficients
/// against the planted value: with planted `targets`, each one's estimate
/// and interval against the planted value (and the campaign's own,
/// `own`, beside it).
fn detail(e: &EffectReport, p: &Planted, targets: &[Target], own: Option<&[f64]>) -> String {
    let mut out: Vec<String> = e
        .params
        .iter()
        .map(|(k, v)| match e.params_ci.get(k) {
            Some(c) => format!("{k} {v:.1} [{:.1}, {:.1}]", c[0], c[1]),
            None => format!("{k} {v:.1}"),
        })
        .collect();
    if !targets.is_empty() {
        for (k, (column, a, v)) in targets.iter().enumerate() {
            let Some(c) = e.size.iter().find(|c| &c.column == column) else {
                continue;
            };
            let own = own
                .and_then(|o| o.get(k))
                .map_or(String::new(), |o| format!(" + own {o:+.3e}"));
            out.push(format!(
                "{column} [{}] {:+.3e}±{:.2e} (planted {v:+.3e}{own})",
                ["x", "y", "z"][*a],
                c.estimate[*a],
                c.ci95[*a]
            ));
        }
        return out.join(", ");
    }
    for c in e.size.iter().take(2) {
        let f = |a: usize| format!("{:+.3e}±{:.2e}", c.estimate[a], c.ci95[a]);
        out.push(format!("{} {}/{}/{}", c.column, f(0), f(1), f(2)));
    }
    let v = p.value;
    out.push(format!("planted {:+.3}/{:+.3}/{:+.3}", v[0], v[1], v[2]));
    out.join(", ")
}
