//! The model file: versioned JSON, written atomically, checked on load.
//!
//! - Version 4 may hold the kinematic calibration the Kriging outputs sit
//!   on (`calibration`); a file without one is a version-3 model.
//! - Version 3 stores the input map ([`crate::inputs::InputMap`]: space,
//!   joints, periodic joints, extras, column names, normalisation) as one
//!   object, `inputs`.
//! - Version 2 kept those parts at the top level (`space`, `n_joints`,
//!   `input_names`, `input_norm`, `extras`) and the periodic joints in the
//!   options (`options.periodic`); it stopped storing the Cholesky factor
//!   (O(m·d) files; it is recomputed when first needed).
//! - Version 1 stored the factor.
//!
//! Files of versions 1 and 2 load: their parts are moved into `inputs`
//! ([`migrate_to_v3`]) before the model is read, and the model is held (and
//! saved again) as version 3. An older robokrige refuses a version-3 file
//! by its version.

use super::{AXES, ErrorModel, MODEL_FORMAT, MODEL_VERSION, MODEL_VERSION_MIN};
use crate::{Error, Result};
use std::path::Path;

impl ErrorModel {
    /// Write as JSON, atomically. The text is loaded back first: a model
    /// that would not load (e.g. a `y_std` that overflowed to `null`)
    /// is never written.
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = self.to_json()?;
        Self::from_json(&text, &path.display().to_string()).map_err(|e| {
            Error::Numerical(format!(
                "refusing to write {}: the model would not load back ({e})",
                path.display()
            ))
        })?;
        crate::output::write_text(path, &text)
    }

    /// The model file's JSON text.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string(self).map_err(|e| Error::Json {
            context: "model".into(),
            source: e,
        })
    }

    /// The ranges of a loaded model's values (left unchecked, a model file
    /// with ξ < 0, an input scale of 0 or `y_std = 1e308` predicted NaN or
    /// constants). Shapes are checked by the caller; ξ, ν, σ² and
    /// finiteness by [`KrigingModel`]'s own loader.
    fn check_values(&self) -> std::result::Result<(), String> {
        use crate::dataset::{MAX_ABS_ERROR_MM, MAX_ABS_JOINT};
        let n_joints = self.n_joints();
        if n_joints == 0 {
            return Err("n_joints is 0".into());
        }
        self.input_norm()
            .validate(crate::dataset::MAX_ABS_COVARIATE)
            .map_err(|why| format!("inputs.norm: {why}"))?;
        if !self.joint_range.is_empty() && self.joint_range.len() != n_joints {
            return Err(format!(
                "joint_range has {} entries for {n_joints} joints",
                self.joint_range.len(),
            ));
        }
        for (j, &(lo, hi)) in self.joint_range.iter().enumerate() {
            if !(lo.abs() <= MAX_ABS_JOINT && hi.abs() <= MAX_ABS_JOINT && lo <= hi) {
                return Err(format!("joint_range[{j}] = ({lo}, {hi}) is not a range"));
            }
        }
        for (axis, o) in AXES.iter().zip(&self.outputs) {
            let (mean, scale) = o.output_scale();
            if mean.is_nan() || mean.abs() > MAX_ABS_ERROR_MM {
                return Err(format!(
                    "output {axis}: y_mean = {mean:e} mm is not a TCP error"
                ));
            }
            if !(scale > 0.0 && scale <= 2.0 * MAX_ABS_ERROR_MM) {
                return Err(format!(
                    "output {axis}: y_std = {scale:e} mm is not a scale of TCP errors"
                ));
            }
            if o.data.x_train.iter().flatten().any(|v| v.abs() > 1e6) {
                return Err(format!(
                    "output {axis}: a normalised training input is beyond ±1e6"
                ));
            }
        }
        self.options.validate().map_err(|e| format!("options: {e}"))
    }

    /// Read a model saved by [`ErrorModel::save`], checking format and version.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_json(&text, &path.display().to_string())
    }

    /// The D-H calibration held by the model file `path` (fitted with
    /// `fit --robot`); an error names the file when it holds none.
    pub fn load_calibration(path: &Path) -> Result<crate::calibration::Calibration> {
        let model = Self::load(path)?;
        model.calibration().cloned().ok_or_else(|| Error::Input {
            source_name: path.display().to_string(),
            message: "holds no calibration: fit it with --robot (and without --no-calibrate)"
                .into(),
        })
    }

    /// Parse a saved model from JSON text (`source_name` for messages).
    pub fn from_json(text: &str, source_name: &str) -> Result<Self> {
        let head: serde_json::Value = serde_json::from_str(text).map_err(|e| Error::Json {
            context: source_name.into(),
            source: e,
        })?;
        let format = head.get("format").and_then(|v| v.as_str()).unwrap_or("");
        let version = head.get("version").and_then(|v| v.as_u64()).unwrap_or(0);
        let known = u64::from(MODEL_VERSION_MIN)..=u64::from(MODEL_VERSION);
        if format != MODEL_FORMAT || !known.contains(&version) {
            return Err(Error::Input {
                source_name: source_name.into(),
                message: format!(
                    "not a robokrige error model of version {MODEL_VERSION_MIN}–{MODEL_VERSION} (found format '{format}', version {version}); refit it with this version"
                ),
            });
        }
        let mut head = head;
        if version < 3 {
            migrate_to_v3(&mut head);
        }
        let mut model: ErrorModel = serde_json::from_value(head).map_err(|e| Error::Json {
            context: source_name.into(),
            source: e,
        })?;
        let inconsistent = |message: String| Error::Input {
            source_name: source_name.into(),
            message,
        };
        model
            .inputs
            .check_shape()
            .map_err(|why| inconsistent(format!("model file is inconsistent (inputs: {why})")))?;
        let dim = model.inputs.dim();
        if model.outputs.len() != 3 || model.outputs.iter().any(|o| o.dim() != dim) {
            return Err(inconsistent(
                "model file is inconsistent (outputs or input dimension)".into(),
            ));
        }
        model.check_values().map_err(|why| Error::Input {
            source_name: source_name.into(),
            message: format!("model file holds an impossible value: {why}"),
        })?;
        if let Some(c) = &model.calibration {
            c.validate(source_name)?;
            if c.nominal().dof() != model.n_joints() {
                return Err(inconsistent(format!(
                    "model file is inconsistent (a calibration of a {}-joint robot on a {}-joint model)",
                    c.nominal().dof(),
                    model.n_joints()
                )));
            }
        }
        // held in memory (and saved again) in the current form
        model.version = model.file_version();
        Ok(model)
    }
}

/// Rewrite the JSON of a version 1 or 2 model in the version 3 layout: its
/// top-level `space`, `n_joints`, `input_names` (→ `names`), `input_norm`
/// (→ `norm`), `extras` and the options' `periodic` become the object
/// `inputs` (an [`crate::inputs::InputMap`]). Parts it lacks stay missing,
/// and reading the model then names them.
fn migrate_to_v3(head: &mut serde_json::Value) {
    let Some(top) = head.as_object_mut() else {
        return;
    };
    let mut inputs = serde_json::Map::new();
    for (old, new) in [
        ("space", "space"),
        ("n_joints", "n_joints"),
        ("periodic", "periodic"),
        ("extras", "extras"),
        ("input_names", "names"),
        ("input_norm", "norm"),
    ] {
        let part = if old == "periodic" {
            top.get_mut("options")
                .and_then(serde_json::Value::as_object_mut)
                .and_then(|o| o.remove("periodic"))
        } else {
            top.remove(old)
        };
        if let Some(v) = part {
            inputs.insert(new.into(), v);
        }
    }
    top.insert("inputs".into(), serde_json::Value::Object(inputs));
}
