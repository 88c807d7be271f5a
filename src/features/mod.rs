//! Extra model inputs beyond `[θ, λ]`: the effects `diagnose` can add
//! (a covariate column, measurement order, a step, a joint harmonic, a
//! cross-joint interaction, direction history, the motion into the pose).
//! A covariate, the order, direction history and a joint's moves become
//! input dimensions of the Kriging model (with their own correlation length)
//! and a linear trend term, so the GP can also let the effect vary with the
//! pose; a step, harmonic, interaction, cross-talk basis, a lag mapped
//! through the Jacobian or a feature times a joint angle has a known shape
//! and enters the trend only ([`Feature::trend_only`]).
//!
//! Motion-history features ([`Feature::Moves`], [`Feature::MoveSize`],
//! [`Feature::MovesJacobian`], [`Feature::TcpMove`]) are computed from the
//! pose order: the move into pose k is `q(k) − q(k−1)` (0 for the first row),
//! so a prediction along a trajectory uses its previous commanded pose, as λ
//! does.
//!
//! Values come from a campaign ([`Feature::columns`]), where a precomputed
//! covariate column of the same name wins (so a feature keeps the values of the
//! full campaign inside CV folds), or from a pose sequence alone
//! ([`Feature::columns_from_poses`]): every campaign-state feature then takes
//! its value at the start of the campaign (row 0, step 0, a covariate's first
//! value when the feature records it), so the model predicts the robot in the
//! state it was in when the campaign began.

mod motion;

use crate::dataset::Dataset;
use crate::space::MOVE_EPS;
use crate::{Error, Result};
pub use motion::Clock;
use motion::{memory, moves_columns, moves_name};
use serde::{Deserialize, Serialize};

/// One extra input (or a pair, for a harmonic).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "feature", rename_all = "kebab-case")]
pub enum Feature {
    /// A numeric covariate column (temperature, time, payload, …), with its
    /// value at the start of the campaign for predictions without the column.
    Covariate {
        /// The covariate's column name in the campaign CSV.
        name: String,
        /// Its value at the start of the campaign (first row), used when
        /// predicting from poses alone; `None`: such predictions are refused.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reference: Option<f64>,
    },
    /// Measurement order: the 0-based row index (slow drift).
    Row,
    /// 0 before `row`, 1 from it on (an abrupt change, e.g. a tracker bump).
    Step {
        /// 0-based row where the step begins.
        row: usize,
    },
    /// `sin` and `cos` of `2π (θ_j − c) / P` (1-based joint j, period P and
    /// phase reference c in degrees).
    Harmonic {
        /// 1-based joint j.
        joint: usize,
        /// Period P in joint units (degrees; mm for a prismatic joint), > 0.
        period_deg: f64,
        /// The joint value c where the phase is counted from (0 in files
        /// written before it existed). `diagnose` puts it at the campaign's
        /// mean of the joint: a period found 1 % off then moves the phase by
        /// 1 % of a cycle per period *from the data's centre*, not from
        /// θ = 0, which may lie many periods away, and the sin and cos
        /// coefficients describe the effect where it was measured.
        #[serde(default, skip_serializing_if = "is_zero")]
        centre_deg: f64,
    },
    /// `θ_a · θ_b` (1-based joints).
    Interaction {
        /// 1-based index of the first joint.
        a: usize,
        /// 1-based index of the second joint.
        b: usize,
    },
    /// λ_j of the previous row (+1 for the first).
    PreviousDirection {
        /// 1-based joint j.
        joint: usize,
    },
    /// Travel of joint j since its direction last changed (degrees or mm).
    SinceReversal {
        /// 1-based joint j.
        joint: usize,
    },
    /// Joint j's moves into the pose, `h_k = Δq_k + e^(−1/τ)·h_(k−1)`
    /// (`Δq_k = q_j(k) − q_j(k−1)`, 0 for the first row; τ = 0: the last move
    /// alone): servo lag or incomplete settling. With a [`Clock`] the memory
    /// is counted in time: `h_k = Δq_k + e^(−Δt_k/τ_s)·h_(k−1)`.
    Moves {
        /// 1-based joint j.
        joint: usize,
        /// Memory τ of earlier moves, in poses (0: the last move only; 0
        /// with a clock).
        tau_poses: f64,
        /// A memory in seconds from a time column instead.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        clock: Option<Clock>,
    },
    /// `|Δq_j|`, the size of joint j's last move.
    MoveSize {
        /// 1-based joint j.
        joint: usize,
    },
    /// A lag of joint j proportional to its moves ([`Feature::Moves`]) mapped
    /// to the TCP: `∂P/∂θ_j(q)·h_k`, three columns (x, y, z).
    MovesJacobian {
        /// The measured robot (its position Jacobian).
        #[serde(deserialize_with = "crate::kinematics::robot_or_preset_name")]
        robot: Box<crate::kinematics::Robot>,
        /// 1-based joint j.
        joint: usize,
        /// Memory τ of earlier moves, in poses (0: the last move only; 0
        /// with a clock).
        tau_poses: f64,
        /// A memory in seconds from a time column instead.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        clock: Option<Clock>,
    },
    /// The TCP's last move `P(q_k) − P(q_(k−1))` through the nominal robot
    /// (x, y, z; 0 for the first row): a Cartesian lag.
    TcpMove {
        /// The measured robot (its forward kinematics).
        #[serde(deserialize_with = "crate::kinematics::robot_or_preset_name")]
        robot: Box<crate::kinematics::Robot>,
    },
    /// Time since the previous pose from a time column, `t_k − t_(k−1)`; the
    /// first row, and predictions from poses alone, take `reference` (the
    /// campaign's median interval).
    Interval {
        /// The time column's name.
        column: String,
        /// Interval used where none is measured; `None`: such predictions
        /// are refused.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reference: Option<f64>,
    },
    /// A one-column feature, less a centre `c`, times joint k's angle:
    /// `(f − c)·θ_k`, `(f − c)·sin θ_k`, `(f − c)·cos θ_k` (θ in degrees for
    /// the first). The centre is the feature's campaign mean, so the product
    /// adds the span of the interaction and not, under the feature's name, a
    /// joint-angle trend `c·θ_k` (a covariate near 22 °C times θ is mostly
    /// θ). Files written before the centre load with `c = 0`.
    Times {
        /// The one-column feature.
        of: Box<Feature>,
        /// 1-based joint k.
        joint: usize,
        /// Value subtracted from the feature before the product.
        #[serde(default)]
        centre: f64,
    },
    /// A one-column feature `lag` rows earlier, `f(k − lag)` (the first
    /// rows take `f(0)`).
    Lagged {
        /// The one-column feature.
        of: Box<Feature>,
        /// Rows back (≥ 1).
        lag: usize,
    },
    /// Joint j deviating with the angle of joint k (cross-talk, seed 000
    /// §5.2): `∂P/∂θ_j(q) · sin θ_k` and `· cos θ_k`, the TCP displacement a
    /// deviation `a·sin θ_k + b·cos θ_k` of joint j causes (six columns: x, y, z
    /// of each). Carries the robot for the Jacobian (files written before
    /// robot files name a preset instead).
    Crosstalk {
        /// The measured robot, whose position Jacobian `∂P/∂θ_j` maps the
        /// deviation to the TCP.
        #[serde(deserialize_with = "crate::kinematics::robot_or_preset_name")]
        robot: Box<crate::kinematics::Robot>,
        /// 1-based joint j that deviates.
        joint: usize,
        /// 1-based joint k whose angle drives the deviation.
        from: usize,
    },
    /// A harmonic of joint j mapped to the TCP: `∂P/∂θ_j(q) · sin(2π (θ_j − c) / P)`
    /// and `· cos(2π (θ_j − c) / P)`, the displacement a periodic deviation of
    /// joint j (a gear's error over its turn) causes (six columns: x, y, z
    /// of each). Where the Jacobian varies over the campaign, a joint's
    /// periodic error is not a pure harmonic of its angle at the TCP, and
    /// [`Feature::Harmonic`] finds it only through sidebands of its period.
    HarmonicJacobian {
        /// The measured robot (its position Jacobian).
        #[serde(deserialize_with = "crate::kinematics::robot_or_preset_name")]
        robot: Box<crate::kinematics::Robot>,
        /// 1-based joint j.
        joint: usize,
        /// Period P in joint units (degrees; mm for a prismatic joint), > 0.
        period_deg: f64,
        /// The phase reference c, degrees ([`Feature::Harmonic`]'s).
        #[serde(default, skip_serializing_if = "is_zero")]
        centre_deg: f64,
    },
}

/// Serde: leave a zero phase reference out of a file (the files written
/// before it existed read back the same).
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// `2π (θ − c) / P`'s argument text for a column name: `2π·q{j}/P°`, or
/// with a reference `2π·(q{j}±|c|°)/P°` (the sign that of −c).
fn harmonic_arg(joint: usize, period_deg: f64, centre_deg: f64) -> String {
    if centre_deg == 0.0 {
        format!("2π·q{joint}/{period_deg:.4}°")
    } else {
        format!("2π·(q{joint}{:+.2}°)/{period_deg:.4}°", -centre_deg)
    }
}

impl Feature {
    /// The covariate this feature reads (itself, or the one inside a
    /// product or a lag), with its reference: the value a prediction from
    /// poses alone takes.
    pub fn covariate(&self) -> Option<(&str, Option<f64>)> {
        match self {
            Feature::Covariate { name, reference } => Some((name, *reference)),
            Feature::Times { of, .. } | Feature::Lagged { of, .. } => of.covariate(),
            _ => None,
        }
    }

    /// Set the reference of covariate `name` (itself, or inside a product
    /// or a lag) to `value`: predictions from poses alone then take it.
    /// Returns whether this feature reads that covariate.
    pub fn set_covariate_reference(&mut self, covariate: &str, value: f64) -> bool {
        match self {
            Feature::Covariate { name, reference } if name == covariate => {
                *reference = Some(value);
                true
            }
            Feature::Times { of, .. } | Feature::Lagged { of, .. } => {
                of.set_covariate_reference(covariate, value)
            }
            _ => false,
        }
    }

    /// Column names, one per input dimension this feature adds.
    pub fn names(&self) -> Vec<String> {
        match self {
            Feature::Covariate { name, .. } => vec![name.clone()],
            Feature::Row => vec!["row".into()],
            Feature::Step { row } => vec![format!("step@{row}")],
            Feature::Harmonic {
                joint,
                period_deg,
                centre_deg,
            } => {
                let arg = harmonic_arg(*joint, *period_deg, *centre_deg);
                vec![format!("sin({arg})"), format!("cos({arg})")]
            }
            Feature::Interaction { a, b } => vec![format!("q{a}*q{b}")],
            Feature::PreviousDirection { joint } => vec![format!("prev_dir{joint}")],
            Feature::SinceReversal { joint } => vec![format!("since_reversal{joint}")],
            Feature::Crosstalk { joint, from, .. } => ["sin", "cos"]
                .iter()
                .flat_map(|f| ["x", "y", "z"].map(|a| format!("J{a}{joint}·{f}(q{from})")))
                .collect(),
            Feature::HarmonicJacobian {
                joint,
                period_deg,
                centre_deg,
                ..
            } => {
                let arg = harmonic_arg(*joint, *period_deg, *centre_deg);
                ["sin", "cos"]
                    .iter()
                    .flat_map(|f| ["x", "y", "z"].map(|a| format!("J{a}{joint}·{f}({arg})")))
                    .collect()
            }
            Feature::Moves {
                joint,
                tau_poses,
                clock,
            } => vec![moves_name(*joint, *tau_poses, clock.as_ref())],
            Feature::MoveSize { joint } => vec![format!("|move{joint}|")],
            Feature::MovesJacobian {
                joint,
                tau_poses,
                clock,
                ..
            } => {
                let h = moves_name(*joint, *tau_poses, clock.as_ref());
                ["x", "y", "z"].map(|a| format!("J{a}{joint}·{h}")).to_vec()
            }
            Feature::TcpMove { .. } => ["x", "y", "z"].map(|a| format!("tcp_move_{a}")).to_vec(),
            Feature::Interval { column, .. } => vec![format!("Δ{column}")],
            Feature::Times { of, joint, .. } => {
                let f = of.names().concat();
                vec![
                    format!("{f}·q{joint}"),
                    format!("{f}·sin(q{joint})"),
                    format!("{f}·cos(q{joint})"),
                ]
            }
            Feature::Lagged { of, lag } => vec![format!("{}[-{lag}]", of.names().concat())],
        }
    }

    /// Whether the feature (or one it is built from) is a harmonic whose
    /// phase is counted from a joint value other than 0: a model file with
    /// one needs a build that reads `centre_deg` (file version 5).
    pub fn has_phase_reference(&self) -> bool {
        match self {
            Feature::Harmonic { centre_deg, .. } | Feature::HarmonicJacobian { centre_deg, .. } => {
                *centre_deg != 0.0
            }
            Feature::Times { of, .. } | Feature::Lagged { of, .. } => of.has_phase_reference(),
            _ => false,
        }
    }

    /// Whether the feature enters the model as trend terms only (a step or
    /// harmonic regressor, a fixed interaction or cross-talk basis: its
    /// shape is known, so the GP need not learn a correlation length over
    /// it), rather than as an input dimension of the correlation with a
    /// linear trend term (a covariate, the measurement order, direction
    /// history: the effect may vary with the pose).
    pub fn trend_only(&self) -> bool {
        matches!(
            self,
            Feature::Step { .. }
                | Feature::Harmonic { .. }
                | Feature::Interaction { .. }
                | Feature::Crosstalk { .. }
                | Feature::HarmonicJacobian { .. }
                | Feature::MovesJacobian { .. }
                | Feature::TcpMove { .. }
                | Feature::Times { .. }
        )
    }

    /// The output axis each column is a regressor of, one per
    /// [`Feature::names`] entry: `Some(a)` for the x, y or z row of a
    /// deviation of a joint mapped to the TCP through the Jacobian
    /// ([`Feature::Crosstalk`], [`Feature::HarmonicJacobian`],
    /// [`Feature::MovesJacobian`]), `None` (every axis) for any other
    /// column. A deviation `δθ_j` moves axis `a` by `∂P_a/∂θ_j·δθ_j`: axis
    /// a's error has `∂P_a/∂θ_j·h` as its regressor, and the other axes'
    /// rows of the Jacobian are not part of it.
    pub fn column_axes(&self) -> Vec<Option<usize>> {
        match self {
            Feature::Crosstalk { .. } | Feature::HarmonicJacobian { .. } => {
                [0, 1, 2, 0, 1, 2].map(Some).to_vec()
            }
            Feature::MovesJacobian { .. } => [0, 1, 2].map(Some).to_vec(),
            _ => vec![None; self.names().len()],
        }
    }

    /// Check joint indices against `n` joints.
    pub fn validate(&self, n: usize) -> Result<()> {
        let joints: Vec<usize> = match self {
            Feature::Harmonic {
                joint,
                period_deg,
                centre_deg,
            }
            | Feature::HarmonicJacobian {
                joint,
                period_deg,
                centre_deg,
                ..
            } => {
                if period_deg.is_nan() || *period_deg <= 0.0 {
                    return Err(Error::InvalidParameter(format!(
                        "harmonic period must be > 0, got {period_deg}"
                    )));
                }
                if !centre_deg.is_finite() {
                    return Err(Error::InvalidParameter(format!(
                        "harmonic phase reference must be finite, got {centre_deg}"
                    )));
                }
                vec![*joint]
            }
            Feature::Interaction { a, b } => vec![*a, *b],
            Feature::Crosstalk { joint, from, .. } => vec![*joint, *from],
            Feature::PreviousDirection { joint }
            | Feature::SinceReversal { joint }
            | Feature::MoveSize { joint } => vec![*joint],
            Feature::Moves {
                joint,
                tau_poses,
                clock,
            }
            | Feature::MovesJacobian {
                joint,
                tau_poses,
                clock,
                ..
            } => {
                if !(*tau_poses >= 0.0 && tau_poses.is_finite()) {
                    return Err(Error::InvalidParameter(format!(
                        "moves of joint {joint}: tau_poses must be finite and ≥ 0, got {tau_poses}"
                    )));
                }
                if let Some(c) = clock {
                    c.validate(*joint)?;
                    if *tau_poses != 0.0 {
                        return Err(Error::InvalidParameter(format!(
                            "moves of joint {joint}: a memory in poses (tau_poses {tau_poses}) and one in time (tau_s {}) cannot both be given",
                            c.tau_s
                        )));
                    }
                }
                vec![*joint]
            }
            Feature::Times { of, joint, centre } => {
                one_column(of)?;
                if !centre.is_finite() {
                    return Err(Error::InvalidParameter(format!(
                        "{:?} × q{joint}: the centre must be finite, got {centre}",
                        of.names()
                    )));
                }
                of.validate(n)?;
                vec![*joint]
            }
            Feature::Lagged { of, lag } => {
                one_column(of)?;
                if *lag == 0 {
                    return Err(Error::InvalidParameter(format!(
                        "lagged {:?}: the lag must be ≥ 1 row",
                        of.names()
                    )));
                }
                of.validate(n)?;
                Vec::new()
            }
            _ => Vec::new(),
        };
        match joints.iter().find(|&&j| j == 0 || j > n) {
            Some(j) => Err(Error::InvalidParameter(format!(
                "feature {:?} names joint {j}, but there are {n} joints",
                self.names()
            ))),
            None => Ok(()),
        }
    }

    /// Values on a campaign, in row order. A covariate column with this
    /// feature's name (precomputed on the full campaign) is used when present.
    pub fn columns(&self, data: &Dataset) -> Result<Vec<Vec<f64>>> {
        self.validate(data.n_joints())?;
        let names = self.names();
        if let Some(cols) = names
            .iter()
            .map(|n| data.covariate(n).map(|c| c.values.clone()))
            .collect::<Option<Vec<_>>>()
        {
            return check_complete(data, &names, cols);
        }
        match self {
            Feature::Covariate { name, .. } => Err(Error::Input {
                source_name: data.source.clone(),
                message: match data.text.iter().find(|t| &t.name == name) {
                    Some(t) => format!(
                        "the model needs covariate column '{name}', but it is read as text: {}",
                        t.note.as_deref().unwrap_or("its cells are not numbers")
                    ),
                    None => format!("the model needs covariate column '{name}', which is missing"),
                },
            }),
            Feature::Row => Ok(vec![(0..data.len()).map(|i| i as f64).collect()]),
            Feature::Step { row } => Ok(vec![
                (0..data.len())
                    .map(|i| if i >= *row { 1.0 } else { 0.0 })
                    .collect(),
            ]),
            Feature::Interval { column, reference } => {
                let t = Feature::Covariate {
                    name: column.clone(),
                    reference: None,
                }
                .columns(data)?
                .remove(0);
                let first = reference.unwrap_or(0.0);
                Ok(vec![
                    (0..t.len())
                        .map(|i| if i == 0 { first } else { t[i] - t[i - 1] })
                        .collect(),
                ])
            }
            Feature::Times { of, joint, centre } => {
                Ok(times(of.columns(data)?.remove(0), *centre, &data.q, *joint))
            }
            Feature::Moves {
                joint,
                clock: Some(c),
                ..
            } => moves_columns(&data.q, *joint, None, &c.keep_in(data)?),
            Feature::MovesJacobian {
                robot,
                joint,
                clock: Some(c),
                ..
            } => moves_columns(&data.q, *joint, Some(robot), &c.keep_in(data)?),
            Feature::Lagged { of, lag } => Ok(vec![lagged(&of.columns(data)?[0], *lag)]),
            _ => self.columns_from_poses(&data.q, &data.dir),
        }
    }

    /// Values for a pose sequence without covariates: order and step features
    /// take their reference value 0, a covariate its recorded reference (an
    /// error without one).
    pub fn columns_from_poses(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<Vec<f64>>> {
        let m = q.len();
        let col = |f: &dyn Fn(usize) -> f64| (0..m).map(f).collect::<Vec<f64>>();
        Ok(match self {
            Feature::Covariate {
                reference: Some(v), ..
            } => vec![vec![*v; m]],
            Feature::Covariate { name, .. } => {
                return Err(Error::InvalidParameter(format!(
                    "the model uses covariate '{name}': predict from a CSV that has that column"
                )));
            }
            Feature::Row | Feature::Step { .. } => vec![vec![0.0; m]],
            Feature::Interval {
                reference: Some(v), ..
            } => vec![vec![*v; m]],
            Feature::Interval { column, .. } => {
                return Err(Error::InvalidParameter(format!(
                    "the model uses the interval of time column '{column}': predict from a CSV that has that column"
                )));
            }
            Feature::Moves {
                joint,
                tau_poses,
                clock,
            } => moves_columns(q, *joint, None, &memory(m, *joint, *tau_poses, clock)?)?,
            Feature::MovesJacobian {
                robot,
                joint,
                tau_poses,
                clock,
            } => moves_columns(
                q,
                *joint,
                Some(robot),
                &memory(m, *joint, *tau_poses, clock)?,
            )?,
            Feature::MoveSize { joint } => vec![col(&|i| {
                if i == 0 {
                    0.0
                } else {
                    (q[i][joint - 1] - q[i - 1][joint - 1]).abs()
                }
            })],
            Feature::TcpMove { robot: r } => {
                let p: Vec<nalgebra::Vector3<f64>> = q
                    .iter()
                    .map(|qi| r.fk(qi).map(|t| t.translation.vector))
                    .collect::<Result<_>>()?;
                (0..3)
                    .map(|a| col(&|i| if i == 0 { 0.0 } else { p[i][a] - p[i - 1][a] }))
                    .collect()
            }
            Feature::Times { of, joint, centre } => {
                times(of.columns_from_poses(q, dir)?.remove(0), *centre, q, *joint)
            }
            Feature::Lagged { of, lag } => vec![lagged(&of.columns_from_poses(q, dir)?[0], *lag)],
            Feature::Harmonic {
                joint,
                period_deg,
                centre_deg,
            } => {
                let w = std::f64::consts::TAU / period_deg;
                let phase = |i: usize| w * (q[i][joint - 1] - centre_deg);
                vec![col(&|i| phase(i).sin()), col(&|i| phase(i).cos())]
            }
            Feature::Interaction { a, b } => vec![col(&|i| q[i][a - 1] * q[i][b - 1])],
            Feature::PreviousDirection { joint } => {
                vec![col(&|i| if i == 0 { 1.0 } else { dir[i - 1][joint - 1] })]
            }
            Feature::Crosstalk {
                robot: r,
                joint,
                from,
            } => jacobian_sin_cos(r, q, *joint, |qi| qi[from - 1].to_radians())?,
            Feature::HarmonicJacobian {
                robot: r,
                joint,
                period_deg,
                centre_deg,
            } => {
                let w = std::f64::consts::TAU / period_deg;
                jacobian_sin_cos(r, q, *joint, |qi| w * (qi[joint - 1] - centre_deg))?
            }
            Feature::SinceReversal { joint } => {
                let j = joint - 1;
                let mut out = Vec::with_capacity(m);
                let mut travel = 0.0;
                for i in 0..m {
                    if i > 0 {
                        if dir[i][j] != dir[i - 1][j] {
                            travel = 0.0;
                        }
                        let step = (q[i][j] - q[i - 1][j]).abs();
                        if step > MOVE_EPS {
                            travel += step;
                        }
                    }
                    out.push(travel);
                }
                vec![out]
            }
        })
    }
}

/// `(f − c)·θ_k`, `(f − c)·sin θ_k`, `(f − c)·cos θ_k` of 1-based joint
/// `joint`.
fn times(mut f: Vec<f64>, c: f64, q: &[Vec<f64>], joint: usize) -> Vec<Vec<f64>> {
    f.iter_mut().for_each(|v| *v -= c);
    let th = |i: usize| q[i][joint - 1];
    vec![
        f.iter().enumerate().map(|(i, v)| v * th(i)).collect(),
        f.iter()
            .enumerate()
            .map(|(i, v)| v * th(i).to_radians().sin())
            .collect(),
        f.iter()
            .enumerate()
            .map(|(i, v)| v * th(i).to_radians().cos())
            .collect(),
    ]
}

/// `f(k − lag)`, the first `lag` rows taking `f(0)`.
fn lagged(f: &[f64], lag: usize) -> Vec<f64> {
    (0..f.len()).map(|i| f[i.saturating_sub(lag)]).collect()
}

/// `Times` and `Lagged` wrap a feature of one column.
fn one_column(f: &Feature) -> Result<()> {
    match f.names().len() {
        1 => Ok(()),
        k => Err(Error::InvalidParameter(format!(
            "a product or lag needs a one-column feature, but {:?} has {k} columns",
            f.names()
        ))),
    }
}

fn check_complete(data: &Dataset, names: &[String], cols: Vec<Vec<f64>>) -> Result<Vec<Vec<f64>>> {
    for (n, c) in names.iter().zip(&cols) {
        let missing = c.iter().filter(|v| !v.is_finite()).count();
        if let Some(first) = c.iter().position(|v| !v.is_finite()) {
            let message = format!(
                "missing value ({missing} in this column); a model input needs every row (fill or drop them)"
            );
            return Err(match data.line(first) {
                Some(line) => Error::Csv {
                    file: data.source.clone(),
                    line,
                    column: Some(n.clone()),
                    message,
                },
                None => Error::Input {
                    source_name: data.source.clone(),
                    message: format!("column '{n}', {}: {message}", data.row_label(first)),
                },
            });
        }
    }
    Ok(cols)
}

/// [`jacobian_sin_cos_at`] with `robot`'s position Jacobian at each pose.
fn jacobian_sin_cos(
    robot: &crate::kinematics::Robot,
    q: &[Vec<f64>],
    joint: usize,
    phase: impl Fn(&[f64]) -> f64,
) -> Result<Vec<Vec<f64>>> {
    let jac = q
        .iter()
        .map(|qi| robot.position_jacobian(qi))
        .collect::<Result<Vec<_>>>()?;
    Ok(jacobian_sin_cos_at(&jac, q, joint, phase))
}

/// The six columns of a deviation `sin φ(q)`, `cos φ(q)` of 1-based joint
/// `joint` mapped to the TCP through the position Jacobian `jac[k]` of
/// each pose `q[k]`: x, y, z of `∂P/∂θ_j·sin φ`, then of `∂P/∂θ_j·cos φ`
/// ([`Feature::Crosstalk`], [`Feature::HarmonicJacobian`]; the diagnosis
/// scans many phases on the same Jacobians).
pub(crate) fn jacobian_sin_cos_at(
    jac: &[nalgebra::Matrix3xX<f64>],
    q: &[Vec<f64>],
    joint: usize,
    phase: impl Fn(&[f64]) -> f64,
) -> Vec<Vec<f64>> {
    let mut cols: Vec<Vec<f64>> = (0..6).map(|_| Vec::with_capacity(q.len())).collect();
    for (qi, jq) in q.iter().zip(jac) {
        let th = phase(qi);
        for (f, v) in [th.sin(), th.cos()].into_iter().enumerate() {
            for a in 0..3 {
                cols[3 * f + a].push(jq[(a, joint - 1)] * v);
            }
        }
    }
    cols
}

/// Number of input columns of `extras` that enter the correlation (the
/// others are trend-only).
pub fn correlation_dims(extras: &[Feature]) -> usize {
    extras.iter().map(|f| f.names().len()).sum::<usize>() - trend_only_dims(extras)
}

/// Number of input columns of `extras` that are trend-only.
pub fn trend_only_dims(extras: &[Feature]) -> usize {
    extras
        .iter()
        .filter(|f| f.trend_only())
        .map(|f| f.names().len())
        .sum()
}

/// Append the columns of `features` to `rows` (one row per pose).
pub fn append_columns(rows: &mut [Vec<f64>], cols: &[Vec<f64>]) {
    for c in cols {
        for (r, v) in rows.iter_mut().zip(c) {
            r.push(*v);
        }
    }
}
