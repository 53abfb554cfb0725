//! The robot's links as rerun entities: a tree that nests as the kinematic tree does, each link
//! under a static entity holding its joint's origin, so a frame logs only the root's pose and each
//! joint's rotation. Shared by the walk's recording and `hexsim robot --record`.

use crate::robot::{RobotModel, Shape, Visual};
use anyhow::Result;
use glam::{DAffine3, DQuat};

/// The entities of a robot's links, with their shapes logged.
pub struct LinkTree {
    /// Per link, its entity path, parsed once (a path given as text is parsed at every log).
    entities: Vec<rerun::EntityPath>,
}

impl LinkTree {
    /// Logs the joint origins and the links' shapes (static) under `root` (e.g. `world/robot`).
    pub fn log(rec: &rerun::RecordingStream, model: &RobotModel, root: &str) -> Result<Self> {
        Self::log_tinted(rec, model, root, None)
    }

    /// [`Self::log`] with every shape in one colour instead of the URDF's (RGB), to tell robots
    /// apart.
    pub fn log_tinted(
        rec: &rerun::RecordingStream,
        model: &RobotModel,
        root: &str,
        tint: Option<[u8; 3]>,
    ) -> Result<Self> {
        let mut paths: Vec<String> = Vec::new();
        for link in &model.links {
            let entity = match link.parent_joint {
                None => format!("{root}/{}", link.name),
                Some(j) => {
                    let joint = &model.joints[j];
                    let frame = format!("{}/{}", paths[joint.parent], joint.name);
                    log_pose(rec, frame.as_str(), &joint.origin, true)?;
                    format!("{frame}/{}", link.name)
                }
            };
            for (k, visual) in link.visuals.iter().enumerate() {
                log_visual(rec, &format!("{entity}/visual_{k}"), visual, tint)?;
            }
            paths.push(entity);
        }
        let entities = paths.iter().map(|p| p.as_str().into()).collect();
        Ok(LinkTree { entities })
    }

    /// Logs the links at their world poses `frames`: the root's pose and each joint's rotation
    /// (or, with `joints_drift`, for joints that do not hold their links exactly, each link's full
    /// pose relative to its joint frame). Static for a still picture, else at the current time.
    pub fn log_frames(
        &self,
        rec: &rerun::RecordingStream,
        model: &RobotModel,
        frames: &[DAffine3],
        joints_drift: bool,
        is_static: bool,
    ) -> Result<()> {
        for ((entity, link), frame) in self.entities.iter().zip(&model.links).zip(frames) {
            match link.parent_joint {
                None => log_pose(rec, entity.clone(), frame, is_static)?,
                Some(j) => {
                    let joint = &model.joints[j];
                    let joint_frame = frames[joint.parent] * joint.origin;
                    let relative = joint_frame.inverse() * *frame;
                    if joints_drift {
                        log_pose(rec, entity.clone(), &relative, is_static)?;
                    } else {
                        // a rigid joint only turns: its link sits at the joint frame's origin
                        let turn = rerun::Transform3D::from_rotation(quaternion(&relative));
                        if is_static {
                            rec.log_static(entity.clone(), &turn)?;
                        } else {
                            rec.log(entity.clone(), &turn)?;
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

fn quaternion(m: &DAffine3) -> rerun::Quaternion {
    rerun::Quaternion::from_xyzw(
        DQuat::from_mat3(&m.matrix3)
            .normalize()
            .as_quat()
            .to_array(),
    )
}

fn rgba(c: [f32; 4]) -> [u8; 4] {
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Logs `pose` (translation and rotation) at `entity`, static or at the current time.
fn log_pose(
    rec: &rerun::RecordingStream,
    entity: impl Into<rerun::EntityPath>,
    pose: &DAffine3,
    is_static: bool,
) -> Result<()> {
    let transform = rerun::Transform3D::from_translation_rotation(
        pose.translation.as_vec3().to_array(),
        quaternion(pose),
    );
    if is_static {
        rec.log_static(entity, &transform)?;
    } else {
        rec.log(entity, &transform)?;
    }
    Ok(())
}

fn log_visual(
    rec: &rerun::RecordingStream,
    entity: &str,
    visual: &Visual,
    tint: Option<[u8; 3]>,
) -> Result<()> {
    let mut origin = visual.origin;
    let color = match tint {
        Some([r, g, b]) => [r, g, b, 255],
        None => rgba(visual.color),
    };
    match &visual.shape {
        Shape::Box { half_extents } => rec.log_static(
            entity,
            &rerun::Boxes3D::from_half_sizes([half_extents.as_vec3().to_array()])
                .with_colors([color])
                .with_fill_mode(rerun::FillMode::Solid),
        )?,
        Shape::Cylinder { radius, length } => rec.log_static(
            entity,
            &rerun::Cylinders3D::from_lengths_and_radii([*length as f32], [*radius as f32])
                .with_colors([color])
                .with_fill_mode(rerun::FillMode::Solid),
        )?,
        Shape::Capsule { radius, length } => {
            // rerun's capsule runs from its origin along +z; the URDF's is centred
            origin *= DAffine3::from_translation(glam::DVec3::new(0.0, 0.0, -length / 2.0));
            rec.log_static(
                entity,
                &rerun::Capsules3D::from_lengths_and_radii([*length as f32], [*radius as f32])
                    .with_colors([color])
                    .with_fill_mode(rerun::FillMode::Solid),
            )?
        }
        Shape::Sphere { radius } => rec.log_static(
            entity,
            &rerun::Ellipsoids3D::from_radii([*radius as f32])
                .with_colors([color])
                .with_fill_mode(rerun::FillMode::Solid),
        )?,
        Shape::Mesh { path, scale } => {
            // a CAD mesh too detailed to copy into every link's entity is drawn simplified
            let drawn = match super::mesh::simplified_stl(path) {
                Some(mesh) => {
                    let mesh = rerun::Mesh3D::new(mesh.vertices)
                        .with_vertex_normals(mesh.normals)
                        .with_triangle_indices(mesh.triangles)
                        .with_albedo_factor(color);
                    rec.log_static(entity, &mesh).map(|()| true)
                }
                None => match rerun::Asset3D::from_file_path(path) {
                    Ok(asset) => rec
                        .log_static(entity, &asset.with_albedo_factor(color))
                        .map(|()| true),
                    Err(_) => Ok(false),
                },
            }?;
            if drawn {
                // the URDF's mesh scale (e.g. 0.001 for a mesh drawn in millimetres)
                let transform = rerun::Transform3D::from_translation_rotation_scale(
                    origin.translation.as_vec3().to_array(),
                    quaternion(&origin),
                    scale.as_vec3().to_array(),
                );
                rec.log_static(entity, &transform)?;
                return Ok(());
            }
            rec.log_static(
                entity,
                &rerun::Ellipsoids3D::from_radii([0.01f32]).with_colors([color]),
            )?
        }
    }
    log_pose(rec, entity, &origin, true)
}
