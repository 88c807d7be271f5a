//! Identification of the SCARA model of seed 000 from single-axis indexing
//! tests (§2.3–2.4, §5.1, §5.3).
//!
//! Input: an indexing campaign (`robokrige simulate --kind indexing`, or a
//! real one in the same format): measured TCP positions `x, y, z` in any
//! Cartesian frame (e.g. the tracker's), commanded `q`, directions `dir`, and
//! a covariate `axis` naming the indexed joint (1-based) of every row. J1 is
//! indexed with J2 at rest, J2 with J1 at rest, each bidirectionally.
//!
//! 1. **Reference CS** (eqs 7–9): the plane of the J1 test (eq 9) gives the
//!    J1 axis direction (Z, oriented so J1 turns counter-clockwise); the
//!    best-fit circle of the J1 test in that plane (eq 7) puts the origin on
//!    the axis average line; the Z origin is chosen so the J1 test lies at the
//!    nominal height of the rest pose. X is along link 1 at `θ̂1 = 0`: the
//!    paper fixes X through the measured J1 reference point (Remark 1); here the
//!    direction to the J2 circle centre `Q2`, rotated back by the J1 angle
//!    `θ̂1` it was measured at, so that eq 3 holds without a J1 offset.
//! 2. **J2 circle** (eq 10): centre `Q2`, radius `R2` in the reference XY plane.
//! 3. **Angular positioning deviation** (eq 11), per direction:
//!    `Δθ_n,map(i, ±) = ∠(P_n(i, ±) − Q_n) − ∠_ref − (θ*(i) − θ*(i⁰))`, with
//!    `∠_ref` the mean over both directions of the angle at the reference
//!    index `i⁰` (the rest angle). The paper writes `∠(P_n(i⁰, ±1) − Q_n)` per
//!    direction, which would zero a constant backlash; taking the mean of both
//!    directions keeps the backlash and splits it evenly. Averaged over the
//!    repeated cycles; the max − min over cycles is reported (Fig. 6 bars).
//! 4. **Link errors**: `ΔL2 = R2 − L2` (eq 13); `ΔL1 = ‖Q2 − Q1‖ − L1`, the
//!    exact J1–J2 distance (eq 12, `R_rlt − R2 − L1`, is its first-order form
//!    for a straight arm).
//! 5. **θ20** (eq 14): `∠_ref,2 − ∠(Q2 − Q1) − θ2*(i⁰)`.
//! 6. **Radial error motion** (eq 20): `‖P_n(i, ±) − Q_n‖` minus its mean.
//! 7. **Parallelism** of J2 to J1 (eq 22): the plane `z = a·x' + b·y' + z1` of
//!    the J2 test in link-1 coordinates; it gives the Z of eq 23.

use super::BidirectionalTable;
use super::model::{Geometry, PhysicsModel, ScaraGeometry};
use crate::dataset::Dataset;
use crate::frames::{Circle2, Plane, angle_2d, fit_circle_2d, fit_plane, wrap_pi};
use crate::kinematics::{JointKind, Robot};
use crate::{Error, Result};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Options of [`identify_scara`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScaraOptions {
    /// Identify the radial error motion tables (eq 20).
    pub radial: bool,
    /// Identify the parallelism of J2 to J1 (eq 22); otherwise Z is nominal.
    pub parallelism: bool,
}

impl Default for ScaraOptions {
    fn default() -> Self {
        ScaraOptions {
            radial: true,
            parallelism: true,
        }
    }
}

/// What the identification saw, per indexed axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AxisReport {
    /// 1-based joint.
    pub axis: usize,
    /// Rows of this axis's indexing test.
    pub rows: usize,
    /// Indexed angles (both directions each).
    pub angles: usize,
    /// Repeated cycles (distinct values of the `cycle` column; 1 without it).
    pub cycles: usize,
    /// Radius of the best-fit circle of the TCP positions, mm.
    pub radius_mm: f64,
    /// rms of the radial residuals of that circle fit, mm.
    pub circle_rms_mm: f64,
    /// rms distance from the best-fit plane, mm.
    pub plane_rms_mm: f64,
    /// Largest max − min over the cycles of one table entry, degrees.
    pub repeat_spread_deg: f64,
    /// Mean backlash half-width `mean(Δθ(+) − Δθ(−))/2`, degrees.
    pub backlash_half_deg: f64,
}

/// Result of [`identify_scara`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScaraIdentification {
    /// The identified SCARA model (geometry, APD and radial tables).
    pub model: PhysicsModel,
    /// What the identification saw, per indexed axis (J1, J2).
    pub axes: Vec<AxisReport>,
    /// Indexed axes that could not be used, with the reason.
    pub skipped: Vec<String>,
}

/// The rows of an indexing campaign per indexed joint (0-based), in order.
/// Needs the measured positions and the `axis` column (1-based joint).
pub(super) fn indexing_rows(data: &Dataset) -> Result<Vec<Vec<Row>>> {
    let src = &data.source;
    let positions = data.positions.as_ref().ok_or_else(|| Error::Input {
        source_name: src.clone(),
        message: "indexing tests need the measured positions x,y,z".into(),
    })?;
    let axis = data.covariate("axis").ok_or_else(|| Error::Input {
        source_name: src.clone(),
        message: "indexing tests need a column 'axis' naming the indexed joint of each row".into(),
    })?;
    let cycle = data.covariate("cycle");
    let n = data.n_joints();
    let mut out: Vec<Vec<Row>> = (0..n).map(|_| Vec::new()).collect();
    for (k, (&a, p)) in axis.values.iter().zip(positions).enumerate() {
        if a.fract() != 0.0 || a < 1.0 || a > n as f64 {
            return Err(Error::Input {
                source_name: src.clone(),
                message: format!("row {}: axis = {a} is not a joint number 1..{n}", k + 1),
            });
        }
        out[a as usize - 1].push(Row {
            q: data.q[k].clone(),
            dir: data.dir[k].clone(),
            p: Vector3::from(*p),
            cycle: cycle.map_or(1, |c| c.values[k].max(0.0) as usize),
        });
    }
    Ok(out)
}

/// One indexing row (position in the frame being worked in).
#[derive(Debug, Clone)]
pub(super) struct Row {
    pub q: Vec<f64>,
    pub dir: Vec<f64>,
    pub p: Vector3<f64>,
    pub cycle: usize,
}

/// Identify the seed 000 model of a SCARA robot (`nominal`: J1, J2 revolute
/// about parallel vertical axes, link lengths `a1`, `a2`) from its indexing
/// tests.
pub fn identify_scara(
    data: &Dataset,
    nominal: &Robot,
    opts: &ScaraOptions,
) -> Result<ScaraIdentification> {
    let n = nominal.dof();
    nominal.check_dataset(data)?;
    if n < 2
        || nominal.links[..2]
            .iter()
            .any(|l| l.kind != JointKind::Revolute)
    {
        return Err(Error::InvalidParameter(format!(
            "robot '{}' is not a SCARA: joints 1 and 2 must be revolute",
            nominal.name
        )));
    }
    let by_axis = indexing_rows(data)?;
    let rows_of = |j: usize| by_axis.get(j - 1).cloned().unwrap_or_default();
    let mut r1 = rows_of(1);
    let mut r2 = rows_of(2);
    for (j, rows) in [(1, &r1), (2, &r2)] {
        if rows.len() < 6 {
            return Err(Error::Input {
                source_name: data.source.clone(),
                message: format!(
                    "the J{j} indexing test has {} rows (axis = {j}); at least 6 are needed",
                    rows.len()
                ),
            });
        }
    }
    let rest = rest_pose(&r1, &r2);

    // 1. provisional frame: J1 plane (eq 9) and circle (eq 7)
    let prov = ProvisionalFrame::fit(&r1)?;
    for r in r1.iter_mut().chain(r2.iter_mut()) {
        r.p = prov.to_frame(&r.p);
    }
    // 2.–3. the J2 circle, the reference frame and the tables
    let refs = References::identify(&mut r1, &mut r2, &rest, nominal)?;
    let geometry = refs.geometry(&r2, nominal, rest.clone(), opts)?;
    let mut model = PhysicsModel::new(
        format!(
            "seed 000 SCARA model identified from the indexing tests of {}",
            data.source
        ),
        nominal.clone(),
        Geometry::Scara(geometry),
    );
    // measurement ← reference: p = origin + R_prov·Rz(ψ)·(p_ref − z0·ẑ)
    let r_total =
        prov.rotation * Rotation3::from_axis_angle(&Vector3::z_axis(), refs.psi).into_inner();
    let rq = UnitQuaternion::from_matrix(&r_total);
    let shift = prov.origin - (rq * Vector3::new(0.0, 0.0, refs.z0));
    model.frame = Isometry3::from_parts(Translation3::from(shift), rq);
    model.apd[0] = Some(refs.t1.table.clone());
    model.apd[1] = Some(refs.t2.table.clone());
    if opts.radial {
        model.radial[0] = Some(refs.t1.radial.clone());
        model.radial[1] = Some(refs.t2.radial.clone());
    }
    let plane2 = fit_plane(&r2.iter().map(|r| r.p).collect::<Vec<_>>())?.rms;
    let axes = vec![
        axis_report(
            1,
            &refs.t1,
            prov.circle.radius,
            prov.circle.rms,
            prov.plane.rms,
        ),
        axis_report(2, &refs.t2, refs.c2.radius, refs.c2.rms, plane2),
    ];
    let skipped = (3..=n)
        .map(|j| (j, rows_of(j)))
        .filter(|(_, rows)| !rows.is_empty())
        .map(|(j, rows)| skipped_axis(j, &rows, &prov))
        .collect();
    Ok(ScaraIdentification {
        model,
        axes,
        skipped,
    })
}

/// The frame of step 1 (eqs 7, 9): Z the J1 test's plane normal, oriented
/// so that J1 turns counter-clockwise with increasing q1; the origin the
/// centre of its best-fit circle in that plane; X toward its first point.
struct ProvisionalFrame {
    /// The best-fit plane of the J1 test (measurement frame).
    plane: Plane,
    /// The best-fit circle of the J1 test in that plane.
    circle: Circle2,
    /// The origin, in the measurement frame.
    origin: Vector3<f64>,
    /// Columns X, Y, Z of the frame, in the measurement frame.
    rotation: Matrix3<f64>,
}

impl ProvisionalFrame {
    fn fit(r1: &[Row]) -> Result<Self> {
        let pts1: Vec<Vector3<f64>> = r1.iter().map(|r| r.p).collect();
        let plane = fit_plane(&pts1)?;
        let mut ez = plane.normal;
        let ex0 = (pts1[0] - plane.point - ez * ez.dot(&(pts1[0] - plane.point))).normalize();
        let uv = |p: &Vector3<f64>, ex: &Vector3<f64>, ey: &Vector3<f64>| {
            let d = p - plane.point;
            [d.dot(ex), d.dot(ey)]
        };
        // orient Z so that J1 turns counter-clockwise with increasing q1
        let ey0 = ez.cross(&ex0);
        let (lo, hi) = extreme_pair(r1, 0);
        let (a, b) = (uv(&r1[lo].p, &ex0, &ey0), uv(&r1[hi].p, &ex0, &ey0));
        let turn = wrap_pi(angle_2d(b) - angle_2d(a));
        let (ex0, ey0) = if turn < 0.0 {
            ez = -ez;
            (ex0, ez.cross(&ex0))
        } else {
            (ex0, ey0)
        };
        let uv1: Vec<[f64; 2]> = pts1.iter().map(|p| uv(p, &ex0, &ey0)).collect();
        let circle = fit_circle_2d(&uv1)?;
        let origin = plane.point + ex0 * circle.center[0] + ey0 * circle.center[1];
        Ok(ProvisionalFrame {
            plane,
            circle,
            origin,
            rotation: Matrix3::from_columns(&[ex0, ey0, ez]),
        })
    }

    /// A measured point in this frame.
    fn to_frame(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation.transpose() * (p - self.origin)
    }
}

/// Steps 2–3: the J1 table (eq 11) about the axis, the J2 circle (eq 10),
/// the rotation ψ about Z that puts X along link 1 at `θ̂1 = 0`, the height
/// `z0` of the rest pose, and the J2 table about its circle's centre.
struct References {
    t1: AxisTable,
    t2: AxisTable,
    /// The J2 circle, in the provisional frame.
    c2: Circle2,
    /// Its centre `Q2` in the reference frame (XY).
    q2c: [f64; 2],
    /// The J1 angle the J2 test ran at, `θ̂1 = q1* + Δθ1(q1*, λ1)`, degrees.
    th1_j2: f64,
    /// Rotation of the reference frame about the provisional Z, radians.
    psi: f64,
    /// Nominal TCP height of the rest pose, mm.
    z0: f64,
}

impl References {
    /// Moves the rows (in the provisional frame) into the reference frame.
    fn identify(r1: &mut [Row], r2: &mut [Row], rest: &[f64], nominal: &Robot) -> Result<Self> {
        // 3. J1 table (eq 11) about Q1 = 0
        let zero = [0.0, 0.0];
        let t1 = angle_table(r1, 0, rest[0], &about(zero), &radius_about(zero))?;
        // 2. J2 circle (eq 10)
        let xy2: Vec<[f64; 2]> = r2.iter().map(|r| [r.p.x, r.p.y]).collect();
        let c2 = fit_circle_2d(&xy2)?;
        // J1 angle at which the J2 test was run: θ̂1 = q1* + Δθ1(q1*, λ1)
        let th1_j2 = r2[0].q[0] + t1.table.at(r2[0].q[0], r2[0].dir[0]);
        let psi = angle_2d(c2.center) - th1_j2.to_radians();
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), -psi);
        let z0 = nominal.fk_unchecked(rest).translation.vector.z;
        for r in r1.iter_mut().chain(r2.iter_mut()) {
            r.p = rot * r.p + Vector3::new(0.0, 0.0, z0);
        }
        let q2c = rot * Vector3::new(c2.center[0], c2.center[1], 0.0);
        let q2c = [q2c.x, q2c.y];
        let t2 = angle_table(r2, 1, rest[1], &about(q2c), &radius_about(q2c))?;
        Ok(References {
            t1,
            t2,
            c2,
            q2c,
            th1_j2,
            psi,
            z0,
        })
    }

    /// Steps 4, 5 and 7: `ΔL1`, `ΔL2`, θ20 and, if asked, the parallelism
    /// of J2 to J1 (the plane of the J2 test `r2`, in link-1 coordinates).
    fn geometry(
        &self,
        r2: &[Row],
        nominal: &Robot,
        rest: Vec<f64>,
        opts: &ScaraOptions,
    ) -> Result<ScaraGeometry> {
        let l1 = nominal.links[0].a_mm;
        let l2 = nominal.links[1].a_mm;
        let q2c = self.q2c;
        // 4.–5. link errors and θ20
        let dl1 = q2c[0].hypot(q2c[1]) - l1;
        let dl2 = self.c2.radius - l2;
        let theta20 = (self.t2.ref_angle - angle_2d(q2c)).to_degrees() - rest[1];
        let theta20 = wrap_pi(theta20.to_radians()).to_degrees();
        // 7. parallelism (eq 22) in link-1 coordinates
        let (pa, pb, z1) = if opts.parallelism {
            let (s, c) = self.th1_j2.to_radians().sin_cos();
            let local: Vec<Vector3<f64>> = r2
                .iter()
                .map(|r| Vector3::new(c * r.p.x + s * r.p.y, -s * r.p.x + c * r.p.y, r.p.z))
                .collect();
            let pl = fit_plane(&local)?;
            let nz = pl.normal.z;
            let (a, b) = (-pl.normal.x / nz, -pl.normal.y / nz);
            (a, b, pl.point.z - a * pl.point.x - b * pl.point.y)
        } else {
            (0.0, 0.0, self.z0)
        };
        Ok(ScaraGeometry {
            l1_mm: l1,
            l2_mm: l2,
            dl1_mm: dl1,
            dl2_mm: dl2,
            theta20_deg: theta20,
            parallel_a: pa,
            parallel_b: pb,
            z1_mm: if opts.parallelism { z1 } else { self.z0 },
            rest,
        })
    }
}

/// ∠(P − c) in the XY plane, radians.
fn about(c: [f64; 2]) -> impl Fn(&Vector3<f64>) -> f64 {
    move |p: &Vector3<f64>| angle_2d([p.x - c[0], p.y - c[1]])
}

/// ‖P − c‖ in the XY plane, mm.
fn radius_about(c: [f64; 2]) -> impl Fn(&Vector3<f64>) -> f64 {
    move |p: &Vector3<f64>| (p.x - c[0]).hypot(p.y - c[1])
}

/// The report of axis `j` from its table and its circle and plane fits.
fn axis_report(j: usize, t: &AxisTable, radius: f64, rms: f64, plane_rms: f64) -> AxisReport {
    AxisReport {
        axis: j,
        rows: t.rows,
        angles: t.table.angles_deg.len(),
        cycles: t.cycles,
        radius_mm: radius,
        circle_rms_mm: rms,
        plane_rms_mm: plane_rms,
        repeat_spread_deg: t.spread,
        backlash_half_deg: t.table.mean_half_difference(),
    }
}

/// Why the indexing test of joint `j` ≥ 3 is not used: the model has tables
/// for J1 and J2 only, and the TCP's circle about such an axis is too small.
fn skipped_axis(j: usize, rows: &[Row], prov: &ProvisionalFrame) -> String {
    let xy: Vec<[f64; 2]> = rows
        .iter()
        .map(|r| {
            let p = prov.to_frame(&r.p);
            [p.x, p.y]
        })
        .collect();
    let why = match fit_circle_2d(&xy) {
        Ok(c) => format!(
            "the TCP turns on a circle of radius {:.4} mm (rms {:.4} mm) about it: too close to the axis to resolve its angle",
            c.radius, c.rms
        ),
        Err(e) => format!("no circle could be fitted ({e})"),
    };
    format!(
        "J{j} indexing test ({} rows) not used: the seed 000 model has tables for J1 and J2 only; {why}",
        rows.len()
    )
}

/// The rest pose of the tests: J1's value during the J2 test, J2's during
/// the J1 test, the other joints as in the J1 test.
fn rest_pose(r1: &[Row], r2: &[Row]) -> Vec<f64> {
    let mut rest = r1[0].q.clone();
    rest[0] = r2[0].q[0];
    rest
}

/// Rows with the smallest and next-smallest commanded value of joint `j`
/// (for the turning sense).
pub(super) fn extreme_pair(rows: &[Row], j: usize) -> (usize, usize) {
    let mut idx: Vec<usize> = (0..rows.len()).collect();
    idx.sort_by(|&a, &b| rows[a].q[j].total_cmp(&rows[b].q[j]));
    let first = idx[0];
    let next = idx
        .iter()
        .copied()
        .find(|&k| rows[k].q[j] > rows[first].q[j] + 1e-6)
        .unwrap_or(idx[idx.len() - 1]);
    (first, next)
}

/// Tables of one axis.
pub(super) struct AxisTable {
    pub table: BidirectionalTable,
    pub radial: BidirectionalTable,
    /// Mean over both directions of ∠(P(i⁰) − Q), radians.
    pub ref_angle: f64,
    /// Largest max − min over the cycles of one entry, degrees.
    pub spread: f64,
    pub rows: usize,
    pub cycles: usize,
}

/// Eq 11 and eq 20 for joint `j` (0-based): `angle(p)` is ∠(P − Q_n) about
/// the axis (radians, counter-clockwise for increasing `q_j`), `radius(p)`
/// is ‖P − Q_n‖; the reference index is the indexed angle nearest `rest`.
pub(super) fn angle_table(
    rows: &[Row],
    j: usize,
    rest: f64,
    angle: &dyn Fn(&Vector3<f64>) -> f64,
    radius: &dyn Fn(&Vector3<f64>) -> f64,
) -> Result<AxisTable> {
    let mut angles: Vec<f64> = rows.iter().map(|r| r.q[j]).collect();
    angles.sort_by(f64::total_cmp);
    angles.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let i0 = (0..angles.len())
        .min_by(|&a, &b| {
            (angles[a] - rest)
                .abs()
                .total_cmp(&(angles[b] - rest).abs())
        })
        .expect("rows checked non-empty");
    let slot = |q: f64| angles.iter().position(|a| (a - q).abs() < 1e-6).unwrap();
    let ang = |r: &Row| angle(&r.p);
    let at_ref: Vec<f64> = rows
        .iter()
        .filter(|r| slot(r.q[j]) == i0)
        .map(ang)
        .collect();
    // mean of angles near each other: average the wrapped differences
    let a0 = at_ref[0];
    let ref_angle = a0 + at_ref.iter().map(|a| wrap_pi(a - a0)).sum::<f64>() / at_ref.len() as f64;
    let na = angles.len();
    let mut acc = vec![[Vec::new(), Vec::new()]; na];
    let mut rad = vec![[Vec::new(), Vec::new()]; na];
    let mut cycles = std::collections::BTreeSet::new();
    for r in rows {
        let i = slot(r.q[j]);
        let d = usize::from(r.dir[j] < 0.0);
        let dev = wrap_pi(ang(r) - ref_angle - (angles[i] - angles[i0]).to_radians());
        acc[i][d].push(dev.to_degrees());
        rad[i][d].push(radius(&r.p));
        cycles.insert(r.cycle);
    }
    let mean = |v: &Vec<f64>| v.iter().sum::<f64>() / v.len() as f64;
    let mut plus = Vec::with_capacity(na);
    let mut minus = Vec::with_capacity(na);
    let mut rp = Vec::with_capacity(na);
    let mut rm = Vec::with_capacity(na);
    let mut spread = 0.0_f64;
    let (mut ss, mut dof, mut reps) = (0.0, 0usize, 1usize);
    for i in 0..na {
        for (d, cell) in acc[i].iter().enumerate() {
            if cell.is_empty() {
                return Err(Error::InvalidParameter(format!(
                    "J{} indexing test: angle {} was not measured in the {} direction (the test must be bidirectional)",
                    j + 1,
                    angles[i],
                    if d == 0 { "positive" } else { "negative" }
                )));
            }
            let (lo, hi) = cell
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
            spread = spread.max(hi - lo);
            let m = mean(cell);
            ss += cell.iter().map(|v| (v - m).powi(2)).sum::<f64>();
            dof += cell.len() - 1;
            reps = reps.max(cell.len());
        }
        plus.push(mean(&acc[i][0]));
        minus.push(mean(&acc[i][1]));
        rp.push(mean(&rad[i][0]));
        rm.push(mean(&rad[i][1]));
    }
    let r_mean = (rp.iter().sum::<f64>() + rm.iter().sum::<f64>()) / (2 * na) as f64;
    rp.iter_mut()
        .chain(rm.iter_mut())
        .for_each(|v| *v -= r_mean);
    let mut table = BidirectionalTable::new(angles.clone(), plus, minus)?;
    if dof > 0 {
        table.entry_se = (ss / dof as f64).sqrt() / (reps as f64).sqrt();
    }
    Ok(AxisTable {
        table,
        radial: BidirectionalTable::new(angles, rp, rm)?,
        ref_angle,
        spread,
        rows: rows.len(),
        cycles: cycles.len(),
    })
}
