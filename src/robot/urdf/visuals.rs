//! What the recording draws of each link: its visual shapes and colours, and the meshes it
//! cannot draw, gathered for one warning a kind.

use crate::robot::mesh;
use crate::robot::model::Shape;
use glam::DVec3;
use std::path::{Path, PathBuf};

pub(super) fn color_of(robot: &urdf_rs::Robot, material: &Option<urdf_rs::Material>) -> [f32; 4] {
    let default = [0.6, 0.6, 0.65, 1.0];
    let Some(material) = material else {
        return default;
    };
    let rgba = material.color.as_ref().or_else(|| {
        robot
            .materials
            .iter()
            .find(|m| m.name == material.name)
            .and_then(|m| m.color.as_ref())
    });
    rgba.map_or(default, |c| c.rgba.0.map(|v| v as f32))
}

/// Visual meshes that could not be used, gathered over the robot so that `build` warns once per
/// kind of problem rather than once per link.
#[derive(Default)]
pub(super) struct MeshProblems {
    /// (link, file) of meshes in a format the recording cannot draw.
    pub(super) undrawable: Vec<(String, PathBuf)>,
    /// Per mesh not found: the warning for it (link, URI, where it was looked for).
    pub(super) missing: Vec<String>,
}

impl MeshProblems {
    /// At most one warning for the undrawable meshes and one for the missing ones.
    pub(super) fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        if let Some((link, file)) = self.undrawable.first() {
            let n = self.undrawable.len();
            warnings.push(format!(
                "{n} visual mesh{} in a format the recording cannot draw (it draws STL, OBJ, glTF), e.g. link {link}: {}; drawn as the link's collision shape (or a small sphere)",
                if n == 1 { " is" } else { "es are" },
                file.display()
            ));
        }
        if let Some(first) = self.missing.first() {
            let mut warning = first.clone();
            if self.missing.len() > 1 {
                warning.push_str(&format!(
                    "; {} more visual meshes not found, drawn as their links' collision shapes (or small spheres)",
                    self.missing.len() - 1
                ));
            }
            warnings.push(warning);
        }
        warnings
    }
}

/// A visual's shape, or None for a mesh the recording cannot draw (missing, or a format rerun
/// does not read), noted in `problems`: the caller draws the link's collision shape instead
/// where it has one (`has_fallback`), else a small sphere.
pub(super) fn shape(
    geometry: &urdf_rs::Geometry,
    base: &Path,
    link: &str,
    has_fallback: bool,
    problems: &mut MeshProblems,
) -> Option<Shape> {
    Some(match geometry {
        urdf_rs::Geometry::Box { size } => Shape::Box {
            half_extents: DVec3::from_array(size.0) * 0.5,
        },
        urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
            radius: *radius,
            length: *length,
        },
        urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
            radius: *radius,
            length: *length,
        },
        urdf_rs::Geometry::Sphere { radius } => Shape::Sphere { radius: *radius },
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let scale = scale
                .as_ref()
                .map_or(DVec3::ONE, |s| DVec3::from_array(s.0));
            match mesh::resolve(filename, base) {
                Ok(path) if let Some(why) = mesh::unreadable(&path) => {
                    problems.missing.push(format!(
                        "link `{link}`: visual mesh {filename} ({}) cannot be read: {why}; drawn as {}",
                        path.display(),
                        if has_fallback {
                            "its collision shape"
                        } else {
                            "a small sphere"
                        }
                    ));
                    return None;
                }
                Ok(path) if mesh::drawable(&path) => Shape::Mesh { path, scale },
                Ok(path) => {
                    problems.undrawable.push((link.to_string(), path));
                    return None;
                }
                Err(tried) => {
                    let tried: Vec<String> =
                        tried.iter().map(|p| p.display().to_string()).collect();
                    // a robot whose meshes were not shipped with it still shows its shape
                    let drawn = if has_fallback {
                        "its collision shape"
                    } else {
                        "a small sphere"
                    };
                    problems.missing.push(format!(
                        "link `{link}`: visual mesh {filename} not found (looked in {}); drawn as {drawn}",
                        tried.join(", ")
                    ));
                    return None;
                }
            }
        }
    })
}
