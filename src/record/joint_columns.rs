//! The trajectory's joint columns, named by leg and role (`lf_coxa`, `lf_femur`, `lf_tibia`, …
//! `rr_tibia`): a tool reads the same columns for every hexapod, whatever its URDF calls the
//! joints (Kraby's rr coxa is `servomotor_0`). `hexsim robot` prints the URDF joint each name
//! stands for. A redundant leg's roles are its three that place the foot; its other joints (a
//! tarsus, a hip roll) keep their URDF names.

use crate::robot::RobotModel;
use std::collections::HashSet;

/// A leg's joints from the body outwards.
pub const ROLES: [&str; 3] = ["coxa", "femur", "tibia"];

/// Each joint's column name, indexed like `model.joints`: its leg and role, or for a joint on no
/// leg its URDF name; never two alike (a name already taken gets `_2`, `_3`, …), so a URDF's
/// repeated or clashing names cannot make two columns of one name.
pub fn joint_columns(model: &RobotModel) -> Vec<String> {
    let mut names: Vec<Option<String>> = vec![None; model.joints.len()];
    for leg in &model.legs {
        let placing = leg
            .joints
            .iter()
            .zip(&leg.posture)
            .filter(|(_, rest)| rest.is_none());
        for (role, (&j, _)) in ROLES.iter().zip(placing) {
            names[j] = Some(format!("{}_{role}", leg.name));
        }
    }
    let mut taken: HashSet<String> = names.iter().flatten().cloned().collect();
    names
        .into_iter()
        .zip(&model.joints)
        .map(|(name, joint)| {
            name.unwrap_or_else(|| {
                let mut name = joint.name.clone();
                let mut n = 2;
                while !taken.insert(name.clone()) {
                    name = format!("{}_{n}", joint.name);
                    n += 1;
                }
                name
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn hex18() -> RobotModel {
        crate::robot::urdf::from_str(
            include_str!("../../robots/hex18.urdf"),
            Path::new("robots/hex18.urdf"),
        )
        .unwrap()
    }

    #[test]
    fn every_leg_joint_is_named_by_leg_and_role() {
        let model = hex18();
        let names = joint_columns(&model);
        assert_eq!(names.len(), 18);
        for leg in ["lf", "lm", "lr", "rf", "rm", "rr"] {
            for role in ROLES {
                assert!(names.contains(&format!("{leg}_{role}")), "{names:?}");
            }
        }
    }

    /// A joint on no leg keeps its URDF name, made unique against the leg names and the others.
    #[test]
    fn a_joint_off_the_legs_never_repeats_a_name() {
        let mut model = hex18();
        let mut extra = model.joints[0].clone();
        extra.name = "lf_coxa".into();
        model.joints.push(extra.clone());
        model.joints.push(extra);
        let names = joint_columns(&model);
        assert_eq!(&names[18..], ["lf_coxa_2", "lf_coxa_3"]);
        let unique: HashSet<&String> = names.iter().collect();
        assert_eq!(unique.len(), names.len());
    }
}
