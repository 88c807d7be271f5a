//! `holdout`: the table of models, and with `--cv` their predictive scores,
//! worst folds and flagged rows.

use crate::cv::Folds;
use crate::holdout::{CV_MODELS, HoldoutCv, HoldoutRow, HoldoutSplit, HyperRows};
use crate::kriging::OptimizerKind;
use crate::params::ErrorModelParams;
use crate::stats::PredictiveScores;
use std::fmt::Write as _;
use std::path::Path;

/// What `holdout` prints for a split of the campaign `data` into
/// `n_train` training and `n_test` test rows, fitted from `base`: the
/// rows, the Kriging search and nugget, the periodic joints, then the
/// calibration and the table ([`rows`]).
pub fn split(
    data: &Path,
    (n_train, n_test): (usize, usize),
    base: &ErrorModelParams,
    split: &HoldoutSplit,
) -> String {
    let (k, data) = (base.get_kriging(), data.display());
    format!(
        "{data}: train rows 1–{n_train}, test rows {}–{}; Kriging by {}{}; periodic joints (sin/cos): {}\n{}{}",
        n_train + 1,
        n_train + n_test,
        match k.get_optimizer() {
            OptimizerKind::Gps => "GPS",
            OptimizerKind::HookeJeeves => "Hooke–Jeeves",
            OptimizerKind::Bfgs => "BFGS (analytic gradient)",
        },
        if k.get_nugget() {
            ", nugget estimated"
        } else {
            ""
        },
        joint_list(base.get_periodic()),
        super::fit::calibration(&split.calibration),
        rows(&split.rows)
    )
}

/// What the header says of a calibration with the joints' backlash.
fn backlash_note(base: &ErrorModelParams) -> &'static str {
    if base.get_calibration().is_some_and(|c| c.backlash) {
        "; the calibrated models' calibration identifies the joints' backlash"
    } else {
        ""
    }
}

/// What `holdout --cv` (or `--groups`) prints for the `rows` rows of the
/// campaign `data` partitioned by `folds`, fitted from `base`: how, the
/// hyperparameters' rows and time, the periodic joints, then the tables
/// ([`rows`], [`scores`]) and [`cv_tail`].
pub fn cv(
    data: &Path,
    (folds, rows_all): (&Folds, usize),
    base: &ErrorModelParams,
    cv: &HoldoutCv,
) -> String {
    let data = data.display();
    let how = match folds {
        Folds::Random { k, seed } => format!("{k}-fold CV (fold seed {seed})"),
        Folds::Groups(_) => super::cv::how(folds, cv.folds),
    };
    let chosen = match cv.hyper {
        HyperRows::First(n) => format!(
            "once on the first {n} rows{} ({:.1} s), refitted per fold at those values",
            if matches!(folds, Folds::Groups(_)) {
                ", held-out groups included"
            } else {
                ""
            },
            cv.hyper_seconds
        ),
        HyperRows::EachFold => format!(
            "on each fold's training rows ({:.1} s of searches, summed over folds run side by side)",
            cv.hyper_seconds
        ),
    };
    format!(
        "{data}: {how} on all {rows_all} rows; Kriging ξ{} chosen {chosen}; periodic joints: {}{}\n{}{}{}",
        if base.get_kriging().get_nugget() {
            " and nugget"
        } else {
            ""
        },
        joint_list(base.get_periodic()),
        backlash_note(base),
        rows(&cv.rows),
        scores(&cv.scores),
        cv_tail(cv)
    )
}

/// The Markdown table of the models' held-out errors: mean and max 3D,
/// RMS per axis, wall time.
pub fn rows(rows: &[HoldoutRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| model | mean 3D (mm) | max 3D (mm) | RMS x / y / z (mm) | time |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {:.4} | {:.4} | {:.4} / {:.4} / {:.4} | {:.1} s |",
            r.model,
            r.mean_mm,
            r.max_mm,
            r.rms_xyz_mm[0],
            r.rms_xyz_mm[1],
            r.rms_xyz_mm[2],
            r.seconds
        );
    }
    s
}

/// The Markdown table of the models' predictive scores: 95 % coverage per
/// axis, NLPD, the share of rows flagged and of gross errors among them.
pub fn scores(scores: &[PredictiveScores]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| model | 95 % coverage x / y / z | NLPD | flagged | gross errors flagged |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for (name, sc) in CV_MODELS.iter().zip(scores) {
        let _ = writeln!(
            s,
            "| {name} | {} | {:.3} | {:.1} % | {} |",
            super::coverage3(sc),
            sc.nlpd,
            100.0 * sc.flag_rate,
            match sc.flag_recall {
                Some(r) => format!("{:.0} % of {}", 100.0 * r, sc.gross_rows),
                None => "none gross".into(),
            }
        );
    }
    s
}

/// After a hold-out CV's tables: per fold, the worst Kriging model's max
/// error over the D-H calibration's (`f[k≥1].max / f[0]`), and per model
/// the held-out rows flagged as outside its coverage.
pub fn cv_tail(cv: &HoldoutCv) -> String {
    let worst: Vec<String> = cv
        .fold_max_mm
        .iter()
        .map(|f| {
            format!(
                "{:.2}",
                f.iter().skip(1).fold(0.0f64, |a, b| a.max(*b)) / f[0]
            )
        })
        .collect();
    let mut s = format!(
        "worst Kriging model's max over the D-H calibration's max, per fold: {}\n",
        worst.join(" ")
    );
    for (k, (name, (rows, worst))) in CV_MODELS
        .iter()
        .zip(cv.flagged.iter().zip(cv.max_covered_mm()))
        .enumerate()
        .skip(1)
    {
        let all = cv.scores.get(k).is_some_and(|sc| sc.flag_rate >= 1.0);
        if all {
            let _ = writeln!(
                s,
                "{name}: all {} held-out rows flagged as outside the model's coverage",
                rows.len()
            );
        } else if !rows.is_empty() {
            let _ = writeln!(
                s,
                "{name}: {} held-out row(s) flagged as outside the model's coverage (max {worst:.4} mm over the others)",
                rows.len()
            );
        }
        // the gross errors the warning missed, counted from 1 as data rows
        let missed: Vec<String> = cv
            .gross
            .get(k)
            .into_iter()
            .flatten()
            .filter(|i| !rows.contains(i))
            .map(|i| (i + 1).to_string())
            .collect();
        if !missed.is_empty() {
            let _ = writeln!(
                s,
                "{name}: gross errors not flagged at data row(s) {}",
                missed.join(", ")
            );
        }
    }
    s
}

/// `q1, q4` (or `none`): the periodic joints.
pub fn joint_list(periodic: &[usize]) -> String {
    if periodic.is_empty() {
        "none".to_string()
    } else {
        periodic
            .iter()
            .map(|j| format!("q{}", j + 1))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tail_lists_the_gross_errors_the_warning_missed_from_row_1() {
        let mut gross = vec![Vec::new(); 5];
        gross[2] = vec![3, 7];
        gross[3] = vec![4];
        let mut flagged = vec![Vec::new(); 5];
        flagged[2] = vec![3, 5];
        flagged[3] = vec![4];
        let cv = HoldoutCv {
            rows: Vec::new(),
            scores: Vec::new(),
            folds: 1,
            fold_max_mm: vec![[1.0, 1.2, 0.5, 0.9, 0.4]],
            fold_max_covered_mm: vec![[1.0, 1.2, 0.5, 0.9, 0.4]],
            flagged,
            gross,
            hyper: HyperRows::First(10),
            hyper_seconds: 0.0,
        };
        let tail = cv_tail(&cv);
        let missed: Vec<&str> = tail.lines().filter(|l| l.contains("not flagged")).collect();
        assert_eq!(missed.len(), 1, "{tail}");
        assert!(missed[0].starts_with(CV_MODELS[2]), "{tail}");
        assert!(missed[0].ends_with("data row(s) 8"), "{tail}");
        assert!(tail.contains("2 held-out row(s) flagged"), "{tail}");
        // a model that flagged every held-out row (a held-out group) says
        // so, with no "max over the others"
        let score = |flag_rate: f64| PredictiveScores {
            coverage_95: [0.95; 3],
            nlpd: 0.0,
            flag_rate,
            flag_recall: None,
            gross_rows: 0,
        };
        let all = HoldoutCv {
            scores: vec![score(0.0), score(0.5), score(1.0), score(0.5), score(0.0)],
            ..cv
        };
        let tail = cv_tail(&all);
        let line = tail
            .lines()
            .find(|l| l.starts_with(CV_MODELS[2]) && l.contains("flagged as outside"))
            .unwrap();
        assert_eq!(
            line,
            format!(
                "{}: all 2 held-out rows flagged as outside the model's coverage",
                CV_MODELS[2]
            )
        );
    }
}
