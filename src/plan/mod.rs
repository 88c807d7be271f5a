//! Planning a measurement campaign: which poses to measure next, from which
//! side each joint arrives, in which order, and when to stop.
//!
//! One call plans one stretch of a sequential design:
//!
//! 1. **Candidates**: poses drawn in the robot's working ranges with a λ
//!    per joint ([`candidates::draw`]) — and as many around a task's poses
//!    ([`candidates::around`]) — or the poses of a pool; those the tracker
//!    cannot see are dropped ([`TrackerView`]).
//! 2. **Region**: the poses whose prediction error matters — a task's
//!    poses ([`Region::Poses`], task-specific calibration), the pool's, or
//!    by default a sample of the working ranges.
//! 3. **Hyperparameters**: re-estimated on the measured campaign when
//!    there is one (the default error model, calibrated when a robot is
//!    given); else those of a prior model (a robot of the same type),
//!    conditioned on whatever has been measured; else unknown — the first
//!    batch covers the region ([`candidates::covering`]) and the next
//!    call, with its measurements, plans by the model.
//! 4. **Choice**: with hyperparameters, the budget is chosen greedily by the
//!    largest reduction of the region's integrated MSE (`imse`), summed over
//!    the three axes, in output units (mm²). A calibrated model adds its
//!    calibration's share (`calibration`): the parameters' posterior
//!    covariance, conditioned on each chosen pose like the Kriging
//!    outputs.
//! 5. **Order** ([`order::in_passes`]): a greedy tour from the robot's
//!    current pose (in one pass by default, or in several, each over the
//!    region), with a pre-position move wherever the direct move would not
//!    realise the planned λ. The plan says when its order follows the joint
//!    space ([`Plan::order_in_joint_space`]): `diagnose` could not tell an
//!    order effect from a pose effect on such a campaign.
//!
//! [`Plan::imse_curve`] records the region's integrated MSE after each
//! chosen pose: the model's own forecast of how the error falls with the
//! number of poses ([`stop`] turns it into a held-out error forecast).

mod calibration;
pub mod candidates;
mod imse;
mod io;
pub mod order;
pub mod stop;

pub use candidates::{PoseSet, TrackerView};
pub use order::PlannedMove;

use crate::cancel::Cancel;
use crate::dataset::Dataset;
use crate::diagnose::OrderInJointSpace;
use crate::kinematics::Robot;
use crate::methods::default_params;
use crate::model::ErrorModel;
use crate::{Error, Result};
use calibration::CalibrationDesign;
use imse::AxisDesign;

/// The region whose prediction error a plan lowers.
#[derive(Debug, Clone, PartialEq)]
pub enum Region {
    /// A sample of the robot's working ranges, both directions of every
    /// joint equally likely.
    WorkRange,
    /// These poses (a task, a trajectory's joint solutions, a pool).
    Poses(PoseSet),
}

/// Rows of a measured campaign from which the hyperparameters are
/// re-estimated; below it a prior model's are used (or the batch is
/// space-filling).
pub const MIN_FIT_ROWS: usize = 30;

/// Candidates around a task's poses move each joint by at most this
/// fraction of its range ([`candidates::around`]).
pub const AROUND_SPREAD: f64 = 0.05;

/// What to plan, set by builder methods; [`PlanParams::check`] validates.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanParams {
    budget: usize,
    first_batch: usize,
    candidates: usize,
    region_points: usize,
    via_step: f64,
    passes: usize,
    tracker: Option<TrackerView>,
    seed: u64,
    calibration_share: bool,
    cancel: Cancel,
}

impl PlanParams {
    /// Plan `budget` poses: 5 000 candidates drawn, 1 000 region points, a
    /// first space-filling batch of at most 50, via-points 5° (5 mm) back,
    /// no tracker constraint, seed 1.
    pub fn new(budget: usize) -> Self {
        PlanParams {
            budget,
            first_batch: 50,
            candidates: 5000,
            region_points: 1000,
            via_step: 5.0,
            passes: 1,
            tracker: None,
            seed: 1,
            calibration_share: true,
            cancel: Cancel::never(),
        }
    }

    /// Whether a calibrated model's IMSE counts the calibration's parameter
    /// uncertainty as well as its Kriging outputs' (default: yes; without
    /// it the design sees the Kriging part alone).
    pub fn calibration_share(mut self, on: bool) -> Self {
        self.calibration_share = on;
        self
    }

    /// Poses of the first, space-filling batch when no hyperparameter is
    /// known yet.
    pub fn first_batch(mut self, n: usize) -> Self {
        self.first_batch = n;
        self
    }

    /// Candidates drawn in the working ranges (without a pool).
    pub fn candidates(mut self, n: usize) -> Self {
        self.candidates = n;
        self
    }

    /// Points of the region the integrated MSE averages over (a larger
    /// region is thinned evenly to this many).
    pub fn region_points(mut self, n: usize) -> Self {
        self.region_points = n;
        self
    }

    /// How far back a pre-position move starts, degrees (mm for prismatic
    /// joints).
    pub fn via_step(mut self, step: f64) -> Self {
        self.via_step = step;
        self
    }

    /// Measure the poses in `passes` passes over the region
    /// ([`order::in_passes`]); default 1: one tour of all of them, the
    /// shortest path.
    pub fn passes(mut self, passes: usize) -> Self {
        self.passes = passes;
        self
    }

    /// Plan only poses this tracker sees (all poses for `None`).
    pub fn tracker(mut self, view: impl Into<Option<TrackerView>>) -> Self {
        self.tracker = view.into();
        self
    }

    /// Seed of the candidates and of the region sample.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// The token that stops the planning ([`crate::cancel`]): read by the
    /// fit of the hyperparameters, between the outputs' designs and
    /// between the poses chosen; a cancelled plan returns
    /// [`Error::Interrupted`].
    pub fn cancel(mut self, token: Cancel) -> Self {
        self.cancel = token;
        self
    }

    /// Check the parameters.
    pub fn check(self) -> Result<ValidPlanParams> {
        let bad = |what: &str| Err(Error::InvalidParameter(what.into()));
        if self.budget == 0 {
            return bad("the budget must be at least one pose");
        }
        if self.first_batch == 0 || self.candidates == 0 || self.region_points == 0 {
            return bad("the first batch, the candidates and the region points must be positive");
        }
        if !(self.via_step.is_finite() && self.via_step > 0.0) {
            return bad("the via-point step must be a positive angle (degrees) or length (mm)");
        }
        if self.passes == 0 {
            return bad("--passes (passes=) must be at least 1");
        }
        Ok(ValidPlanParams(self))
    }
}

/// [`PlanParams`] that passed [`PlanParams::check`].
#[derive(Debug, Clone, PartialEq)]
pub struct ValidPlanParams(PlanParams);

/// Where the hyperparameters of a plan came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HyperSource {
    /// Estimated on the measured campaign.
    Campaign,
    /// A prior model's (conditioned on the campaign's poses, if any).
    Prior,
    /// None yet: a space-filling batch.
    SpaceFilling,
}

/// A planned stretch of a campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The moves in order: measured poses and via-points.
    pub moves: Vec<PlannedMove>,
    /// The chosen candidates in the order chosen (indices into the
    /// candidates: the pool's rows with a pool).
    pub chosen: Vec<usize>,
    /// The chosen poses with their planned λ, in the order chosen.
    pub poses: PoseSet,
    /// Where the hyperparameters came from.
    pub source: HyperSource,
    /// The region's integrated MSE (mm², summed over x, y, z) before the
    /// plan and after each chosen pose (empty for a space-filling batch).
    pub imse_curve: Vec<f64>,
    /// Whether `imse_curve` counts the calibration's share (a calibrated
    /// model planned with [`PlanParams::calibration_share`]) besides the
    /// Kriging outputs': the stopping rule ([`stop::Forecast`]) then counts
    /// it in the held-out MSE it compares the curve with.
    pub imse_counts_calibration: bool,
    /// Candidates considered (after the tracker's line of sight).
    pub candidates: usize,
    /// Measured poses whose planned λ the order could not realise (a joint
    /// at its limit).
    pub unrealised: usize,
    /// Passes over the region the poses are measured in
    /// ([`order::in_passes`]).
    pub passes: usize,
    /// How far the order of the measured poses follows the joint space
    /// (`None`: too few poses to tell): where it does, `diagnose` on the
    /// campaign cannot tell an order effect from a pose effect.
    pub order_in_joint_space: Option<OrderInJointSpace>,
    /// The model the plan used (re-estimated, or the prior refitted).
    pub model: Option<ErrorModel>,
    /// What the user should know.
    pub notes: Vec<String>,
}

/// What a plan starts from.
#[derive(Debug, Clone, Copy)]
pub struct PlanInputs<'a> {
    /// The robot: working ranges, limits, home pose, nominal kinematics.
    pub robot: &'a Robot,
    /// What has been measured (errors needed for the hyperparameters).
    pub campaign: Option<&'a Dataset>,
    /// A prior model (e.g. of a robot of the same type).
    pub prior: Option<&'a ErrorModel>,
    /// Choose among these poses only (their errors, if any, are ignored).
    pub pool: Option<&'a Dataset>,
    /// The region that matters.
    pub region: &'a Region,
}

impl ValidPlanParams {
    /// The parameters.
    pub fn params(&self) -> &PlanParams {
        &self.0
    }

    /// Plan the next poses.
    pub fn plan(&self, inputs: &PlanInputs) -> Result<Plan> {
        let p = &self.0;
        let robot = inputs.robot;
        let n = robot.dof();
        let ranges = working_ranges(robot);
        let step = vec![p.via_step; n];
        let measured = measured_poses(robot, inputs.campaign)?;
        let mut notes = Vec::new();
        let (cand, cand_rows) =
            self.candidate_set(inputs, &ranges, &step, &measured, &mut notes)?;
        if cand.is_empty() {
            return Err(Error::InvalidParameter(format!(
                "no candidate pose is left to plan{}",
                if notes.is_empty() {
                    String::new()
                } else {
                    format!(": {}", notes.join("; "))
                }
            )));
        }
        let (model, source) = self.hyperparameters(inputs, &mut notes)?;
        let region = self.region_set(inputs.region, &ranges, &robot.limits, &step, n)?;
        p.cancel.check()?;
        let (chosen, imse_curve, imse_counts_calibration) = match &model {
            Some(m) => {
                let k = p.budget.min(cand.len());
                choose_by_imse(m, &cand, &region, k, p.calibration_share, &p.cancel)?
            }
            None => {
                let k = p.budget.min(p.first_batch);
                if k < p.budget {
                    notes.push(format!(
                        "no hyperparameters yet: planned a space-filling first batch of {k} of the \
                         {} poses; measure it, then plan the rest with --campaign",
                        p.budget
                    ));
                }
                let chosen = candidates::covering(&cand, &region, &measured, &ranges, k);
                (chosen, Vec::new(), false)
            }
        };
        let wanted = if model.is_some() {
            p.budget
        } else {
            p.budget.min(p.first_batch)
        };
        if chosen.len() < wanted {
            notes.push(format!(
                "only {} candidates: planned {} of {} poses",
                cand.len(),
                chosen.len(),
                wanted
            ));
        }
        let poses = cand.select(&chosen);
        let (start, start_dir) = match measured.q.last() {
            Some(q) => (
                q.clone(),
                measured.dir.last().cloned().unwrap_or(vec![1.0; n]),
            ),
            None => (robot.home.clone(), vec![1.0; n]),
        };
        let order::Tour {
            moves,
            unrealised,
            at_limit,
            passes,
        } = order::in_passes(
            &poses,
            p.passes,
            (&start, &start_dir),
            &ranges,
            &robot.limits,
            &step,
        );
        let measured_q: Vec<Vec<f64>> = moves
            .iter()
            .filter(|m| m.measure)
            .map(|m| m.q.clone())
            .collect();
        let order_in_joint_space = OrderInJointSpace::measure(&measured_q);
        let remedy = if passes == 1 {
            "; measuring in passes over the region (`--passes K`, Python `passes=K`) spreads each stretch of the order over it"
        } else {
            "; more passes spread each stretch of the order over the region"
        };
        if let Some(text) = order_in_joint_space
            .as_ref()
            .and_then(|o| o.plan_text(remedy))
        {
            notes.push(text);
        }
        if at_limit.iter().any(|&c| c > 0) {
            let prismatic = robot.prismatic_joints();
            let joints: Vec<String> = at_limit
                .iter()
                .enumerate()
                .filter(|(_, c)| **c > 0)
                .map(|(j, c)| format!("q{} in {c}", j + 1))
                .collect();
            // one step for every joint: one unit, unless they differ
            let unit = match (prismatic.iter().all(|p| *p), prismatic.iter().any(|p| *p)) {
                (all, any) if all || !any => crate::kinematics::unit_suffix(all),
                _ => " (degrees, mm for prismatic joints)",
            };
            notes.push(format!(
                "pre-position moves go to a joint's hard limit where --via-step {}{unit} back would leave it: {} of the {} via-points; a smaller --via-step keeps them inside",
                p.via_step,
                joints.join(", "),
                moves.iter().filter(|m| !m.measure).count()
            ));
        }
        Ok(Plan {
            moves,
            chosen: chosen.iter().map(|&i| cand_rows[i]).collect(),
            poses,
            source,
            imse_curve,
            imse_counts_calibration,
            candidates: cand.len(),
            unrealised,
            passes,
            order_in_joint_space,
            model,
            notes,
        })
    }

    /// The candidates (and the row each came from): the pool's rows not
    /// measured, or poses drawn in the working ranges; only those the
    /// tracker sees.
    fn candidate_set(
        &self,
        inputs: &PlanInputs,
        ranges: &[(f64, f64)],
        step: &[f64],
        measured: &PoseSet,
        notes: &mut Vec<String>,
    ) -> Result<(PoseSet, Vec<usize>)> {
        let p = &self.0;
        let robot = inputs.robot;
        let all = match inputs.pool {
            Some(pool) => {
                robot.check_dataset(pool)?;
                PoseSet::from(pool)
            }
            None => {
                let mut all = candidates::draw(ranges, &robot.limits, step, p.candidates, p.seed);
                // a task's poses: as many candidates again around them
                if let Region::Poses(task) = inputs.region {
                    let near = candidates::around(
                        task,
                        ranges,
                        &robot.limits,
                        step,
                        AROUND_SPREAD,
                        p.candidates,
                        p.seed,
                    );
                    all.q.extend(near.q);
                    all.dir.extend(near.dir);
                }
                all
            }
        };
        let key =
            |q: &[f64], d: &[f64]| -> Vec<u64> { q.iter().chain(d).map(|v| v.to_bits()).collect() };
        let done: std::collections::HashSet<Vec<u64>> = measured
            .q
            .iter()
            .zip(&measured.dir)
            .map(|(q, d)| key(q, d))
            .collect();
        // why each pose left out is: measured, beyond the limits, unseen
        let mut dropped = [0usize; 3];
        let rows: Vec<usize> = (0..all.len())
            .filter(|&i| {
                let (q, d) = (&all.q[i], &all.dir[i]);
                let why = if done.contains(&key(q, d)) {
                    Some(0)
                } else if !robot.within_limits(q) {
                    Some(1)
                } else if !p.tracker.as_ref().is_none_or(|t| t.sees(robot, q)) {
                    Some(2)
                } else {
                    None
                };
                if let Some(k) = why {
                    dropped[k] += 1;
                }
                why.is_none()
            })
            .collect();
        // a pool's poses left out are the user's: say how many and why (the
        // drawn candidates are drawn within the limits)
        let source = if inputs.pool.is_some() {
            "of the pool's poses"
        } else {
            "candidates"
        };
        let reasons = [
            "already measured",
            "outside the robot's joint limits",
            "not seen by the tracker",
        ];
        for (n, why) in dropped.into_iter().zip(reasons) {
            if n > 0 && (inputs.pool.is_some() || rows.is_empty()) {
                notes.push(format!("{n} {source} {why}, left out"));
            }
        }
        Ok((all.select(&rows), rows))
    }

    /// The model whose hyperparameters the plan uses, and where they came
    /// from.
    fn hyperparameters(
        &self,
        inputs: &PlanInputs,
        notes: &mut Vec<String>,
    ) -> Result<(Option<ErrorModel>, HyperSource)> {
        let measured = inputs
            .campaign
            .filter(|c| c.errors.is_some() && !c.is_empty());
        if let Some(c) = measured.filter(|c| c.len() >= MIN_FIT_ROWS) {
            if inputs.prior.is_some() {
                notes.push(format!(
                    "the prior model is not used: the {} measured poses re-estimate the \
                     hyperparameters (a prior is used below {MIN_FIT_ROWS})",
                    c.len()
                ));
            }
            let params = default_params(inputs.robot, c)?.cancel(self.0.cancel.clone());
            return Ok((Some(params.check()?.fit(c)?), HyperSource::Campaign));
        }
        if let Some(prior) = inputs.prior {
            let model = match measured {
                Some(c) => prior.refit(c)?,
                None => prior.clone(),
            };
            if measured.is_none() {
                notes.push(
                    "the prior model's hyperparameters, with nothing of this robot measured yet"
                        .into(),
                );
            }
            return Ok((Some(model), HyperSource::Prior));
        }
        if let Some(c) = measured {
            notes.push(format!(
                "{} measured poses are too few to estimate hyperparameters (at least {MIN_FIT_ROWS})",
                c.len()
            ));
        }
        Ok((None, HyperSource::SpaceFilling))
    }

    /// The region's points: the given poses thinned, or a sample of the
    /// working ranges.
    fn region_set(
        &self,
        region: &Region,
        ranges: &[(f64, f64)],
        limits: &[(f64, f64)],
        step: &[f64],
        n: usize,
    ) -> Result<PoseSet> {
        let p = &self.0;
        let set = match region {
            Region::Poses(set) => set.thinned(p.region_points),
            Region::WorkRange => {
                candidates::draw(ranges, limits, step, p.region_points, p.seed ^ 0x5eed)
            }
        };
        if set.is_empty() || set.q.iter().any(|q| q.len() != n) {
            return Err(Error::InvalidParameter(format!(
                "the region needs at least one pose of {n} joints"
            )));
        }
        Ok(set)
    }
}

/// The working ranges of `robot` (its joint limits where a range is empty).
fn working_ranges(robot: &Robot) -> Vec<(f64, f64)> {
    robot
        .work_ranges
        .iter()
        .zip(&robot.limits)
        .map(|(w, l)| if w.1 > w.0 { *w } else { *l })
        .collect()
}

/// The measured poses of a campaign (none without one).
fn measured_poses(robot: &Robot, campaign: Option<&Dataset>) -> Result<PoseSet> {
    match campaign {
        Some(c) => {
            robot.check_dataset(c)?;
            Ok(PoseSet::from(c))
        }
        None => Ok(PoseSet::default()),
    }
}

/// Choose `k` candidates greedily by the largest reduction of the region's
/// integrated MSE summed over the model's outputs (and, with
/// `calibration_share`, its calibration's); the IMSE before and after each
/// choice. `cancel` is read after each output's design and each
/// choice.
fn choose_by_imse(
    model: &ErrorModel,
    cand: &PoseSet,
    region: &PoseSet,
    k: usize,
    calibration_share: bool,
    cancel: &Cancel,
) -> Result<(Vec<usize>, Vec<f64>, bool)> {
    let map = model.input_map();
    if !map.extras().is_empty() {
        return Err(Error::InvalidParameter(
            "planning needs a model of the joints and directions only (this one has extra inputs)"
                .into(),
        ));
    }
    let sc = map.encode(&cand.q, &cand.dir)?;
    let sz = map.encode(&region.q, &region.dir)?;
    let mut axes: Vec<AxisDesign> = model
        .outputs()
        .iter()
        .map(|o| cancel.check().and_then(|()| AxisDesign::new(o, &sc, &sz)))
        .collect::<Result<_>>()?;
    let mut cal = match model.calibration().filter(|_| calibration_share) {
        Some(c) => Some(CalibrationDesign::new(c, cand, region)?),
        None => None,
    };
    let imse = |axes: &[AxisDesign], cal: &Option<CalibrationDesign>| {
        axes.iter().map(AxisDesign::imse).sum::<f64>() + cal.as_ref().map_or(0.0, |c| c.imse())
    };
    let mut curve = vec![imse(&axes, &cal)];
    let mut chosen = Vec::with_capacity(k);
    let mut taken = vec![false; cand.len()];
    let mut gain = vec![0.0; cand.len()];
    for _ in 0..k {
        cancel.check()?;
        gain.iter_mut().for_each(|g| *g = 0.0);
        for a in &axes {
            a.gains(&mut gain);
        }
        if let Some(c) = &cal {
            c.gains(&mut gain);
        }
        let best = candidates::best_untaken(&gain, &taken).expect("a candidate left");
        taken[best] = true;
        chosen.push(best);
        for a in &mut axes {
            a.choose(best);
        }
        if let Some(c) = &mut cal {
            c.choose(best);
        }
        curve.push(imse(&axes, &cal));
    }
    Ok((chosen, curve, cal.is_some()))
}
