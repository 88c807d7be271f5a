//! A plan measured in one tour against the same poses in passes over the
//! region: how far the order follows the joint space (the measure
//! `diagnose` reports), and what the passes cost in motion.
//!
//! ```sh
//! cargo run --release --example plan_passes
//! ```
//!
//! Space-filling plans of 300 poses (1 500 candidates, 300 region points,
//! seed 1) on the COMAU NJ220 and the UR10, in 1, 2 and 6 passes. The
//! motion is the largest joint move of each move, summed: what the time of
//! a tour of point-to-point moves follows.

use robokrige::plan::{PlanInputs, PlanParams, Region};

fn main() -> robokrige::Result<()> {
    for name in ["comau-nj220", "ur10"] {
        let robot = robokrige::kinematics::preset(name)?;
        let region = Region::from_options(None, None, &robot)?;
        for passes in [1, 2, 6] {
            let plan = PlanParams::new(300)
                .first_batch(300)
                .candidates(1500)
                .region_points(300)
                .passes(passes)
                .check()?
                .plan(&PlanInputs {
                    robot: &robot,
                    campaign: None,
                    prior: None,
                    pool: None,
                    region: &region,
                })?;
            let motion: f64 = plan
                .moves
                .windows(2)
                .map(|w| {
                    w[0].q
                        .iter()
                        .zip(&w[1].q)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max)
                })
                .sum();
            let order = plan
                .order_in_joint_space
                .as_ref()
                .map_or(f64::NAN, |o| o.order_correlation);
            println!(
                "{name}, {passes} pass(es): order correlation {order:.2}, {} via-points, motion {motion:.0}°",
                plan.moves.iter().filter(|m| !m.measure).count()
            );
        }
    }
    Ok(())
}
