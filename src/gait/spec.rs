//! Gait files (TOML): timing, per-leg phase offsets, foot trajectory shape and stance geometry.
//!
//! ```toml
//! name = "tripod"
//! period = 1.0          # s, one full cycle
//! duty_factor = 0.5     # fraction of the cycle a foot is on the ground
//! stride_length = 0.06  # m, foot travel over a stance at the nominal speed
//! step_height = 0.03    # m, swing apex above the stance
//! stance_height = 0.10  # m, the hips' plane above the ground
//! reach = 0.15          # m, horizontal foot distance from the hip (default: 60 % of the leg)
//! swing = "sine"        # sine | cycloid | rectangle
//! [phase_offsets]       # cycle fraction at which each leg's stance starts
//! lf = 0.0
//! lm = 0.5
//! ...
//! ```

use crate::robot::LEG_NAMES;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The shape of a foot's path through the air.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SwingShape {
    /// Height h·sin(πs); the foot leaves and lands moving with the ground (see the controller).
    #[default]
    Sine,
    /// Height h·(1 − cos 2πs)/2: lifts off and lands with no vertical speed.
    Cycloid,
    /// Lift, move, lower in thirds of the swing (for stepping over obstacles).
    Rectangle,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitSpec {
    pub name: String,
    pub period: f64,
    pub duty_factor: f64,
    pub stride_length: f64,
    pub step_height: f64,
    /// Height of the hips' plane (the mean height of the legs' first joints) above the feet's
    /// ground, standing (m).
    pub stance_height: f64,
    #[serde(default)]
    pub reach: Option<f64>,
    #[serde(default)]
    pub swing: SwingShape,
    pub phase_offsets: BTreeMap<String, f64>,
}

/// A gait file that makes no sense; names the file and field.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {message}")]
pub struct GaitError {
    pub file: PathBuf,
    pub message: String,
}

impl GaitSpec {
    pub fn from_file(path: &Path) -> Result<Self, GaitError> {
        let text = std::fs::read_to_string(path).map_err(|e| GaitError {
            file: path.to_path_buf(),
            message: format!("cannot read the gait file: {e}"),
        })?;
        Self::from_toml(&text, path)
    }

    pub fn from_toml(text: &str, origin: &Path) -> Result<Self, GaitError> {
        let fail = |message: String| GaitError {
            file: origin.to_path_buf(),
            message,
        };
        let spec: GaitSpec =
            toml::from_str(text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
        spec.validate().map_err(fail)?;
        Ok(spec)
    }

    /// The offset of each leg in [`LEG_NAMES`] order.
    pub fn offsets(&self) -> [f64; 6] {
        LEG_NAMES.map(|name| self.phase_offsets[name])
    }

    /// Nominal forward speed: stride over the stance time, stride / (duty · period).
    pub fn nominal_speed(&self) -> f64 {
        self.stride_length / (self.duty_factor * self.period)
    }

    /// Checks every field; the error names the field and what was expected.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |field: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!(
                    "field `{field}`: expected a finite number > 0, got {v}"
                ))
            }
        };
        positive("period", self.period)?;
        if !(self.duty_factor > 0.0 && self.duty_factor < 1.0) {
            return Err(format!(
                "field `duty_factor`: expected a fraction in (0, 1), got {}",
                self.duty_factor
            ));
        }
        if !(self.stride_length.is_finite() && self.stride_length >= 0.0) {
            return Err(format!(
                "field `stride_length`: expected a finite number ≥ 0, got {}",
                self.stride_length
            ));
        }
        if !(self.step_height.is_finite() && self.step_height >= 0.0) {
            return Err(format!(
                "field `step_height`: expected a finite number ≥ 0, got {}",
                self.step_height
            ));
        }
        positive("stance_height", self.stance_height)?;
        if let Some(reach) = self.reach {
            positive("reach", reach)?;
        }
        for name in LEG_NAMES {
            match self.phase_offsets.get(name) {
                None => {
                    return Err(format!(
                        "field `phase_offsets.{name}`: missing (give all six legs: {})",
                        LEG_NAMES.join(", ")
                    ));
                }
                Some(v) if !(v.is_finite() && (0.0..1.0).contains(v)) => {
                    return Err(format!(
                        "field `phase_offsets.{name}`: expected a cycle fraction in [0, 1), got {v}"
                    ));
                }
                Some(_) => {}
            }
        }
        if let Some(extra) = self
            .phase_offsets
            .keys()
            .find(|k| !LEG_NAMES.contains(&k.as_str()))
        {
            return Err(format!(
                "field `phase_offsets.{extra}`: unknown leg (legs are {})",
                LEG_NAMES.join(", ")
            ));
        }
        Ok(())
    }
}
