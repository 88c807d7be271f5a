//! Where a prediction leaves what the training campaign covers (issue 16
//! §3): joint ranges, prediction standard deviations, and Kriging
//! corrections far from the trend.

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
    },
    /// The prediction's standard deviation is a large share of the prior
    /// (process) standard deviation: no training pose is near.
    Uncertain {
        /// Output axis (0 x, 1 y, 2 z).
        axis: usize,
        /// The prediction's standard deviation √MSE, mm.
        std_mm: f64,
        /// The process standard deviation σ of that output, mm.
        process_std_mm: f64,
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
}

impl std::fmt::Display for CoverageIssue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CoverageIssue::JointRange {
                joint,
                value_deg,
                min_deg,
                max_deg,
            } => write!(
                f,
                "q{} = {value_deg:.2}° outside the campaign's [{min_deg:.2}, {max_deg:.2}]°",
                joint + 1
            ),
            CoverageIssue::Uncertain {
                axis,
                std_mm,
                process_std_mm,
            } => write!(
                f,
                "{} std {std_mm:.4} mm is {:.0} % of the prior {process_std_mm:.4} mm (far from every training pose)",
                AXES[*axis],
                100.0 * std_mm / process_std_mm
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

/// Share of the process standard deviation above which a prediction's
/// standard deviation counts as "far from the data" (the Kriging std tends
/// to the process std away from every training pose).
pub const UNCERTAIN_SHARE: f64 = 0.7;
/// Process σ's by which the Kriging correction may depart from the trend.
pub const TREND_SIGMAS: f64 = 6.0;

impl ErrorModel {
    /// The points of a prediction that leave what the training data
    /// covers (issue 16 §3): a joint outside the campaign's range, a
    /// standard deviation over [`UNCERTAIN_SHARE`] of the process std, or a
    /// Kriging correction more than [`TREND_SIGMAS`] process σ from the
    /// trend-only prediction. `mean` is this model's predicted mean at `q`,
    /// `dir`; `std` its standard deviations when they were computed (the
    /// std check is skipped without them, so a caller that needs only the
    /// mean, like compensation, never pays for the m × m factor). Only
    /// points with an issue are listed, in order.
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
                    });
                }
            }
            for (a, o) in self.outputs.iter().enumerate() {
                let process = o.process_std();
                if let Some(s) = std
                    .map(|s| s[k][a])
                    .filter(|s| *s > UNCERTAIN_SHARE * process)
                {
                    issues.push(CoverageIssue::Uncertain {
                        axis: a,
                        std_mm: s,
                        process_std_mm: process,
                    });
                }
                let correction = mean[k][a] - trend[a][k];
                if correction.abs() > TREND_SIGMAS * process {
                    issues.push(CoverageIssue::TrendDisagrees {
                        axis: a,
                        correction_mm: correction,
                        process_std_mm: process,
                    });
                }
            }
            if !issues.is_empty() {
                out.push(CoverageWarning { index: k, issues });
            }
        }
        Ok(out)
    }
}
