//! Coordinate frames: best-fit plane, circle and axis line, SVD registration.
//!
//! This module owns the small pieces of geometry that turn raw tracker
//! measurements into frames and axis lines:
//!
//! | item | math | source |
//! |---|---|---|
//! | [`fit_plane`] → [`Plane`] | total-least-squares plane, min Σ (n·(p_k − c))² | seed 000 eq 9 (the tilt α_rlt, β_rlt and z₀ of the J1 plane) |
//! | [`fit_circle_2d`] → [`Circle2`] | geometric circle fit, min Σ (‖p_k − Q‖ − R)² | seed 000 eqs 7, 10 |
//! | [`fit_circle_3d`] → [`Circle3`] | circle-point analysis of an axis line: plane fit, then circle fit in that plane | seed 000 §2.4 steps 1–2 |
//! | [`Circle3::angle_of`], [`angle_2d`], [`wrap_pi`] | the angle ∠(P − Q) about an axis | seed 000 eq 11 |
//! | [`register`] → [`Registration`] | rigid registration, min Σ ‖q_i − (R p_i + t)‖², reflection-safe | seed 004 eqs 29–35 |
//!
//! Conventions: lengths in the caller's unit (mm in this crate), angles in
//! radians. All fits are solved with orthogonal factorisations (SVD), never by
//! inverting normal equations. Bad input (too few points, non-finite values,
//! coincident or collinear points, mismatched lengths) is reported as
//! [`Error::InvalidParameter`]; a factorisation or iteration that breaks down
//! as [`Error::Numerical`]. No function panics on user input.

use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3,
};
use std::f64::consts::{PI, TAU};

use crate::{Error, Result};

/// Ratio σ₂/σ₁ of the centred point cloud's singular values below which the
/// points count as collinear (or all coincident).
const COLLINEAR_RATIO: f64 = 1e-9;
/// Relative step size at which the geometric circle fit stops.
const CIRCLE_STEP_TOL: f64 = 1e-12;
/// Maximum Levenberg–Marquardt iterations of the geometric circle fit.
const CIRCLE_MAX_ITER: usize = 500;

fn invalid(msg: String) -> Error {
    Error::InvalidParameter(msg)
}

fn check_count(func: &str, n: usize, min: usize) -> Result<()> {
    if n < min {
        return Err(invalid(format!(
            "{func}: needs at least {min} points, got {n}"
        )));
    }
    Ok(())
}

fn check_finite<const D: usize>(func: &str, what: &str, pts: &[[f64; D]]) -> Result<()> {
    match pts.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        Some(i) => Err(invalid(format!(
            "{func}: {what}point {i} has a non-finite coordinate {:?}",
            pts[i]
        ))),
        None => Ok(()),
    }
}

fn as_arrays(pts: &[Vector3<f64>]) -> Vec<[f64; 3]> {
    pts.iter().map(|p| [p.x, p.y, p.z]).collect()
}

/// Centroid and SVD of the centred `n × D` point matrix: `(centroid,
/// singular values descending, Vᵀ)`.
fn centred_svd<const D: usize>(
    func: &str,
    pts: &[[f64; D]],
) -> Result<([f64; D], DVector<f64>, DMatrix<f64>)> {
    let n = pts.len();
    let mut c = [0.0; D];
    for p in pts {
        for (ci, pi) in c.iter_mut().zip(p) {
            *ci += pi / n as f64;
        }
    }
    let m = DMatrix::from_fn(n, D, |r, k| pts[r][k] - c[k]);
    let svd = m
        .try_svd(false, true, f64::EPSILON, 10_000)
        .ok_or_else(|| Error::Numerical(format!("{func}: SVD of the centred points failed")))?;
    let v_t = svd
        .v_t
        .ok_or_else(|| Error::Numerical(format!("{func}: SVD returned no right vectors")))?;
    Ok((c, svd.singular_values, v_t))
}

/// Reject clouds whose second singular value vanishes against the first
/// (all points on one line, or all coincident).
fn check_not_collinear(func: &str, what: &str, s: &DVector<f64>) -> Result<()> {
    if s.len() < 2 || s[0] == 0.0 || s[1] <= COLLINEAR_RATIO * s[0] {
        return Err(invalid(format!(
            "{func}: {what}points are collinear or coincident (singular values {:.3e}, {:.3e})",
            s.get(0).copied().unwrap_or(0.0),
            s.get(1).copied().unwrap_or(0.0)
        )));
    }
    Ok(())
}

/// Angle of the 2-D vector `v`, `atan2(y, x)` ∈ [−π, π] (the ∠(·) of seed 000 eq 11).
pub fn angle_2d(v: [f64; 2]) -> f64 {
    v[1].atan2(v[0])
}

/// Wrap an angle to (−π, π]. Non-finite input gives NaN.
pub fn wrap_pi(a: f64) -> f64 {
    let r = a.rem_euclid(TAU);
    if r > PI { r - TAU } else { r }
}

/// Best-fit (total least squares) plane through a point cloud.
///
/// With c = (1/N) Σ p_k the centroid and `A` the `N × 3` matrix of rows
/// (p_k − c)ᵀ, the plane minimises Σ_k (n·(p_k − c))² over unit normals `n`
/// (the general-orientation form of seed 000 eq 9, which fits
/// z = −β x + α y + z₀ for small tilts). The minimiser is the right singular
/// vector of `A` for its smallest singular value σ₃, and
/// `rms = σ₃ / √N = √((1/N) Σ (n·(p_k − c))²)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point on the plane: the centroid c of the fitted points.
    pub point: Vector3<f64>,
    /// Unit normal, signed so that `z > 0`; if |z| is negligible (≤ 1e-9)
    /// then `x > 0`, and failing that `y > 0` (deterministic orientation).
    pub normal: Vector3<f64>,
    /// Root mean square of the signed point-to-plane distances.
    pub rms: f64,
}

impl Plane {
    /// Signed distance n·(p − c) of `p` from the plane.
    pub fn distance(&self, p: &Vector3<f64>) -> f64 {
        self.normal.dot(&(p - self.point))
    }
}

/// Fit a [`Plane`] to at least 3 non-collinear, finite points.
pub fn fit_plane(points: &[Vector3<f64>]) -> Result<Plane> {
    plane_impl("fit_plane", points)
}

fn plane_impl(func: &str, points: &[Vector3<f64>]) -> Result<Plane> {
    check_count(func, points.len(), 3)?;
    let arr = as_arrays(points);
    check_finite(func, "", &arr)?;
    let (c, s, v_t) = centred_svd(func, &arr)?;
    check_not_collinear(func, "", &s)?;
    let mut normal = Vector3::new(v_t[(2, 0)], v_t[(2, 1)], v_t[(2, 2)]).normalize();
    let lead = [normal.z, normal.x, normal.y]
        .into_iter()
        .find(|v| v.abs() > 1e-9)
        .unwrap_or(1.0);
    if lead < 0.0 {
        normal = -normal;
    }
    Ok(Plane {
        point: Vector3::from(c),
        normal,
        rms: s[2] / (points.len() as f64).sqrt(),
    })
}

/// Best-fit circle in the plane (seed 000 eqs 7, 10).
///
/// Solves the geometric problem
///
/// ```text
/// min_{Q, R} Σ_k ( ‖p_k − Q‖ − R )²                                   (seed 000 eq 10)
/// ```
///
/// in two stages, in coordinates centred on the centroid and scaled to unit
/// rms spread:
///
/// 1. algebraic (Kåsa) start: x² + y² + D x + E y + F = 0 solved for (D, E, F)
///    in the least-squares sense by SVD, giving Q = −(D, E)/2,
///    R² = |Q|² − F;
/// 2. Levenberg–Marquardt on the geometric residuals r_k = ‖p_k − Q‖ − R with
///    Jacobian rows [−(p_k − Q)ᵀ/‖p_k − Q‖, −1]; each step solves the
///    augmented least-squares system [J; √λ·diag(JᵀJ)^½] δ = [−r; 0] by SVD.
///    It stops when ‖δ‖ < 1e-12 · max(1, ‖(Q, R)‖).
///
/// Works on short arcs and on bidirectional indexing data (every angle
/// visited twice); exactly collinear points are rejected.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle2 {
    /// Centre Q.
    pub center: [f64; 2],
    /// Radius R > 0.
    pub radius: f64,
    /// Root mean square of the radial residuals ‖p_k − Q‖ − R.
    pub rms: f64,
}

/// Fit a [`Circle2`] to at least 3 non-collinear, finite points.
pub fn fit_circle_2d(points: &[[f64; 2]]) -> Result<Circle2> {
    circle2_impl("fit_circle_2d", points)
}

fn circle2_impl(func: &str, points: &[[f64; 2]]) -> Result<Circle2> {
    let n = points.len();
    check_count(func, n, 3)?;
    check_finite(func, "", points)?;
    let (c, s, _) = centred_svd(func, points)?;
    check_not_collinear(func, "", &s)?;
    // Scale σ₁/√N > 0: the spread along the major direction.
    let scale = s[0] / (n as f64).sqrt();
    let u: Vec<[f64; 2]> = points
        .iter()
        .map(|p| [(p[0] - c[0]) / scale, (p[1] - c[1]) / scale])
        .collect();

    // Stage 1: Kåsa, A [D E F]ᵀ = −(x² + y²).
    let a = DMatrix::from_fn(n, 3, |r, k| if k < 2 { u[r][k] } else { 1.0 });
    let b = DVector::from_fn(n, |r, _| -(u[r][0].powi(2) + u[r][1].powi(2)));
    let x = lstsq(func, a, &b)?;
    let (qa, qb) = (-x[0] / 2.0, -x[1] / 2.0);
    let r2 = qa * qa + qb * qb - x[2];
    if !(r2.is_finite() && r2 > 0.0) {
        return Err(Error::Numerical(format!(
            "{func}: algebraic start gave R² = {r2:.3e}"
        )));
    }
    let mut theta = [qa, qb, r2.sqrt()];

    // Stage 2: Levenberg–Marquardt on the geometric residual.
    let eval = |t: &[f64; 3]| -> (DVector<f64>, DMatrix<f64>) {
        let mut r = DVector::zeros(n);
        let mut j = DMatrix::zeros(n, 3);
        for (k, p) in u.iter().enumerate() {
            let (dx, dy) = (p[0] - t[0], p[1] - t[1]);
            let d = dx.hypot(dy);
            r[k] = d - t[2];
            if d > 0.0 {
                j[(k, 0)] = -dx / d;
                j[(k, 1)] = -dy / d;
            }
            j[(k, 2)] = -1.0;
        }
        (r, j)
    };
    let (mut r, mut j) = eval(&theta);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    let mut converged = false;
    for _ in 0..CIRCLE_MAX_ITER {
        let jtj_diag: Vec<f64> = (0..3).map(|k| j.column(k).norm_squared()).collect();
        let mut aug = DMatrix::zeros(n + 3, 3);
        aug.rows_mut(0, n).copy_from(&j);
        for k in 0..3 {
            aug[(n + k, k)] = (lambda * jtj_diag[k].max(1e-30)).sqrt();
        }
        let mut rhs = DVector::zeros(n + 3);
        rhs.rows_mut(0, n).copy_from(&(-&r));
        let delta = lstsq(func, aug, &rhs)?;
        let size = theta.iter().map(|v| v * v).sum::<f64>().sqrt().max(1.0);
        if delta.norm() < CIRCLE_STEP_TOL * size {
            converged = true;
            break;
        }
        let trial = [
            theta[0] + delta[0],
            theta[1] + delta[1],
            theta[2] + delta[2],
        ];
        let (r_t, j_t) = eval(&trial);
        let cost_t = r_t.norm_squared();
        if cost_t.is_finite() && cost_t <= cost {
            (theta, r, j, cost) = (trial, r_t, j_t, cost_t);
            lambda = (lambda / 10.0).max(1e-15);
        } else {
            lambda *= 10.0;
        }
        if theta.iter().any(|v| v.abs() > 1e12) {
            return Err(Error::Numerical(format!(
                "{func}: circle fit diverged (points nearly collinear?)"
            )));
        }
    }
    if !converged {
        return Err(Error::Numerical(format!(
            "{func}: circle fit did not converge in {CIRCLE_MAX_ITER} iterations"
        )));
    }
    Ok(Circle2 {
        center: [c[0] + scale * theta[0], c[1] + scale * theta[1]],
        radius: scale * theta[2].abs(),
        rms: scale * (cost / n as f64).sqrt(),
    })
}

/// Least-squares solution of `a x = b` by SVD (rank-revealing, relative
/// cut-off 1e-14 · σ₁).
fn lstsq(func: &str, a: DMatrix<f64>, b: &DVector<f64>) -> Result<DVector<f64>> {
    let svd = a
        .try_svd(true, true, f64::EPSILON, 10_000)
        .ok_or_else(|| Error::Numerical(format!("{func}: least-squares SVD failed")))?;
    let cut = 1e-14 * svd.singular_values.max();
    svd.solve(b, cut)
        .map_err(|e| Error::Numerical(format!("{func}: {e}")))
}

/// A circle in space and its axis line (circle-point analysis).
///
/// Points measured while one joint alone rotates lie on a circle; its axis —
/// the line through [`center`](Self::center) along [`normal`](Self::normal) —
/// is the joint's axis average line (seed 000 §2.4). [`fit_circle_3d`] fits
/// the plane (seed 000 eq 9, as [`fit_plane`]), projects the points onto it
/// with an orthonormal in-plane basis (e₁, e₂, n), e₁ × e₂ = n, and fits the
/// circle in those coordinates (seed 000 eq 10, as [`fit_circle_2d`]).
///
/// **Signed axis.** `normal` is right-handed with the *order* of the points:
/// with φ_k the in-plane angle of point k about the centre and
/// S_k = Σ_{j<k} wrap_pi(φ_{j+1} − φ_j) the accumulated (unwrapped) angle, the
/// sign is chosen so that the largest excursion max_k |S_k| is positive,
/// i.e. the points turn counter-clockwise about `normal`. For a one-way sweep
/// this is the sweep direction; for a there-and-back (bidirectional) indexing
/// test it is the direction of the first pass. Consecutive points must be
/// less than π apart in angle for this to be meaningful.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle3 {
    /// Centre Q of the circle: a point on the axis line.
    pub center: Vector3<f64>,
    /// Unit axis direction, signed as described above.
    pub normal: Vector3<f64>,
    /// Radius R.
    pub radius: f64,
    /// Root mean square of the in-plane radial residuals.
    pub rms: f64,
    /// Root mean square of the out-of-plane distances (the plane fit's rms).
    pub plane_rms: f64,
}

impl Circle3 {
    /// Angle of `p` about the axis (seed 000 eq 11's ∠(P − Q)), in (−π, π].
    ///
    /// With x̂ the unit projection of `x_ref` onto the circle plane,
    /// x̂ = (x_ref − (x_ref·n) n)/‖·‖, and ŷ = n × x̂, the angle is
    /// atan2(ŷ·(p − Q), x̂·(p − Q)): counter-clockwise about `normal`.
    /// Returns NaN if `x_ref` is (nearly) parallel to the axis or any input is
    /// non-finite; 0 for a point on the axis.
    pub fn angle_of(&self, p: &Vector3<f64>, x_ref: &Vector3<f64>) -> f64 {
        let n = self.normal;
        let xp = x_ref - n * x_ref.dot(&n);
        let len = xp.norm();
        if !(len.is_finite() && len > 1e-12 * x_ref.norm()) {
            return f64::NAN;
        }
        let x = xp / len;
        let y = n.cross(&x);
        let v = p - self.center;
        wrap_pi(angle_2d([x.dot(&v), y.dot(&v)]))
    }
}

/// Fit a [`Circle3`] to at least 3 non-collinear, finite points, given in
/// the order they were measured (the order signs the axis).
pub fn fit_circle_3d(points: &[Vector3<f64>]) -> Result<Circle3> {
    const F: &str = "fit_circle_3d";
    let plane = plane_impl(F, points)?;
    let n = plane.normal;
    // In-plane basis: e1 ⟂ n from the coordinate axis least aligned with n.
    let k = n.iamin();
    let e1 = (Vector3::ith(k, 1.0) - n * n[k]).normalize();
    let e2 = n.cross(&e1);
    let uv: Vec<[f64; 2]> = points
        .iter()
        .map(|p| {
            let d = p - plane.point;
            [e1.dot(&d), e2.dot(&d)]
        })
        .collect();
    let c2 = circle2_impl(F, &uv)?;

    // Orientation from the largest excursion of the accumulated angle.
    let phi: Vec<f64> = uv
        .iter()
        .map(|q| angle_2d([q[0] - c2.center[0], q[1] - c2.center[1]]))
        .collect();
    let (mut acc, mut extreme) = (0.0_f64, 0.0_f64);
    for w in phi.windows(2) {
        acc += wrap_pi(w[1] - w[0]);
        if acc.abs() > extreme.abs() {
            extreme = acc;
        }
    }
    let sign = if extreme < 0.0 { -1.0 } else { 1.0 };
    Ok(Circle3 {
        center: plane.point + e1 * c2.center[0] + e2 * c2.center[1],
        normal: n * sign,
        radius: c2.radius,
        rms: c2.rms,
        plane_rms: plane.rms,
    })
}

/// Result of a rigid registration (seed 004 eqs 29–35).
///
/// Minimises F(R, t) = Σ_i ‖(R p_i + t) − q_i‖² (eq 29). Setting ∂F/∂t = 0
/// gives t = q̄ − R p̄ (eqs 30–31), with p̄, q̄ the centroids; substituting,
/// with a_i = p_i − p̄, b_i = q_i − q̄, the problem becomes max tr(R H),
/// H = Σ a_i b_iᵀ (eqs 32–33). With the SVD H = U Σ Vᵀ the maximiser over
/// orthogonal matrices is R = V Uᵀ (eqs 34–35).
///
/// **Reflection guard** (Arun et al. 1987; Umeyama 1991): eq 35 may return a
/// reflection, det R = −1 — for coplanar points (σ₃ = 0, the sign of the
/// third singular pair is arbitrary), under noise, or for mirrored data. Then
/// the last column of V (smallest singular value) is negated,
/// R = V diag(1, 1, −1) Uᵀ, the best *proper* rotation, and
/// [`reflection_guarded`](Self::reflection_guarded) is set. For coplanar
/// data this is the exact answer; for genuinely mirrored data the residuals
/// stay large.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Registration {
    /// Maps `from`-frame points into the `to` frame: q ≈ transform · p.
    pub transform: Isometry3<f64>,
    /// Root mean square of the residual distances ‖q_i − transform · p_i‖.
    pub rms: f64,
    /// Largest residual distance.
    pub max: f64,
    /// Whether the unguarded R = V Uᵀ had det −1 and was corrected.
    pub reflection_guarded: bool,
}

/// Rigid registration of `from` onto `to` (point i corresponds to point i);
/// needs equal lengths ≥ 3, finite values, and non-collinear points in both
/// sets.
pub fn register(from: &[Vector3<f64>], to: &[Vector3<f64>]) -> Result<Registration> {
    const F: &str = "register";
    if from.len() != to.len() {
        return Err(invalid(format!(
            "{F}: point sets differ in length ({} `from` vs {} `to` points)",
            from.len(),
            to.len()
        )));
    }
    check_count(F, from.len(), 3)?;
    let (pa, qa) = (as_arrays(from), as_arrays(to));
    check_finite(F, "`from` ", &pa)?;
    check_finite(F, "`to` ", &qa)?;
    let (_, sp, _) = centred_svd(F, &pa)?;
    check_not_collinear(F, "`from` ", &sp)?;
    let (_, sq, _) = centred_svd(F, &qa)?;
    check_not_collinear(F, "`to` ", &sq)?;

    let m = from.len() as f64;
    let p_bar = from.iter().sum::<Vector3<f64>>() / m;
    let q_bar = to.iter().sum::<Vector3<f64>>() / m;
    // H is accumulated in units of `k` (the largest centred coordinate) so
    // that it cannot overflow; U and V do not depend on the scale of H.
    let k = from
        .iter()
        .map(|p| (p - p_bar).amax())
        .chain(to.iter().map(|q| (q - q_bar).amax()))
        .fold(0.0_f64, f64::max);
    let h: Matrix3<f64> = from
        .iter()
        .zip(to)
        .map(|(p, q)| ((p - p_bar) / k) * ((q - q_bar) / k).transpose())
        .sum();
    // Dynamic SVD (Golub–Kahan); nalgebra's fixed 3×3 path goes through the
    // eigen-decomposition of HᵀH, which squares the condition number.
    let svd = DMatrix::from_column_slice(3, 3, h.as_slice())
        .try_svd(true, true, f64::EPSILON, 10_000)
        .ok_or_else(|| Error::Numerical(format!("{F}: SVD of the cross-covariance failed")))?;
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(Error::Numerical(format!("{F}: SVD returned no vectors")));
    };
    let u = Matrix3::from_fn(|r, c| u[(r, c)]);
    let mut v = Matrix3::from_fn(|r, c| v_t[(c, r)]);
    let mut rot = v * u.transpose();
    let reflection_guarded = rot.determinant() < 0.0;
    if reflection_guarded {
        // Singular values are sorted descending: column 2 is the smallest.
        v.column_mut(2).neg_mut();
        rot = v * u.transpose();
    }
    if !rot.iter().all(|x| x.is_finite()) || (rot.determinant() - 1.0).abs() > 1e-6 {
        return Err(Error::Numerical(format!(
            "{F}: SVD gave a non-rotation (det {:.6})",
            rot.determinant()
        )));
    }
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot));
    let t = q_bar - rotation * p_bar;
    let transform = Isometry3::from_parts(Translation3::from(t), rotation);
    let (mut ss, mut max) = (0.0_f64, 0.0_f64);
    for (p, q) in from.iter().zip(to) {
        let e = (q - (rotation * p + t)).norm();
        ss += e * e;
        max = max.max(e);
    }
    Ok(Registration {
        transform,
        rms: (ss / m).sqrt(),
        max,
        reflection_guarded,
    })
}
