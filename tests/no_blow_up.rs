//! Issue 16, "done when": on a simulated wide-range campaign (five joints
//! over 180°, as on the real UR10 campaign where universal Kriging with the
//! kinematic trend had 43–46 mm folds), random K-fold CV of every model of
//! `holdout --cv` — the D-H calibration, the hybrids, universal Kriging with
//! the kinematic trend — with the default optimiser and a nugget: no fold's
//! max error may exceed 3× the D-H calibration's max in the same fold.

use robokrige::holdout::{CV_MODELS, holdout_cv};
use robokrige::kinematics::preset;
use robokrige::kriging::KrigingOptions;
use robokrige::sim::{CampaignKind, CampaignSpec, campaign};
use robokrige::space::periodic_joints;

#[test]
fn no_fold_of_a_wide_range_campaign_blows_up() {
    let mut robot = preset("ur10").unwrap();
    robot.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
    let spec = CampaignSpec {
        poses: 400,
        ranges: Some(vec![
            (-175.0, 175.0),
            (-180.0, 0.0),
            (-160.0, 160.0),
            (-200.0, 20.0),
            (-120.0, 120.0),
            (-190.0, 190.0),
        ]),
        ..CampaignSpec::new(CampaignKind::Lhs, 911)
    };
    let data = match campaign::simulate(&robot, &spec).unwrap().0 {
        campaign::SimOutput::Measurements(d) => d,
        campaign::SimOutput::Trajectory(_) => unreachable!("an LHS campaign is measured"),
    };
    let opts = KrigingOptions {
        nugget: true,
        periodic: periodic_joints(&data.q),
        ..KrigingOptions::default()
    };
    // q1, q3, q4, q6 and q2 at 180° exactly is not "over"; four or five
    assert!(opts.periodic.len() >= 4, "{:?}", opts.periodic);
    let cv = holdout_cv(&data, &robot, &opts, 10, 3, 300, &|_, _| {}).unwrap();
    for (f, worst) in cv.fold_max_mm.iter().enumerate() {
        let dh = worst[0];
        eprintln!(
            "fold {f}: max {}",
            worst
                .iter()
                .map(|v| format!("{v:.3}"))
                .collect::<Vec<_>>()
                .join(" / ")
        );
        for (k, v) in worst.iter().enumerate().skip(1) {
            assert!(
                *v <= 3.0 * dh,
                "fold {f}: {} max {v:.3} mm against the D-H calibration's {dh:.3} mm",
                CV_MODELS[k]
            );
        }
    }
    // and the Kriging models do improve on the calibration overall
    let dh_mean = cv.rows[1].mean_mm;
    let best = cv.rows[2..]
        .iter()
        .map(|r| r.mean_mm)
        .fold(f64::MAX, f64::min);
    assert!(
        best < dh_mean,
        "best Kriging {best:.4} mm, D-H {dh_mean:.4} mm"
    );
}
