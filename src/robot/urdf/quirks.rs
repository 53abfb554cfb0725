//! Exporters' quirks, undone after parsing as a list of passes, each with its test: a pass
//! rewrites urdf-rs's robot in place and says what it changed (a warning), or nothing.
//! Quirks read while folding (CAD exporters' empty `<limit>`s, `joint_limits`; simulators'
//! force-sensor slides, `fold`) stay where they are read.

/// A pass: rewrites the robot in place; the warning to give if it changed anything.
type Pass = fn(&mut urdf_rs::Robot) -> Option<String>;

/// The passes, in the order they run, each named with the exporter that writes its quirk.
const PASSES: &[Pass] = &[
    marker_frames, // Phobos (Blender): a free base and foot marker frames on floating joints
];

/// Runs every pass in order; the warnings of those that changed something.
pub(super) fn apply(robot: &mut urdf_rs::Robot) -> Vec<String> {
    PASSES.iter().filter_map(|pass| pass(robot)).collect()
}

/// [`drop_marker_frames`] as a pass.
fn marker_frames(robot: &mut urdf_rs::Robot) -> Option<String> {
    let dropped = drop_marker_frames(robot);
    (!dropped.is_empty()).then(|| {
        format!(
            "{} floating joint{} to massless frames without shapes dropped ({}): a free base and marker frames, as Phobos writes them; hexsim's base floats anyway",
            dropped.len(),
            super::plural(dropped.len()),
            dropped.join(", ")
        )
    })
}

/// Drops a URDF's marker frames: links of negligible mass (under 1 % of the robot's) with no
/// visual or collision and no children, hung from anything by a floating joint (Phobos writes a
/// foot's frame so), then a root of that kind whose one remaining joint is floating (Phobos's
/// free base: the body floats from a 1 g root). hexsim's base floats already; any other floating
/// joint is still refused. Returns the dropped joints' names.
fn drop_marker_frames(robot: &mut urdf_rs::Robot) -> Vec<String> {
    let total: f64 = robot.links.iter().map(|l| l.inertial.mass.value).sum();
    let bare = |link: &urdf_rs::Link| {
        link.inertial.mass.value <= 0.01 * total
            && link.visual.is_empty()
            && link.collision.is_empty()
    };
    let floating = |j: &urdf_rs::Joint| matches!(j.joint_type, urdf_rs::JointType::Floating);
    let mut dropped = Vec::new();
    let markers: Vec<String> = robot
        .joints
        .iter()
        .filter(|j| floating(j))
        .filter(|j| {
            let child = &j.child.link;
            !robot.joints.iter().any(|o| &o.parent.link == child)
                && robot.links.iter().any(|l| &l.name == child && bare(l))
        })
        .map(|j| j.child.link.clone())
        .collect();
    robot.joints.retain(|j| {
        let marker = markers.contains(&j.child.link);
        if marker {
            dropped.push(j.name.clone());
        }
        !marker
    });
    robot.links.retain(|l| !markers.contains(&l.name));
    // the root: the link no joint has as its child
    let root = robot
        .links
        .iter()
        .find(|l| !robot.joints.iter().any(|j| j.child.link == l.name))
        .filter(|l| bare(l))
        .map(|l| l.name.clone());
    if let Some(root) = root {
        let from_root: Vec<&urdf_rs::Joint> = robot
            .joints
            .iter()
            .filter(|j| j.parent.link == root)
            .collect();
        if let [only] = from_root[..]
            && floating(only)
        {
            let name = only.name.clone();
            dropped.push(name.clone());
            robot.joints.retain(|j| j.name != name);
            robot.links.retain(|l| l.name != root);
        }
    }
    dropped
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Phobos's free base and foot frames (1 g links without shapes, on floating joints) are
    /// dropped and the body becomes the root; a floating joint to a real link is still refused.
    #[test]
    fn phobos_marker_frames_are_dropped() {
        let urdf = |body_shape: &str, tail_mass: f64| {
            format!(
                r#"<robot name="r">
  <link name="root"><inertial><mass value="0.001"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>
  <link name="body"><inertial><mass value="2"/><inertia ixx="1e-2" ixy="0" ixz="0" iyy="1e-2" iyz="0" izz="1e-2"/></inertial>{body_shape}</link>
  <link name="foot_frame"><inertial><mass value="{tail_mass}"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>
  <joint name="body_jnt" type="floating"><parent link="root"/><child link="body"/></joint>
  <joint name="foot_jnt" type="floating"><parent link="root"/><child link="foot_frame"/></joint>
</robot>"#
            )
        };
        let mut robot = urdf_rs::read_from_string(&urdf("", 0.001)).unwrap();
        assert_eq!(drop_marker_frames(&mut robot), ["foot_jnt", "body_jnt"]);
        assert_eq!(robot.links.len(), 1);
        assert_eq!(robot.links[0].name, "body");
        assert!(robot.joints.is_empty());
        // a 0.5 kg link on a floating joint is not a marker: nothing is dropped
        let mut robot = urdf_rs::read_from_string(&urdf("", 0.5)).unwrap();
        assert!(drop_marker_frames(&mut robot).is_empty());
        assert_eq!(robot.joints.len(), 2);
    }
}
