//! Bidirectional lookup tables of a rotary axis (seed 000 eqs 3–6, 19).

use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// A quantity tabulated at the indexed angles `θ*_map(i)` of one axis, once
/// per direction of rotation: the angular positioning deviation
/// `Δθ*_map(i, ±1)` (seed 000 eqs 3–6; degrees) or the radial error motion
/// `E_radial,map(i, ±1)` (eq 19; mm).
///
/// Between two indexed angles the value is interpolated linearly (eqs 4–6):
///
/// `v(θ*, λ) = δ·map(i, λ) + (1 − δ)·map(i+1, λ)` … written in the paper with
/// `δ` weighting the *lower* node as `1 − (θ* − θ_i)/(θ_{i+1} − θ_i)`; this
/// type uses the usual `v = map(i) + t·(map(i+1) − map(i))`,
/// `t = (θ* − θ_i)/(θ_{i+1} − θ_i)` (eq 6), which is the same line.
/// Outside the indexed range the end value is held (no extrapolation).
/// λ ≥ 0 reads the `plus` row, λ < 0 the `minus` row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BidirectionalTable {
    /// Indexed command angles `θ*_map(i)`, strictly increasing, degrees.
    pub angles_deg: Vec<f64>,
    /// Values for positive rotation (λ = +1).
    pub plus: Vec<f64>,
    /// Values for negative rotation (λ = −1).
    pub minus: Vec<f64>,
    /// Standard error of one entry when it is a mean of repeated cycles
    /// (pooled over the table), in the table's unit; 0 when unknown.
    #[serde(default)]
    pub entry_se: f64,
}

impl BidirectionalTable {
    /// A checked table: ≥ 2 strictly increasing finite angles, rows of the
    /// same length, finite values.
    pub fn new(angles_deg: Vec<f64>, plus: Vec<f64>, minus: Vec<f64>) -> Result<Self> {
        let t = BidirectionalTable {
            angles_deg,
            plus,
            minus,
            entry_se: 0.0,
        };
        t.validate()?;
        Ok(t)
    }

    /// The checks of [`BidirectionalTable::new`] (also run after loading).
    pub fn validate(&self) -> Result<()> {
        let n = self.angles_deg.len();
        if n < 2 {
            return Err(Error::InvalidParameter(format!(
                "lookup table needs at least 2 indexed angles, got {n}"
            )));
        }
        if self.plus.len() != n || self.minus.len() != n {
            return Err(Error::InvalidParameter(format!(
                "lookup table has {n} angles but {} (+) and {} (−) values",
                self.plus.len(),
                self.minus.len()
            )));
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(&self.angles_deg) || !finite(&self.plus) || !finite(&self.minus) {
            return Err(Error::InvalidParameter(
                "lookup table has a non-finite entry".into(),
            ));
        }
        if let Some(w) = self.angles_deg.windows(2).find(|w| w[1] <= w[0]) {
            return Err(Error::InvalidParameter(format!(
                "lookup table angles must increase strictly ({} then {})",
                w[0], w[1]
            )));
        }
        Ok(())
    }

    /// A table of zeros at `angles_deg`.
    pub fn zeros(angles_deg: Vec<f64>) -> Result<Self> {
        let n = angles_deg.len();
        Self::new(angles_deg, vec![0.0; n], vec![0.0; n])
    }

    /// Interpolated value at command angle `q` (degrees) approached in
    /// direction `dir` (eqs 4–6).
    pub fn at(&self, q: f64, dir: f64) -> f64 {
        let row = if dir >= 0.0 { &self.plus } else { &self.minus };
        let a = &self.angles_deg;
        let n = a.len();
        if q <= a[0] {
            return row[0];
        }
        if q >= a[n - 1] {
            return row[n - 1];
        }
        // eq 5: θ_map(i) ≤ θ* ≤ θ_map(i+1)
        let i = a.partition_point(|&x| x <= q).saturating_sub(1).min(n - 2);
        let t = (q - a[i]) / (a[i + 1] - a[i]); // eq 6
        row[i] + t * (row[i + 1] - row[i])
    }

    /// Half the mean `plus − minus` difference: the mean backlash half-width.
    pub fn mean_half_difference(&self) -> f64 {
        let n = self.plus.len() as f64;
        self.plus
            .iter()
            .zip(&self.minus)
            .map(|(p, m)| 0.5 * (p - m))
            .sum::<f64>()
            / n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_per_direction_and_holds_the_ends() {
        let t = BidirectionalTable::new(vec![0.0, 10.0, 30.0], vec![0.0, 1.0, 3.0], vec![-1.0; 3])
            .unwrap();
        assert_eq!(t.at(5.0, 1.0), 0.5);
        assert_eq!(t.at(20.0, 1.0), 2.0);
        assert_eq!(t.at(10.0, 1.0), 1.0);
        assert_eq!(t.at(20.0, -1.0), -1.0);
        assert_eq!(t.at(-5.0, 1.0), 0.0);
        assert_eq!(t.at(99.0, 1.0), 3.0);
        assert!((t.mean_half_difference() - (0.5 + 1.0 + 2.0) / 3.0).abs() < 1e-12);
    }

    #[test]
    fn rejects_bad_tables() {
        assert!(BidirectionalTable::new(vec![0.0], vec![0.0], vec![0.0]).is_err());
        assert!(BidirectionalTable::new(vec![0.0, 0.0], vec![0.0; 2], vec![0.0; 2]).is_err());
        assert!(BidirectionalTable::new(vec![0.0, 1.0], vec![0.0; 3], vec![0.0; 2]).is_err());
        assert!(
            BidirectionalTable::new(vec![0.0, 1.0], vec![f64::NAN, 0.0], vec![0.0; 2]).is_err()
        );
    }
}
