//! URDF text → urdf-rs's robot, and the tree its joints make: what urdf-rs does not check (one
//! root, no cycles, unique names, finite origins), and templates refused before parsing.

use std::collections::HashMap;
use std::path::Path;

/// Parses URDF text with urdf-rs, its nesting checked first (urdf-rs's parser is recursive: a
/// deep nesting would overflow the stack). An error comes with its line where one is found
/// (`places`).
pub(super) fn read(text: &str) -> Result<urdf_rs::Robot, (Option<u32>, String)> {
    crate::limits::xml_depth(text, crate::limits::XML_DEPTH).map_err(|(depth, line)| {
        (
            None,
            format!(
                "not a valid URDF: line {line}: elements nested {depth} deep, deeper than the {} hexsim reads (a URDF's are 4 or 5)",
                crate::limits::XML_DEPTH
            ),
        )
    })?;
    urdf_rs::read_from_string(text).map_err(|e| match super::places::syntax_error(text) {
        Some(place) => (
            Some(place.line),
            format!("not a valid URDF: {}", place.message),
        ),
        None => (None, format!("not a valid URDF: {e}")),
    })
}

/// A xacro file is a URDF template, which only xacro (ROS) expands. xacro's own output keeps the
/// `xmlns:xacro` declaration and often comments holding xacro elements: only a live xacro
/// element or a `${…}` expression outside comments marks a template.
pub(super) fn refuse_xacro(text: &str, path: &Path) -> Result<(), String> {
    let named = path.extension().is_some_and(|e| e == "xacro");
    let live = without_comments(text);
    if named || live.contains("<xacro:") || live.contains("${") {
        return Err(
            "this is a xacro file (a URDF template): expand it first with xacro (from ROS: `xacro FILE > robot.urdf`) and give hexsim the URDF".into(),
        );
    }
    Ok(())
}

/// XML text without its `<!-- … -->` comments (an unclosed comment runs to the end).
fn without_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<!--") {
        out.push_str(&rest[..start]);
        rest = rest[start + 4..]
            .find("-->")
            .map_or("", |end| &rest[start + 4 + end + 3..]);
    }
    out.push_str(rest);
    out
}

pub(super) struct Tree<'a> {
    /// link name → index in robot.links
    pub(super) index: HashMap<&'a str, usize>,
    /// link index → the joint (index in robot.joints) whose child it is
    pub(super) parent: Vec<Option<usize>>,
    pub(super) children: Vec<Vec<usize>>,
    pub(super) root: usize,
}

pub(super) fn tree(robot: &urdf_rs::Robot) -> Result<Tree<'_>, String> {
    if robot.links.is_empty() {
        return Err("no <link> elements: a robot needs at least a body".into());
    }
    let mut index = HashMap::new();
    for (k, link) in robot.links.iter().enumerate() {
        if index.insert(link.name.as_str(), k).is_some() {
            return Err(format!("link `{}` is defined twice", link.name));
        }
    }
    let mut joint_names = std::collections::HashSet::new();
    for joint in &robot.joints {
        if !joint_names.insert(joint.name.as_str()) {
            return Err(format!(
                "joint `{}` is defined twice (joint names must be unique: they name the trajectory's columns)",
                joint.name
            ));
        }
        let origin = &joint.origin;
        if origin
            .xyz
            .iter()
            .chain(origin.rpy.iter())
            .any(|v| !v.is_finite())
        {
            return Err(format!(
                "joint `{}`: <origin xyz rpy> must be finite numbers, got xyz = {:?}, rpy = {:?}",
                joint.name, *origin.xyz, *origin.rpy
            ));
        }
    }
    let mut parent = vec![None; robot.links.len()];
    let mut children = vec![Vec::new(); robot.links.len()];
    for (j, joint) in robot.joints.iter().enumerate() {
        let find = |name: &str, role: &str| {
            index.get(name).copied().ok_or_else(|| {
                format!(
                    "joint `{}`: its {role} link `{name}` is not defined",
                    joint.name
                )
            })
        };
        let p = find(&joint.parent.link, "parent")?;
        let c = find(&joint.child.link, "child")?;
        if let Some(other) = parent[c] {
            let other: usize = other;
            return Err(format!(
                "link `{}` has two parent joints, `{}` and `{}` (a URDF is a tree)",
                joint.child.link, robot.joints[other].name, joint.name
            ));
        }
        parent[c] = Some(j);
        children[p].push(j);
    }
    let roots: Vec<&str> = (0..robot.links.len())
        .filter(|&k| parent[k].is_none())
        .map(|k| robot.links[k].name.as_str())
        .collect();
    match roots.len() {
        0 => return Err("every link has a parent: the joints form a cycle".into()),
        1 => {}
        _ => {
            return Err(format!(
                "{} root links ({}), expected one body all others hang from",
                roots.len(),
                roots.join(", ")
            ));
        }
    }
    let root = index[roots[0]];
    // reachability from the root: any link not reached sits on a cycle
    let mut seen = vec![false; robot.links.len()];
    let mut stack = vec![root];
    while let Some(k) = stack.pop() {
        seen[k] = true;
        for &j in &children[k] {
            stack.push(index[robot.joints[j].child.link.as_str()]);
        }
    }
    if let Some(k) = seen.iter().position(|s| !s) {
        return Err(format!(
            "link `{}` is on a cycle of joints, not in the tree under `{}`",
            robot.links[k].name, roots[0]
        ));
    }
    Ok(Tree {
        index,
        parent,
        children,
        root,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// xacro's output (the namespace declared, xacro elements commented out) is a URDF; a live
    /// xacro element or expression is a template.
    #[test]
    fn only_live_xacro_marks_a_template() {
        let urdf = Path::new("robot.urdf");
        let output = r#"<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <!-- <xacro:include filename="legs.xacro"/> -->
  <!--<xacro:property name="l" value="${2*r}"/>--><link name="a"/>
</robot>"#;
        assert_eq!(refuse_xacro(output, urdf), Ok(()));
        for template in [
            r#"<robot xmlns:xacro="x"><xacro:property name="l" value="1"/></robot>"#,
            r#"<robot><link name="a"><!-- a --><mass value="${m}"/></link></robot>"#,
            r#"<robot><!-- unclosed <link/> --> <xacro:leg/></robot>"#,
        ] {
            assert!(refuse_xacro(template, urdf).is_err(), "{template}");
        }
        assert!(refuse_xacro(output, Path::new("robot.urdf.xacro")).is_err());
        assert_eq!(without_comments("a<!-- b"), "a");
    }
}
