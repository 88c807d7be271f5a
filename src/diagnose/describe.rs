//! An effect in words: its label with the parameters of its best grid point
//! (and, once added, their 95 % intervals), as every report prints it.

use super::EffectReport;

impl EffectReport {
    /// The label with the parameters of the best grid point, e.g. "step in
    /// the measurement order (at row 150)"; for an added effect each scanned
    /// parameter's 95 % support interval follows it.
    pub fn describe(&self) -> String {
        let params: Vec<String> = self
            .params
            .iter()
            .map(|(k, v)| {
                let text = match k.as_str() {
                    "period_deg" => format!("period {v:.3}°"),
                    "row" => format!("at row {v:.0}"),
                    "from_row" => format!("from row {v:.0}"),
                    "to_row" => format!("to row {v:.0}"),
                    "scale_deg" => format!("scale {v:.1}°"),
                    _ => format!("{k} {}", param(*v)),
                };
                match self.params_ci.get(k) {
                    Some([lo, hi]) if lo < hi && self.accepted => {
                        format!("{text}, 95 %: {}–{}", param(*lo), param(*hi))
                    }
                    _ => text,
                }
            })
            .collect();
        if params.is_empty() {
            self.label.clone()
        } else {
            format!("{} ({})", self.label, params.join(", "))
        }
    }
}

/// A parameter value: whole numbers without decimals, others with three.
fn param(v: f64) -> String {
    if v.fract() == 0.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.3}")
    }
}

#[cfg(test)]
mod tests {
    use super::EffectReport;

    fn effect(params: &str, ci: &str, accepted: bool) -> EffectReport {
        serde_json::from_str(&format!(
            r#"{{"round": 1, "kind": "order", "source": ["row"], "label": "step in the measurement order",
                "params": {params}, "params_ci": {ci}, "score": 0.5, "explained": 0.5, "p_value": 0.001,
                "q_value": 0.01, "significant": true, "accepted": {accepted}}}"#
        ))
        .unwrap()
    }

    #[test]
    fn an_effect_is_described_with_its_parameters_and_once_added_their_intervals() {
        let ci = r#"{"row": [148.0, 152.0]}"#;
        assert_eq!(
            effect(r#"{"row": 150.0}"#, ci, false).describe(),
            "step in the measurement order (at row 150)"
        );
        assert_eq!(
            effect(r#"{"row": 150.0}"#, ci, true).describe(),
            "step in the measurement order (at row 150, 95 %: 148–152)"
        );
        assert_eq!(
            effect(r#"{"period_deg": 7.5, "gain": 0.25}"#, "{}", true).describe(),
            "step in the measurement order (gain 0.250, period 7.500°)"
        );
        assert_eq!(
            effect("{}", "{}", true).describe(),
            "step in the measurement order"
        );
    }
}
