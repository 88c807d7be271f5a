//! The joint CSV of a program: `id,q1..qN,measure`, and `label` when a pose
//! has one.
//!
//! `id` is the move's 0-based index, `q1..qN` its joints in degrees (mm for
//! a prismatic joint) at full precision, `measure` 1 for a measured pose and
//! 0 for a via-point. The file reads back as a robokrige pose list
//! (`measure` a covariate, `label` a text column).

use super::ProgramPose;

/// The CSV text of checked `poses`.
pub(super) fn render(poses: &[ProgramPose]) -> String {
    let n = poses[0].q.len();
    let labelled = poses.iter().any(|p| p.label.is_some());
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec!["id".to_string()];
    header.extend((1..=n).map(|k| format!("q{k}")));
    header.push("measure".into());
    if labelled {
        header.push("label".into());
    }
    // writing to a Vec cannot fail
    w.write_record(&header).expect("CSV into memory");
    for (i, p) in poses.iter().enumerate() {
        let mut rec = vec![i.to_string()];
        rec.extend(p.q.iter().map(|v| (v + 0.0).to_string()));
        rec.push(if p.measure { "1" } else { "0" }.into());
        if labelled {
            rec.push(p.label.clone().unwrap_or_default());
        }
        w.write_record(&rec).expect("CSV into memory");
    }
    let bytes = w.into_inner().expect("CSV into memory");
    String::from_utf8(bytes).expect("CSV of ASCII labels and numbers")
}
