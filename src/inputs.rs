//! The input map of a model: how a pose becomes the normalised input vector
//! the Kriging outputs see.
//!
//! `s = N(E(q, λ) ⊕ f(q, λ, …))`: the space encoding `E` (JS `[θ]` or EJS
//! `[θ, λ]`, seed 003 eq 5, with periodic joints entered as sin/cos), then the
//! extra features `f` that `diagnose` can add, then the normalisation `N`
//! (zero mean, unit standard deviation per column, fitted on the training
//! rows). One type owns that chain, so a fit, a prediction, a CV and a
//! selection encode the same way.
//!
//! The periodic joints are part of the map, not of the Kriging options: a
//! joint `j` in [`InputMap::periodic`] enters as the two columns
//! `(sin θ_j, cos θ_j)` instead of `θ_j`, so that θ and θ ± 360° give the
//! same input. A fit is told them by `params::ErrorModelParams::periodic`;
//! a fitted model keeps its map (`model::ErrorModel::input_map`),
//! and its file stores the map as one field, `inputs` (model file version 3).

use crate::dataset::Dataset;
use crate::features::{Feature, append_columns, trend_only_dims};
use crate::space::{Normalizer, Space};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Space, periodic joints, extra features and the fitted normalisation.
/// Saved with a model as its `inputs` field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputMap {
    space: Space,
    n_joints: usize,
    #[serde(default)]
    periodic: Vec<usize>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    extras: Vec<Feature>,
    names: Vec<String>,
    norm: Normalizer,
}

impl InputMap {
    /// Fit the map on a campaign: the encoding of its rows (extras from its
    /// columns, [`Feature::columns`]) and the normalisation of those rows.
    /// Returns the map and the campaign's normalised inputs (what
    /// [`InputMap::encode_dataset`] would give, computed once). Errors if a
    /// periodic joint does not exist.
    pub fn fit(
        data: &Dataset,
        space: Space,
        periodic: &[usize],
        extras: &[Feature],
    ) -> Result<(Self, Vec<Vec<f64>>)> {
        let n = data.n_joints();
        if let Some(j) = periodic.iter().find(|&&j| j >= n) {
            return Err(Error::InvalidParameter(format!(
                "periodic joint {} does not exist: the data has {n} joints",
                j + 1
            )));
        }
        let mut map = InputMap {
            space,
            n_joints: n,
            periodic: periodic.to_vec(),
            extras: extras.to_vec(),
            names: space.encoded_names(n, periodic),
            norm: Normalizer {
                mean: Vec::new(),
                std: Vec::new(),
            },
        };
        map.names.extend(extras.iter().flat_map(Feature::names));
        let raw = map.raw_dataset(data)?;
        map.norm = Normalizer::fit(&raw);
        let x = map.norm.apply_rows(&raw);
        Ok((map, x))
    }

    /// Check the shape of a map read from a file: periodic joints that
    /// exist (each once), extras valid for the joints, and one name and one
    /// normalisation entry per input column (the space encoding's, then the
    /// extras'). The values of the normalisation are the loader's to check.
    pub(crate) fn check_shape(&self) -> std::result::Result<(), String> {
        let n = self.n_joints;
        for (k, &j) in self.periodic.iter().enumerate() {
            if j >= n || self.periodic[..k].contains(&j) {
                return Err(format!(
                    "periodic joint {} is out of range or repeated ({n} joints)",
                    j + 1
                ));
            }
        }
        if self.extras.iter().any(|f| f.validate(n).is_err()) {
            return Err(format!("an extra input does not fit {n} joints"));
        }
        let dim = self.space_dim() + self.extras.iter().map(|f| f.names().len()).sum::<usize>();
        if self.names.len() != dim || self.norm.mean.len() != dim {
            return Err(format!(
                "{} names and {} normalisation entries for {dim} input columns",
                self.names.len(),
                self.norm.mean.len()
            ));
        }
        Ok(())
    }

    /// The rows of `data` before normalisation.
    fn raw_dataset(&self, data: &Dataset) -> Result<Vec<Vec<f64>>> {
        let mut rows = self.space.encode_rows(&self.periodic, &data.q, &data.dir);
        for f in &self.extras {
            append_columns(&mut rows, &f.columns(data)?);
        }
        Ok(rows)
    }

    /// The normalised inputs of every row of a campaign (extras from its columns).
    pub fn encode_dataset(&self, data: &Dataset) -> Result<Vec<Vec<f64>>> {
        Ok(self.norm.apply_rows(&self.raw_dataset(data)?))
    }

    /// The normalised inputs of poses `q` approached in directions `dir`
    /// (extras from the pose sequence, [`Feature::columns_from_poses`]).
    pub fn encode(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<Vec<f64>>> {
        let mut rows = self.space.encode_rows(&self.periodic, q, dir);
        for f in &self.extras {
            append_columns(&mut rows, &f.columns_from_poses(q, dir)?);
        }
        Ok(self.norm.apply_rows(&rows))
    }

    /// The space.
    pub fn space(&self) -> Space {
        self.space
    }

    /// Joints of the robot.
    pub fn n_joints(&self) -> usize {
        self.n_joints
    }

    /// Joints entered as (sin θ, cos θ), 0-based.
    pub fn periodic(&self) -> &[usize] {
        &self.periodic
    }

    /// The extra features after the space's columns.
    pub fn extras(&self) -> &[Feature] {
        &self.extras
    }

    /// Set the reference of covariate `name` in every extra that reads it
    /// ([`Feature::set_covariate_reference`]); whether any does.
    pub(crate) fn set_covariate_reference(&mut self, name: &str, value: f64) -> bool {
        let mut any = false;
        for f in &mut self.extras {
            any |= f.set_covariate_reference(name, value);
        }
        any
    }

    /// Column names, one per input dimension.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The normalisation.
    pub fn normalizer(&self) -> &Normalizer {
        &self.norm
    }

    /// Input dimensions.
    pub fn dim(&self) -> usize {
        self.names.len()
    }

    /// Dimensions of the correlation: all but the trend-only extras, which
    /// come last.
    pub fn corr_dims(&self) -> usize {
        self.dim() - trend_only_dims(&self.extras)
    }

    /// Dimensions of the space encoding alone (without extras).
    pub fn space_dim(&self) -> usize {
        self.space.encoded_dim(self.n_joints, &self.periodic)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dataset_and_pose_encodings_agree_and_are_normalised() {
        let q: Vec<Vec<f64>> = (0..20)
            .map(|i| vec![i as f64, (i * i) as f64 % 7.0])
            .collect();
        let data = Dataset::from_poses("t", q.clone(), None).unwrap();
        let (map, x) = InputMap::fit(&data, Space::Ejs, &[], &[]).unwrap();
        let a = map.encode_dataset(&data).unwrap();
        assert_eq!(a, x);
        let b = map.encode(&q, &data.dir).unwrap();
        assert_eq!(a, b);
        let mean: f64 = a.iter().map(|r| r[0]).sum::<f64>() / 20.0;
        assert!(mean.abs() < 1e-12);
        assert_eq!(map.dim(), 4);
        assert!(InputMap::fit(&data, Space::Ejs, &[5], &[]).is_err());
    }
}
