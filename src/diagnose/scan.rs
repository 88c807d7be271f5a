//! Candidate effects and their significance (step 2–3 of `diagnose`).
//!
//! A *family* is one named effect scanned over a parameter grid (a step over
//! the split row, a harmonic over the period, …); each grid point is a set of
//! regressor columns. Every grid point is tried *inside* the current model
//! ([`super::gls`]): its columns join the trend at the model's ξ and
//! nugget, and the statistic is the pooled leave-one-out gain, maximised
//! over the grid; the strongest few families are tried again at the ξ the
//! model would choose with them. Significance is a test of that maximum
//! against pseudo-campaigns of the fitted model (its whitened residuals with
//! random signs, the same resamples for every family, so the scan over the
//! grid is paid for), with the Benjamini–Hochberg correction across
//! families. The score used for ranking is the closed-form K-fold CV drop
//! of the best grid point.

use super::gls::{self, AxisSystem, FamilyTest};
use super::rows::ScanRows;
use crate::dataset::{Covariate, Dataset};
use crate::features::{Clock, Feature};
use crate::kinematics::Robot;
use crate::stats::rng_for;
use rand::RngExt;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What kind of effect a family is (the JSON `kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EffectKind {
    /// A numeric covariate column, alone or times the joint angles.
    Covariate,
    /// The measurement order: slow drift, or a step at one row.
    Order,
    /// A harmonic of one joint angle over a scanned period.
    Harmonic,
    /// A cross-joint product, or joint cross-talk through the Jacobian.
    Interaction,
    /// The direction history of a joint: its previous direction, or the travel
    /// since its last reversal.
    DirectionHistory,
    /// How the robot moved into the pose: a joint's last moves (signed,
    /// decaying, or their size), the TCP's last move, the time since the
    /// previous pose (servo lag, incomplete settling).
    MotionHistory,
}

impl EffectKind {
    /// Whether its candidates are functions of the joint angles alone (a
    /// harmonic, a cross-joint product, cross-talk): the GP can soak such an
    /// effect up itself by shortening its length scales, so at the model's
    /// ξ it looks smaller than it is and only the ξ re-estimated with it in
    /// the trend shows it. Such a family, once re-estimated, is tested at
    /// that ξ ([`test_families`]); every other kind (the measurement order,
    /// a covariate, the motion history), which the GP cannot represent from
    /// the pose, is tested at the model's ξ.
    pub fn pose_function(self) -> bool {
        matches!(self, EffectKind::Harmonic | EffectKind::Interaction)
    }

    /// The kind's name, as in the JSON `kind` and in plot file names.
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::Covariate => "covariate",
            EffectKind::Order => "order",
            EffectKind::Harmonic => "harmonic",
            EffectKind::Interaction => "interaction",
            EffectKind::DirectionHistory => "direction-history",
            EffectKind::MotionHistory => "motion-history",
        }
    }
}

/// One parameter value of a family.
#[derive(Debug, Clone)]
pub struct GridPoint {
    /// The grid parameters of this point by name (e.g. `period_deg`, `row`,
    /// `scale_deg`); empty for a family of one point.
    pub params: BTreeMap<String, f64>,
    /// Regressors, one column per entry (row order).
    pub columns: Vec<Vec<f64>>,
    /// What to add to the model if this is accepted.
    pub add: Vec<Feature>,
}

/// A candidate effect: a name and a grid of regressor sets.
#[derive(Debug, Clone)]
pub struct Family {
    /// What kind of effect it is.
    pub kind: EffectKind,
    /// Column(s) / joint(s) it comes from, e.g. `["temp_c"]`, `["q2"]`, `["row"]`.
    pub source: Vec<String>,
    /// Short description, e.g. "temp_c × joint angles".
    pub label: String,
    /// The parameter grid; each point is one set of regressor columns.
    pub grid: Vec<GridPoint>,
    /// For a grid on a lattice coarser than the data resolve (the block's
    /// edges): the finer points around a grid point, among which the
    /// reported one is chosen once the lattice is tested ([`Refined`]).
    pub zoom: Option<Zoom>,
}

/// The finer grid points around `point`, on the scanned rows `rows`.
pub type Zoom = fn(point: &GridPoint, rows: &ScanRows) -> Vec<GridPoint>;

/// Edges of the block lattice: its grid has about `BLOCK_EDGES²/2` points
/// (one column each), as many as the step family's at 1 000 rows.
const BLOCK_EDGES: usize = 32;

/// Rows before the first and after the last step or block edge scanned.
fn order_margin(m: usize) -> usize {
    (m / 20).max(5)
}

/// The rows a step is scanned at in a campaign of `m` rows (the step
/// family's grid: the one that grows with the campaign, one value a row).
pub fn step_rows(m: usize) -> std::ops::Range<usize> {
    let margin = order_margin(m);
    margin..m.saturating_sub(margin).max(margin)
}

/// Rows between two edges of the block lattice: about [`BLOCK_EDGES`]
/// edges evenly from the margin to `m − margin`.
fn block_spacing(m: usize) -> usize {
    let span = m.saturating_sub(2 * order_margin(m));
    span.div_ceil(BLOCK_EDGES).max(1)
}

/// Grid point of the block of scanned positions `[from, to)`: one indicator
/// column (a bump of one height, back at its end), added to the model as
/// two steps at the campaign rows of its edges (each edge its own height: a
/// second step need not return to the first level).
fn block_point(rows: &ScanRows, from: usize, to: usize) -> GridPoint {
    let (a, b) = (rows.row(from), rows.row(to));
    GridPoint {
        params: params(&[("from_row", a as f64), ("to_row", b as f64)]),
        columns: vec![
            (0..rows.len())
                .map(|i| if (from..to).contains(&i) { 1.0 } else { 0.0 })
                .collect(),
        ],
        add: vec![Feature::Step { row: a }, Feature::Step { row: b }],
    }
}

/// Grid point of a step at scanned position `t` (the campaign row there).
fn step_point(rows: &ScanRows, t: usize) -> GridPoint {
    let row = rows.row(t);
    GridPoint {
        params: params(&[("row", row as f64)]),
        columns: vec![
            (0..rows.len())
                .map(|i| if i >= t { 1.0 } else { 0.0 })
                .collect(),
        ],
        add: vec![Feature::Step { row }],
    }
}

/// [`Zoom`] of a block: each edge moved a scanned row at a time within one
/// lattice spacing, the other held.
fn zoom_block(point: &GridPoint, rows: &ScanRows) -> Vec<GridPoint> {
    let (from, to) = (
        rows.position(point.params["from_row"] as usize),
        rows.position(point.params["to_row"] as usize),
    );
    let m = rows.len();
    let margin = order_margin(m);
    let s = block_spacing(m);
    let near = |c: usize| c.saturating_sub(s).max(margin)..(c + s + 1).min(m - margin);
    let mut out: Vec<GridPoint> = near(from)
        .filter(|&a| to >= a + margin)
        .map(|a| block_point(rows, a, to))
        .collect();
    out.extend(
        near(to)
            .filter(|&b| b >= from + margin && b != to)
            .map(|b| block_point(rows, from, b)),
    );
    out
}

/// Where [`families`] puts its families: each grid point's columns,
/// computed on the whole campaign, are taken at the scanned rows (and
/// standardised again there); the order families are built on the scanned
/// rows directly ([`Sink::push_scanned`]).
struct Sink<'a> {
    rows: &'a ScanRows,
    out: Vec<Family>,
}

impl Sink<'_> {
    /// A family whose columns have a value on every row of the campaign.
    fn push(&mut self, mut family: Family) {
        if !self.rows.is_all() {
            for g in &mut family.grid {
                for c in &mut g.columns {
                    *c = zscore(&self.rows.pick(c));
                }
            }
        }
        self.out.push(family);
    }

    /// A family built on the scanned rows.
    fn push_scanned(&mut self, family: Family) {
        self.out.push(family);
    }
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

/// Rows that must differ from a covariate's median for it to be a
/// candidate: a column that varies in fewer rows is an indicator of those
/// rows, not a covariate.
pub const MIN_VARYING_ROWS: usize = 5;

/// A covariate left out of the candidates because it does not vary over the
/// rows used: with a constant covariate, "covariate × joint
/// angles" is only a linear trend in the joint angles, and its name would
/// claim an effect the data cannot show.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DroppedCovariate {
    /// Column name.
    pub name: String,
    /// Why, in words, with the value.
    pub reason: String,
}

/// `Some(reason)` when covariate `c` is constant or nearly constant over its
/// rows: fewer than [`MIN_VARYING_ROWS`] rows differ from its median by more
/// than 1e-9 of its magnitude.
pub fn constant_covariate(c: &Covariate) -> Option<String> {
    let mut v: Vec<f64> = c.values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return Some(format!("no values in the {} rows used", c.values.len()));
    }
    v.sort_by(f64::total_cmp);
    let median = v[v.len() / 2];
    let tol = 1e-9 * median.abs().max(1.0);
    let varying = v.iter().filter(|x| (**x - median).abs() > tol).count();
    let m = c.values.len();
    if varying == 0 {
        Some(format!("constant ({median}) in all {m} rows used"))
    } else if varying < MIN_VARYING_ROWS.min(m) {
        Some(format!(
            "nearly constant: {median} in all but {varying} of the {m} rows used"
        ))
    } else {
        None
    }
}

/// The covariates that may become candidates: not in `exclude` (already
/// in the model), no missing values, not a precomputed feature column (`@…`).
fn usable_covariates<'a>(
    data: &'a Dataset,
    exclude: &'a [String],
) -> impl Iterator<Item = &'a Covariate> {
    data.covariates
        .iter()
        .filter(|c| !exclude.contains(&c.name) && c.missing == 0 && !c.name.starts_with('@'))
}

/// The covariates [`families`] leaves out as constant, with the reason.
pub fn dropped_covariates(data: &Dataset, exclude: &[String]) -> Vec<DroppedCovariate> {
    dropped_covariates_on(data, exclude, &ScanRows::all(data.len()))
}

/// The covariates [`families_on`] leaves out as constant on the scanned
/// rows `rows`, with the reason: a column that varies in a few rows of the
/// campaign may vary in fewer still of the scanned ones, where it would be
/// an indicator of those rows under its name.
pub fn dropped_covariates_on(
    data: &Dataset,
    exclude: &[String],
    rows: &ScanRows,
) -> Vec<DroppedCovariate> {
    usable_covariates(data, exclude)
        .filter_map(|c| {
            let scanned = Covariate {
                name: c.name.clone(),
                values: rows.pick(&c.values),
                missing: c.missing,
            };
            constant_covariate(&scanned).map(|reason| DroppedCovariate {
                name: c.name.clone(),
                reason,
            })
        })
        .collect()
}

/// The candidate families a campaign supports. Covariates named in
/// `exclude` (already in the model), columns with missing values and
/// constant ones ([`constant_covariate`]) are left out; the harmonic periods run from 2° to half the joint's range, in steps
/// of a tenth of a cycle over the range (a phase error of at most 1/20
/// cycle at the ends). With a robot preset (`robot`), joint cross-talk
/// candidates mapped through its Jacobian are added.
pub fn families(data: &Dataset, exclude: &[String], robot: Option<&Robot>) -> Vec<Family> {
    families_on(data, exclude, robot, &ScanRows::all(data.len()))
}

/// [`families`] on the scanned rows `rows` of `data` ([`ScanRows`]): every
/// column is computed on the whole campaign (a joint's moves into a pose
/// need the pose before it) and taken at those rows; a step or a block
/// edge is scanned at each of them and reported, and added, at its
/// campaign row.
pub fn families_on(
    data: &Dataset,
    exclude: &[String],
    robot: Option<&Robot>,
    rows: &ScanRows,
) -> Vec<Family> {
    let n = data.n_joints();
    // covariates constant on the scanned rows are left out like constant ones
    let mut exclude = exclude.to_vec();
    exclude.extend(
        dropped_covariates_on(data, &exclude, rows)
            .into_iter()
            .map(|d| d.name),
    );
    let exclude = &exclude[..];
    let u: Vec<Vec<f64>> = (0..n)
        .map(|j| zscore(&data.q.iter().map(|r| r[j]).collect::<Vec<_>>()))
        .collect();
    let mut out = Sink {
        rows,
        out: Vec::new(),
    };
    covariate_families(data, exclude, &u, &mut out);
    order_families(data.len(), rows, &mut out);
    harmonic_families(data, &mut out);
    interaction_families(&u, &mut out);
    if let Some(robot) = robot {
        crosstalk_families(data, robot, &mut out);
    }
    for j in 0..n {
        direction_families(data, j, &mut out);
    }
    motion_families(data, exclude, robot, &u, &mut out);
    out.out
}

/// A grid point of one column and one feature.
fn single(params: BTreeMap<String, f64>, col: Vec<f64>, add: Feature) -> GridPoint {
    GridPoint {
        params,
        columns: vec![col],
        add: vec![add],
    }
}

/// Each usable covariate alone and times the joint angles `u` (z-scored).
fn covariate_families(data: &Dataset, exclude: &[String], u: &[Vec<f64>], out: &mut Sink) {
    // a constant column z-scores to round-off (or to ±1 everywhere): "c ×
    // joint angles" would then be a joint-angle trend in c's name
    for c in usable_covariates(data, exclude).filter(|c| constant_covariate(c).is_none()) {
        let z = zscore(&c.values);
        let add = Feature::Covariate {
            name: c.name.clone(),
            reference: Some(c.values[0]),
        };
        out.push(Family {
            kind: EffectKind::Covariate,
            source: vec![c.name.clone()],
            label: format!("{} (alone)", c.name),
            grid: vec![single(BTreeMap::new(), z.clone(), add.clone())],
            zoom: None,
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
            zoom: None,
        });
    }
}

/// The measurement order (of `m` rows): a slow drift on all rows, a step
/// and a block of rows at each scanned row.
fn order_families(m: usize, rows: &ScanRows, out: &mut Sink) {
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
        zoom: None,
    });
    // the order families on the scanned rows: a step, a block's edges at
    // each of them
    let ms = rows.len();
    if !step_rows(ms).is_empty() {
        out.push_scanned(Family {
            kind: EffectKind::Order,
            source: vec!["row".into()],
            label: "step in the measurement order".into(),
            grid: step_rows(ms).map(|t| step_point(rows, t)).collect(),
            zoom: None,
        });
    }
    // a block of rows: a bump that returns (a tracker knocked and put back,
    // a warm-up that settles), both edges scanned on a lattice, the reported
    // ones then row by row ([`zoom_block`]); one column, so a bump is not
    // split into two steps that each explain half of it
    let margin = order_margin(ms);
    if ms > 3 * margin {
        let edges: Vec<usize> = (margin..ms - margin).step_by(block_spacing(ms)).collect();
        let grid: Vec<GridPoint> = edges
            .iter()
            .enumerate()
            .flat_map(|(i, &a)| {
                edges[i + 1..]
                    .iter()
                    .filter(move |&&b| b >= a + margin)
                    .map(move |&b| block_point(rows, a, b))
            })
            .collect();
        if !grid.is_empty() {
            out.push_scanned(Family {
                kind: EffectKind::Order,
                source: vec!["row".into()],
                label: "block of rows (a bump, back at its end)".into(),
                grid,
                zoom: Some(zoom_block),
            });
        }
    }
}

/// Harmonics of each joint, periods from 2° to half its range.
fn harmonic_families(data: &Dataset, out: &mut Sink) {
    for j in 0..data.n_joints() {
        let (lo, hi) = data
            .q
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                (a.min(r[j]), b.max(r[j]))
            });
        let range = hi - lo;
        let mut grid = Vec::new();
        let mut cycles = 2.0;
        while range / cycles >= 2.0 && grid.len() < 480 {
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
            cycles += 0.1;
        }
        if !grid.is_empty() {
            out.push(Family {
                kind: EffectKind::Harmonic,
                source: vec![format!("q{}", j + 1)],
                label: format!("harmonic of q{}", j + 1),
                grid,
                zoom: None,
            });
        }
    }
}

/// Products of two joint angles `u` (z-scored).
fn interaction_families(u: &[Vec<f64>], out: &mut Sink) {
    let n = u.len();
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
                zoom: None,
            });
        }
    }
}

/// Joint cross-talk mapped through `robot`'s Jacobian.
fn crosstalk_families(data: &Dataset, robot: &Robot, out: &mut Sink) {
    let n = data.n_joints();
    for j in 1..=n {
        for k in (1..=n).filter(|&k| k != j) {
            let f = Feature::Crosstalk {
                robot: Box::new(robot.clone()),
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
                zoom: None,
            });
        }
    }
}

/// Direction history of joint `j` (0-based): its previous direction, and
/// its travel since the last reversal (linear, and saturating over a scan
/// of scales); each alone and signed by the current direction λ (a history
/// effect on a joint acts along its λ, like backlash).
fn direction_families(data: &Dataset, j: usize, out: &mut Sink) {
    let lam: Vec<f64> = data.dir.iter().map(|d| d[j]).collect();
    let signed = |v: &[f64]| -> Vec<Vec<f64>> {
        vec![
            zscore(v),
            zscore(&v.iter().zip(&lam).map(|(a, l)| a * l).collect::<Vec<_>>()),
        ]
    };
    let prev = Feature::PreviousDirection { joint: j + 1 };
    let pv = prev
        .columns_from_poses(&data.q, &data.dir)
        .expect("pose feature");
    if pv[0].iter().any(|v| *v != pv[0][0]) {
        out.push(Family {
            kind: EffectKind::DirectionHistory,
            source: vec![format!("dir{}", j + 1)],
            label: format!("previous direction of q{}", j + 1),
            grid: vec![GridPoint {
                params: BTreeMap::new(),
                columns: signed(&pv[0]),
                add: vec![prev],
            }],
            zoom: None,
        });
    }
    // travel s since the last reversal: linear, and saturating
    // 1 − e^(−s/S) over a geometric scan of the scale S
    let since = Feature::SinceReversal { joint: j + 1 };
    let s = since
        .columns_from_poses(&data.q, &data.dir)
        .expect("pose feature")[0]
        .clone();
    let smax = s.iter().cloned().fold(0.0, f64::max);
    if smax <= 0.0 {
        return;
    }
    let mut grid = vec![GridPoint {
        params: BTreeMap::new(),
        columns: signed(&s),
        add: vec![since.clone()],
    }];
    let mut scale = smax / 2.0;
    while scale >= 0.5 && grid.len() < 24 {
        let sat: Vec<f64> = s.iter().map(|v| 1.0 - (-v / scale).exp()).collect();
        grid.push(GridPoint {
            params: params(&[("scale_deg", scale)]),
            columns: signed(&sat),
            add: vec![since.clone()],
        });
        scale /= 1.5;
    }
    out.push(Family {
        kind: EffectKind::DirectionHistory,
        source: vec![format!("dir{}", j + 1)],
        label: format!("travel of q{} since its last reversal", j + 1),
        grid,
        zoom: None,
    });
}

/// Memories τ (poses) scanned for a joint's decaying sum of moves.
pub const MOVE_TAUS: [f64; 6] = [0.0, 0.5, 1.0, 2.0, 4.0, 8.0];

/// Lags (rows) scanned by the generic search.
const LAGS: [usize; 3] = [1, 2, 3];

/// Names of a time column: the interval since the previous pose is a
/// candidate when one of these is present and never decreases.
const TIME_COLUMNS: [&str; 5] = ["time_s", "time", "t_s", "timestamp", "time_ms"];

/// The time column of a campaign, when it has one that never decreases.
fn time_column<'a>(data: &'a Dataset, exclude: &'a [String]) -> Option<&'a Covariate> {
    usable_covariates(data, exclude).find(|c| {
        TIME_COLUMNS.contains(&c.name.as_str())
            && c.values.windows(2).all(|w| w[1] >= w[0])
            && constant_covariate(c).is_none()
    })
}

/// The median interval between consecutive rows of a time column.
fn median_interval(t: &Covariate) -> Option<f64> {
    let mut dt: Vec<f64> = t.values.windows(2).map(|w| w[1] - w[0]).collect();
    dt.sort_by(f64::total_cmp);
    dt.get(dt.len() / 2).copied()
}

/// How the robot moved into each pose, and the generic search:
/// - per joint j, its signed moves with a scanned memory τ (through the
///   robot's Jacobian when it is given, so that the candidate is the TCP
///   displacement a lag of joint j causes; else the moves and their product
///   with every joint angle) and the size of its last move;
/// - the TCP's last move (with the robot), the time since the previous pose
///   (with a time column);
/// - for each numeric column, the interval and each joint's last move: the
///   feature times one joint angle (θ, sin θ, cos θ; the joint scanned),
///   and the columns and the interval lagged by 1–3 rows.
///
/// The scans are grids of one family each, so a family's p-value pays for
/// its scan (the null takes the maximum over the same grid).
fn motion_families(
    data: &Dataset,
    exclude: &[String],
    robot: Option<&Robot>,
    u: &[Vec<f64>],
    out: &mut Sink,
) {
    let memories = move_memories(data, exclude);
    for j in 1..=data.n_joints() {
        move_families(data, j, robot, u, &memories, out);
    }
    if let Some(r) = robot {
        tcp_move_family(data, r, out);
    }
    let (bases, lagged) = generic_bases(data, exclude, out);
    for (b, base) in bases.iter().enumerate() {
        generic_families(data, base, b < lagged, out);
    }
}

/// Every column z-scored.
fn z_all(cols: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    cols.iter().map(|c| zscore(c)).collect()
}

/// The memories a joint's moves are scanned over: `MOVE_TAUS` in poses
/// and, when the campaign has a time column, the same multiples of its
/// median interval in time.
fn move_memories(data: &Dataset, exclude: &[String]) -> Vec<(f64, Option<Clock>)> {
    let clocks: Vec<Clock> = time_column(data, exclude)
        .and_then(|t| {
            let median = median_interval(t)?;
            (median > 0.0).then(|| {
                MOVE_TAUS
                    .iter()
                    .filter(|&&k| k > 0.0)
                    .map(|&k| Clock {
                        column: t.name.clone(),
                        tau_s: k * median,
                        interval_s: Some(median),
                    })
                    .collect()
            })
        })
        .unwrap_or_default();
    MOVE_TAUS
        .iter()
        .map(|&tau| (tau, None))
        .chain(clocks.into_iter().map(|c| (0.0, Some(c))))
        .collect()
}

/// Joint `j`'s (1-based) moves into the pose over `memories` (through the
/// robot's Jacobian when given, else times the joint angles `u`), and the
/// size of its last move.
fn move_families(
    data: &Dataset,
    j: usize,
    robot: Option<&Robot>,
    u: &[Vec<f64>],
    memories: &[(f64, Option<Clock>)],
    out: &mut Sink,
) {
    let grid: Vec<GridPoint> = memories
        .iter()
        .filter_map(|(tau, clock)| move_point(data, j, *tau, clock, robot, u))
        .collect();
    if !grid.is_empty() {
        out.push(Family {
            kind: EffectKind::MotionHistory,
            source: vec![format!("move{j}")],
            label: format!("moves of q{j} into the pose (lag)"),
            grid,
            zoom: None,
        });
    }
    // the size alone: signed by λ it would be the signed move, which the
    // family above tests (and a candidate's columns must be what it adds)
    let size = Feature::MoveSize { joint: j };
    if let Ok(s) = size.columns_from_poses(&data.q, &data.dir) {
        out.push(Family {
            kind: EffectKind::MotionHistory,
            source: vec![format!("move{j}")],
            label: format!("size of q{j}'s last move"),
            grid: vec![GridPoint {
                params: BTreeMap::new(),
                columns: vec![zscore(&s[0])],
                add: vec![size],
            }],
            zoom: None,
        });
    }
}

/// One memory (`tau` poses, or `clock`) of joint `j`'s moves: through the
/// robot's Jacobian when given, else the moves alone and times the joint
/// angles `u`. `None` when the columns cannot be computed.
fn move_point(
    data: &Dataset,
    j: usize,
    tau: f64,
    clock: &Option<Clock>,
    robot: Option<&Robot>,
    u: &[Vec<f64>],
) -> Option<GridPoint> {
    let (columns, add) = match robot {
        Some(r) => {
            let f = Feature::MovesJacobian {
                robot: Box::new(r.clone()),
                joint: j,
                tau_poses: tau,
                clock: clock.clone(),
            };
            (z_all(f.columns(data).ok()?), f)
        }
        None => {
            let plain = Feature::Moves {
                joint: j,
                tau_poses: tau,
                clock: clock.clone(),
            };
            let h = plain.columns(data).ok()?;
            let z = zscore(&h[0]);
            let mut cols = vec![z.clone()];
            cols.extend(
                u.iter()
                    .map(|uk| z.iter().zip(uk).map(|(a, b)| a * b).collect()),
            );
            (cols, plain)
        }
    };
    Some(GridPoint {
        params: match clock {
            Some(c) => params(&[("tau_s", c.tau_s)]),
            None => params(&[("tau_poses", tau)]),
        },
        columns,
        add: vec![add],
    })
}

/// The TCP's last move (needs the robot).
fn tcp_move_family(data: &Dataset, robot: &Robot, out: &mut Sink) {
    let f = Feature::TcpMove {
        robot: Box::new(robot.clone()),
    };
    if let Ok(c) = f.columns_from_poses(&data.q, &data.dir) {
        out.push(Family {
            kind: EffectKind::MotionHistory,
            source: vec!["tcp_move".into()],
            label: "the TCP's last move".into(),
            grid: vec![GridPoint {
                params: BTreeMap::new(),
                columns: z_all(c),
                add: vec![f],
            }],
            zoom: None,
        });
    }
}

/// A one-column basis of the generic search: the feature, its values, its
/// label.
type Base = (Feature, Vec<f64>, String);

/// The one-column bases of the generic search, and how many of them (the
/// first) are also tried lagged: the usable covariates, the time since the
/// previous pose (whose family is pushed here, with a time column), each
/// joint's last move.
fn generic_bases(data: &Dataset, exclude: &[String], out: &mut Sink) -> (Vec<Base>, usize) {
    let mut bases: Vec<Base> = Vec::new();
    for c in usable_covariates(data, exclude).filter(|c| constant_covariate(c).is_none()) {
        let f = Feature::Covariate {
            name: c.name.clone(),
            reference: Some(c.values[0]),
        };
        bases.push((f, c.values.clone(), c.name.clone()));
    }
    if let Some(t) = time_column(data, exclude) {
        let f = Feature::Interval {
            column: t.name.clone(),
            reference: median_interval(t),
        };
        if let Ok(v) = f.columns(data) {
            out.push(Family {
                kind: EffectKind::MotionHistory,
                source: vec![t.name.clone()],
                label: format!("time since the previous pose (Δ{})", t.name),
                grid: vec![GridPoint {
                    params: BTreeMap::new(),
                    columns: vec![zscore(&v[0])],
                    add: vec![f.clone()],
                }],
                zoom: None,
            });
            bases.push((f, v[0].clone(), format!("Δ{}", t.name)));
        }
    }
    let lagged = bases.len();
    for j in 1..=data.n_joints() {
        let f = Feature::Moves {
            joint: j,
            tau_poses: 0.0,
            clock: None,
        };
        if let Ok(v) = f.columns_from_poses(&data.q, &data.dir) {
            bases.push((f, v[0].clone(), format!("q{j}'s last move")));
        }
    }
    (bases, lagged)
}

/// A base times one joint angle (θ, sin θ, cos θ), and lagged when
/// `lagged`.
fn generic_families(data: &Dataset, (f, v, label): &Base, lagged: bool, out: &mut Sink) {
    let n = data.n_joints();
    let (kind, source) = match f {
        Feature::Covariate { name, .. } => (EffectKind::Covariate, name.clone()),
        Feature::Interval { column, .. } => (EffectKind::MotionHistory, column.clone()),
        other => (EffectKind::MotionHistory, other.names().concat()),
    };
    // the columns as the model would get them ([`Feature::Times`]),
    // centred at the feature's mean: the product with a covariate near
    // 22 °C must not be a joint-angle trend in the covariate's name
    let centre = v.iter().sum::<f64>() / v.len() as f64;
    let grid: Vec<GridPoint> = (1..=n)
        .filter_map(|k| {
            let t = Feature::Times {
                of: Box::new(f.clone()),
                joint: k,
                centre,
            };
            Some(GridPoint {
                params: params(&[("joint", k as f64)]),
                columns: z_all(t.columns(data).ok()?),
                add: vec![t],
            })
        })
        .collect();
    out.push(Family {
        kind,
        source: vec![source.clone()],
        label: format!("{label} × one joint angle (θ, sin θ, cos θ)"),
        grid,
        zoom: None,
    });
    if !lagged {
        return;
    }
    out.push(Family {
        kind,
        source: vec![source],
        label: format!("{label}, lagged"),
        grid: LAGS
            .iter()
            .map(|&lag| GridPoint {
                params: params(&[("lag", lag as f64)]),
                columns: vec![zscore(
                    &(0..v.len())
                        .map(|i| v[i.saturating_sub(lag)])
                        .collect::<Vec<_>>(),
                )],
                add: vec![Feature::Lagged {
                    of: Box::new(f.clone()),
                    lag,
                }],
            })
            .collect(),
        zoom: None,
    });
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
    /// For a family with a [`Family::zoom`]: its best point among the finer
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
pub type Refit<'a> = dyn Fn(&[Vec<f64>]) -> Option<Vec<AxisSystem>> + Sync + 'a;

/// Resamples per batch of the sequential test.
const BATCH: usize = 100;
/// Exceedances after which a family's p-value is settled (Besag & Clifford
/// 1991): a clearly null family stops after a batch or two.
const SETTLED: usize = 10;

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
/// [`super::gls`], on the scanned rows `rows` the families were built on):
/// statistic, the pooled leave-one-out gain of the best
/// grid point at the model's ξ. Its null distribution is that of the same
/// statistic in pseudo-campaigns (sign-flipped whitened residuals, seeded,
/// the same for every family, sequential: a family stops once `SETTLED`
/// resamples reach its statistic, `p = (1 + exceed)/(1 + run)`), so the
/// p-value accounts for the scan over the family's grid. Benjamini–Hochberg
/// across families.
///
/// The `refine` families with the largest statistic are tried again at the
/// ξ the model would choose with their best grid point (`refit` returns the
/// systems there; `None` keeps the first test). Their score and reported
/// point become those of the new ξ when it gives more: the smaller of the
/// candidate's gain there and the improvement over the model as it is,
/// `LOO(model) − LOO(model + candidate at its ξ)`. A family of a
/// [`EffectKind::pose_function`] kind is then also *tested* with that
/// statistic (the GP had partly soaked the effect up at the model's ξ). The
/// re-estimated statistic has no re-estimation in its null, so that p-value
/// is optimistic, and [`super::diagnose`] counts such a candidate only once
/// the refit CV confirms it (pseudo-campaigns at the re-estimated ξ itself
/// were worse: controls reached p = 0.0005). Every other family keeps the
/// p-value of the model's ξ: in 160-row controls a step, and then a block
/// of rows, reached the smallest p-value the resamples allow at the
/// re-estimated ξ, and the GP cannot soak up an effect it has no input for.
/// Score, the closed-form K-fold CV drop at the partition the systems were
/// built for.
#[allow(clippy::too_many_arguments)]
pub fn test_families(
    families: &[Family],
    rows: &ScanRows,
    systems: Vec<AxisSystem>,
    permutations: usize,
    seed: u64,
    refine: usize,
    refit: &Refit<'_>,
    progress: &dyn Fn(&str),
) -> Vec<Tested> {
    let grids: Vec<Vec<Vec<Vec<f64>>>> = families
        .iter()
        .map(|f| f.grid.iter().map(|g| g.columns.clone()).collect())
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
    let null = base.sign_flip(&trials, &observed, permutations, seed, progress);
    let p = null.p_values(&trials);
    let q = benjamini_hochberg(&p);
    let within = support_width(&systems);
    (0..families.len())
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
                t.refined = resolve(zoom, start, rows, &systems, &base.data, within);
            }
            t
        })
        .collect()
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
/// statistics.
struct Null {
    exceed: Vec<usize>,
    run: Vec<usize>,
    moments: Vec<[f64; 2]>,
}

impl Null {
    /// `(1 + exceedances) / (1 + resamples)`, 1 for a family without a
    /// finite statistic.
    fn p_values(&self, trials: &[Trial]) -> Vec<f64> {
        (0..trials.len())
            .map(|k| {
                if trials[k].stat.is_finite() {
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
    fn trial(&self, grid: &[Vec<Vec<f64>>]) -> Trial {
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
    /// statistic, at most `permutations` in all.
    fn sign_flip(
        &self,
        trials: &[Trial],
        observed: &[f64],
        permutations: usize,
        seed: u64,
        progress: &dyn Fn(&str),
    ) -> Null {
        let (f, m) = (trials.len(), self.systems[0].rows());
        let mut null = Null {
            exceed: vec![0; f],
            run: vec![0; f],
            moments: vec![[0.0; 2]; f],
        };
        let mut done = 0;
        while done < permutations {
            let active: Vec<usize> = (0..f)
                .filter(|&k| null.exceed[k] < SETTLED && trials[k].stat.is_finite())
                .collect();
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
    grids: &[Vec<Vec<Vec<f64>>>],
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
        let Some(sys) = refit(&families[k].grid[trials[k].best].columns) else {
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
    rows: &ScanRows,
    systems: &[AxisSystem],
    data: &[gls::Response],
    within: f64,
) -> Option<Refined> {
    let mut found: Option<Refined> = None;
    for _ in 0..ZOOM_PASSES {
        let centre = found.as_ref().map_or(start, |r| &r.point);
        let local = zoom(centre, rows);
        if local.is_empty() {
            break;
        }
        let grid: Vec<Vec<Vec<f64>>> = local.iter().map(|g| g.columns.clone()).collect();
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_names_are_the_json_names() {
        use EffectKind::*;
        for k in [
            Covariate,
            Order,
            Harmonic,
            Interaction,
            DirectionHistory,
            MotionHistory,
        ] {
            assert_eq!(
                serde_json::to_string(&k).unwrap(),
                format!("\"{}\"", k.name())
            );
        }
    }

    #[test]
    fn bh_adjustment_is_monotone_and_matches_hand_values() {
        let q = benjamini_hochberg(&[0.01, 0.04, 0.03, 0.5]);
        assert!((q[0] - 0.04).abs() < 1e-12);
        assert!((q[2] - 0.0533333333333).abs() < 1e-9);
        assert!((q[1] - 0.0533333333333).abs() < 1e-9);
        assert!((q[3] - 0.5).abs() < 1e-12);
    }
}
