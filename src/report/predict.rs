//! `predict`: the warnings about a pose file and the summary of its
//! prediction.

use crate::dataset::Dataset;
use crate::model::{CampaignPrediction, CoverageWarning};
use crate::stats::summarize;
use crate::vec3::residuals;
use std::fmt::Write as _;
use std::path::Path;

/// The warning for points that leave the campaign's coverage (at most 20
/// listed, by id when `ids` are given, else by row); empty without any.
pub fn coverage(warnings: &[CoverageWarning], total: usize, ids: Option<&[String]>) -> String {
    let mut s = String::new();
    if warnings.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "warning: {} of {total} pose(s) leave what the training campaign covers; their predictions are extrapolations:",
        warnings.len()
    );
    for w in warnings.iter().take(20) {
        let label = ids.map_or_else(
            || format!("row {}", w.index + 1),
            |v| format!("id {}", v[w.index]),
        );
        let issues: Vec<String> = w.issues.iter().map(ToString::to_string).collect();
        let _ = writeln!(s, "  {label}: {}", issues.join("; "));
    }
    if warnings.len() > 20 {
        let _ = writeln!(
            s,
            "  … and {} more (all of them in --json)",
            warnings.len() - 20
        );
    }
    s
}

/// The warning (without its `warning: ` prefix) for a pose file `poses`
/// without direction columns whose first pose's assumed λ changes its
/// prediction `p` ([`CampaignPrediction::assumed_direction_mm`]); none when
/// it does not.
pub fn direction_warning(poses: &Path, data: &Dataset, p: &CampaignPrediction) -> Option<String> {
    let (joints, assumed) = (data.n_joints(), p.assumed_direction_mm);
    (assumed > 0.0).then(|| {
        format!(
            "{} has no dir1..dir{joints} columns: λ is derived from the row order, and the \
             first pose gets λ = +1 on every joint (assumed; a joint that has not moved yet keeps it). \
             Reversing it changes that pose's prediction by {assumed:.3} mm: give the dir columns, or put \
             the pose the robot came from first.",
            poses.display()
        )
    })
}

/// The summary of the prediction `p` of `data`, written to `output`: the
/// JSON of `predict --json`, and the text `predict` prints: when `data`
/// has measured errors, a line that compares them before and after
/// subtracting the prediction; then the file written.
pub fn summary(
    data: &Dataset,
    p: &CampaignPrediction,
    output: &Path,
) -> (serde_json::Value, String) {
    let (mean, coverage) = (&p.prediction.mean, &p.coverage);
    let wrote = format!("wrote {}\n", output.display());
    let Some(e) = &data.errors else {
        let v = serde_json::json!({"poses": data.len(), "output": output,
            "coverage_warnings": coverage});
        return (v, wrote);
    };
    let before = summarize(e);
    let after = summarize(&residuals(e, mean));
    let v = serde_json::json!({"poses": data.len(), "output": output,
        "measured": before, "after_subtracting_prediction": after,
        "coverage_warnings": coverage});
    let text = format!(
        "{} poses: mean 3D error {:.4} mm; after subtracting the prediction {:.4} mm (max {:.4} → {:.4})\n{wrote}",
        data.len(),
        before.mean_3d_mm,
        after.mean_3d_mm,
        before.max_3d_mm,
        after.max_3d_mm
    );
    (v, text)
}
