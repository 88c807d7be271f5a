//! Undeclared effects: physics the Kriging model is not told about, switched on
//! per campaign. They reach the data only through the columns a real campaign
//! would have (`time_s`, `temp_c`, `payload_kg`) or through no column at all
//! (a tracker bump). Their parameters go to the truth sidecar only.
//!
//! Command-line syntax: `NAME[:key=value,key=value…]`, e.g.
//! `temperature:delta_k=6,tau_s=1800`, `payload:kg=0/25/50`,
//! `harmonic:joint=2,period_deg=7.5,amp_deg=0.004`,
//! `tracker-step:row=150,dx=0.15,dy=0,dz=-0.1` (`until=250`: put back there),
//! `crosstalk:joint=1,from=2,gain_deg=0.004`,
//! `hysteresis:joint=2,amp_deg=0.01,travel_deg=20`,
//! `lag:joint=2,gain=0.0005,tau_poses=0`.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::f64::consts::TAU;

/// One undeclared effect and its parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Effect {
    /// Warm-up drift: `T(t) = T0 + ΔT·(1 − e^(−t/τ))`; every length of the
    /// true robot scales by `1 + κ·(T − T0)`. Written as `temp_c` (sensor
    /// noise 0.02 K) next to `time_s`.
    Temperature {
        /// Temperature rise ΔT at saturation, K (default 6).
        delta_k: f64,
        /// Time constant τ of the warm-up, s (> 0; default 1200).
        tau_s: f64,
        /// Expansion coefficient κ of every length, per K (default 4e-5).
        expansion_per_k: f64,
    },
    /// Payload changes in equal blocks of rows through the given levels;
    /// compliance bends the arm more under load. Written as `payload_kg`.
    Payload {
        /// Payload masses in the order the blocks run through them, kg (≥ 0).
        levels_kg: Vec<f64>,
    },
    /// An extra gear harmonic `A·sin(2π·q/P + φ)` on one joint (1-based).
    Harmonic {
        /// 1-based joint.
        joint: usize,
        /// Period P in the joint's angle, degrees (> 0).
        period_deg: f64,
        /// Amplitude A, degrees.
        amp_deg: f64,
        /// Phase φ, radians.
        phase_rad: f64,
    },
    /// The tracker set-up is bumped before row `row` (0-based): every later
    /// measurement (up to `until`, when it is put back) is offset by
    /// `offset_mm`. No column records it.
    TrackerStep {
        /// 0-based row from which the offset applies.
        row: usize,
        /// 0-based row from which the offset is gone again (a bump); `None`:
        /// to the end of the campaign.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        until: Option<usize>,
        /// Offset added to every later measured position (x, y, z), mm.
        offset_mm: [f64; 3],
    },
    /// Cross-talk: joint `joint` deviates by `gain·sin(q_from)` (both 1-based).
    Crosstalk {
        /// 1-based joint that deviates.
        joint: usize,
        /// 1-based joint whose angle drives the deviation (≠ `joint`).
        from: usize,
        /// Gain: the deviation's amplitude, degrees.
        gain_deg: f64,
    },
    /// Hysteresis that builds up after a reversal (Dahl-type friction):
    /// joint `joint` deviates by `λ·A·(1 − e^(−s/S))`, `s` its travel since
    /// its last reversal (the move to the pose included). Constant backlash
    /// (EJS's λ) is the saturated value; for moves of the order of `S` the
    /// deviation depends on the move history, which no column records.
    Hysteresis {
        /// 1-based joint.
        joint: usize,
        /// Saturated deviation A, degrees.
        amp_deg: f64,
        /// Travel scale S of the build-up, degrees (> 0).
        travel_deg: f64,
    },
    /// Servo lag or incomplete settling: joint `joint` stops short of its
    /// command by a share of the moves that brought it there,
    /// `−g·h_k` with `h_k = Δq_k + e^(−1/τ)·h_(k−1)` over the visiting
    /// sequence (`Δq_k` the joint's move into pose k, from home for the
    /// first; τ = 0: the last move alone). The error depends on how the
    /// robot moved into the pose, not on the pose or its direction λ.
    Lag {
        /// 1-based joint.
        joint: usize,
        /// Share g of the move left unfinished (degrees per degree).
        gain: f64,
        /// Memory τ of earlier moves, in poses (≥ 0; 0: the last move only).
        tau_poses: f64,
    },
}

/// Names accepted by [`Effect::parse`].
pub const EFFECT_NAMES: [&str; 7] = [
    "temperature",
    "payload",
    "harmonic",
    "tracker-step",
    "crosstalk",
    "hysteresis",
    "lag",
];

/// Effects of [`EFFECT_NAMES`] that act on a campaign's measurements only
/// (its pose context, its tracker): a commanded trajectory runs without them
/// ([`execute`](super::execute())), so they mean nothing for a circle.
pub const MEASUREMENT_EFFECTS: [&str; 3] = ["temperature", "payload", "tracker-step"];

impl Effect {
    /// [`Effect::parse`] of each spec, in order.
    pub fn parse_all(specs: &[String]) -> Result<Vec<Effect>> {
        specs.iter().map(|s| Effect::parse(s)).collect()
    }

    /// Parse `NAME[:key=value,…]` (see module docs); missing keys take defaults.
    pub fn parse(spec: &str) -> Result<Effect> {
        let (name, rest) = spec.split_once(':').unwrap_or((spec, ""));
        let mut kv = Params::parse(spec, rest)?;
        let effect = match name.trim() {
            "temperature" => Effect::Temperature {
                delta_k: kv.f("delta_k", 6.0)?,
                tau_s: kv.f("tau_s", 1200.0)?,
                expansion_per_k: kv.f("expansion_per_k", 4.0e-5)?,
            },
            "payload" => Effect::Payload {
                levels_kg: kv.list("kg", &[0.0, 60.0, 120.0])?,
            },
            "harmonic" => Effect::Harmonic {
                joint: kv.joint("joint", 2)?,
                period_deg: kv.f("period_deg", 7.5)?,
                amp_deg: kv.f("amp_deg", 0.004)?,
                phase_rad: kv.f("phase_rad", 0.0)?,
            },
            "tracker-step" => Effect::TrackerStep {
                row: kv.f("row", 150.0)? as usize,
                until: kv.opt("until")?.map(|u| u as usize),
                offset_mm: [kv.f("dx", 0.15)?, kv.f("dy", -0.1)?, kv.f("dz", 0.1)?],
            },
            "crosstalk" => Effect::Crosstalk {
                joint: kv.joint("joint", 1)?,
                from: kv.joint("from", 2)?,
                gain_deg: kv.f("gain_deg", 0.01)?,
            },
            "hysteresis" => Effect::Hysteresis {
                joint: kv.joint("joint", 2)?,
                amp_deg: kv.f("amp_deg", 0.01)?,
                travel_deg: kv.f("travel_deg", 20.0)?,
            },
            "lag" => Effect::Lag {
                joint: kv.joint("joint", 2)?,
                gain: kv.f("gain", 0.0005)?,
                tau_poses: kv.f("tau_poses", 0.0)?,
            },
            other => {
                return Err(Error::InvalidParameter(format!(
                    "unknown effect '{other}' in '{spec}' (known: {})",
                    EFFECT_NAMES.join(", ")
                )));
            }
        };
        kv.finish()?;
        effect.validate()?;
        Ok(effect)
    }

    /// The effect's name, as [`Effect::parse`] reads it (one of
    /// [`EFFECT_NAMES`]).
    pub fn name(&self) -> &'static str {
        match self {
            Effect::Temperature { .. } => "temperature",
            Effect::Payload { .. } => "payload",
            Effect::Harmonic { .. } => "harmonic",
            Effect::TrackerStep { .. } => "tracker-step",
            Effect::Crosstalk { .. } => "crosstalk",
            Effect::Hysteresis { .. } => "hysteresis",
            Effect::Lag { .. } => "lag",
        }
    }

    /// Check parameter ranges.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(m));
        match self {
            Effect::Temperature { tau_s, .. } if *tau_s <= 0.0 => {
                bad(format!("temperature: tau_s must be > 0, got {tau_s}"))
            }
            Effect::Payload { levels_kg }
                if levels_kg.is_empty() || levels_kg.iter().any(|m| *m < 0.0 || !m.is_finite()) =>
            {
                bad("payload: kg must be a '/'-separated list of masses ≥ 0".into())
            }
            Effect::Harmonic { period_deg, .. } if *period_deg <= 0.0 => bad(format!(
                "harmonic: period_deg must be > 0, got {period_deg}"
            )),
            Effect::Crosstalk { joint, from, .. } if joint == from => {
                bad("crosstalk: joint and from must differ".into())
            }
            Effect::Hysteresis { travel_deg, .. } if travel_deg.is_nan() || *travel_deg <= 0.0 => {
                bad(format!(
                    "hysteresis: travel_deg must be > 0, got {travel_deg}"
                ))
            }
            Effect::TrackerStep {
                row,
                until: Some(until),
                ..
            } if until <= row => bad(format!(
                "tracker-step: until must be a row after row={row}, got {until}"
            )),
            Effect::Lag { tau_poses, .. } if tau_poses.is_nan() || *tau_poses < 0.0 => {
                bad(format!("lag: tau_poses must be ≥ 0, got {tau_poses}"))
            }
            _ => Ok(()),
        }
    }

    /// Check joint indices against a robot with `dof` joints.
    pub fn check_joints(&self, dof: usize) -> Result<()> {
        let check = |j: usize| {
            if j >= 1 && j <= dof {
                Ok(())
            } else {
                Err(Error::InvalidParameter(format!(
                    "effect joint {j} outside 1..={dof}"
                )))
            }
        };
        match self {
            Effect::Harmonic { joint, .. } => check(*joint),
            Effect::Crosstalk { joint, from, .. } => check(*joint).and(check(*from)),
            Effect::Hysteresis { joint, .. } | Effect::Lag { joint, .. } => check(*joint),
            _ => Ok(()),
        }
    }

    /// Extra joint deviation (API units) this effect adds at commanded `q`.
    pub fn joint_deviation(&self, q: &[f64], out: &mut [f64]) {
        match self {
            Effect::Harmonic {
                joint,
                period_deg,
                amp_deg,
                phase_rad,
            } => out[joint - 1] += amp_deg * (TAU * q[joint - 1] / period_deg + phase_rad).sin(),
            Effect::Crosstalk {
                joint,
                from,
                gain_deg,
            } => out[joint - 1] += gain_deg * q[from - 1].to_radians().sin(),
            _ => {}
        }
    }

    /// Extra joint deviation that depends on the move history: `dir` the
    /// approach directions λ, `since_reversal` every joint's travel since its
    /// last reversal (`travel_since_reversal`).
    pub fn history_deviation(&self, dir: &[f64], since_reversal: &[f64], out: &mut [f64]) {
        if let Effect::Hysteresis {
            joint,
            amp_deg,
            travel_deg,
        } = self
        {
            let j = joint - 1;
            out[j] += dir[j] * amp_deg * (1.0 - (-since_reversal[j] / travel_deg).exp());
        }
    }
}

/// Joint deviations of the lag effects ([`Effect::Lag`]) at every pose of a
/// visiting sequence `q` that starts from `start`.
pub fn lag_deviations(effects: &[Effect], q: &[Vec<f64>], start: &[f64]) -> Vec<Vec<f64>> {
    let n = start.len();
    let mut out = vec![vec![0.0; n]; q.len()];
    for e in effects {
        let Effect::Lag {
            joint,
            gain,
            tau_poses,
        } = e
        else {
            continue;
        };
        let j = joint - 1;
        let keep = if *tau_poses > 0.0 {
            (-1.0 / tau_poses).exp()
        } else {
            0.0
        };
        let (mut h, mut prev) = (0.0, start[j]);
        for (o, qk) in out.iter_mut().zip(q) {
            h = (qk[j] - prev) + keep * h;
            prev = qk[j];
            o[j] -= gain * h;
        }
    }
    out
}

/// Every joint's travel since its direction last changed, for a visiting
/// sequence `q` with directions `dir` (from `start`, where the travel is 0):
/// reset at a reversal, then the move to the pose added.
pub fn travel_since_reversal(
    q: &[Vec<f64>],
    dir: &[Vec<f64>],
    start: Option<&[f64]>,
) -> Vec<Vec<f64>> {
    let n = q.first().map_or(0, Vec::len);
    let mut travel = vec![0.0; n];
    let mut prev_q: Option<&[f64]> = start;
    let mut prev_dir: Option<&[f64]> = None;
    q.iter()
        .zip(dir)
        .map(|(qi, di)| {
            for j in 0..n {
                if prev_dir.is_some_and(|p| p[j] != di[j]) {
                    travel[j] = 0.0;
                }
                if let Some(p) = prev_q {
                    let step = (qi[j] - p[j]).abs();
                    if step > crate::space::MOVE_EPS {
                        travel[j] += step;
                    }
                }
            }
            prev_q = Some(qi);
            prev_dir = Some(di);
            travel.clone()
        })
        .collect()
}

/// `key=value` pairs of one effect spec, consumed as they are read so that a
/// misspelt key is an error, not silently ignored.
struct Params<'a> {
    spec: &'a str,
    map: BTreeMap<&'a str, &'a str>,
}

impl<'a> Params<'a> {
    fn parse(spec: &'a str, rest: &'a str) -> Result<Self> {
        let mut map = BTreeMap::new();
        for part in rest.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (k, v) = part.split_once('=').ok_or_else(|| {
                Error::InvalidParameter(format!(
                    "effect '{spec}': expected key=value, found '{part}'"
                ))
            })?;
            map.insert(k.trim(), v.trim());
        }
        Ok(Params { spec, map })
    }

    fn f(&mut self, key: &str, default: f64) -> Result<f64> {
        Ok(self.opt(key)?.unwrap_or(default))
    }

    /// The value of `key`, `None` when the spec does not give it.
    fn opt(&mut self, key: &str) -> Result<Option<f64>> {
        self.map
            .remove(key)
            .map(|v| {
                v.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        Error::InvalidParameter(format!(
                            "effect '{}': {key}={v} is not a finite number",
                            self.spec
                        ))
                    })
            })
            .transpose()
    }

    fn joint(&mut self, key: &str, default: usize) -> Result<usize> {
        let v = self.f(key, default as f64)?;
        if v >= 1.0 && v.fract() == 0.0 {
            Ok(v as usize)
        } else {
            Err(Error::InvalidParameter(format!(
                "effect '{}': {key} must be a joint number ≥ 1",
                self.spec
            )))
        }
    }

    fn list(&mut self, key: &str, default: &[f64]) -> Result<Vec<f64>> {
        match self.map.remove(key) {
            None => Ok(default.to_vec()),
            Some(v) => v
                .split('/')
                .map(|x| x.trim().parse::<f64>())
                .collect::<std::result::Result<Vec<_>, _>>()
                .map_err(|_| {
                    Error::InvalidParameter(format!(
                        "effect '{}': {key}={v} is not a '/'-separated list of numbers",
                        self.spec
                    ))
                }),
        }
    }

    fn finish(self) -> Result<()> {
        match self.map.keys().next() {
            None => Ok(()),
            Some(k) => Err(Error::InvalidParameter(format!(
                "effect '{}': unknown key '{k}'",
                self.spec
            ))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_defaults_and_overrides() {
        let e = Effect::parse("harmonic:joint=3,period_deg=10").unwrap();
        assert_eq!(
            e,
            Effect::Harmonic {
                joint: 3,
                period_deg: 10.0,
                amp_deg: 0.004,
                phase_rad: 0.0
            }
        );
        assert!(
            matches!(Effect::parse("payload:kg=0/10").unwrap(), Effect::Payload { levels_kg } if levels_kg == vec![0.0, 10.0])
        );
        assert!(Effect::parse("harmonic:jiont=3").is_err());
        assert!(Effect::parse("warp-drive").is_err());
        assert!(Effect::parse("temperature:tau_s=-1").is_err());
        assert!(Effect::parse("crosstalk:joint=2,from=2").is_err());
        assert!(Effect::parse("hysteresis:travel_deg=0").is_err());
        assert!(Effect::parse("lag:tau_poses=-1").is_err());
        assert!(Effect::parse("lag:joint=0").is_err());
    }

    #[test]
    fn hysteresis_builds_up_with_the_travel_since_a_reversal() {
        let q: Vec<Vec<f64>> = [0.0, 10.0, 25.0, 20.0, 5.0, 30.0]
            .iter()
            .map(|v| vec![*v])
            .collect();
        let dir = crate::space::derive_directions(&q, Some(&[-5.0]));
        let s = travel_since_reversal(&q, &dir, Some(&[-5.0]));
        let s: Vec<f64> = s.iter().map(|r| r[0]).collect();
        assert_eq!(s, vec![5.0, 15.0, 30.0, 5.0, 20.0, 25.0]);
        let e = Effect::parse("hysteresis:joint=1,amp_deg=0.01,travel_deg=10").unwrap();
        let mut out = [0.0];
        e.history_deviation(&dir[3], &[5.0], &mut out);
        assert!((out[0] + 0.01 * (1.0 - (-0.5f64).exp())).abs() < 1e-15);
    }

    #[test]
    fn lag_follows_the_moves_into_each_pose() {
        let q: Vec<Vec<f64>> = [10.0, 30.0, 25.0].iter().map(|v| vec![0.0, *v]).collect();
        let e = Effect::parse("lag:joint=2,gain=0.01,tau_poses=0").unwrap();
        let d = lag_deviations(std::slice::from_ref(&e), &q, &[0.0, 0.0]);
        assert_eq!(d, vec![vec![0.0, -0.1], vec![0.0, -0.2], vec![0.0, 0.05]]);
        let e = Effect::parse("lag:joint=2,gain=0.01,tau_poses=1").unwrap();
        let d = lag_deviations(&[e], &q, &[0.0, 0.0]);
        let k = (-1.0f64).exp();
        assert!((d[1][1] + 0.01 * (20.0 + 10.0 * k)).abs() < 1e-15);
    }
}
