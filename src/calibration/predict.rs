//! What a [`Calibration`] predicts at new poses, and how sure it is: the
//! kinematic part of the error `δ̂_cal(q, λ)`, its variance from the
//! directions the campaign left uncertain and the joint terms'
//! covariances, and the TCP displacements of the directions it saw (what
//! a diagnosis refits beside an effect).

use super::{Calibration, Displacements, backlash, harmonics};
use crate::dataset::Dataset;
use crate::kinematics::identification_jacobian;
use crate::vec3::residuals;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector, DVectorView};
use rayon::prelude::*;

impl Calibration {
    /// The TCP displacement of a unit step along each direction the campaign
    /// saw, at the poses `q`, per axis: `out[a][i][k] = ∂P_a/∂p(q_k)·D v_i`
    /// for the first [`Identifiability::directions_seen`](super::Identifiability::directions_seen) directions `D v_i`
    /// of the scaled Jacobian (at the nominal parameters, as the directions
    /// were found). Whatever of an effect on these poses lies in their span
    /// the calibration has taken up; refitted beside the effect, they give
    /// it back (Frisch–Waugh). Empty per axis for a calibration read from a
    /// file that does not record its directions. The joint harmonics' and
    /// the backlash's unit displacements follow (approach directions `dir`,
    /// as [`Calibration::predict`]).
    pub fn seen_displacements(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Displacements> {
        let seen = &self.uncertainty[..self
            .identifiability
            .directions_seen
            .min(self.uncertainty.len())];
        let mut per_pose = self.displacements_at(q, seen)?;
        for (p, t) in per_pose.iter_mut().zip(self.joint_term_columns_at(q, dir)?) {
            for (pa, ta) in p.iter_mut().zip(t) {
                pa.extend(ta);
            }
        }
        let width = seen.len() + 2 * self.harmonics.len() + self.backlash.len();
        Ok(std::array::from_fn(|a| {
            (0..width)
                .map(|i| per_pose.iter().map(|p| p[a][i]).collect())
                .collect()
        }))
    }

    /// At each pose of `q` approached from `dir`, per axis, the TCP
    /// displacement of a unit coefficient of each joint term (`out[k][a]`):
    /// the joint harmonics' sine and cosine (`2h` values, `J_aj sin,
    /// J_aj cos` per harmonic), then each joint's half backlash
    /// (`J_aj λ_j`), with one pass of Jacobians per degree at the nominal
    /// parameters for both.
    pub(super) fn joint_term_columns_at(
        &self,
        q: &[Vec<f64>],
        dir: &[Vec<f64>],
    ) -> Result<Vec<[Vec<f64>; 3]>> {
        if self.harmonics.is_empty() && self.backlash.is_empty() {
            return Ok(vec![Default::default(); q.len()]);
        }
        self.check_directions(q, dir)?;
        let jac = harmonics::jacobians(&self.nominal, q)?;
        let play = backlash::unit_columns(&self.backlash, &jac, dir);
        Ok(q.iter()
            .zip(&jac)
            .zip(play)
            .map(|((qk, jq), b)| {
                let mut b = b.into_iter();
                std::array::from_fn(|a| {
                    self.harmonics
                        .iter()
                        .flat_map(|h| {
                            let (s, c) = h.unit_terms(qk[h.joint - 1]);
                            let l = jq[(a, h.joint - 1)];
                            [l * s, l * c]
                        })
                        .chain(b.next().unwrap_or_default())
                        .collect()
                })
            })
            .collect())
    }

    /// Error unless `dir` holds a direction row per pose of `q` (or nothing:
    /// not known, a backlash then left at the middle of its play).
    fn check_directions(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<()> {
        if !dir.is_empty() && dir.len() != q.len() {
            return Err(Error::InvalidParameter(format!(
                "{} poses but {} rows of approach directions",
                q.len(),
                dir.len()
            )));
        }
        Ok(())
    }

    /// The kinematic part of the error at joints `q` approached from the
    /// directions `dir` (`λ = ±1` per joint, a row per pose; empty: not
    /// known, each backlash then at the middle of its play):
    /// `δ̂_cal = P_cal(q' + δq(q')) − P_nom(q)`, `q' = q + b∘λ`, mm.
    pub fn predict(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        for r in q {
            self.nominal.check_len(r)?;
        }
        self.check_directions(q, dir)?;
        Ok(q.par_iter()
            .enumerate()
            .map(|(k, qk)| {
                let lambda = dir.get(k).map_or(&[][..], Vec::as_slice);
                let commanded = backlash::reached(&self.backlash, qk, lambda);
                let reached = harmonics::deviated(&self.harmonics, &commanded);
                (self.identified.fk_unchecked(&reached).translation.vector
                    - self.nominal.fk_unchecked(qk).translation.vector)
                    .into()
            })
            .collect())
    }

    /// The variance (mm², per axis) of the calibration's prediction at
    /// joints `q` from what the campaign left uncertain: with the
    /// identification Jacobian `J(q)` and the parameter directions `D v_i`
    /// of the scaled Jacobian ([`identifiability`](super::identifiability)),
    ///
    /// ```text
    /// Var δ̂_cal,a(q) = Σ_i var_i · (J_a(q) D v_i)²,   var_i = 1 / (1 + σ_i²/s²),
    /// ```
    ///
    /// the posterior variance of each direction's coordinate: small for a
    /// direction the campaign sees, the prior's for one fixed at nominal.
    /// Near the campaign's poses the unseen directions move the TCP by
    /// less than the noise; far from them they may not, and the variance
    /// says so. `J` is taken at the nominal parameters, as the directions
    /// were. 2(5n + 9) forward kinematics per pose.
    ///
    /// Joint harmonics add `h_a(q)ᵀ C h_a(q)`, `h_a` the displacements of
    /// their unit coefficients and `C` the coefficients' least-squares
    /// covariance; the backlash (directions `dir`, as [`Calibration::predict`])
    /// adds its own the same way. Each part is conditional on the others
    /// (the geometry's given the backlash it was fitted beside).
    ///
    /// All of it is one quadratic form, the diagonal of `G'(q) Σ' G'(q)ᵀ`
    /// with the design of every coefficient [`Calibration::design_rows`]
    /// and its covariance [`Calibration::design_covariance`] (block
    /// diagonal, `Σ_p = Σ_i var_i (D v_i)(D v_i)ᵀ` first), and it is
    /// computed so.
    pub fn predict_variance(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        let rows = self.design_rows(q, dir)?;
        let sigma = self.design_covariance();
        let p = sigma.nrows();
        if p == 0 {
            return Ok(vec![[0.0; 3]; q.len()]);
        }
        // the diagonal of G'(q) Σ' G'(q)ᵀ, one axis's row g at a time
        Ok(rows
            .par_chunks(3 * p)
            .map(|pose| {
                std::array::from_fn(|a| {
                    let g = DVectorView::from_slice(&pose[a * p..(a + 1) * p], p);
                    g.dot(&(&sigma * g))
                })
            })
            .collect())
    }

    /// At each pose of `q`, per axis, the TCP displacement of a unit step
    /// along each direction of `dirs` (`out[k][a][i]`), with the
    /// identification Jacobian at the nominal parameters, where the
    /// directions were found.
    fn displacements_at(
        &self,
        q: &[Vec<f64>],
        dirs: &[(Vec<f64>, f64)],
    ) -> Result<Vec<[Vec<f64>; 3]>> {
        for r in q {
            self.nominal.check_len(r)?;
        }
        Ok(q.par_iter()
            .map(|qk| {
                let j = identification_jacobian(&self.nominal, qk);
                std::array::from_fn(|a| {
                    dirs.iter()
                        .map(|(dir, _)| j[a].iter().zip(dir).map(|(x, y)| x * y).sum())
                        .collect()
                })
            })
            .collect())
    }

    /// Every coefficient the calibration estimated as one design, at each
    /// pose of `q` approached from `dir` (as [`Calibration::predict`]):
    /// the TCP displacement per axis of a unit step of each, row-major
    /// `3 × P'` per pose, one pose after the other, with `P' = P + 2h + b`
    /// — the P parameter errors (the identification Jacobian at the nominal
    /// parameters), then the joint harmonics' sine and cosine
    /// coefficients, then the half backlashes. With
    /// [`Calibration::design_covariance`] `Σ'`, the diagonal of
    /// `G'(q) Σ' G'(q)ᵀ` is [`Calibration::predict_variance`]: what a
    /// campaign planner conditions on a new pose.
    pub fn design_rows(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<f64>> {
        for r in q {
            self.nominal.check_len(r)?;
        }
        let terms = self.joint_term_columns_at(q, dir)?;
        Ok(q.par_iter()
            .zip(&terms)
            .flat_map_iter(|(qk, t)| {
                identification_jacobian(&self.nominal, qk)
                    .into_iter()
                    .zip(t)
                    .flat_map(|(ja, ta)| ja.into_iter().chain(ta.iter().copied()))
                    .collect::<Vec<f64>>()
            })
            .collect())
    }

    /// The covariance of the coefficients of [`Calibration::design_rows`]
    /// (`P' × P'`): [`Calibration::parameter_covariance`], then the joint
    /// harmonics' and the backlash's least-squares covariances, block by
    /// block (each part conditional on the others, as in
    /// [`Calibration::predict_variance`]).
    pub fn design_covariance(&self) -> DMatrix<f64> {
        let geometric = self.parameter_covariance();
        let (np, nh, nb) = (
            geometric.nrows(),
            2 * self.harmonics.len(),
            self.backlash.len(),
        );
        let mut c = DMatrix::zeros(np + nh + nb, np + nh + nb);
        c.view_mut((0, 0), (np, np)).copy_from(&geometric);
        for (start, w, cov) in [
            (np, nh, &self.harmonic_covariance),
            (np + nh, nb, &self.backlash_covariance),
        ] {
            c.view_mut((start, start), (w, w))
                .copy_from(&DMatrix::from_row_slice(w, w, cov));
        }
        c
    }

    /// The posterior covariance of the parameter errors (P × P, degrees and
    /// mm as the parameters), from the directions `D v_i` of the scaled
    /// Jacobian and their posterior variances:
    ///
    /// ```text
    /// Σ_p = Σ_i var_i · (D v_i)(D v_i)ᵀ,   var_i = 1 / (1 + σ_i²/s²),
    /// ```
    ///
    /// so that [`Calibration::predict_variance`] at `q` is the diagonal of
    /// `J(q) Σ_p J(q)ᵀ`. What a campaign planner conditions on a new pose.
    pub fn parameter_covariance(&self) -> DMatrix<f64> {
        let np = self.parameters.len();
        let mut c = DMatrix::zeros(np, np);
        for (dir, var) in &self.uncertainty {
            let d = DVector::from_column_slice(dir);
            c.ger(*var, &d, &d, 1.0);
        }
        c
    }

    /// Largest [`Calibration::predict_variance`] over the poses it was
    /// identified on, mm² per axis: what a prediction's calibration
    /// variance is compared with to tell an extrapolation.
    pub fn campaign_variance(&self) -> [f64; 3] {
        self.campaign_variance
    }

    /// `data` with its errors replaced by what the calibration leaves,
    /// `e − δ̂_cal(q, λ)`.
    pub fn residual(&self, data: &Dataset) -> Result<Dataset> {
        let pred = self.predict(&data.q, &data.dir)?;
        let mut r = data.clone();
        r.errors = Some(residuals(data.errors_or_err()?, &pred));
        Ok(r)
    }
}
