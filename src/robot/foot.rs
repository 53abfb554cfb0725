//! A foot found from a leg's own geometry, for URDFs that do not mark their feet with a collision
//! sphere (CAD exports, ROS description packages): the last link's tibia mesh, a pad, a box.
//!
//! The tip is the geometry's point farthest from the last joint's axis (the knee): the leg's end
//! as it swings. Below the tip the geometry widens; the foot sphere is the one that fits the tip's
//! own rounding. Going down from the tip by a depth h, the half-width w(h) of the geometry's cross
//! section grows as √(2ρh − h²) for an end rounded with radius ρ, so w(h) ≥ h until h = ρ: the
//! radius is the depth where the half-width first falls behind the depth. A flat pad's sole is
//! as wide as it is at h = 0, so its sphere is the sole's half-width, its bottom on the sole. A
//! sharp point never gets as wide as deep, so its sphere is the smallest allowed. The sphere is
//! centred on the tip's cross section, its surface touching the tip, and its radius kept within
//! [`RADIUS_BOUNDS`] of the tip's distance from the knee.

use super::mesh;
use super::model::{Foot, FootFrom};
use glam::{DAffine3, DVec3};
use std::path::Path;

/// The foot radius as a fraction of the tip's distance from the knee's axis, at least and at
/// most: a needle point gets a sphere 2 % of the tibia, a broad pad no more than 10 % (hex18's
/// foot is 8 %, PhantomX's rounded tip 4 %).
pub const RADIUS_BOUNDS: (f64, f64) = (0.02, 0.10);

/// A shape placed in the leg's last link (collision or visual, from any link merged into it).
#[derive(Debug, Clone)]
pub struct Placed {
    pub origin: DAffine3,
    pub geometry: urdf_rs::Geometry,
}

/// A foot found, and the collision meshes that could not be read on the way (a foot found from
/// the visual geometry instead deserves a warning).
#[derive(Debug)]
pub struct Found {
    pub foot: Foot,
    pub unread: Vec<String>,
}

/// The foot at the tip of a leg's last link: from its collision geometry, else its visual
/// geometry. `knee`: the last joint's unit axis, through the link frame's origin. Err says why no
/// foot could be found (for the message that asks for one).
pub fn find(
    collision: &[Placed],
    visual: &[Placed],
    knee: DVec3,
    base: &Path,
) -> Result<Found, String> {
    let mut unread = Vec::new();
    for (pieces, from) in [
        (collision, FootFrom::CollisionTip),
        (visual, FootFrom::VisualTip),
    ] {
        let points = points(pieces, base, &mut unread);
        if let Some((center, radius)) = tip_sphere(&points, knee) {
            let foot = Foot {
                center,
                radius,
                from,
            };
            return Ok(Found { foot, unread });
        }
    }
    Err(if unread.is_empty() {
        "it has no collision or visual geometry to find its tip from".to_string()
    } else {
        format!(
            "its geometry could not be read to find its tip ({}; hexsim reads STL, COLLADA and OBJ meshes and the URDF's shapes)",
            unread.join(", ")
        )
    })
}

/// Points on the surface of each shape, in the link frame (a mesh's vertices, a box's corners,
/// circles on a cylinder, rings on a sphere). `unread`: meshes that could not be read.
fn points(pieces: &[Placed], base: &Path, unread: &mut Vec<String>) -> Vec<DVec3> {
    let mut out = Vec::new();
    for piece in pieces {
        let local: Vec<DVec3> = match &piece.geometry {
            urdf_rs::Geometry::Box { size } => {
                let h = DVec3::from_array(size.0) * 0.5;
                (0..8)
                    .map(|i| {
                        let s = |bit: usize| if i >> bit & 1 == 1 { 1.0 } else { -1.0 };
                        h * DVec3::new(s(0), s(1), s(2))
                    })
                    .collect()
            }
            urdf_rs::Geometry::Cylinder { radius, length } => [-0.5, 0.5]
                .iter()
                .flat_map(|&end| circle(*radius, end * length))
                .collect(),
            urdf_rs::Geometry::Capsule { radius, length } => [-0.5, 0.5]
                .iter()
                .flat_map(|&end| sphere(*radius, DVec3::Z * end * length))
                .collect(),
            urdf_rs::Geometry::Sphere { radius } => sphere(*radius, DVec3::ZERO),
            urdf_rs::Geometry::Mesh { filename, scale } => {
                mesh::scaled_vertices(filename, scale.as_ref(), base).unwrap_or_else(|why| {
                    // a leg's collision and visual often name one mesh: said once
                    if !unread.contains(&why) {
                        unread.push(why);
                    }
                    Vec::new()
                })
            }
        };
        out.extend(local.into_iter().map(|p| piece.origin.transform_point3(p)));
    }
    out
}

/// 32 points on a circle of radius `r` about the z axis, at height `z`.
fn circle(r: f64, z: f64) -> impl Iterator<Item = DVec3> {
    (0..32).map(move |i| {
        let a = i as f64 * std::f64::consts::TAU / 32.0;
        DVec3::new(r * a.cos(), r * a.sin(), z)
    })
}

/// Points on a sphere of radius `r` about `c`: its poles and 15 rings of 32.
fn sphere(r: f64, c: DVec3) -> Vec<DVec3> {
    let mut out = vec![c + DVec3::Z * r, c - DVec3::Z * r];
    for ring in 1..16 {
        let polar = ring as f64 * std::f64::consts::PI / 16.0;
        out.extend(circle(r * polar.sin(), r * polar.cos()).map(|p| p + c));
    }
    out
}

/// The foot sphere (centre, radius) at the tip of `points`, seen from the knee axis `knee`
/// through the origin; None if there are no points off the axis.
fn tip_sphere(points: &[DVec3], knee: DVec3) -> Option<(DVec3, f64)> {
    let radial = |p: DVec3| p - knee * p.dot(knee);
    let tip = points
        .iter()
        .copied()
        .max_by(|a, b| radial(*a).length().total_cmp(&radial(*b).length()))?;
    let reach = radial(tip).length();
    if !(reach.is_finite() && reach > 1e-6) {
        return None;
    }
    // The farthest point of a flat sole is its corner: look again from the axis towards the
    // middle of the cap first found.
    let first = cap(points, knee, radial(tip) / reach, reach);
    let along = radial(first.middle).normalize_or(radial(tip) / reach);
    let found = cap(points, knee, along, reach);
    Some((found.center, found.radius))
}

/// A sphere fitted to a tip, and the middle of the tip's cross section one radius down.
struct Cap {
    center: DVec3,
    radius: f64,
    middle: DVec3,
}

/// The sphere fitted to the tip along `along` (a unit vector across the knee axis), its radius
/// bounded by [`RADIUS_BOUNDS`] of `reach`.
fn cap(points: &[DVec3], knee: DVec3, along: DVec3, reach: f64) -> Cap {
    let side = along.cross(knee);
    let top = points.iter().map(|p| p.dot(along)).fold(f64::MIN, f64::max);
    let mut by_depth: Vec<(f64, f64, f64)> = points
        .iter()
        .map(|p| (top - p.dot(along), p.dot(knee), p.dot(side)))
        .collect();
    by_depth.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (lo, hi) = (RADIUS_BOUNDS.0 * reach, RADIUS_BOUNDS.1 * reach);
    // the cross section's box (knee, side) of the points down to each depth; between two depths
    // the surface runs straight (a mesh's faces), and the radius is where its half-width falls
    // behind the depth
    let mut bounds = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
    let mut previous = (0.0, 0.0);
    let mut radius = None;
    for (i, &(depth, u, v)) in by_depth.iter().enumerate() {
        bounds = [
            bounds[0].min(u),
            bounds[1].max(u),
            bounds[2].min(v),
            bounds[3].max(v),
        ];
        let next = by_depth.get(i + 1).map_or(f64::INFINITY, |n| n.0);
        if next <= depth {
            continue; // points at one depth are one cross section
        }
        let half_width = 0.5 * (bounds[1] - bounds[0]).max(bounds[3] - bounds[2]);
        // a tip's first points are tessellation, not its shape: look from the smallest radius
        if depth >= lo && half_width < depth {
            let (d0, w0) = previous;
            let slope = (half_width - w0) / (depth - d0);
            radius = Some(if slope < 1.0 {
                (w0 - d0 * slope) / (1.0 - slope)
            } else {
                half_width
            });
            break;
        }
        if depth >= hi {
            radius = Some(hi);
            break;
        }
        previous = (depth, half_width);
    }
    // the geometry ends before it narrows: a pad as wide as it is deep
    let radius = radius.unwrap_or(previous.1);
    let radius = radius.clamp(lo, hi);
    // the middle of the points down to `depth`, across the leg (knee, side)
    let middle = |depth: f64| {
        let mut b = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
        for &(_, u, v) in by_depth.iter().take_while(|p| p.0 <= depth) {
            b = [b[0].min(u), b[1].max(u), b[2].min(v), b[3].max(v)];
        }
        knee * 0.5 * (b[0] + b[1]) + side * 0.5 * (b[2] + b[3]) + along * (top - radius)
    };
    // the sphere sits under the tip: the farthest point, or the middle of a flat sole (the
    // points within 1 % of the radius of the farthest)
    Cap {
        center: middle(0.01 * radius),
        radius,
        middle: middle(radius),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn placed(geometry: urdf_rs::Geometry, at: DVec3) -> Placed {
        Placed {
            origin: DAffine3::from_translation(at),
            geometry,
        }
    }

    fn found(pieces: &[Placed]) -> Foot {
        find(pieces, &[], DVec3::Y, Path::new(".")).unwrap().foot
    }

    /// A tibia (a thin box out along x from the knee, axis y) ending in a sphere: the foot is
    /// that sphere, found from its sampled surface.
    #[test]
    fn a_rounded_tip_gets_its_own_sphere() {
        let rod = urdf_rs::Geometry::Box {
            size: urdf_rs::Vec3([0.12, 0.012, 0.012]),
        };
        let ball = urdf_rs::Geometry::Sphere { radius: 0.008 };
        let foot = found(&[
            placed(rod, DVec3::new(0.06, 0.0, 0.0)),
            placed(ball, DVec3::new(0.12, 0.0, 0.0)),
        ]);
        assert!((foot.radius - 0.008).abs() < 5e-4, "{foot:?}");
        assert!((foot.center - DVec3::new(0.12, 0.0, 0.0)).length() < 5e-4);
        assert_eq!(foot.from, FootFrom::CollisionTip);
    }

    /// A pad (a cylinder across the leg's end, its axis along the leg): the sphere's bottom on
    /// the sole, as wide as the pad within the bounds.
    #[test]
    fn a_pad_puts_the_sphere_on_its_sole() {
        let pad = urdf_rs::Geometry::Cylinder {
            radius: 0.009,
            length: 0.004,
        };
        let origin = DAffine3::from_rotation_translation(
            glam::DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2),
            DVec3::new(0.15, 0.0, 0.0),
        );
        let foot = found(&[Placed {
            origin,
            geometry: pad,
        }]);
        assert!((foot.radius - 0.009).abs() < 1e-4, "{foot:?}");
        let sole = foot.center + DVec3::X * foot.radius;
        assert!(
            (sole - DVec3::new(0.152, 0.0, 0.0)).length() < 1e-4,
            "{sole}"
        );
    }

    /// A needle: the smallest sphere allowed, touching the point.
    #[test]
    fn a_sharp_point_gets_the_smallest_sphere() {
        let points = [DVec3::new(0.1, 0.0, 0.0)]
            .into_iter()
            .chain(circle(0.01, 0.0).map(|p| DVec3::new(0.0, p.x, p.y)))
            .collect::<Vec<_>>();
        let (center, radius) = tip_sphere(&points, DVec3::Y).unwrap();
        assert!((radius - 0.002).abs() < 1e-12);
        assert!((center - DVec3::new(0.098, 0.0, 0.0)).length() < 1e-9);
    }

    #[test]
    fn no_geometry_says_so() {
        let e = find(&[], &[], DVec3::Y, Path::new(".")).unwrap_err();
        assert!(e.contains("no collision or visual geometry"), "{e}");
    }
}
