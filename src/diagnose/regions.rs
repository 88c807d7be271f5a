//! Order effects that are regions of the joint space. A campaign measured
//! region by region (a block of poses, then the next) ties its measurement
//! order to the pose: a step of the rows is then also a region of the
//! joint space, which the model of the poses fits as a function of the
//! pose, and no test on this campaign can tell one from the other.
//!
//! **The measure.** Each row's [`NEIGHBOURS`] nearest other poses
//! (Euclidean in the joint angles, degrees; a repeat of the same pose,
//! within [`SAME_POSE_DEG`] on every joint, is not a neighbour: measured
//! again in a row, it would make any order look regional) stand for its
//! region. A set of
//! rows (a step's rows after it, a block's rows) is a region of the joint
//! space to the degree its indicator correlates with the share of each
//! row's neighbours that are inside too ([`region_overlap`]): 1 when the
//! rows are a region of their own, near 0 when they are spread over the
//! workspace. The order as a whole follows the joint space to the degree
//! the row index correlates with the mean index of each row's neighbours
//! ([`OrderInJointSpace::order_correlation`]). Both are read against
//! [`SAME_RESIDUAL`], the correlation from which two explanations are the
//! same residual.
//!
//! On the public UR10 data, first 600 rows: on series B (joint
//! configurations, measured region by region) a step is a region at 473
//! of the 540 rows a step is scanned at, and steps and blocks planted
//! there at 1× the noise were taken by the model of the poses; on series
//! C (random poses) at 84 of them, late in those rows.

use super::confound::SAME_RESIDUAL;
use super::scan::step_rows;
use serde::{Deserialize, Serialize};

/// Nearest poses in joint space a row's region indicator is averaged over.
pub const NEIGHBOURS: usize = 5;

/// Two poses within this many degrees (mm for a prismatic joint) on every
/// joint are the same pose measured again, not neighbours.
pub const SAME_POSE_DEG: f64 = 0.1;

/// How far a campaign's measurement order follows its joint space
/// (the measure: [`region_overlap`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OrderInJointSpace {
    /// Correlation of each row's index with the mean index of its
    /// [`NEIGHBOURS`] nearest poses: 1 for a campaign measured region by
    /// region, near 0 for a random order.
    pub order_correlation: f64,
    /// The rows (0-based, as a step's `row`) from which a step is a region
    /// of the joint space (its [`region_overlap`] at least
    /// [`SAME_RESIDUAL`]), as inclusive ranges `[from, to]`, among the
    /// rows a step is scanned at.
    pub step_rows: Vec<[usize; 2]>,
    /// The rows a step is scanned at, how many (the campaign rows they
    /// span, when a diagnosis scanned a subset of them).
    pub scanned: usize,
}

impl OrderInJointSpace {
    /// Measure the campaign of poses `q` (in measurement order), a step
    /// scanned at every row but a margin at either end, as `diagnose`
    /// scans it; `None` when it has too few rows to have neighbours.
    pub fn measure(q: &[Vec<f64>]) -> Option<Self> {
        Self::measure_at(q, |t| t)
    }

    /// [`measure`](Self::measure) of the rows `q` a diagnosis scanned,
    /// `row(t)` the campaign row of scanned row `t`: the ranges are
    /// campaign rows.
    pub(super) fn measure_at(q: &[Vec<f64>], row: impl Fn(usize) -> usize) -> Option<Self> {
        let m = q.len();
        if m <= 2 * NEIGHBOURS {
            return None;
        }
        let near = nearest(q);
        let index: Vec<f64> = (0..m).map(|i| i as f64).collect();
        let mean_index: Vec<f64> = near
            .iter()
            .map(|n| n.iter().sum::<usize>() as f64 / n.len().max(1) as f64)
            .collect();
        let steps = step_rows(m);
        // in campaign rows, as the ranges
        let scanned = match (steps.start, steps.end) {
            (a, b) if b > a => row(b - 1) - row(a) + 1,
            _ => 0,
        };
        let mut ranges: Vec<[usize; 2]> = Vec::new();
        let mut last = None;
        let (mut inside, mut scratch) = (vec![false; m], OverlapScratch::default());
        for t in steps {
            for (i, b) in inside.iter_mut().enumerate() {
                *b = i >= t;
            }
            if overlap_with(&near, &inside, &mut scratch) < SAME_RESIDUAL {
                continue;
            }
            match ranges.last_mut() {
                Some(r) if last == Some(t - 1) => r[1] = row(t),
                _ => ranges.push([row(t), row(t)]),
            }
            last = Some(t);
        }
        Some(OrderInJointSpace {
            order_correlation: correlation(&index, &mean_index),
            step_rows: ranges,
            scanned,
        })
    }

    /// How many of the scanned rows a step is a region of the joint space
    /// at (of the campaign's rows within the ranges, when a diagnosis
    /// scanned a subset of them).
    pub fn regional_steps(&self) -> usize {
        self.step_rows.iter().map(|[a, b]| b - a + 1).sum()
    }

    /// Whether a step at `row` is a region of the joint space.
    pub fn step_is_regional(&self, row: usize) -> bool {
        self.step_rows.iter().any(|&[a, b]| (a..=b).contains(&row))
    }

    /// Whether the order matters here: the order as a whole, or a step at
    /// some row, follows the joint space.
    pub fn matters(&self) -> bool {
        self.order_correlation >= SAME_RESIDUAL || !self.step_rows.is_empty()
    }

    /// What a diagnosis report says of it, when it
    /// [`matters`](Self::matters).
    pub fn text(&self) -> Option<String> {
        let drift = self.order_correlation >= SAME_RESIDUAL;
        let parts = self.parts(
            &format!(
                "a step at rows {{}} ({} of the {} rows a step is scanned at)",
                self.regional_steps(),
                self.scanned
            ),
            "the row index",
        )?;
        Some(format!(
            "{parts}: there {} of the rows and an effect of the pose can stand for each other (the model of the poses can take an order effect, and a pose effect an order one); measuring in a random order separates them",
            if drift {
                "a step, a block or a drift"
            } else {
                "a step or a block"
            }
        ))
    }

    /// What a plan says of the order of its measured poses, when it
    /// [`matters`](Self::matters): the ranges count the measured poses
    /// from 0 (via-points not counted); `remedy` is the way to more
    /// passes in the caller's words.
    pub fn plan_text(&self, remedy: &str) -> Option<String> {
        let parts = self.parts(
            "a step from measured pose {} on (counted from 0, via-points not counted)",
            "the place of a pose in the order",
        )?;
        Some(format!(
            "the order planned follows the joint space: {parts}; on such a campaign `diagnose` cannot tell a slow change over the measurement (a warm-up, a tracker step) from an effect of the pose{remedy}"
        ))
    }

    /// The figures a text states: the step ranges (into `steps`, whose
    /// `{}` takes them) and the order's correlation (of `index`).
    fn parts(&self, steps: &str, index: &str) -> Option<String> {
        if !self.matters() {
            return None;
        }
        const SHOWN: usize = 3;
        let mut ranges: Vec<String> = self
            .step_rows
            .iter()
            .take(SHOWN)
            .map(|&[a, b]| {
                if a == b {
                    format!("{a}")
                } else {
                    format!("{a}–{b}")
                }
            })
            .collect();
        if self.step_rows.len() > SHOWN {
            let more = self.step_rows.len() - SHOWN;
            ranges.push(format!(
                "{more} more range{}",
                if more == 1 { "" } else { "s" }
            ));
        }
        let mut parts = Vec::new();
        if !self.step_rows.is_empty() {
            parts.push(format!(
                "{} is a region of the joint space (its rows' indicator correlates ≥ {SAME_RESIDUAL} with their {NEIGHBOURS} nearest poses')",
                steps.replacen("{}", &ranges.join(", "), 1)
            ));
        }
        if self.order_correlation >= SAME_RESIDUAL {
            parts.push(format!(
                "{index} follows the joint space (correlation {:.2} with its {NEIGHBOURS} nearest poses' mean)",
                self.order_correlation
            ));
        }
        Some(parts.join(", and "))
    }
}

/// How much a set of rows (`inside[i]`, a step's rows after it or a
/// block's rows) is a region of the joint space: the correlation of its
/// indicator with the share of each row's [`NEIGHBOURS`] nearest other
/// poses (Euclidean in the joint angles, degrees) that are inside too. 1:
/// the rows are a region of their own; near 0: spread over the workspace.
pub fn region_overlap(q: &[Vec<f64>], inside: &[bool]) -> f64 {
    if q.len() <= NEIGHBOURS + 1 || inside.iter().all(|&b| b) || inside.iter().all(|&b| !b) {
        return 0.0;
    }
    overlap_with(&nearest(q), inside, &mut OverlapScratch::default())
}

/// The columns [`overlap_with`] correlates, kept between calls.
#[derive(Default)]
struct OverlapScratch {
    x: Vec<f64>,
    share: Vec<f64>,
}

/// [`region_overlap`] with each row's neighbours `near` known.
fn overlap_with(near: &[Vec<usize>], inside: &[bool], scratch: &mut OverlapScratch) -> f64 {
    let OverlapScratch { x, share } = scratch;
    share.clear();
    share.extend(
        near.iter()
            .map(|n| n.iter().filter(|&&j| inside[j]).count() as f64 / n.len().max(1) as f64),
    );
    x.clear();
    x.extend(inside.iter().map(|&b| if b { 1.0 } else { 0.0 }));
    correlation(x, share)
}

/// Each row's [`NEIGHBOURS`] nearest other poses (ties by index), a repeat
/// of its pose (within [`SAME_POSE_DEG`] on every joint) left out: fewer
/// where fewer other poses are left.
fn nearest(q: &[Vec<f64>]) -> Vec<Vec<usize>> {
    let m = q.len();
    let mut d: Vec<(f64, usize)> = Vec::with_capacity(m);
    (0..m)
        .map(|i| {
            d.clear();
            d.extend(
                (0..m)
                    .filter(|&j| {
                        j != i
                            && q[i]
                                .iter()
                                .zip(&q[j])
                                .any(|(a, b)| (a - b).abs() > SAME_POSE_DEG)
                    })
                    .map(|j| {
                        let s: f64 = q[i].iter().zip(&q[j]).map(|(a, b)| (a - b).powi(2)).sum();
                        (s, j)
                    }),
            );
            let k = NEIGHBOURS.min(d.len());
            if k > 0 && k < d.len() {
                d.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            }
            d[..k].iter().map(|&(_, j)| j).collect()
        })
        .collect()
}

/// Pearson correlation of two columns (0 when one is constant).
fn correlation(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx).powi(2);
        syy += (b - my).powi(2);
    }
    if sxx > 0.0 && syy > 0.0 {
        sxy / (sxx * syy).sqrt()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic scatter of poses, shifted by `shift` on every joint.
    fn pose(i: usize, shift: f64) -> Vec<f64> {
        (0..3)
            .map(|j| ((i * (7 + 3 * j) + 11 * j) % 97) as f64 + shift)
            .collect()
    }

    /// A block of rows measured in its own corner of the joint space is a
    /// region; the same rows spread over the space are not.
    #[test]
    fn a_block_measured_in_its_own_region_overlaps_it() {
        let m = 120;
        let inside: Vec<bool> = (0..m).map(|i| (40..80).contains(&i)).collect();
        let regional: Vec<Vec<f64>> = (0..m)
            .map(|i| pose(i, if inside[i] { 500.0 } else { 0.0 }))
            .collect();
        let spread: Vec<Vec<f64>> = (0..m).map(|i| pose(i, 0.0)).collect();
        assert!(region_overlap(&regional, &inside) > 0.95);
        assert!(region_overlap(&spread, &inside) < SAME_RESIDUAL);
    }

    /// A campaign measured region by region (three regions at seeded
    /// random places and sizes, its poses in order) follows the joint
    /// space, with a step regional around each change of region; the same
    /// poses shuffled do not.
    #[test]
    fn a_campaign_measured_region_by_region_follows_the_joint_space() {
        use rand::{RngExt, SeedableRng, seq::SliceRandom};
        let mut rng = rand::rngs::StdRng::seed_from_u64(29);
        let m = 240;
        let cut = [rng.random_range(50..110), rng.random_range(130..200)];
        let centres: Vec<Vec<f64>> = (0..3)
            .map(|_| (0..6).map(|_| rng.random_range(-150.0..150.0)).collect())
            .collect();
        let mut q: Vec<Vec<f64>> = (0..m)
            .map(|i| {
                let region = cut.iter().filter(|&&c| i >= c).count();
                centres[region]
                    .iter()
                    .map(|c| c + rng.random_range(-20.0..20.0))
                    .collect()
            })
            .collect();
        let o = OrderInJointSpace::measure(&q).unwrap();
        assert!(o.order_correlation > 0.8, "{o:?}");
        for c in cut {
            assert!(o.step_is_regional(c), "{c}: {o:?}");
        }
        assert!(o.text().unwrap().contains("can stand for each other"));
        q.shuffle(&mut rng);
        let o = OrderInJointSpace::measure(&q).unwrap();
        assert!(o.order_correlation < 0.3, "{o:?}");
        assert!(!o.matters(), "{o:?}");
        assert!(o.text().is_none());
        // each pose measured four times in a row: its repeats are not its
        // neighbours, and the order stays as random as the poses'
        let repeated: Vec<Vec<f64>> = q
            .iter()
            .flat_map(|p| std::iter::repeat_n(p.clone(), 4))
            .collect();
        let o = OrderInJointSpace::measure(&repeated).unwrap();
        assert!(!o.matters(), "{o:?}");
    }
}
