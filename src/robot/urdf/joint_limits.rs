//! A revolute joint's axis, range and effort, with CAD exporters' placeholders (lower = upper = 0,
//! effort = 0) read as unstated: a stated default range, an effort fitted to the robot's weight.

use super::plural;
use crate::robot::model::RobotModel;
use glam::DVec3;

/// A revolute (or continuous) joint's unit axis, limits and effort. A CAD exporter's placeholder
/// limits (lower = upper = 0, also what a missing `<limit>` reads as) are absent: a stated
/// default range; a zero effort is fitted to the robot's weight once its legs are known (NaN
/// until then). Both are noted in `unstated`, for one warning each.
pub(super) fn revolute(
    joint: &urdf_rs::Joint,
    unstated: &mut Unstated,
) -> Result<(DVec3, f64, f64, f64), String> {
    let axis = DVec3::from_array(joint.axis.xyz.0);
    if !(axis.is_finite() && axis.length() > 1e-9) {
        return Err(format!(
            "joint `{}`: <axis xyz> must have a non-zero length, got {axis}",
            joint.name
        ));
    }
    let (mut lower, mut upper) = if matches!(joint.joint_type, urdf_rs::JointType::Continuous) {
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        (joint.limit.lower, joint.limit.upper)
    };
    if lower == 0.0 && upper == 0.0 {
        (lower, upper) = (-UNSTATED_RANGE, UNSTATED_RANGE);
        unstated.range.push(joint.name.clone());
    }
    let ordered = lower < upper; // false for NaN too
    if !ordered {
        return Err(format!(
            "joint `{}`: a revolute joint needs <limit lower=… upper=…> with lower < upper, got lower = {lower}, upper = {upper}",
            joint.name
        ));
    }
    let effort = joint.limit.effort;
    // a NaN written in the file is refused here: below, NaN stands for "not stated" (0, urdf-rs's
    // default), which the fit fills in
    if !(effort == 0.0 || effort.is_finite() && effort > 0.0) {
        return Err(format!(
            "joint `{}`: <limit effort> (the servo's torque limit, N·m) must be > 0, got {effort}",
            joint.name
        ));
    }
    if effort == 0.0 {
        unstated.effort.push(joint.name.clone());
        return Ok((axis.normalize(), lower, upper, f64::NAN));
    }
    Ok((axis.normalize(), lower, upper, effort))
}

/// A joint range left unstated is this wide each way: a hobby servo's 300° (Dynamixel AX/MX).
pub const UNSTATED_RANGE: f64 = 150.0 * std::f64::consts::PI / 180.0;

/// The joints whose `<limit>` states no range (lower = upper = 0) or no effort (0), as CAD
/// exporters write them on every joint.
#[derive(Default)]
pub(super) struct Unstated {
    pub(super) range: Vec<String>,
    pub(super) effort: Vec<String>,
}

impl Unstated {
    /// Fits the unstated efforts and says, in one warning each, what was read as absent and what
    /// was fitted. An unstated effort is the torque that holds a third of the robot's weight at
    /// the longest leg's full length from its femur joint: the most any joint of a leg meets
    /// standing on three feet (a tripod's fewest), reached only with the leg stretched level, so
    /// a stance whose feet are within half that length keeps every servo at or under half its
    /// effort, as the gait fit asks.
    pub(super) fn fill(self, model: &mut RobotModel) {
        let list = |names: &[String]| {
            let shown: Vec<&str> = names.iter().take(6).map(String::as_str).collect();
            let more = names.len().saturating_sub(6);
            let more = if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            };
            format!("{}{more}", shown.join(", "))
        };
        if !self.range.is_empty() {
            model.warnings.push(format!(
                "{} joint{} state{} no range (lower = upper = 0, a CAD exporter's placeholder, or no <limit>): {}; read as absent, ±{:.0}° (a hobby servo's range)",
                self.range.len(),
                plural(self.range.len()),
                if self.range.len() == 1 { "s" } else { "" },
                list(&self.range),
                UNSTATED_RANGE.to_degrees()
            ));
        }
        if self.effort.is_empty() {
            return;
        }
        let weight = model.total_mass() * 9.81;
        let reach = model
            .legs
            .iter()
            .map(|leg| {
                // femur and tibia, and any segments beyond
                crate::robot::statics::segment_lengths(model, leg)[1..]
                    .iter()
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
        let effort = weight / 3.0 * reach;
        for joint in model.joints.iter_mut().filter(|j| j.effort.is_nan()) {
            joint.effort = effort;
        }
        model.warnings.push(format!(
            "{} joint{} state{} no effort (effort = 0, a CAD exporter's placeholder, or no <limit>): {}; fitted from the robot's weight: {effort:.3} N·m, a third of its {weight:.1} N held at the legs' full {reach:.3} m",
            self.effort.len(),
            plural(self.effort.len()),
            if self.effort.len() == 1 { "s" } else { "" },
            list(&self.effort),
        ));
    }
}
