//! The kinematic-error trend (seed 003 eq 4): the rows of the
//! robot's identification Jacobian as trend terms, screened so that each
//! output's GLS stays well conditioned; and the same rows, unscreened, as
//! candidates of the basis selections.

use crate::Result;
use crate::dataset::Dataset;
use crate::inputs::InputMap;
use crate::kinematics::Robot;
use crate::kriging::{KinematicTrend, KrigingOptions, Trend, TrendKind};
use crate::space::Space;
use rayon::prelude::*;

/// Relative tolerance of the per-axis screen of kinematic trend columns
/// ([`kinematic_trends`]): a column is kept when its component orthogonal to
/// the columns kept before it has at least this share of its norm (the
/// column-scaled trend matrix then stays well conditioned: ≲ 10⁴ on the
/// wide-range campaigns of `tests/kinematic_trend_conditioning.rs`, against
/// 10⁷–10¹⁰ without the screen). A column whose independent share is r has
/// its β amplified ~1/r.
pub const KINEMATIC_AXIS_TOL: f64 = crate::kriging::SHARED_SCREEN_TOL;

/// Rows a kinematic trend column's new component must be spread over, on
/// its axis, to be kept ([`crate::kriging::supported_columns`]): the rule of
/// thumb of ten observations per coefficient.
pub const KINEMATIC_MIN_SUPPORT: f64 = crate::kriging::SHARED_SCREEN_SUPPORT;

/// Share of a parameter's 3-axis Jacobian norm below which one axis's
/// column counts as zero: the parameter does not move that axis, and what
/// the finite differences give is rounding noise (e.g. `dPz/dtheta_off1`,
/// ~1e-9 against ~10 on x and y).
pub const KINEMATIC_ZERO_TOL: f64 = 1e-6;

/// The per-axis trends of the kinematic trend (`TrendSpec::Kinematic`): the options'
/// monomials plus, for output axis `a`, the identification-Jacobian rows
/// `∂P_a/∂p_j` of the calibration parameters that are
///
/// 1. identifiable on `data` as a whole (greedy rank revelation of the
///    stacked, column-normalised `3m × (5n + 9)` Jacobian, relative
///    tolerance `1e-7`; earlier parameters win),
/// 2. seen by axis `a` (its column is more than [`KINEMATIC_ZERO_TOL`] of
///    the stacked column, not finite-difference noise), and
/// 3. independent of the monomials and the earlier parameters *on this axis
///    alone*: greedy rank revelation of the axis's own trend matrix with
///    relative tolerance [`KINEMATIC_AXIS_TOL`].
///
/// Each output's GLS sees only its own axis, and a set of columns that is
/// well conditioned when the three axes are stacked can be nearly dependent
/// on one axis (e.g. `dPy/dd6` ≈ the constant when the wrist axis keeps its
/// direction over the campaign). Kept, such columns get opposite β of
/// 10⁴–10⁷ mm that cancel on the training poses only: a held-out pose where
/// they do not cancel (the home pose of a campaign whose tool points one
/// way) is predicted millimetres to metres off. Likewise a column that is
/// rounding noise on the training poses but not zero elsewhere.
///
/// The inputs are `data` in `space` with the joints `periodic` as sin/cos
/// (the model's [`InputMap`]); the monomials are those of `opts`' trend kind.
pub fn kinematic_trends(
    data: &Dataset,
    space: Space,
    periodic: &[usize],
    opts: &KrigingOptions,
    robot: &Robot,
) -> Result<[Trend; 3]> {
    kinematic_trend_set(
        data,
        space,
        periodic,
        opts,
        robot,
        Terms::Screened(KINEMATIC_AXIS_TOL),
    )
}

/// The kinematic trend whose parameter errors are one vector for the three
/// axes ([`KinematicTrend::shared`], solved jointly by
/// [`crate::kriging::share_coefficients`]): every parameter that moves the
/// TCP on the training poses, each on the axes it moves (step 2 of
/// [`kinematic_trends`]). No rank revelation or per-axis screen of the
/// terms (each output's own likelihood search screens its copy,
/// [`crate::kriging::fit_columns`]): keeping the first of nearly dependent
/// parameters is a choice of solution that extrapolates badly (on a small
/// three-cube UR10 campaign, held-out cubes 1.7–5.3× the D-H calibration's
/// max; with every parameter 0.3–1.1×, `tests/grouped_cv.rs`).
/// What the campaign does not see is held at 0 by the shared solve's prior
/// and identifiability rule instead, as the calibration does. On `data`
/// with the space map `map`, its inputs `x` and monomials of kind `poly`.
pub fn shared_kinematic_trends_in(
    data: &Dataset,
    map: &InputMap,
    x: &[Vec<f64>],
    poly: TrendKind,
    robot: &Robot,
) -> Result<[Trend; 3]> {
    kinematic_trend_set_in(data, map, x, poly, robot, Terms::Every)
}

/// The kinematic *candidates* of the basis selections (PCC + PCA, GA): as
/// [`kinematic_trends`] without the per-axis independence screen (step 3),
/// which the selections do themselves (PCA fusion, the GA's own screen).
pub fn kinematic_candidates(
    data: &Dataset,
    space: Space,
    periodic: &[usize],
    opts: &KrigingOptions,
    robot: &Robot,
) -> Result<[Trend; 3]> {
    kinematic_trend_set(data, space, periodic, opts, robot, Terms::Candidates)
}

fn kinematic_trend_set(
    data: &Dataset,
    space: Space,
    periodic: &[usize],
    opts: &KrigingOptions,
    robot: &Robot,
    terms: Terms,
) -> Result<[Trend; 3]> {
    let (map, x) = InputMap::fit(data, space, periodic, &[])?;
    kinematic_trend_set_in(data, &map, &x, opts.trend, robot, terms)
}

/// Which of the robot's calibration parameters become terms of the
/// kinematic trend ([`kinematic_trend_set_in`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Terms {
    /// Identifiable on the stacked axes, then screened per axis to this
    /// tolerance (steps 1–3 of [`kinematic_trends`]: a β per axis).
    Screened(f64),
    /// Identifiable on the stacked axes (steps 1–2: the selections'
    /// candidates).
    Candidates,
    /// Every parameter that moves the TCP at some training pose, on the
    /// axes it moves, the coefficients shared by the axes
    /// ([`shared_kinematic_trends_in`]).
    Every,
}

/// [`kinematic_trend_set`] on the space map `map` of `data` (no extras) and
/// its inputs `x`, with monomials of kind `poly` and the parameters `terms`.
pub(crate) fn kinematic_trend_set_in(
    data: &Dataset,
    map: &InputMap,
    x: &[Vec<f64>],
    poly: TrendKind,
    robot: &Robot,
    terms: Terms,
) -> Result<[Trend; 3]> {
    let axis_tol = match terms {
        Terms::Screened(tol) => Some(tol),
        Terms::Candidates | Terms::Every => None,
    };
    use crate::kinematics::{calib_len, identification_jacobian};
    use crate::kriging::{independent_columns, supported_columns};
    let n = data.n_joints();
    robot.check_dataset(data)?;
    let np = calib_len(n);
    let m = data.len();
    let rows: Vec<[Vec<f64>; 3]> = data
        .q
        .par_iter()
        .map(|q| identification_jacobian(robot, q))
        .collect();
    let mut f = faer::Mat::<f64>::zeros(3 * m, np);
    for (i, r) in rows.iter().enumerate() {
        for a in 0..3 {
            for k in 0..np {
                f[(3 * i + a, k)] = r[a][k];
            }
        }
    }
    let kept: Vec<usize> = if terms == Terms::Every {
        (0..np)
            .filter(|&k| f.col(k).iter().any(|v| *v != 0.0))
            .collect()
    } else {
        independent_columns(&f, 1e-7).0
    };
    let norm = map.normalizer();
    let d = map.dim();
    let nj = d - map.space().dim(n) + n; // joint columns
    let poly = poly.monomials(d);
    let norm2 = |a: Option<usize>, k: usize| -> f64 {
        let axes = a.map_or(0..3, |a| a..a + 1);
        rows.iter()
            .map(|r| axes.clone().map(|b| r[b][k] * r[b][k]).sum::<f64>())
            .sum()
    };
    // the monomial columns of every axis's trend matrix
    let fp = axis_tol.map(|_| crate::kriging::trend_matrix(&poly, x));
    let axis_params = |a: usize| -> Vec<usize> {
        let seen: Vec<usize> = kept
            .iter()
            .copied()
            .filter(|&k| norm2(Some(a), k) > KINEMATIC_ZERO_TOL.powi(2) * norm2(None, k))
            .collect();
        let (Some(tol), Some(fp)) = (axis_tol, &fp) else {
            return seen;
        };
        // the axis's trend matrix: monomials of the normalised inputs, then
        // the Jacobian rows; monomials and earlier parameters win
        let np0 = poly.exponents.len();
        let mut fa = faer::Mat::<f64>::zeros(m, np0 + seen.len());
        for i in 0..m {
            for j in 0..np0 {
                fa[(i, j)] = fp[(i, j)];
            }
            for (c, &k) in seen.iter().enumerate() {
                fa[(i, np0 + c)] = rows[i][a][k];
            }
        }
        let (cols, _) = supported_columns(&fa, tol, KINEMATIC_MIN_SUPPORT);
        cols.iter()
            .filter(|&&j| j >= np0)
            .map(|&j| seen[j - np0])
            .collect()
    };
    let param_norm: Vec<f64> = (0..np).map(|k| (norm2(None, k) / 3.0).sqrt()).collect();
    let make = |axis: usize| {
        Trend::Kinematic(Box::new(KinematicTrend {
            robot: robot.clone(),
            axis,
            params: axis_params(axis),
            joint_mean: norm.mean[..nj].to_vec(),
            joint_std: norm.std[..nj].to_vec(),
            periodic: map.periodic().to_vec(),
            poly: poly.clone(),
            param_norm: param_norm.clone(),
            shared: terms == Terms::Every,
        }))
    };
    Ok([make(0), make(1), make(2)])
}
