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
//!
//! The families are built by kind, one file each, and [`families_on`] calls
//! them in a fixed order (which ties in the ranking keep): `covariate.rs`
//! (each covariate alone and times the joint angles, and which covariates
//! are left out as constant), `order.rs` (drift, a step, a block of rows),
//! `pose.rs` (harmonics, cross-joint products, cross-talk: functions of the
//! pose), `direction.rs` (direction history), `motion.rs` (the motion into
//! the pose) and `generic.rs` (each one-column basis times one joint angle,
//! and lagged). `significance.rs` tests them all ([`test_families`]).

mod covariate;
mod direction;
mod generic;
mod motion;
mod order;
mod pose;
mod significance;

use super::rows::ScanRows;
use crate::dataset::Dataset;
use crate::features::Feature;
use crate::kinematics::Robot;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub use super::rank::{fitted, similarity};
use covariate::covariate_families;
pub use covariate::{
    DroppedCovariate, MIN_VARYING_ROWS, constant_covariate, dropped_covariates,
    dropped_covariates_on,
};
use direction::direction_families;
pub use motion::MOVE_TAUS;
pub(crate) use motion::is_time_column;
use motion::motion_families;
use order::order_families;
pub use order::step_rows;
use pose::{
    crosstalk_families, harmonic_families, harmonic_jacobian_families, interaction_families,
};
pub use significance::{Refined, Refit, Tested, benjamini_hochberg, test_families};

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
    /// The output axis of each column (`None`: every axis,
    /// [`Feature::column_axes`]), one per column.
    pub axes: Vec<Option<usize>>,
    /// What to add to the model if this is accepted.
    pub add: Vec<Feature>,
}

impl GridPoint {
    /// A grid point whose every column is a regressor of every axis.
    pub fn new(params: BTreeMap<String, f64>, columns: Vec<Vec<f64>>, add: Vec<Feature>) -> Self {
        GridPoint {
            params,
            axes: vec![None; columns.len()],
            columns,
            add,
        }
    }

    /// A grid point whose columns are those of its features `add`, in
    /// their order, with their axes ([`Feature::column_axes`]).
    pub fn of_features(
        params: BTreeMap<String, f64>,
        columns: Vec<Vec<f64>>,
        add: Vec<Feature>,
    ) -> Self {
        let axes: Vec<Option<usize>> = add.iter().flat_map(Feature::column_axes).collect();
        debug_assert_eq!(axes.len(), columns.len());
        GridPoint {
            params,
            columns,
            axes,
            add,
        }
    }

    /// The columns that are regressors of output `axis`.
    pub fn on_axis(&self, axis: usize) -> Vec<&[f64]> {
        self.columns
            .iter()
            .zip(&self.axes)
            .filter(|(_, on)| on.is_none_or(|a| a == axis))
            .map(|(v, _)| v.as_slice())
            .collect()
    }

    /// [`GridPoint::on_axis`] of the three axes.
    pub fn by_axis(&self) -> [Vec<&[f64]>; 3] {
        std::array::from_fn(|a| self.on_axis(a))
    }
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

/// The finer grid points around `point`, on the scanned rows `rows` of
/// `data` (the campaign the family was built on).
pub type Zoom = fn(point: &GridPoint, rows: &ScanRows, data: &Dataset) -> Vec<GridPoint>;

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
        harmonic_jacobian_families(data, robot, &mut out);
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
    GridPoint::new(params, vec![col], vec![add])
}

/// Every column z-scored.
fn z_all(cols: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    cols.iter().map(|c| zscore(c)).collect()
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
}
