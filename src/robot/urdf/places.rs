//! Where in a URDF's text a problem is. urdf-rs says what it could not read ("invalid float
//! literal") but not where; the text is read again with roxmltree, whose nodes keep their
//! positions, and each attribute urdf-rs reads is checked the way urdf-rs reads it (a number:
//! `str::parse::<f64>` of the trimmed value; a vector: its whitespace-separated numbers, counted),
//! so that the first one it cannot read is named with its line, element and owner.

/// A problem at a line of the URDF.
#[derive(Debug, PartialEq)]
pub(super) struct Place {
    pub(super) line: u32,
    pub(super) message: String,
}

/// The joint types URDF defines, as urdf-rs reads them.
const JOINT_TYPES: [&str; 7] = [
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];

/// What an attribute holds.
#[derive(Clone, Copy)]
enum Value {
    Number,
    Numbers(usize),
    Text,
}

/// An attribute urdf-rs reads: its name, what it holds, whether it must be there.
type Attribute = (&'static str, Value, bool);

/// The attributes urdf-rs reads of an element, by the element's name (None: an element whose
/// attributes it does not read).
fn attributes(element: &str, velocity_required: bool) -> Option<Vec<Attribute>> {
    use Value::*;
    let number = |name| (name, Number, false);
    Some(match element {
        "mass" => vec![("value", Number, true)],
        "inertia" => ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
            .map(|name| (name, Number, true))
            .to_vec(),
        "origin" => vec![("xyz", Numbers(3), false), ("rpy", Numbers(3), false)],
        "axis" => vec![("xyz", Numbers(3), true)],
        "limit" => vec![
            number("lower"),
            number("upper"),
            number("effort"),
            ("velocity", Number, velocity_required),
        ],
        "dynamics" => vec![number("damping"), number("friction")],
        "box" => vec![("size", Numbers(3), true)],
        "cylinder" | "capsule" => vec![("radius", Number, true), ("length", Number, true)],
        "sphere" => vec![("radius", Number, true)],
        "mesh" => vec![("filename", Text, true), ("scale", Numbers(3), false)],
        "color" => vec![("rgba", Numbers(4), true)],
        "parent" | "child" => vec![("link", Text, true)],
        _ => return None,
    })
}

/// The elements URDF defines inside a link and inside a joint; any other there is ignored by
/// every URDF reader, so a misspelt one (`<limt>`) silently drops what it meant to say. Bullet's
/// `<contact>` (a link's friction, read by PyBullet) is known and ignored quietly.
const LINK_CHILDREN: [&str; 4] = ["inertial", "visual", "collision", "contact"];
const JOINT_CHILDREN: [&str; 9] = [
    "origin",
    "parent",
    "child",
    "axis",
    "limit",
    "dynamics",
    "mimic",
    "calibration",
    "safety_controller",
];

/// A URDF's text as roxmltree reads it, with positions, or None if it cannot (a DTD, which it
/// refuses by default, or text that is not XML: urdf-rs has said so already).
fn document(text: &str) -> Option<roxmltree::Document<'_>> {
    roxmltree::Document::parse(text).ok()
}

fn line_of(document: &roxmltree::Document, position: usize) -> u32 {
    document.text_pos_at(position).row
}

/// What owns an element: "link `x`" or "joint `y`", from the nearest link or joint above it.
fn owner(node: roxmltree::Node) -> Option<String> {
    node.ancestors()
        .find(|n| {
            matches!(n.tag_name().name(), "link" | "joint")
                && n.parent_element()
                    .is_some_and(|p| p.tag_name().name() == "robot")
        })
        .map(|n| {
            format!(
                "{} `{}`",
                n.tag_name().name(),
                n.attribute("name").unwrap_or("?")
            )
        })
}

/// The first attribute of a link or joint that urdf-rs cannot read (a number that is not one, a
/// vector of the wrong length, an unknown joint type, a required attribute missing, an empty
/// `<geometry>`, an `<inertial>` without its mass or inertia), with its line; None if none is
/// found, and urdf-rs's own message then stands.
pub(super) fn syntax_error(text: &str) -> Option<Place> {
    let document = match roxmltree::Document::parse(text) {
        Ok(document) => document,
        Err(roxmltree::Error::DtdDetected) => return None,
        Err(e) => {
            return Some(Place {
                line: e.pos().row,
                message: format!("not XML: {e}"),
            });
        }
    };
    let robot = document.root_element();
    // URDF 1.2 reads a missing velocity as unbounded; earlier versions need it
    let velocity_required = robot
        .attribute("version")
        .is_none_or(|v| matches!(v.trim(), "1.0" | "1.1"));
    for node in robot.descendants().filter(|n| n.is_element()) {
        let Some(owner) = owner(node) else { continue };
        let tag = node.tag_name().name();
        let line = line_of(&document, node.range().start);
        let place = |message: String| Some(Place { line, message });
        if tag == "joint" && node.parent_element() == Some(robot) {
            let Some(kind) = node.attribute("type") else {
                return place(format!(
                    "<joint> {owner}: no type attribute (expected one of {})",
                    JOINT_TYPES.join(", ")
                ));
            };
            if !JOINT_TYPES.contains(&kind) {
                return place(format!(
                    "<joint type=\"{kind}\"> {owner}: expected one of {}, got \"{kind}\"",
                    JOINT_TYPES.join(", ")
                ));
            }
            for needed in ["parent", "child"] {
                if !node.children().any(|c| c.tag_name().name() == needed) {
                    return place(format!(
                        "<joint> {owner}: no <{needed} link=\"…\"/> element"
                    ));
                }
            }
            continue;
        }
        // the elements urdf-rs needs inside these, which it reports only as a parser's state
        if tag == "geometry" && !node.children().any(|c| c.is_element()) {
            return place(format!(
                "<geometry> in {owner}: empty (expected one shape: <box>, <cylinder>, <sphere>, \
                 <capsule> or <mesh>)"
            ));
        }
        if tag == "inertial" {
            for (needed, example) in [
                ("mass", "<mass value=\"0.1\"/>"),
                ("inertia", "<inertia ixx=… ixy=… ixz=… iyy=… iyz=… izz=…/>"),
            ] {
                if !node.children().any(|c| c.tag_name().name() == needed) {
                    return place(format!(
                        "<inertial> in {owner}: no <{needed}> element (expected {example})"
                    ));
                }
            }
        }
        let Some(attributes) = attributes(tag, velocity_required) else {
            continue;
        };
        for (name, value, required) in attributes {
            let Some(attribute) = node.attributes().find(|a| a.name() == name) else {
                if required {
                    return place(format!(
                        "<{tag}> in {owner}: no {name} attribute (expected {})",
                        expected(value)
                    ));
                }
                continue;
            };
            let text = attribute.value();
            let readable = match value {
                Value::Number => text.trim().parse::<f64>().is_ok(),
                Value::Numbers(n) => {
                    text.split_whitespace()
                        .filter(|s| s.parse::<f64>().is_ok())
                        .count()
                        == n
                }
                Value::Text => true,
            };
            if !readable {
                let line = line_of(&document, attribute.range().start);
                let comma = if text.contains(',') {
                    " (with a decimal point, not a comma)"
                } else {
                    ""
                };
                return Some(Place {
                    line,
                    message: format!(
                        "<{tag} {name}=\"{text}\"> in {owner}: expected {}{comma}, got \"{text}\"",
                        expected(value)
                    ),
                });
            }
        }
    }
    None
}

fn expected(value: Value) -> String {
    match value {
        Value::Number => "a number".into(),
        Value::Numbers(n) => format!("{n} numbers separated by spaces"),
        Value::Text => "a name".into(),
    }
}

/// One warning per element inside a link or joint that URDF does not define, naming it, its
/// owner and its line.
pub(super) fn unknown_elements(text: &str) -> Vec<String> {
    let Some(document) = document(text) else {
        return Vec::new();
    };
    let robot = document.root_element();
    let mut warnings = Vec::new();
    for owner in robot.children().filter(|n| n.is_element()) {
        let known: &[&str] = match owner.tag_name().name() {
            "link" => &LINK_CHILDREN,
            "joint" => &JOINT_CHILDREN,
            _ => continue,
        };
        for child in owner.children().filter(|n| n.is_element()) {
            let tag = child.tag_name().name();
            if !known.contains(&tag) {
                warnings.push(format!(
                    "line {}: <{tag}> in {} `{}` is not a URDF element of a {} (expected one of {}): ignored (misspelt?)",
                    line_of(&document, child.range().start),
                    owner.tag_name().name(),
                    owner.attribute("name").unwrap_or("?"),
                    owner.tag_name().name(),
                    known
                        .iter()
                        .filter(|k| **k != "contact")
                        .copied()
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
        }
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROBOT: &str = r#"<robot name="r">
  <link name="body">
    <inertial><mass value="MASS"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <link name="leg"/>
  <joint name="hip" type="TYPE">
    <parent link="body"/><child link="leg"/>
    <axis xyz="AXIS"/>
    <LIMIT lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
</robot>"#;

    fn robot(mass: &str, kind: &str, axis: &str, limit: &str) -> String {
        ROBOT
            .replace("MASS", mass)
            .replace("TYPE", kind)
            .replace("AXIS", axis)
            .replace("LIMIT", limit)
    }

    /// Each of the three syntax errors is found at its line, naming its element and owner; a
    /// well-formed robot has none, and urdf-rs reads it.
    #[test]
    fn syntax_errors_are_placed() {
        let good = robot("0.07", "revolute", "0 1 0", "limit");
        assert_eq!(syntax_error(&good), None);
        assert!(urdf_rs::read_from_string(&good).is_ok());
        let cases = [
            (
                robot("0,07", "revolute", "0 1 0", "limit"),
                3,
                "<mass value=\"0,07\"> in link `body`: expected a number (with a decimal point, not a comma), got \"0,07\"",
            ),
            (
                robot("0.07", "revolut", "0 1 0", "limit"),
                6,
                "<joint type=\"revolut\"> joint `hip`: expected one of revolute,",
            ),
            (
                robot("0.07", "revolute", "0 1", "limit"),
                8,
                "<axis xyz=\"0 1\"> in joint `hip`: expected 3 numbers separated by spaces, got \"0 1\"",
            ),
            (
                robot("0.07", "revolute", "0 1 0", "limit").replace(
                    "<link name=\"leg\"/>",
                    "<link name=\"leg\">\n<collision><geometry></geometry></collision></link>",
                ),
                6,
                "<geometry> in link `leg`: empty (expected one shape",
            ),
            (
                robot("0.07", "revolute", "0 1 0", "limit").replace("<mass value=\"0.07\"/>", ""),
                3,
                "<inertial> in link `body`: no <mass> element (expected <mass value=\"0.1\"/>)",
            ),
            (
                robot("0.07", "revolute", "0 1 0", "limit").replace(
                    "<inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>",
                    "",
                ),
                3,
                "<inertial> in link `body`: no <inertia> element",
            ),
        ];
        for (text, line, message) in cases {
            assert!(urdf_rs::read_from_string(&text).is_err(), "{text}");
            let place = syntax_error(&text).unwrap();
            assert_eq!(place.line, line, "{}", place.message);
            assert!(place.message.starts_with(message), "{}", place.message);
        }
    }

    /// A misspelt `<limt>` is named with its joint and line; URDF's own elements and Bullet's
    /// `<contact>` are not.
    #[test]
    fn unknown_elements_in_a_joint_are_named() {
        assert!(unknown_elements(&robot("1", "revolute", "0 1 0", "limit")).is_empty());
        let warnings = unknown_elements(&robot("1", "revolute", "0 1 0", "limt"));
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].starts_with("line 9: <limt> in joint `hip` is not a URDF element"),
            "{}",
            warnings[0]
        );
        let bullet = ROBOT.replace(
            "<link name=\"leg\"/>",
            "<link name=\"leg\"><contact/></link>",
        );
        assert!(unknown_elements(&bullet.replace("LIMIT", "limit")).is_empty());
    }
}
