//! Locating a tracker: the rigid frame from tracker to robot base and the TCP
//! offset in the flange frame, by least squares over a measured campaign, and
//! the TCP errors that follow.
//!
//! For measured positions `m_k` (tracker frame) at joints `q_k`, with the
//! nominal flange pose `(R06_k, p06_k)` and the unknown tool translation `p`,
//!
//! `r_k = R·m_k + t − (R06_k·p + p06_k)`,   minimise `Σ ‖r_k‖²`
//!
//! over the rotation `R`, the translation `t` (tracker → base) and `p`
//! (9 parameters). The start is `p₀` = the robot's tool and `(R₀, t₀)` from
//! the SVD registration of `m` onto the nominal TCP ([`crate::frames::register`]);
//! Gauss–Newton then updates `R ← exp([δw]×)·R`, `t += δt`, `p += δp`, with
//! per-row Jacobian `[−[R·m_k]×, I, −R06_k]`, solved by QR. The errors are
//! `e_k = r_k` at the optimum: measured − nominal in the base frame. A tool
//! rotation does not move the TCP position, so it is not identified.

use super::Robot;
use crate::dataset::Dataset;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Rotation3, Translation3, Vector3};

/// The located tracker and tool.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackerFit {
    /// Robot base ← tracker.
    pub tracker_to_base: Isometry3<f64>,
    /// TCP offset in the flange frame, mm.
    pub tool_xyz_mm: Vector3<f64>,
    /// Residuals `r_k` at the optimum: TCP errors (measured − nominal), mm,
    /// in the base frame.
    pub errors: Vec<[f64; 3]>,
    /// Root mean square of ‖r_k‖, mm.
    pub rms_mm: f64,
    /// Gauss–Newton iterations taken.
    pub iterations: usize,
}

/// An RMS TCP error above this (mm) is not a robot's absolute error (a few
/// tenths of a mm to a few mm, uncalibrated): the import read the export
/// wrongly. The IPA UR10 export read with its radians as degrees gave
/// 229.9 mm (and a TCP offset of 9 m); read right, 1.06 mm.
const IMPLAUSIBLE_RMS_MM: f64 = 20.0;

impl TrackerFit {
    /// Why these errors are implausible, if they are: their RMS above
    /// `IMPLAUSIBLE_RMS_MM` (20 mm), with what to check (and radians, when
    /// every joint value of `data` lies within ±2π).
    pub fn warnings(&self, data: &Dataset) -> Vec<String> {
        if self.rms_mm <= IMPLAUSIBLE_RMS_MM {
            return Vec::new();
        }
        vec![format!(
            "the errors' RMS is {:.1} mm, far beyond a robot's absolute error (a few mm): check the \
             export's units (--angles, --lengths), the robot (--robot) and its joint convention{}",
            self.rms_mm,
            radians_hint(data)
        )]
    }
}

/// `"; every joint value lies within ±2π: …"` when every joint value of
/// `data` (at least three rows) does: radians read as degrees, the likely
/// cause of a campaign the robot's kinematics cannot place; else `""`.
fn radians_hint(data: &Dataset) -> &'static str {
    let radian_like = data.q.len() >= 3
        && data
            .q
            .iter()
            .all(|q| q.iter().all(|v| v.abs() <= std::f64::consts::TAU));
    if radian_like {
        "; every joint value lies within ±2π: if the export's angles are radians, add --angles rad \
         (angles = \"rad\" in the map)"
    } else {
        ""
    }
}

/// Stop when the step is below this (radians and mm).
const STEP_TOL: f64 = 1e-12;
/// Gauss–Newton iteration cap.
const MAX_ITER: usize = 50;

/// Locate the tracker and the tool from measured TCP positions `measured`
/// (tracker frame, mm) at joints `q` (see the module docs). Needs ≥ 4 poses.
pub fn locate_tracker(robot: &Robot, q: &[Vec<f64>], measured: &[[f64; 3]]) -> Result<TrackerFit> {
    if q.len() != measured.len() || q.len() < 4 {
        return Err(Error::InvalidParameter(format!(
            "locating the tracker needs ≥ 4 poses with one measured position each ({} poses, {} positions)",
            q.len(),
            measured.len()
        )));
    }
    for qi in q {
        robot.check_len(qi)?;
    }
    let flange: Vec<Isometry3<f64>> = q.iter().map(|qi| robot.frames(qi)[robot.dof()]).collect();
    let m: Vec<Vector3<f64>> = measured.iter().map(|v| Vector3::from(*v)).collect();
    let mut p = robot.tool.translation.vector;
    let tcp = |p: &Vector3<f64>| -> Vec<Vector3<f64>> {
        flange
            .iter()
            .map(|f| f.rotation * p + f.translation.vector)
            .collect()
    };
    let start = crate::frames::register(&m, &tcp(&p))?;
    let mut rot: Rotation3<f64> = start.transform.rotation.to_rotation_matrix();
    let mut t = start.transform.translation.vector;
    let residuals =
        |rot: &Rotation3<f64>, t: &Vector3<f64>, p: &Vector3<f64>| -> Vec<Vector3<f64>> {
            m.iter()
                .zip(tcp(p))
                .map(|(mk, nk)| rot * mk + t - nk)
                .collect()
        };
    let mut iterations = 0;
    for it in 1..=MAX_ITER {
        iterations = it;
        let r = residuals(&rot, &t, &p);
        let rows = 3 * m.len();
        let mut jac = DMatrix::<f64>::zeros(rows, 9);
        let mut rhs = DVector::<f64>::zeros(rows);
        for (k, (mk, f)) in m.iter().zip(&flange).enumerate() {
            let rm = rot * mk;
            let skew = Matrix3::new(0.0, -rm.z, rm.y, rm.z, 0.0, -rm.x, -rm.y, rm.x, 0.0);
            let r06 = f.rotation.to_rotation_matrix();
            jac.view_mut((3 * k, 0), (3, 3)).copy_from(&(-skew));
            jac.view_mut((3 * k, 3), (3, 3))
                .copy_from(&Matrix3::identity());
            jac.view_mut((3 * k, 6), (3, 3)).copy_from(&(-r06.matrix()));
            rhs.rows_mut(3 * k, 3).copy_from(&(-r[k]));
        }
        let step = jac
            .svd(true, true)
            .solve(&rhs, 1e-12)
            .map_err(|e| Error::Numerical(format!("locating the tracker: {e}")))?;
        let dw = Vector3::new(step[0], step[1], step[2]);
        rot = Rotation3::new(dw) * rot;
        t += Vector3::new(step[3], step[4], step[5]);
        p += Vector3::new(step[6], step[7], step[8]);
        if step.norm() < STEP_TOL * (1.0 + t.norm() + p.norm()) {
            break;
        }
    }
    let r = residuals(&rot, &t, &p);
    let rms_mm = (r.iter().map(|v| v.norm_squared()).sum::<f64>() / r.len() as f64).sqrt();
    if !rms_mm.is_finite() {
        return Err(Error::Numerical("locating the tracker diverged".into()));
    }
    Ok(TrackerFit {
        tracker_to_base: Isometry3::from_parts(Translation3::from(t), rot.into()),
        tool_xyz_mm: p,
        errors: r.iter().map(|v| [v.x, v.y, v.z]).collect(),
        rms_mm,
        iterations,
    })
}

/// Turn a campaign's measured positions (tracker frame) into errors:
/// locate the tracker and the tool ([`locate_tracker`]) and replace its
/// `x,y,z` by `ex,ey,ez` = measured − nominal in the base frame. Returns the
/// fit, or `None` with `data` unchanged when it has no positions. Refuses a
/// campaign with errors too (which of them would be kept?).
pub fn errors_from_positions(robot: &Robot, data: &mut Dataset) -> Result<Option<TrackerFit>> {
    let Some(positions) = data.positions.as_deref() else {
        return Ok(None);
    };
    if data.errors.is_some() {
        return Err(Error::Input {
            source_name: data.source.clone(),
            message: "has both errors (ex,ey,ez) and positions (x,y,z): keep one".into(),
        });
    }
    let fit = locate_tracker(robot, &data.q, positions)?;
    data.positions = None;
    data.errors = Some(fit.errors.clone());
    Ok(Some(fit))
}

/// Import the export at `path` with `spec` ([`crate::dataset::import::import`])
/// for the measured robot, if one is given: its prismatic joints' values
/// read as lengths, the campaign checked against it
/// ([`Robot::check_dataset`]).
pub fn import_for(
    path: &std::path::Path,
    spec: &crate::dataset::import::ImportSpec,
    robot: Option<&Robot>,
) -> Result<crate::dataset::import::Imported> {
    let prismatic = robot.map(Robot::prismatic_joints).unwrap_or_default();
    let imported = crate::dataset::import::import(path, spec, &prismatic)?;
    if let Some(r) = robot {
        r.check_dataset(&imported.data)?;
    }
    Ok(imported)
}

/// [`errors_from_positions`] of an imported campaign (`import`) with its
/// robot, if one is given; an import map that gives both errors and
/// positions is refused.
pub fn locate_imported(robot: Option<&Robot>, data: &mut Dataset) -> Result<Option<TrackerFit>> {
    let Some(robot) = robot else {
        return Ok(None);
    };
    if data.errors.is_some() && data.positions.is_some() {
        return Err(Error::InvalidParameter(
            "the map gives both errors (ex,ey,ez) and positions (x,y,z) with --robot: map one"
                .into(),
        ));
    }
    // joint values within ±2π read as degrees put the robot nowhere near
    // the tracker's readings: say what most likely happened
    let hint = radians_hint(data);
    errors_from_positions(robot, data).map_err(|e| {
        if hint.is_empty() || e.is_interrupted() {
            e
        } else {
            Error::InvalidParameter(format!("{e}{hint}"))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    #[test]
    fn recovers_a_known_frame_and_tool_from_exact_positions() {
        let mut robot = crate::kinematics::preset("ur10").unwrap();
        let tool = Vector3::new(-0.2, 0.3, 92.8);
        let truth = Isometry3::from_parts(
            Translation3::new(750.0, 3520.0, 1220.0),
            UnitQuaternion::from_euler_angles(0.01, -0.02, -0.35),
        );
        let q: Vec<Vec<f64>> = (0..40)
            .map(|i| {
                let t = i as f64;
                (0..6)
                    .map(|j| 60.0 * ((0.7 * t + j as f64) * 1.3).sin())
                    .collect()
            })
            .collect();
        robot.tool = Isometry3::translation(tool.x, tool.y, tool.z);
        // tracker readings: base ← tracker is `truth`, so m = truth⁻¹ · TCP
        let measured: Vec<[f64; 3]> = q
            .iter()
            .map(|qi| {
                let v =
                    truth.inverse_transform_point(&robot.fk(qi).unwrap().translation.vector.into());
                [v.x, v.y, v.z]
            })
            .collect();
        robot.tool = Isometry3::identity();
        let fit = locate_tracker(&robot, &q, &measured).unwrap();
        assert!(
            (fit.tool_xyz_mm - tool).norm() < 1e-8,
            "{}",
            fit.tool_xyz_mm
        );
        assert!((fit.tracker_to_base.translation.vector - truth.translation.vector).norm() < 1e-7);
        assert!(fit.rms_mm < 1e-8, "{}", fit.rms_mm);
        // the same on a campaign: its positions become the errors
        let mut data = Dataset::from_poses("c.csv", q, None).unwrap();
        assert_eq!(errors_from_positions(&robot, &mut data).unwrap(), None);
        data.positions = Some(measured);
        let located = errors_from_positions(&robot, &mut data).unwrap().unwrap();
        assert_eq!((located, data.positions.is_none()), (fit.clone(), true));
        assert_eq!(data.errors.as_ref(), Some(&fit.errors));
        data.positions = Some(vec![[0.0; 3]; data.len()]);
        let both = errors_from_positions(&robot, &mut data).unwrap_err();
        assert!(both.to_string().contains("both errors"), "{both}");
    }
}
