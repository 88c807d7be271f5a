//! Where the choice of ξ goes in `holdout --cv 10` on a 632-pose UR10
//! campaign of four ISO 9283 cubes of 300 mm (five or six joints wider than
//! 180°, the stress bench's first campaign): the four Kriging models the
//! hold-out compares (calibrated JS and EJS, kinematic trend JS and EJS)
//! fitted once on all rows with the hold-out's defaults (nugget, BFGS,
//! family by CV), each output's wall time, evaluations and families tried.
//!
//! Run: `cargo bench --bench xi_choice` (about half a minute on 2 cores);
//! `-- --csv FILE` writes the campaign as a measurement CSV instead, with
//! a `cube` column for `holdout --groups cube` (for
//! `robokrige holdout FILE --robot ur10 --tool=-0.14,0.30,92.82 --cv 10`).

use robokrige::calibration::{CalibrationOptions, calibrate};
use robokrige::kinematics::{JointKind, load_robot};
use robokrige::kriging::KrigingOptions;
use robokrige::params::{ErrorModelParams, TrendSpec};
use robokrige::sim::iso_cubes::{IsoCubeSpec, iso_cubes, measure_cubes};
use robokrige::sim::{ErrorProfile, TrueRobot};
use robokrige::space::{Space, periodic_joints};
use std::time::Instant;

fn main() -> robokrige::Result<()> {
    let mut robot = load_robot("ur10")?;
    robot.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
    let mut spec = IsoCubeSpec::new(4, 300.0, 158);
    spec.flip_joints = vec![2, 4];
    spec.turn_joints = (0..robot.dof())
        .filter(|&j| robot.links[j].kind == JointKind::Revolute)
        .collect();
    let camp = iso_cubes(&robot, &spec, 2)?;
    let truth = TrueRobot::draw(&robot, &ErrorProfile::for_robot(&robot), 2);
    let mut data = measure_cubes(&truth, camp.q.clone(), 2)?;
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--csv") {
        // the cube of each pose, for `holdout --groups cube`
        data.text.push(robokrige::dataset::TextColumn {
            name: "cube".into(),
            values: camp
                .cube
                .iter()
                .map(|c| format!("cube-{}", c + 1))
                .collect(),
            note: None,
        });
        let path = args.get(i + 1).expect("--csv FILE");
        robokrige::dataset::write_csv(std::path::Path::new(path), &data)?;
        println!("{} poses written to {path}", data.len());
        return Ok(());
    }
    let periodic = periodic_joints(&data.q);
    println!(
        "{} poses, periodic joints {:?}",
        data.len(),
        periodic.iter().map(|j| j + 1).collect::<Vec<_>>()
    );
    let base = ErrorModelParams::new()
        .periodic(periodic)
        .kriging(KrigingOptions::recommended());
    let t = Instant::now();
    let cal = calibrate(&data, &robot, &CalibrationOptions::default())?;
    println!("D-H calibration: {:.2} s", t.elapsed().as_secs_f64());
    let residual = cal.residual(&data)?;
    let mut total = 0.0;
    for (name, space, kinematic) in [
        ("calibrated JS", Space::Js, false),
        ("calibrated EJS", Space::Ejs, false),
        ("kinematic trend JS", Space::Js, true),
        ("kinematic trend EJS", Space::Ejs, true),
    ] {
        let params = base.clone().space(space);
        let (params, rows) = if kinematic {
            let p = params.trend(TrendSpec::Kinematic(Box::new(robot.clone())));
            (p, &data)
        } else {
            (params, &residual)
        };
        let t = Instant::now();
        let model = params.check()?.fit(rows)?;
        let secs = t.elapsed().as_secs_f64();
        total += secs;
        println!("{name}: {secs:.1} s");
        for (a, r) in model.reports().iter().enumerate() {
            let fams: Vec<String> = r
                .families
                .iter()
                .map(|f| format!("{} {:.4}", f.corr, f.cv_rmse))
                .collect();
            println!(
                "  e{}: {:.1} s, {} evaluations, {} starts, {} trend terms, families [{}] -> {}",
                ["x", "y", "z"][a],
                r.seconds,
                r.evals,
                r.starts,
                r.trend_terms.len(),
                fams.join(", "),
                model.outputs()[a].corr()
            );
        }
    }
    println!("four models: {total:.1} s");
    Ok(())
}
