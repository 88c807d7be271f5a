//! Predictions that leave the campaign's coverage are flagged:
//! a joint outside the training range, a standard deviation near the prior,
//! a Kriging correction far from the trend.

use robokrige::dataset::read_csv;
use robokrige::kriging::{KrigingOptions, OptimizerKind};
use robokrige::model::{CoverageIssue, ErrorModel};
use robokrige::space::Space;
use std::path::Path;

#[test]
fn a_pose_far_outside_the_campaign_is_flagged_and_inside_ones_are_not() {
    let d = read_csv(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/datasets/comau_lhs.csv"
    )))
    .unwrap();
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(100)
        .nugget(true);
    let model = ErrorModel::fit(&d, Space::Ejs, &opts).unwrap();
    let (lo, hi) = model.joint_range()[0];
    assert!(lo < hi && hi < 170.0, "campaign range of q1: [{lo}, {hi}]");
    // the training poses themselves, and one pose with q1 = 170°
    let mut q = d.q[..40].to_vec();
    let mut dir = d.dir[..40].to_vec();
    let mut far = d.q[0].clone();
    far[0] = 170.0;
    q.push(far);
    dir.push(d.dir[0].clone());
    let pred = model.predict(&q, &dir).unwrap();
    let warnings = model
        .coverage(&q, &dir, &pred.mean, Some(&pred.std))
        .unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].index, 40);
    let issues = &warnings[0].issues;
    assert!(issues.iter().any(|i| matches!(
        i,
        CoverageIssue::JointRange { joint: 0, value_deg, .. } if *value_deg == 170.0
    )));
    // far from the data the Kriging std is close to the prior
    assert!(
        issues
            .iter()
            .any(|i| matches!(i, CoverageIssue::Uncertain { .. })),
        "{issues:?}"
    );
    // the messages name the joint and the range
    assert!(issues[0].to_string().starts_with("q1 = 170.00°"));
}
