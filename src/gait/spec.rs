//! Gait files (TOML): timing, per-leg phase offsets, foot trajectory shape and, optionally, the
//! stance geometry. A [`GaitSpec`] is the file; a [`Gait`] is the spec on one robot, every length
//! known (given, from the robot file, or fitted: see `fit`).
//!
//! ```toml
//! name = "tripod"
//! period = 1.0          # s, one full cycle
//! duty_factor = 0.5     # fraction of the cycle a foot is on the ground
//! swing = "sine"        # sine | cycloid | rectangle
//! # optional, fitted to the robot when left out (m):
//! stride_length = 0.06  # foot travel over a stance at the nominal speed
//! step_height = 0.03    # swing apex above the stance
//! stance_height = 0.10  # the hips' plane above the ground
//! reach = 0.15          # horizontal foot distance from its hip
//! splay_deg = 0         # front and rear feet turned towards the body's ends (degrees)
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
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stride_length: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step_height: Option<f64>,
    /// Height of the hips' plane (the mean height of the legs' first joints) above the feet's
    /// ground, standing (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stance_height: Option<f64>,
    /// Horizontal distance of each standing foot from its hip (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reach: Option<f64>,
    /// How far the front and rear legs' standing feet are turned about their hips towards the
    /// body's ends, from the legs' own direction (degrees; see [`Gait::splay`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub splay_deg: Option<f64>,
    #[serde(default)]
    pub swing: SwingShape,
    pub phase_offsets: BTreeMap<String, f64>,
}

/// A gait on one robot: the spec's timing and shape with every length known.
#[derive(Debug, Clone, PartialEq)]
pub struct Gait {
    pub name: String,
    pub period: f64,
    pub duty_factor: f64,
    pub stride_length: f64,
    pub step_height: f64,
    /// The hips' plane above the ground, standing (m).
    pub stance_height: f64,
    /// Each standing foot's horizontal distance from its hip (m).
    pub reach: f64,
    /// The front legs' standing feet turned this far about their hips towards the front, the
    /// rear legs' towards the rear, from the direction each leg points at rest (rad; the middle
    /// legs keep theirs). A robot whose legs all point sideways from hips close together fore
    /// and aft stands on tripods shorter than its stride: splayed, their triangles lengthen.
    pub splay: f64,
    pub swing: SwingShape,
    /// Cycle fraction at which each leg's stance starts, in [`LEG_NAMES`] order.
    pub offsets: [f64; 6],
}

impl Gait {
    /// Nominal forward speed: stride over the stance time, stride / (duty · period).
    pub fn nominal_speed(&self) -> f64 {
        self.stride_length / (self.duty_factor * self.period)
    }

    /// The gait as a file that gives every length (what `fit` chose, written out).
    pub fn to_spec(&self) -> GaitSpec {
        GaitSpec {
            name: self.name.clone(),
            period: self.period,
            duty_factor: self.duty_factor,
            stride_length: Some(self.stride_length),
            step_height: Some(self.step_height),
            stance_height: Some(self.stance_height),
            reach: Some(self.reach),
            splay_deg: (self.splay != 0.0).then(|| self.splay.to_degrees()),
            swing: self.swing,
            phase_offsets: LEG_NAMES
                .iter()
                .zip(self.offsets)
                .map(|(name, o)| (name.to_string(), o))
                .collect(),
        }
    }
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
        let text =
            crate::limits::read_to_string(path, crate::limits::TEXT_FILE_BYTES).map_err(|e| {
                GaitError {
                    file: path.to_path_buf(),
                    message: format!("cannot read the gait file: {e}"),
                }
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
        for (field, value) in [
            ("stride_length", self.stride_length),
            ("step_height", self.step_height),
        ] {
            if let Some(v) = value
                && !(v.is_finite() && v >= 0.0)
            {
                return Err(format!(
                    "field `{field}`: expected a finite number ≥ 0, got {v}"
                ));
            }
        }
        // the walk's nominal speed, which the default command takes: over a command's bound it is
        // the stride's fault, named here rather than the command's
        if let Some(stride) = self.stride_length {
            let stance = self.duty_factor * self.period;
            let (speed, most) = (stride / stance, super::command::MAX_SPEED);
            if speed > most {
                return Err(format!(
                    "field `stride_length`: {stride} m over a stance of {} s (duty_factor × period) \
                     walks at {} m/s, more than the {most} m/s a walk may command; expected a \
                     stride in metres, at most {} m",
                    crate::limits::num(stance),
                    crate::limits::num(speed),
                    crate::limits::num(most * stance)
                ));
            }
        }
        if let Some(stance_height) = self.stance_height {
            positive("stance_height", stance_height)?;
        }
        if let Some(reach) = self.reach {
            positive("reach", reach)?;
        }
        if let Some(splay) = self.splay_deg
            && !(splay.is_finite() && splay.abs() < 90.0)
        {
            return Err(format!(
                "field `splay_deg`: expected an angle in degrees between -90 and 90, got {splay}"
            ));
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
