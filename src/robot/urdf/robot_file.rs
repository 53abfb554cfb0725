//! The robot file beside a URDF (`NAME.toml`): what the URDF does not say (its feet, its front,
//! its designed stance), read and checked against the URDF.

use crate::robot::model::GaitHints;
use std::path::Path;

/// A robot file beside the URDF (`NAME.toml` next to `NAME.urdf`) says what the URDF does not:
///
/// ```toml
/// forward = "+y"              # walking direction: "+x" (default) "-x" "+y" "-y", or degrees about z
/// redundant_legs = "driven"   # legs of 4 to 6 joints: every joint servoed, or "held" (default)
/// inertia = "collision"       # each link's centre of mass and inertia from its collision
///                             # geometry, its mass kept, or "urdf" (default: its <inertial>)
/// [feet]                      # for a URDF that does not mark its feet with collision spheres
/// links = ["lf_tibia", "lm_tibia", "lr_tibia", "rf_tibia", "rm_tibia", "rr_tibia"]
/// offset = [0.12, 0.0, 0.0]   # foot centre in each link's frame (m)
/// radius = 0.01               # m
/// [gait]                      # the stance this robot was designed for (m); any may be left out
/// stance_height = 0.10        # and is then fitted, and a gait file's own values win
/// reach = 0.15
/// ```
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeetConfig {
    pub links: Vec<String>,
    pub offset: [f64; 3],
    pub radius: f64,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    #[serde(default)]
    feet: Option<FeetConfig>,
    #[serde(default)]
    forward: Option<toml::Value>,
    #[serde(default)]
    gait: Option<GaitHints>,
    #[serde(default)]
    redundant_legs: Option<RedundantLegs>,
    #[serde(default)]
    inertia: Option<InertiaFrom>,
}

/// Where each link's centre of mass and inertia come from: the URDF's `<inertial>` (the
/// default), or its collision geometry at uniform density, its URDF mass kept
/// (`inertia_from`: for placeholder inertials, as MuJoCo's `inertiafromgeom`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InertiaFrom {
    #[default]
    Urdf,
    Collision,
}

/// How a leg of more than three joints is driven (`branches`): its extra joints held still at
/// rest, welded (the default: stiffest, and the walk it had), or every joint servoed, the foot
/// placed by redundant inverse kinematics (`robot::redundant`: the extra joints add reach).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RedundantLegs {
    #[default]
    Held,
    Driven,
}

/// The robot file's `forward` as an angle about z (rad).
fn forward_yaw(value: &toml::Value) -> Result<f64, String> {
    let yaw = match value {
        toml::Value::String(s) => match s.as_str() {
            "+x" | "x" => 0.0,
            "+y" | "y" => 90.0,
            "-x" => 180.0,
            "-y" => -90.0,
            other => {
                return Err(format!(
                    "field `forward`: expected \"+x\", \"-x\", \"+y\", \"-y\" or an angle in degrees, got {other:?}"
                ));
            }
        },
        toml::Value::Integer(d) => *d as f64,
        toml::Value::Float(d) if d.is_finite() => *d,
        other => {
            return Err(format!(
                "field `forward`: expected \"+x\", \"-x\", \"+y\", \"-y\" or an angle in degrees, got {other}"
            ));
        }
    };
    Ok(yaw.to_radians())
}

/// What a robot file says, checked against the URDF it goes with.
#[derive(Debug, Default)]
pub(super) struct RobotFileSettings {
    pub(super) feet: Option<FeetConfig>,
    pub(super) forward: Option<f64>,
    pub(super) gait: GaitHints,
    pub(super) redundant_legs: RedundantLegs,
    pub(super) inertia: InertiaFrom,
}

pub(super) fn read(
    text: &str,
    robot: &urdf_rs::Robot,
    urdf: &Path,
) -> Result<RobotFileSettings, String> {
    let file: RobotFile = toml::from_str(text).map_err(|e| e.to_string().trim_end().to_string())?;
    if let Some(feet) = &file.feet {
        if !(feet.radius.is_finite() && feet.radius > 0.0) {
            return Err(format!(
                "field `feet.radius`: expected a finite number > 0, got {}",
                feet.radius
            ));
        }
        if let Some(missing) = feet
            .links
            .iter()
            .find(|name| !robot.links.iter().any(|l| &l.name == *name))
        {
            return Err(format!(
                "field `feet.links`: `{missing}` is not a link of {}",
                urdf.display()
            ));
        }
    }
    let gait = file.gait.unwrap_or_default();
    gait.validate()?;
    Ok(RobotFileSettings {
        forward: file.forward.as_ref().map(forward_yaw).transpose()?,
        feet: file.feet,
        gait,
        redundant_legs: file.redundant_legs.unwrap_or_default(),
        inertia: file.inertia.unwrap_or_default(),
    })
}
