//! Every link's contact set: its collision geometry reduced to spheres, so that shins, knees and
//! the belly touch the terrain through the same sphere contact as the feet (the paper's model is
//! of a sphere on a height grid; a sphere's closest point on the terrain is all it needs).
//!
//! How each URDF shape becomes spheres (in the link frame):
//! - a sphere is itself;
//! - a capsule is spheres of its radius along its axis, centres at most [`SPACING`]·r apart (the
//!   surface sags between two by at most r·(1 − √(1 − (s/2r)²)) = 0.2·r at s = 1.2·r);
//! - a cylinder longer than its diameter is the same with its ends rounded; a disc (shorter) is
//!   spheres of half its thickness over its face;
//! - a box is spheres of its smallest half-extent ρ on a grid over its mid-plane, the grid's
//!   edges inset by ρ so the spheres reach the faces: its edges and corners come out rounded, and
//!   a point of its broad faces is at most 0.3·ρ from the spheres (amid four of them);
//! - a mesh is sampled: its vertices binned in cubes of the sphere spacing, each bin's mean pulled
//!   into the mesh's bounding box shrunk by ρ (half its smallest extent), so a surface sample
//!   becomes a sphere that reaches back to the surface.
//!
//! At most [`MOST_PER_AXIS`] spheres along any axis of a shape: a long thin plate's spheres then
//! stand apart, and the ground can reach between them (said in docs/physics.md). Only collision
//! geometry touches, as in every URDF simulator: a description that gives only its feet collision
//! shapes (a simplified model) keeps its other links out of the ground's way. The foot sphere stands for its link's tip: spheres that overlap it are left out, so the foot's
//! contact is the foot's alone.

use super::foot::Placed;
use super::mesh;
use super::model::{ContactSphere, Link};
use glam::{DAffine3, DVec3};
use std::collections::BTreeMap;
use std::path::Path;

/// Sphere centres are at most this many radii apart along a shape.
pub const SPACING: f64 = 1.2;

/// At most this many spheres along any axis of one shape.
pub const MOST_PER_AXIS: usize = 12;

/// The smallest sphere a shape is reduced to (m): a mesh of a sheet has no thickness.
const SMALLEST_RADIUS: f64 = 1e-3;

/// What was found while building the contact sets, for the model's warnings.
#[derive(Debug, Default)]
pub struct Notes {
    /// (link, why) for meshes that could not be read: those pieces do not touch.
    pub unread: Vec<(String, String)>,
}

impl Notes {
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some((link, why)) = self.unread.first() {
            out.push(format!(
                "{} collision mesh{} could not be read and do not touch the ground (e.g. link `{link}`: {why})",
                self.unread.len(),
                if self.unread.len() == 1 { "" } else { "es" }
            ));
        }
        out
    }
}

/// Gives each link its contact spheres from its collision shapes, leaving out those that overlap
/// the link's foot.
pub fn attach(links: &mut [Link], shapes: &[(Vec<Placed>, Vec<Placed>)], base: &Path) -> Notes {
    let mut notes = Notes::default();
    for (link, (collisions, _visuals)) in links.iter_mut().zip(shapes) {
        let mut spheres = Vec::new();
        for piece in collisions {
            match spheres_of(piece, base) {
                Ok(found) => spheres.extend(found),
                Err(why) => notes.unread.push((link.name.clone(), why)),
            }
        }
        if let Some(foot) = link.foot {
            spheres.retain(|s| s.center.distance(foot.center) >= s.radius + foot.radius);
        }
        link.contacts = spheres;
    }
    notes
}

/// How far short of the foot's reach (in foot radii) a sphere of the foot's link may end and
/// still be part of its sole: the reach measured from the link's origin, on the knee's axis.
const SOLE_DEPTH: f64 = 1.5;

/// True if `sphere`, of the link that carries `foot`, is part of the foot's sole: it reaches as
/// far from the knee as the foot's tip, within [`SOLE_DEPTH`] foot radii. A flat pad wider than
/// its foot sphere (WORMS's rubber feet, 23 cm across on a 56 mm sphere) touches the ground with
/// its rim whenever the shin leans; that is the foot on the ground, not a shin, and is reported
/// and felt as the foot's contact. The shin above it reaches less far (WORMS: 0.43 against 0.46 m).
pub fn in_sole(sphere: &ContactSphere, foot: &super::model::Foot) -> bool {
    let reach = foot.center.length() + foot.radius;
    sphere.center.length() + sphere.radius >= reach - SOLE_DEPTH * foot.radius
}

/// How far leg `leg`'s foot reaches across the ground from its sphere's centre: its radius, or
/// farther where a sole ([`in_sole`]) is wider (WORMS's pads: 0.115 m on a 56 mm sphere).
pub fn sole_reach(model: &super::RobotModel, leg: usize) -> f64 {
    let leg = &model.legs[leg];
    model.links[leg.foot_link]
        .contacts
        .iter()
        .filter(|sphere| in_sole(sphere, &leg.foot))
        .map(|sphere| sphere.center.distance(leg.foot.center) + sphere.radius)
        .fold(leg.foot.radius, f64::max)
}

/// For each contact sphere of link `link`, the leg whose foot's sole it is part of
/// ([`in_sole`]): what the ground contact reports it as, and `hexsim robot` counts.
pub fn soles(model: &super::RobotModel, link: usize) -> impl Iterator<Item = Option<usize>> + '_ {
    let leg = model.legs.iter().position(|leg| leg.foot_link == link);
    model.links[link]
        .contacts
        .iter()
        .map(move |sphere| leg.filter(|&leg| in_sole(sphere, &model.legs[leg].foot)))
}

/// The sphere around a set of spheres (not the least one, but one that costs nothing to test):
/// centred on their box's centre. None for an empty set.
pub fn bound(spheres: &[ContactSphere]) -> Option<ContactSphere> {
    let lo = spheres.iter().map(|s| s.center).reduce(DVec3::min)?;
    let hi = spheres.iter().map(|s| s.center).reduce(DVec3::max)?;
    let center = 0.5 * (lo + hi);
    let radius = spheres
        .iter()
        .map(|s| s.center.distance(center) + s.radius)
        .fold(0.0, f64::max);
    Some(ContactSphere { center, radius })
}

/// One shape's spheres, in the link frame.
fn spheres_of(piece: &Placed, base: &Path) -> Result<Vec<ContactSphere>, String> {
    let local = match &piece.geometry {
        urdf_rs::Geometry::Sphere { radius } => vec![(DVec3::ZERO, *radius)],
        urdf_rs::Geometry::Capsule { radius, length } => segment(*radius, 0.5 * length),
        urdf_rs::Geometry::Cylinder { radius, length } => {
            let half = 0.5 * length;
            if half >= *radius {
                segment(*radius, half - radius)
            } else {
                disc(*radius, half)
            }
        }
        urdf_rs::Geometry::Box { size } => slab(DVec3::from_array(size.0) * 0.5),
        urdf_rs::Geometry::Mesh { filename, scale } => {
            sampled(&mesh::scaled_vertices(filename, scale.as_ref(), base)?)
        }
    };
    Ok(placed(&piece.origin, local))
}

fn placed(origin: &DAffine3, local: Vec<(DVec3, f64)>) -> Vec<ContactSphere> {
    local
        .into_iter()
        .filter(|(c, r)| c.is_finite() && r.is_finite() && *r > 0.0)
        .map(|(c, r)| ContactSphere {
            center: origin.transform_point3(c),
            radius: r,
        })
        .collect()
}

/// How many evenly spaced points cover [−half, half] with gaps of at most `gap` (at most
/// [`MOST_PER_AXIS`]), and the points.
fn spread(half: f64, gap: f64) -> Vec<f64> {
    if half <= 0.0 || gap <= 0.0 {
        return vec![0.0];
    }
    // (less a hair: a span of exactly three gaps is three gaps, not four)
    let n = ((2.0 * half / gap - 1e-9).ceil() as usize + 1).clamp(2, MOST_PER_AXIS);
    (0..n)
        .map(|i| -half + 2.0 * half * i as f64 / (n - 1) as f64)
        .collect()
}

/// Spheres of radius r with centres on the z axis from −half to half.
fn segment(r: f64, half: f64) -> Vec<(DVec3, f64)> {
    spread(half, SPACING * r)
        .into_iter()
        .map(|z| (DVec3::Z * z, r))
        .collect()
}

/// A disc of radius `r` about the z axis, `half` thick each way: spheres of radius `half` over it.
fn disc(r: f64, half: f64) -> Vec<(DVec3, f64)> {
    let reach = r - half;
    let rim = reach + 1e-12;
    let row = spread(
        reach,
        (SPACING * half).max(2.0 * reach / MOST_PER_AXIS as f64),
    );
    let mut out: Vec<(DVec3, f64)> = row
        .iter()
        .flat_map(|&x| row.iter().map(move |&y| DVec3::new(x, y, 0.0)))
        .filter(|p| p.length() <= rim)
        .map(|p| (p, half))
        .collect();
    // the rim, where the grid's corners were cut off
    let around = (std::f64::consts::TAU * reach / (SPACING * half))
        .ceil()
        .clamp(4.0, 4.0 * MOST_PER_AXIS as f64) as usize;
    out.extend((0..around).map(|i| {
        let a = i as f64 * std::f64::consts::TAU / around as f64;
        (DVec3::new(reach * a.cos(), reach * a.sin(), 0.0), half)
    }));
    out
}

/// A box of half-extents `h`: spheres of its smallest half-extent over its mid-plane.
fn slab(h: DVec3) -> Vec<(DVec3, f64)> {
    let rho = h.min_element().max(SMALLEST_RADIUS);
    let thin = h.min_position();
    let gap = (SPACING * rho).max(2.0 * h.max_element() / MOST_PER_AXIS as f64);
    let along = |axis: usize| -> Vec<f64> {
        if axis == thin {
            vec![0.0]
        } else {
            spread(h[axis] - rho, gap)
        }
    };
    let (xs, ys, zs) = (along(0), along(1), along(2));
    let mut out = Vec::with_capacity(xs.len() * ys.len() * zs.len());
    for &x in &xs {
        for &y in &ys {
            for &z in &zs {
                out.push((DVec3::new(x, y, z), rho));
            }
        }
    }
    out
}

/// A mesh's vertices as spheres (see the module docs).
fn sampled(vertices: &[DVec3]) -> Vec<(DVec3, f64)> {
    let finite: Vec<DVec3> = vertices.iter().copied().filter(|v| v.is_finite()).collect();
    let Some(lo) = finite.iter().copied().reduce(DVec3::min) else {
        return Vec::new();
    };
    let hi = finite.iter().copied().fold(lo, DVec3::max);
    let extent = hi - lo;
    let rho = (0.5 * extent.min_element()).max(SMALLEST_RADIUS);
    let cell = (SPACING * rho).max(extent.max_element() / MOST_PER_AXIS as f64);
    let bin = |p: DVec3| {
        let k = ((p - lo) / cell).floor();
        (k.x as i64, k.y as i64, k.z as i64)
    };
    // the mean of each bin's vertices (a BTreeMap: the order, hence the model, is deterministic)
    let mut bins: BTreeMap<(i64, i64, i64), (DVec3, usize)> = BTreeMap::new();
    for &v in &finite {
        let entry = bins.entry(bin(v)).or_insert((DVec3::ZERO, 0));
        entry.0 += v;
        entry.1 += 1;
    }
    let inner_lo = (lo + DVec3::splat(rho)).min(0.5 * (lo + hi));
    let inner_hi = (hi - DVec3::splat(rho)).max(0.5 * (lo + hi));
    let mut centres: BTreeMap<(i64, i64, i64), DVec3> = BTreeMap::new();
    for (sum, count) in bins.into_values() {
        let centre = (sum / count as f64).clamp(inner_lo, inner_hi);
        centres.entry(bin(centre)).or_insert(centre);
    }
    centres.into_values().map(|c| (c, rho)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn piece(geometry: urdf_rs::Geometry) -> Placed {
        Placed {
            origin: DAffine3::IDENTITY,
            geometry,
        }
    }

    /// The least distance from `p` to the surface of the union of spheres (negative inside).
    fn gap(spheres: &[ContactSphere], p: DVec3) -> f64 {
        spheres
            .iter()
            .map(|s| p.distance(s.center) - s.radius)
            .fold(f64::INFINITY, f64::min)
    }

    /// Spheres of the capsule's radius at most 1.2·r apart leave its surface at most
    /// (√(1 + 0.6²) − 1)·r = 0.166·r from them: midway between two, r out and 0.6·r along.
    #[test]
    fn a_capsule_is_covered_to_a_sixth_of_its_radius() {
        let (r, length) = (0.01, 0.12);
        let spheres = spheres_of(
            &piece(urdf_rs::Geometry::Capsule { radius: r, length }),
            Path::new("."),
        )
        .unwrap();
        // every point of the capsule's surface is within that of the spheres' union, never
        // outside; and the widest gap is that, the spheres no closer than they need be
        let bound = ((1.0f64 + 0.6 * 0.6).sqrt() - 1.0) * r;
        let mut widest = 0.0f64;
        for k in 0..=2400 {
            let z = -0.5 * length + length * k as f64 / 2400.0;
            let p = DVec3::new(r, 0.0, z);
            let g = gap(&spheres, p);
            assert!((-1e-12..=bound + 1e-12).contains(&g), "z = {z}: {g}");
            widest = widest.max(g);
        }
        assert!(
            widest > 0.9 * bound,
            "the widest gap {widest} of the bound {bound}"
        );
        // and nothing reaches beyond the capsule
        let tip = gap(&spheres, DVec3::new(0.0, 0.0, 0.5 * length + r));
        assert!(tip.abs() < 1e-12, "{tip}");
    }

    #[test]
    fn a_box_touches_a_plane_at_its_face_whatever_face_is_down() {
        let h = DVec3::new(0.12, 0.07, 0.025);
        let spheres = slab(h);
        assert_eq!(spheres.len(), 32, "hex18's body: 8 × 4");
        for axis in 0..3 {
            let lowest = spheres
                .iter()
                .map(|(c, r)| c[axis] - r)
                .fold(f64::INFINITY, f64::min);
            assert!((lowest + h[axis]).abs() < 1e-12, "axis {axis}: {lowest}");
        }
        // the bottom face's points are within 0.3·ρ of the spheres (ρ = 0.025): 0.14·ρ midway
        // between two, 0.29·ρ amid four
        let as_spheres: Vec<ContactSphere> = spheres
            .iter()
            .map(|&(center, radius)| ContactSphere { center, radius })
            .collect();
        for i in 0..=20 {
            for j in 0..=20 {
                let p = DVec3::new(
                    -0.095 + 0.19 * i as f64 / 20.0,
                    -0.045 + 0.09 * j as f64 / 20.0,
                    -0.025,
                );
                let g = gap(&as_spheres, p);
                assert!((-1e-12..=0.3 * 0.025).contains(&g), "{p}: {g}");
            }
        }
    }

    #[test]
    fn a_disc_lies_flat() {
        let spheres = disc(0.05, 0.005);
        assert!(spheres.iter().all(|(c, r)| (c.z - r + 0.005).abs() < 1e-12));
        let reach = spheres
            .iter()
            .map(|(c, r)| c.truncate().length() + r)
            .fold(0.0, f64::max);
        assert!((reach - 0.05).abs() < 1e-12, "{reach}");
    }

    #[test]
    fn a_mesh_of_a_rod_becomes_spheres_along_it_within_its_box() {
        // the corners of a 0.12 × 0.02 × 0.02 rod, and points along its edges
        let mut vertices = Vec::new();
        for k in 0..=24 {
            let x = -0.06 + 0.005 * k as f64;
            for (y, z) in [(-0.01, -0.01), (0.01, -0.01), (-0.01, 0.01), (0.01, 0.01)] {
                vertices.push(DVec3::new(x, y, z));
            }
        }
        let spheres = sampled(&vertices);
        assert!(
            spheres.len() >= 8 && spheres.len() <= 12,
            "{}",
            spheres.len()
        );
        for (c, r) in &spheres {
            assert!((r - 0.01).abs() < 1e-12);
            assert!(c.y.abs() < 1e-12 && c.z.abs() < 1e-12, "{c}");
            assert!(c.x.abs() <= 0.05 + 1e-12);
        }
    }

    #[test]
    fn spheres_that_overlap_the_foot_are_the_foots() {
        let mut links = vec![super::super::urdf::empty_link("tibia", None)];
        links[0].foot = Some(super::super::model::Foot {
            center: DVec3::new(0.0, 0.0, -0.06),
            radius: 0.01,
            from: super::super::model::FootFrom::Sphere,
        });
        let shapes = vec![(
            vec![piece(urdf_rs::Geometry::Capsule {
                radius: 0.01,
                length: 0.12,
            })],
            Vec::new(),
        )];
        attach(&mut links, &shapes, Path::new("."));
        let spheres = &links[0].contacts;
        assert!(!spheres.is_empty());
        assert!(
            spheres
                .iter()
                .all(|s| s.center.distance(DVec3::new(0.0, 0.0, -0.06)) >= 0.02 - 1e-12)
        );
    }

    /// WORMS's shin: a box 0.45 m long to 0.425 m from the knee, then a pad 0.23 m across and
    /// 18 mm thick at 0.535 m, its foot sphere (56 mm) at the tip. The pad's spheres are the
    /// foot's sole, the shin's are not.
    #[test]
    fn a_pad_wider_than_its_foot_is_the_foots_sole() {
        let at = |z: f64, geometry| Placed {
            origin: DAffine3::from_translation(DVec3::new(0.0, 0.0, z)),
            geometry,
        };
        let shin = spheres_of(
            &at(
                0.2,
                urdf_rs::Geometry::Box {
                    size: urdf_rs::Vec3([0.11, 0.15, 0.45]),
                },
            ),
            Path::new("."),
        )
        .unwrap();
        let pad = spheres_of(
            &at(
                0.535,
                urdf_rs::Geometry::Cylinder {
                    radius: 0.115,
                    length: 0.018,
                },
            ),
            Path::new("."),
        )
        .unwrap();
        let foot = super::super::model::Foot {
            center: DVec3::new(0.0, 0.0, 0.4884),
            radius: 0.0556,
            from: super::super::model::FootFrom::CollisionTip,
        };
        assert!(
            !shin.is_empty() && pad.len() > 20,
            "{} {}",
            shin.len(),
            pad.len()
        );
        assert!(pad.iter().all(|s| in_sole(s, &foot)));
        assert!(shin.iter().all(|s| !in_sole(s, &foot)));
    }
}
