//! The text report of `plan`.

use crate::plan::stop::{Forecast, Verdict};
use crate::plan::{HyperSource, Plan};

/// What was planned, from which hyperparameters, the region's integrated
/// MSE before and after, and, with a target, the forecast and its verdict.
pub fn text(plan: &Plan, forecast: Option<&Forecast>, target_mm: Option<f64>) -> String {
    let measured = plan.moves.iter().filter(|m| m.measure).count();
    let vias = plan.moves.len() - measured;
    let source = match plan.source {
        HyperSource::Campaign => "re-estimated on the measured campaign",
        HyperSource::Prior => "the prior model's",
        HyperSource::SpaceFilling => "none yet (a batch covering the region)",
    };
    let mut s = format!(
        "planned {measured} poses to measure and {vias} pre-position moves, from {} candidates\n\
         hyperparameters: {source}\n",
        plan.candidates
    );
    if plan.passes > 1 {
        let (lo, hi) = (measured / plan.passes, measured.div_ceil(plan.passes));
        let run = if lo == hi {
            format!("{lo}")
        } else {
            format!("{lo}–{hi}")
        };
        s += &format!(
            "order: {} passes over the region, each a tour of the next {run} poses in the order chosen\n",
            plan.passes
        );
    }
    if let (Some(first), Some(last)) = (plan.imse_curve.first(), plan.imse_curve.last()) {
        s += &format!(
            "region's integrated MSE (x+y+z): {:.5} → {:.5} mm² (RMS {:.4} → {:.4} mm)\n",
            first,
            last,
            first.sqrt(),
            last.sqrt()
        );
    }
    if plan.unrealised > 0 {
        s += &format!(
            "{} poses cannot arrive from their planned side (a joint at its limit)\n",
            plan.unrealised
        );
    }
    if let Some(f) = forecast.filter(|f| !f.floor_identified) {
        s += &format!(
            "the floor (repeatability) is not measured: the model's noise estimate is at the \
             bottom of its range (it interpolates the {} poses measured), so the {:.4} mm below \
             says nothing of the robot's repeatability; measure a few poses twice to see it\n",
            f.measured, f.floor_mean_3d
        );
    }
    if let Some(f) = forecast {
        s += &format!(
            "held-out mean 3D error: {:.4} mm at the {} poses measured (10-fold CV), \
             {:.4} mm over the region now, forecast {:.4} mm after the plan; \
             floor (repeatability) {:.4} mm\n",
            f.cv_mean_3d,
            f.measured,
            f.now_mean_3d(),
            f.mean_3d.last().copied().unwrap_or(f.cv_mean_3d),
            f.floor_mean_3d
        );
        if let Some(t) = target_mm {
            s += &match f.verdict(t) {
                Verdict::Met => format!("target {t} mm: already met\n"),
                Verdict::After(k) => format!(
                    "target {t} mm: expected after {k} more poses ({} in all)\n",
                    f.measured + k
                ),
                Verdict::BeyondPlan => format!(
                    "target {t} mm: not within these {measured} poses; plan a larger budget\n"
                ),
                Verdict::Unreachable => format!(
                    "target {t} mm: unreachable — below the repeatability floor of {:.4} mm; \
                     more poses will not get there\n",
                    f.floor_mean_3d
                ),
            };
        }
    } else if target_mm.is_some() {
        s += "target: no forecast without a measured campaign (measure the first batch)\n";
    }
    for n in &plan.notes {
        s += &format!("note: {n}\n");
    }
    s
}

/// The plan's summary as JSON: where the hyperparameters came from, the
/// candidates, the chosen rows in the order chosen, the moves' measure
/// flags, the IMSE curve (mm²), the unrealised directions, the passes and
/// how far the order follows the joint space, the notes and,
/// with a measured campaign, the forecast.
pub fn json(plan: &Plan, forecast: Option<&Forecast>) -> serde_json::Value {
    serde_json::json!({
        "source": format!("{:?}", plan.source).to_lowercase(),
        "candidates": plan.candidates,
        "chosen": plan.chosen,
        "measure": plan.moves.iter().map(|m| m.measure).collect::<Vec<_>>(),
        "imse_curve_mm2": plan.imse_curve,
        "unrealised": plan.unrealised,
        "passes": plan.passes,
        "order_in_joint_space": plan.order_in_joint_space,
        "notes": plan.notes,
        "forecast": forecast.map(|f| serde_json::json!({
            "measured": f.measured,
            "cv_mean_3d_mm": f.cv_mean_3d,
            "region_ratio": f.region_ratio,
            "floor_mean_3d_mm": f.floor_mean_3d,
            "floor_identified": f.floor_identified,
            "mean_3d_mm": f.mean_3d,
        })),
    })
}
