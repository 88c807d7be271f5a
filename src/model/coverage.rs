//! Where a prediction leaves what the training campaign covers: joint
//! ranges, predictive intervals that reach a gross error, Kriging
//! corrections far from the trend, and training measurements the model
//! leans on but cannot reproduce.

use super::{AXES, ErrorModel};
use crate::Result;
use serde::{Deserialize, Serialize};

/// Why a prediction point is outside what the training data covers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum CoverageIssue {
    /// A joint outside the campaign's range.
    JointRange {
        /// 0-based joint.
        joint: usize,
        /// The joint's value at the point, degrees (mm if prismatic).
        value_deg: f64,
        /// Smallest value of that joint in the training campaign.
        min_deg: f64,
        /// Largest value of that joint in the training campaign.
        max_deg: f64,
        /// Whether the joint is prismatic (values in mm), when the model
        /// records its robot; `None`: not known, the values are shown
        /// without a unit.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        prismatic: Option<bool>,
    },
    /// The 95 % predictive interval of a new measurement reaches a gross
    /// error: `1.96 √(MSE + noise²)`, calibrated on the model's
    /// leave-one-out residuals ([`ErrorModel::loo_check`]), exceeds
    /// [`GROSS_FACTOR`] times the RMS of those residuals on that axis (no
    /// training pose is near enough for the model to vouch for the point).
    /// With a calibration, its variance beyond its largest at a measured
    /// pose is in the MSE.
    Uncertain {
        /// Output axis (0 x, 1 y, 2 z).
        axis: usize,
        /// The predictive standard deviation of a new measurement,
        /// `√(MSE + noise²)`, mm.
        std_mm: f64,
        /// The RMS of the model's leave-one-out residuals on that axis
        /// ([`super::LooCheck::loo_rmse`]), mm.
        loo_rmse_mm: f64,
    },
    /// The Kriging correction `r(s)ᵀγ` departs from the trend-only
    /// prediction by more than the process σ allows: a trend that
    /// extrapolates wildly, corrected by the GP near the data only.
    TrendDisagrees {
        /// Output axis (0 x, 1 y, 2 z).
        axis: usize,
        /// The correction `r(s)ᵀγ` added to the trend, mm.
        correction_mm: f64,
        /// The process standard deviation σ of that output, mm.
        process_std_mm: f64,
    },
    /// A training measurement the prediction leans on most (the training
    /// row of largest process correlation, at least [`LEAN_CORRELATION`],
    /// for some output) is one the model cannot reproduce: its
    /// leave-one-out 3D residual exceeds [`GROSS_FACTOR`] times the model's
    /// leave-one-out 3D RMS, the gross-error rule of `cv` and `holdout`.
    /// The campaign contradicts itself there (a configuration measured
    /// twice with different errors, a bad reading) or has a local effect
    /// the model lacks; either way the model is confident where its data
    /// are not.
    Contradicted {
        /// The training row, 0-based among the model's training rows (the
        /// message counts data rows from 1, as `predict` does).
        row: usize,
        /// The process correlation between the point and that row.
        correlation: f64,
        /// That row's leave-one-out residual x, y, z, mm.
        loo_residual_mm: [f64; 3],
        /// The RMS of the model's leave-one-out 3D residuals, mm.
        loo_rmse_mm: f64,
    },
}

impl std::fmt::Display for CoverageIssue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CoverageIssue::JointRange {
                joint,
                value_deg,
                min_deg,
                max_deg,
                prismatic,
            } => {
                let unit = prismatic.map_or("", crate::kinematics::unit_suffix);
                write!(
                    f,
                    "q{} = {value_deg:.2}{unit} outside the campaign's [{min_deg:.2}, {max_deg:.2}]{unit}",
                    joint + 1
                )
            }
            CoverageIssue::Uncertain {
                axis,
                std_mm,
                loo_rmse_mm,
            } => write!(
                f,
                "{} predictive std {std_mm:.4} mm is {:.1}× the model's leave-one-out RMS {loo_rmse_mm:.4} mm (its 95 % interval reaches a gross error)",
                AXES[*axis],
                std_mm / loo_rmse_mm
            ),
            CoverageIssue::TrendDisagrees {
                axis,
                correction_mm,
                process_std_mm,
            } => write!(
                f,
                "{} Kriging correction {correction_mm:.3} mm is {:.1} process σ ({process_std_mm:.4} mm) from the trend",
                AXES[*axis],
                correction_mm.abs() / process_std_mm
            ),
            CoverageIssue::Contradicted {
                row,
                correlation,
                loo_residual_mm,
                loo_rmse_mm,
            } => {
                let e = loo_residual_mm.iter().map(|v| v * v).sum::<f64>().sqrt();
                write!(
                    f,
                    "leans on the training campaign's data row {} (correlation {correlation:.2}), whose measurement the model misses by {e:.3} mm left out ({:.1}× its leave-one-out RMS {loo_rmse_mm:.4} mm)",
                    row + 1,
                    e / loo_rmse_mm
                )
            }
        }
    }
}

/// A prediction point with its coverage issues.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoverageWarning {
    /// 0-based index of the point.
    pub index: usize,
    /// Every way the point leaves what the data covers.
    pub issues: Vec<CoverageIssue>,
}

/// A gross error: this many times the model's leave-one-out RMS.
pub const GROSS_FACTOR: f64 = 3.0;
pub use crate::stats::Z95;
/// Training rows sampled (evenly over the campaign) for the model's
/// leave-one-out residuals ([`ErrorModel::loo_check`]): the interval
/// scale and power and the RMS of the [`CoverageIssue::Uncertain`] rule,
/// at a cost of one m-sized triangular solve each (one multi-column solve
/// for all of them). The power lives in the tail of the stated variances,
/// and a few hundred rows hold too little of it: on the 2 773 rows of UR10
/// series C, 256 or 512 rows spread over the campaign gave κ = 0.2, 1 024
/// about 0.75 and all rows 0.6.
pub const LOO_SAMPLE: usize = 1024;
/// Process σ's by which the Kriging correction may depart from the trend.
pub const TREND_SIGMAS: f64 = 6.0;
/// The correlation at which a prediction leans on a training measurement
/// ([`CoverageIssue::Contradicted`]): that measurement weighs more in it
/// than what the process leaves independent of it.
pub const LEAN_CORRELATION: f64 = 0.5;

/// A prediction with what an honest report needs: the standard deviation
/// of a new measurement and the points outside the model's coverage.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckedPrediction {
    /// Mean and √MSE ([`ErrorModel::predict_dataset`]).
    pub prediction: super::Prediction,
    /// Standard deviation of a new measurement, `√(MSE + noise²)` with the
    /// noise of [`ErrorModel::predictive_noise_std`], per axis.
    pub std_new: Vec<[f64; 3]>,
    /// Indices of the points with a coverage warning
    /// ([`ErrorModel::coverage`]); `None` for a model with extra inputs,
    /// whose warnings would need more than the poses.
    pub flagged: Option<Vec<usize>>,
}

/// A pose file's prediction as `robokrige predict` writes it
/// ([`ErrorModel::predict_campaign`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignPrediction {
    /// Mean and √MSE of every row.
    pub prediction: super::Prediction,
    /// The model's noise standard deviation per axis
    /// ([`ErrorModel::predictive_noise_std`]), mm.
    pub noise_std: [f64; 3],
    /// The rows outside the model's coverage ([`ErrorModel::coverage`]).
    pub coverage: Vec<CoverageWarning>,
    /// What the assumed direction of the first pose is worth
    /// ([`ErrorModel::assumed_direction_sensitivity`]), mm; 0 when the
    /// file gives its directions.
    pub assumed_direction_mm: f64,
}

impl CampaignPrediction {
    /// Write the prediction CSV of `data`'s rows to `path`
    /// ([`crate::dataset::write_predictions`]).
    pub fn write(&self, path: &std::path::Path, data: &crate::dataset::Dataset) -> Result<()> {
        let p = &self.prediction;
        crate::dataset::write_predictions(path, data, &p.mean, &p.std, self.noise_std)
    }
}

impl ErrorModel {
    /// Predict every row of the pose file `data`, checked to have this
    /// model's joints, with what a report of it needs: the model's noise,
    /// the rows outside its coverage and the weight of an assumed first
    /// direction.
    pub fn predict_campaign(&self, data: &crate::dataset::Dataset) -> Result<CampaignPrediction> {
        self.check_dataset(data)?;
        let prediction = self.predict_dataset(data)?;
        let assumed_direction_mm = self.assumed_direction_sensitivity(data)?;
        let (mean, std) = (&prediction.mean, &prediction.std);
        let coverage = self.coverage(&data.q, &data.dir, mean, Some(std))?;
        Ok(CampaignPrediction {
            noise_std: self.predictive_noise_std()?,
            prediction,
            coverage,
            assumed_direction_mm,
        })
    }

    /// Error unless the poses of `data` have this model's joints.
    pub fn check_dataset(&self, data: &crate::dataset::Dataset) -> Result<()> {
        if data.n_joints() == self.n_joints() {
            return Ok(());
        }
        Err(crate::Error::Input {
            source_name: data.source.clone(),
            message: format!(
                "has {} joints but the model was fitted on {}",
                data.n_joints(),
                self.n_joints()
            ),
        })
    }

    /// What the assumed direction λ of `data`'s first pose is worth
    /// ([`ErrorModel::direction_sensitivity`], mm) when its directions were
    /// derived from the row order (no dir columns); 0 when they were given.
    pub fn assumed_direction_sensitivity(&self, data: &crate::dataset::Dataset) -> Result<f64> {
        match data.q.first() {
            Some(q0) if data.dir_source == crate::dataset::DirSource::Derived => {
                self.direction_sensitivity(q0, &data.dir[0])
            }
            _ => Ok(0.0),
        }
    }

    /// Predict every row of `data` with the standard deviation of a new
    /// measurement and the rows outside the model's coverage: what the
    /// held-out scores of `cv` and `holdout` are computed from.
    pub fn predict_checked(&self, data: &crate::dataset::Dataset) -> Result<CheckedPrediction> {
        let prediction = self.predict_dataset(data)?;
        let noise = self.predictive_noise_std()?;
        let std_new = prediction
            .std
            .iter()
            .map(|s| std::array::from_fn(|a| s[a].hypot(noise[a])))
            .collect();
        let flagged = if self.extras().is_empty() {
            let w = self.coverage(&data.q, &data.dir, &prediction.mean, Some(&prediction.std))?;
            Some(w.into_iter().map(|w| w.index).collect())
        } else {
            None
        };
        Ok(CheckedPrediction {
            prediction,
            std_new,
            flagged,
        })
    }

    /// The model's expected leave-one-out RMS per axis (mm), from the
    /// closed form on up to [`LOO_SAMPLE`] training rows spread over the
    /// campaign ([`crate::kriging::HeldOut::expected_loo_rmse`]).
    pub fn expected_loo_rmse(&self) -> Result<[f64; 3]> {
        self.loo_check().map(|c| c.expected_loo_rmse)
    }

    /// The points of a prediction that leave what the training data
    /// covers: a joint outside the campaign's range, a 95 % predictive
    /// interval that reaches a gross error ([`CoverageIssue::Uncertain`]), a
    /// Kriging correction more than [`TREND_SIGMAS`] process σ from the
    /// trend-only prediction, or a training measurement it leans on that the
    /// model cannot reproduce ([`CoverageIssue::Contradicted`]). `mean` is
    /// this model's predicted mean at `q`, `dir`; `std` its standard
    /// deviations when they were computed (the std and contradiction checks
    /// are skipped without them, so a caller that needs only the mean, like
    /// compensation, never pays for the m × m factor). Only points with an
    /// issue are listed, in order.
    pub fn coverage(
        &self,
        q: &[Vec<f64>],
        dir: &[Vec<f64>],
        mean: &[[f64; 3]],
        std: Option<&[[f64; 3]]>,
    ) -> Result<Vec<CoverageWarning>> {
        self.check_rows(q, dir)?;
        let s = self.input_map().encode(q, dir)?;
        let trend: Vec<Vec<f64>> = self.outputs.iter().map(|o| o.predict_trend(&s)).collect();
        // the Kriging outputs' part of `mean` (a calibration's is not theirs)
        let kinematic = match self.calibration() {
            Some(c) => c.predict(q, dir)?,
            None => vec![[0.0; 3]; q.len()],
        };
        // the reference: the model's held-out error where it was trained
        let loo = match std {
            Some(_) => self.loo_check()?.loo_rmse,
            None => [f64::INFINITY; 3],
        };
        let noise = self.predictive_noise_std()?;
        let contradicted = match std {
            Some(_) => self.contradicted(&s, &loo)?,
            None => vec![None; q.len()],
        };
        let mut out = Vec::new();
        for (k, qk) in q.iter().enumerate() {
            let mut issues = Vec::new();
            for (j, (&v, &(lo, hi))) in qk.iter().zip(&self.joint_range).enumerate() {
                if v < lo || v > hi {
                    issues.push(CoverageIssue::JointRange {
                        joint: j,
                        value_deg: v,
                        min_deg: lo,
                        max_deg: hi,
                        prismatic: self
                            .robot
                            .as_ref()
                            .and_then(|r| r.prismatic.get(j).copied()),
                    });
                }
            }
            for (a, o) in self.outputs.iter().enumerate() {
                let process = o.process_std();
                if let Some(s) = std
                    .map(|s| s[k][a].hypot(noise[a]))
                    .filter(|s| Z95 * s > GROSS_FACTOR * loo[a])
                {
                    issues.push(CoverageIssue::Uncertain {
                        axis: a,
                        std_mm: s,
                        loo_rmse_mm: loo[a],
                    });
                }
                let correction = mean[k][a] - kinematic[k][a] - trend[a][k];
                if correction.abs() > TREND_SIGMAS * process {
                    issues.push(CoverageIssue::TrendDisagrees {
                        axis: a,
                        correction_mm: correction,
                        process_std_mm: process,
                    });
                }
            }
            if let Some(issue) = contradicted[k].clone() {
                issues.push(issue);
            }
            if !issues.is_empty() {
                out.push(CoverageWarning { index: k, issues });
            }
        }
        Ok(out)
    }

    /// Per point (normalised inputs `s`), the
    /// [`CoverageIssue::Contradicted`] of a training row it leans on most
    /// (for some output), if any: those rows' leave-one-out residuals, read
    /// from the model's [`LooCheck`](super::LooCheck) where its sample holds
    /// them and solved for the others (one multi-column triangular solve
    /// per output), against `loo`, the leave-one-out RMS per axis.
    fn contradicted(&self, s: &[Vec<f64>], loo: &[f64; 3]) -> Result<Vec<Option<CoverageIssue>>> {
        let near: Vec<Vec<(usize, f64)>> =
            self.outputs.iter().map(|o| o.nearest_training(s)).collect();
        let check = self.loo_check()?;
        let mut e = check.residuals;
        let mut missing: Vec<usize> = near
            .iter()
            .flatten()
            .filter(|&&(i, r)| r >= LEAN_CORRELATION && e.iter().any(|ea| ea[i].is_nan()))
            .map(|(i, _)| *i)
            .collect();
        missing.sort_unstable();
        missing.dedup();
        if !missing.is_empty() {
            let blocks: Vec<Vec<usize>> = missing.iter().map(|&i| vec![i]).collect();
            for (ea, o) in e.iter_mut().zip(&self.outputs) {
                let got = o.held_out_residuals(&blocks)?;
                for &i in &missing {
                    ea[i] = got[i];
                }
            }
        }
        let rmse = loo.iter().map(|v| v * v).sum::<f64>().sqrt();
        Ok((0..s.len())
            .map(|k| {
                near.iter().find_map(|n| {
                    let (row, correlation) = n[k];
                    let r: [f64; 3] = std::array::from_fn(|a| e[a][row]);
                    let norm = r.iter().map(|v| v * v).sum::<f64>().sqrt();
                    (correlation >= LEAN_CORRELATION && norm > GROSS_FACTOR * rmse).then_some(
                        CoverageIssue::Contradicted {
                            row,
                            correlation,
                            loo_residual_mm: r,
                            loo_rmse_mm: rmse,
                        },
                    )
                })
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::CoverageIssue;

    #[test]
    fn a_joint_range_is_shown_in_its_joints_unit_or_none_when_unknown() {
        let issue = |prismatic| CoverageIssue::JointRange {
            joint: 2,
            value_deg: 190.0,
            min_deg: 75.0,
            max_deg: 80.0,
            prismatic,
        };
        let shown = |p| issue(p).to_string();
        assert_eq!(
            shown(Some(true)),
            "q3 = 190.00 mm outside the campaign's [75.00, 80.00] mm"
        );
        assert_eq!(
            shown(Some(false)),
            "q3 = 190.00° outside the campaign's [75.00, 80.00]°"
        );
        assert_eq!(
            shown(None),
            "q3 = 190.00 outside the campaign's [75.00, 80.00]"
        );
        // files without the field read as not known
        let json =
            r#"{"kind":"joint-range","joint":2,"value_deg":190.0,"min_deg":75.0,"max_deg":80.0}"#;
        assert_eq!(
            serde_json::from_str::<CoverageIssue>(json).unwrap(),
            issue(None)
        );
    }
}
