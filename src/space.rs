//! Joint space and extended joint space.
//!
//! JS = `[θ1..θn]`; EJS = `[θ1..θn, λ1..λn]` (seed 003 §II.B). Inputs and
//! outputs are z-scored before modelling (seed 003 §III.A) with a
//! [`Normalizer`] that the fitted model keeps.
//!
//! The direction coefficient of seed 003 eq 5: `λi = +1` for forward motion,
//! `−1` for backward motion of joint i into the pose. For a visited sequence
//! `θ(k)`:
//!
//! `λi(k) = sign(θi(k) − θi(k−1))`; a joint that did not move keeps its
//! previous λ; the first pose's λ comes from the start pose (and is +1 where the
//! joint did not move from it, or when no start pose is known).

/// Joint moves smaller than this (degrees or mm) count as "did not move":
/// far above the round-off of an IK solution (~1e-8°), far below an encoder
/// count (~1e-4°), so a joint held still along an IK-solved path keeps its λ.
pub const MOVE_EPS: f64 = 1e-6;

/// Direction coefficients (±1) for a sequence of joint vectors visited in order.
///
/// `start` is the pose the robot came from before `q[0]`; `None` means unknown,
/// in which case the first pose gets +1 on every joint (the convention of the
/// public UR10 data set). Rows of `q` must all have the same length.
pub fn derive_directions(q: &[Vec<f64>], start: Option<&[f64]>) -> Vec<Vec<f64>> {
    let n = q.first().map_or(0, Vec::len);
    let mut prev_dir = vec![1.0; n];
    let mut prev_q: Option<&[f64]> = start;
    let mut out = Vec::with_capacity(q.len());
    for row in q {
        let mut dir = prev_dir.clone();
        if let Some(p) = prev_q {
            for i in 0..n {
                let step = row[i] - p[i];
                if step > MOVE_EPS {
                    dir[i] = 1.0;
                } else if step < -MOVE_EPS {
                    dir[i] = -1.0;
                }
            }
        }
        prev_q = Some(row);
        prev_dir.clone_from(&dir);
        out.push(dir);
    }
    out
}

use serde::{Deserialize, Serialize};

/// Which input space a model uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Space {
    /// Joint space `[θ1..θn]`.
    #[cfg_attr(feature = "cli", value(help = "Joint space [θ]"))]
    Js,
    /// Extended joint space `[θ1..θn, λ1..λn]`.
    #[cfg_attr(
        feature = "cli",
        value(help = "Extended joint space [θ, λ] (seed 003 §II.B)")
    )]
    Ejs,
}

impl Space {
    /// Input dimension for `n` joints.
    pub fn dim(self, n: usize) -> usize {
        match self {
            Space::Js => n,
            Space::Ejs => 2 * n,
        }
    }

    /// Names of the input columns (`q1..qn`, then `dir1..dirn` for EJS).
    pub fn names(self, n: usize) -> Vec<String> {
        let mut v: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
        if self == Space::Ejs {
            v.extend((1..=n).map(|i| format!("dir{i}")));
        }
        v
    }

    /// One feature row `s` from joint values and directions.
    pub fn row(self, q: &[f64], dir: &[f64]) -> Vec<f64> {
        let mut s = q.to_vec();
        if self == Space::Ejs {
            s.extend_from_slice(dir);
        }
        s
    }

    /// Feature rows for a sequence of poses.
    pub fn rows(self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Vec<Vec<f64>> {
        q.iter().zip(dir).map(|(a, b)| self.row(a, b)).collect()
    }

    /// One row with the joints in `periodic` (0-based) encoded as
    /// `(sin θ, cos θ)` instead of θ, so that θ and θ ± 360° are the same
    /// input and the correlation wraps around: joint columns in
    /// joint order (one or two each), then the λ's for EJS.
    pub fn encode(self, periodic: &[usize], q: &[f64], dir: &[f64]) -> Vec<f64> {
        let mut s = Vec::with_capacity(q.len() + periodic.len() + dir.len());
        for (j, v) in q.iter().enumerate() {
            if periodic.contains(&j) {
                let (sn, cs) = v.to_radians().sin_cos();
                s.push(sn);
                s.push(cs);
            } else {
                s.push(*v);
            }
        }
        if self == Space::Ejs {
            s.extend_from_slice(dir);
        }
        s
    }

    /// [`Space::encode`] for a sequence of poses (`periodic` empty: [`Space::rows`]).
    pub fn encode_rows(
        self,
        periodic: &[usize],
        q: &[Vec<f64>],
        dir: &[Vec<f64>],
    ) -> Vec<Vec<f64>> {
        q.iter()
            .zip(dir)
            .map(|(a, b)| self.encode(periodic, a, b))
            .collect()
    }

    /// Names of the encoded columns (`sin q1`, `cos q1` for a periodic joint).
    pub fn encoded_names(self, n: usize, periodic: &[usize]) -> Vec<String> {
        let mut v = Vec::new();
        for i in 0..n {
            if periodic.contains(&i) {
                v.push(format!("sin q{}", i + 1));
                v.push(format!("cos q{}", i + 1));
            } else {
                v.push(format!("q{}", i + 1));
            }
        }
        if self == Space::Ejs {
            v.extend((1..=n).map(|i| format!("dir{i}")));
        }
        v
    }

    /// Input dimension with `periodic` joints encoded.
    pub fn encoded_dim(self, n: usize, periodic: &[usize]) -> usize {
        self.dim(n) + periodic.iter().filter(|&&j| j < n).count()
    }
}

/// Joints whose range in `q` exceeds half a turn (180°): the automatic choice
/// of periodic joints (a revolute joint that turns that far reaches poses
/// where θ and θ ± 360° are near each other).
pub fn periodic_joints(q: &[Vec<f64>]) -> Vec<usize> {
    let n = q.first().map_or(0, Vec::len);
    (0..n)
        .filter(|&j| {
            let (lo, hi) = q
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), r| (l.min(r[j]), h.max(r[j])));
            hi - lo > 180.0
        })
        .collect()
}

/// Column-wise z-score `(x − μ)/σ` with the sample standard deviation
/// (ddof = 1, as DACE and SMT). A constant column (σ ≤ 1e-12·max(1, |μ|))
/// gets σ = 1 so it maps to 0 instead of dividing by zero.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Normalizer {
    /// Training mean μ of each input column.
    pub mean: Vec<f64>,
    /// Sample standard deviation σ of each column (ddof = 1; 1 for a constant column).
    pub std: Vec<f64>,
}

impl Normalizer {
    /// Check a normaliser read from a file: equal lengths, means within
    /// ±`limit` (the largest input value accepted), and scales that
    /// [`Normalizer::fit`] can give (at most `limit`, more than
    /// `1e-12·max(1, |mean|)`). The message names the first bad entry.
    pub fn validate(&self, limit: f64) -> std::result::Result<(), String> {
        if self.mean.len() != self.std.len() {
            return Err(format!(
                "{} means but {} scales",
                self.mean.len(),
                self.std.len()
            ));
        }
        for (k, (&mu, &s)) in self.mean.iter().zip(&self.std).enumerate() {
            if mu.is_nan() || mu.abs() > limit {
                return Err(format!("mean[{k}] = {mu:e} is not a finite input mean"));
            }
            if !(s.is_finite() && s > 1e-12 * mu.abs().max(1.0) && s <= limit) {
                return Err(format!("std[{k}] = {s:e} is not a valid input scale"));
            }
        }
        Ok(())
    }

    /// Fit on rows (all of equal length; at least one row).
    pub fn fit(rows: &[Vec<f64>]) -> Self {
        let d = rows.first().map_or(0, Vec::len);
        let m = rows.len() as f64;
        let mut mean = vec![0.0; d];
        for r in rows {
            for (a, v) in mean.iter_mut().zip(r) {
                *a += v / m;
            }
        }
        let mut std = vec![0.0; d];
        for r in rows {
            for ((s, v), mu) in std.iter_mut().zip(r).zip(&mean) {
                *s += (v - mu) * (v - mu);
            }
        }
        for (s, mu) in std.iter_mut().zip(&mean) {
            *s = (*s / (m - 1.0).max(1.0)).sqrt();
            if s.is_nan() || *s <= 1e-12 * mu.abs().max(1.0) {
                *s = 1.0;
            }
        }
        Normalizer { mean, std }
    }

    /// Fit on one column of values.
    pub fn fit_column(values: &[f64]) -> Self {
        let rows: Vec<Vec<f64>> = values.iter().map(|v| vec![*v]).collect();
        Normalizer::fit(&rows)
    }

    /// Normalised copy of a row.
    pub fn apply(&self, row: &[f64]) -> Vec<f64> {
        row.iter()
            .zip(self.mean.iter().zip(&self.std))
            .map(|(v, (mu, s))| (v - mu) / s)
            .collect()
    }

    /// Normalised copies of rows.
    pub fn apply_rows(&self, rows: &[Vec<f64>]) -> Vec<Vec<f64>> {
        rows.iter().map(|r| self.apply(r)).collect()
    }
}

/// Periodic joints from a specification: `auto` ([`periodic_joints`] of
/// the rows `q`), `none` (or empty), or 1-based joint numbers `1,4,6`.
/// Returns 0-based joints.
pub fn parse_periodic(spec: &str, q: &[Vec<f64>]) -> crate::Result<Vec<usize>> {
    let n = q.first().map_or(0, Vec::len);
    match spec.trim() {
        "auto" => Ok(periodic_joints(q)),
        "none" | "" => Ok(Vec::new()),
        list => list
            .split(',')
            .map(|t| match t.trim().parse::<usize>() {
                Ok(j) if (1..=n).contains(&j) => Ok(j - 1),
                _ => Err(crate::Error::InvalidParameter(format!(
                    "--periodic '{spec}': expected auto, none or joint numbers 1..{n}"
                ))),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_follow_sign_of_motion_and_hold_when_still() {
        let q = vec![
            vec![0.0, 5.0],
            vec![1.0, 5.0],
            vec![0.5, 5.0],
            vec![0.5, 6.0],
        ];
        let d = derive_directions(&q, Some(&[1.0, 5.0]));
        assert_eq!(d[0], vec![-1.0, 1.0]);
        assert_eq!(d[1], vec![1.0, 1.0]);
        assert_eq!(d[2], vec![-1.0, 1.0]);
        assert_eq!(d[3], vec![-1.0, 1.0]);
        let d = derive_directions(&q, None);
        assert_eq!(d[0], vec![1.0, 1.0]);
    }

    #[test]
    fn normalizer_uses_sample_std_and_survives_constant_columns() {
        let rows = vec![vec![1.0, 5.0], vec![3.0, 5.0]];
        let n = Normalizer::fit(&rows);
        assert_eq!(n.mean, vec![2.0, 5.0]);
        assert!((n.std[0] - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(n.std[1], 1.0);
        assert_eq!(n.apply(&[3.0, 5.0])[1], 0.0);
        assert_eq!(Space::Ejs.row(&[1.0], &[-1.0]), vec![1.0, -1.0]);
        assert_eq!(Space::Ejs.names(2), vec!["q1", "q2", "dir1", "dir2"]);
    }
}
