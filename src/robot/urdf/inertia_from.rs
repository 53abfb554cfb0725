//! A link's centre of mass and inertia from its collision geometry, its URDF mass kept (MuJoCo's
//! `inertiafromgeom`): for URDFs whose inertials are placeholders.
//!
//! PhantomX's published URDF puts every leg link's centre of mass at its joint, with an inertia
//! a thousand times what its 24 g allow. Corrected by that factor alone, the tibia is a point at
//! the knee: its foot, 15 cm out, weighs a fraction of a gram sideways, and it chattered on the
//! ground, its slip flipping ±1 m/s every step at any time step (2.6–4.3 m of slip per foot in
//! 5 s). With the mass spread over the link's collision geometry it walks as hex18 does. The
//! geometry is read as a solid of uniform density: boxes, cylinders, capsules and spheres as they
//! are, a mesh as its convex hull (as MuJoCo does by default: CAD meshes are seldom closed), each
//! placed at its `<origin>`; parry's mass properties do the integrals.

use super::pose;
use glam::{DAffine3, DMat3, DQuat, DVec3};
use rapier3d::parry::mass_properties::MassProperties;
use rapier3d::parry::math::{Pose, Vector};
use rapier3d::parry::shape::SharedShape;
use std::path::Path;

/// The centre of mass and inertia tensor (about it, in the link's frame) of `mass` spread evenly
/// over the link's collision geometry, or why not (no geometry, a mesh unread, no volume).
pub(super) fn from_collision(
    link: &urdf_rs::Link,
    mass: f64,
    base: &Path,
) -> Result<(DVec3, DMat3), String> {
    if link.collision.is_empty() {
        return Err("it has no collision geometry".into());
    }
    let mut parts = Vec::with_capacity(link.collision.len());
    for collision in &link.collision {
        let (shape, turn) = solid(&collision.geometry, base)?;
        let at = pose(&collision.origin) * turn;
        parts.push((pose_of(&at), shape));
    }
    let solid = MassProperties::from_compound(1.0, &parts);
    let volume = solid.mass() as f64;
    if !(volume.is_finite() && volume > 0.0) {
        return Err("its collision geometry encloses no volume".into());
    }
    let density = mass / volume;
    Ok((
        solid.local_com.as_dvec3(),
        solid.reconstruct_inertia_matrix().as_dmat3() * density,
    ))
}

/// A URDF geometry as a parry solid, and the turn from the URDF's axes to parry's (a cylinder is
/// along z in a URDF, along y in parry).
fn solid(geometry: &urdf_rs::Geometry, base: &Path) -> Result<(SharedShape, DAffine3), String> {
    let still = DAffine3::IDENTITY;
    Ok(match geometry {
        urdf_rs::Geometry::Box { size } => {
            let [x, y, z] = size.0.map(|v| (0.5 * v) as f32);
            (SharedShape::cuboid(x, y, z), still)
        }
        urdf_rs::Geometry::Sphere { radius } => (SharedShape::ball(*radius as f32), still),
        urdf_rs::Geometry::Cylinder { radius, length } => (
            SharedShape::cylinder((0.5 * length) as f32, *radius as f32),
            DAffine3::from_rotation_x(std::f64::consts::FRAC_PI_2),
        ),
        urdf_rs::Geometry::Capsule { radius, length } => (
            SharedShape::capsule_z((0.5 * length) as f32, *radius as f32),
            still,
        ),
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let vertices = crate::robot::mesh::scaled_vertices(filename, scale.as_ref(), base)?;
            let points: Vec<Vector> = vertices.iter().map(|v| v.as_vec3()).collect();
            let hull = SharedShape::convex_hull(&points)
                .ok_or_else(|| format!("mesh {filename} has no convex hull (flat or empty)"))?;
            (hull, still)
        }
    })
}

/// A frame as parry's pose (as `sim::articulation` converts them for rapier).
fn pose_of(frame: &DAffine3) -> Pose {
    Pose::from_parts(
        frame.translation.as_vec3(),
        DQuat::from_mat3(&frame.matrix3).normalize().as_quat(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn link(collisions: &str) -> urdf_rs::Link {
        let text = format!(
            r#"<robot name="r"><link name="a">
                 <inertial><mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
                 {collisions}
               </link></robot>"#
        );
        urdf_rs::read_from_string(&text).unwrap().links.remove(0)
    }

    /// Equal to f32's precision, relative to the largest entry.
    fn close(a: DMat3, b: DMat3) -> bool {
        let scale = b.to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (a - b)
            .to_cols_array()
            .iter()
            .all(|d| d.abs() <= 1e-5 * scale)
    }

    /// A box at an offset: its centre, and m·(b² + c²)/12 about each axis.
    #[test]
    fn a_box_gives_its_centre_and_its_inertia() {
        let a = link(
            r#"<collision><origin xyz="0.1 0 0.2"/><geometry><box size="0.3 0.2 0.1"/></geometry></collision>"#,
        );
        let (com, inertia) = from_collision(&a, 2.0, Path::new(".")).unwrap();
        assert!(com.abs_diff_eq(DVec3::new(0.1, 0.0, 0.2), 1e-6), "{com}");
        let (x, y, z) = (0.3f64, 0.2f64, 0.1f64);
        let expected =
            DMat3::from_diagonal(DVec3::new(y * y + z * z, x * x + z * z, x * x + y * y))
                * (2.0 / 12.0);
        assert!(close(inertia, expected), "{inertia} vs {expected}");
    }

    /// A URDF cylinder lies along z: m·r²/2 about z, m·(3r² + l²)/12 across, even turned by its
    /// origin's rpy onto x.
    #[test]
    fn a_cylinder_lies_along_its_z() {
        let (r, l, m) = (0.05f64, 0.4f64, 2.0);
        let across = m * (3.0 * r * r + l * l) / 12.0;
        let along = m * r * r / 2.0;
        let a = link(
            r#"<collision><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>"#,
        );
        let (com, inertia) = from_collision(&a, m, Path::new(".")).unwrap();
        assert!(com.length() < 1e-6);
        let expected = DMat3::from_diagonal(DVec3::new(across, across, along));
        assert!(close(inertia, expected), "{inertia} vs {expected}");
        let turned = link(
            r#"<collision><origin rpy="0 1.5707963267948966 0"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>"#,
        );
        let (_, inertia) = from_collision(&turned, m, Path::new(".")).unwrap();
        let expected = DMat3::from_diagonal(DVec3::new(along, across, across));
        assert!(close(inertia, expected), "{inertia} vs {expected}");
    }

    /// Two equal spheres: the mass shared by volume, the centre between them, the parallel axes.
    #[test]
    fn two_pieces_share_the_mass_by_volume() {
        let a = link(
            r#"<collision><origin xyz="0 0 0"/><geometry><sphere radius="0.1"/></geometry></collision>
               <collision><origin xyz="0.4 0 0"/><geometry><sphere radius="0.1"/></geometry></collision>"#,
        );
        let (com, inertia) = from_collision(&a, 2.0, Path::new(".")).unwrap();
        assert!(com.abs_diff_eq(DVec3::new(0.2, 0.0, 0.0), 1e-6), "{com}");
        let own = 2.0 * 0.4 * 0.1 * 0.1; // two spheres of 1 kg: 2/5·m·r² each
        let apart = 2.0 * 0.2 * 0.2; // 1 kg each, 0.2 m off the centre
        let expected = DMat3::from_diagonal(DVec3::new(own, own + apart, own + apart));
        assert!(close(inertia, expected), "{inertia} vs {expected}");
    }

    /// Through the loader: hex18 with `inertia = "collision"` in its robot file keeps every mass,
    /// and its coxa (a 5 cm cylinder of 1 cm radius, along x from the joint) gets the cylinder's
    /// centre and inertia; a value other than "urdf" or "collision" is refused, naming the field.
    #[test]
    fn a_robot_file_takes_the_inertials_from_the_collision_geometry() {
        let urdf = include_str!("../../../robots/hex18.urdf");
        let file = include_str!("../../../robots/hex18.toml");
        let origin = Path::new("robots/hex18.urdf");
        let load = |file: &str| crate::robot::urdf::from_str_with(urdf, Some(file), origin);
        let given = load(file).unwrap();
        let found = load(&format!("inertia = \"collision\"\n{file}")).unwrap();
        assert_eq!(given.total_mass(), found.total_mass());
        let coxa = found.links.iter().find(|l| l.name == "lf_coxa").unwrap();
        assert!(
            coxa.com.abs_diff_eq(DVec3::new(0.025, 0.0, 0.0), 1e-6),
            "{}",
            coxa.com
        );
        let (m, r, l) = (coxa.mass, 0.01, 0.05);
        let across = m * (3.0 * r * r + l * l) / 12.0;
        let expected = DMat3::from_diagonal(DVec3::new(m * r * r / 2.0, across, across));
        assert!(
            close(coxa.inertia, expected),
            "{} vs {expected}",
            coxa.inertia
        );
        let e = load(&format!("inertia = \"mass\"\n{file}")).unwrap_err();
        assert!(e.to_string().contains("inertia"), "{e}");
    }

    #[test]
    fn a_link_without_collision_geometry_says_so() {
        let a = link("");
        let e = from_collision(&a, 2.0, Path::new(".")).unwrap_err();
        assert!(e.contains("no collision geometry"), "{e}");
        let missing =
            link(r#"<collision><geometry><mesh filename="nowhere.stl"/></geometry></collision>"#);
        let e = from_collision(&missing, 2.0, Path::new(".")).unwrap_err();
        assert!(e.contains("nowhere.stl"), "{e}");
    }
}
