//! The robot on the ground, each step: which feet and which of the links' contact spheres touch
//! the terrain, their ground frames and penetrations (paper §2), their forces solved together
//! through the articulation's contact mobility (a stance foot's stopping force moves the others,
//! and a belly's spheres push each other through the body: see [`crate::contact::joint`]), and
//! those forces applied to the links. This is the only ground force on the robot.
//!
//! Every link touches, not only the feet: a shin against a riser, a knee on a rock, the belly
//! of a robot that sat down (its contact spheres: `robot::contact_set`). Most of them are far
//! above the ground most of the time, so a broad phase goes first: a link whose bounding sphere
//! is above the highest the terrain reaches is passed over whole, and a sphere above the
//! terrain's bound around it ([`HeightGrid::ceiling_near`]) needs no closest-point search.
//!
//! A sphere in a concave corner — a foot on a pit's floor against its wall, a foot in a trench
//! its own width — presses into each face at once, and each face is a contact of its own, with
//! its own damper along its own normal and its own friction ([`crate::contact::sphere_faces`]).
//! Their springs summed into one contact would couple them: the summed normal tilts from one
//! wall to the other within a fraction of a millimetre, and a foot far more mobile sideways than
//! up (hex18's: 0.026 kg along x, 0.095 kg along z in a trench) is damped along one step's tilt
//! and moves along the next step's mirror image, swinging from wall to wall ×1.35 a step
//! (`ladder/gaps.toml` at 2 cm: a divergence).

use super::articulation::{ContactPoint, Joints};
use super::engine::Engine;
use super::face_slots::{Slot, SlotStates, free, match_faces};
use crate::contact::joint::{JointContact, JointSolver};
use crate::contact::{
    ContactForce, ContactModel, Faces, MAX_FACES, SphereGeometry, Variant, closest_from_each,
    faces_from_below_into, search_start,
};
use crate::robot::{ContactSphere, RobotModel, contact_set};
use crate::terrain::HeightGrid;
use glam::{DAffine3, DMat3, DVec3};
use rapier3d::prelude::RigidBodyHandle;

/// A touching contact of a link other than its foot (a shin, a knee, the belly).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkContact {
    /// The model link.
    pub link: usize,
    /// The contact sphere's radius (m): a penetration deeper than it has gone through.
    pub radius: f64,
    pub force: ContactForce,
}

/// A link's contact spheres and the sphere and box around them, for the broad phase.
struct LinkSpheres {
    link: usize,
    bound: ContactSphere,
    /// The box of the spheres' centres about `bound.center` (half-extents along the link's
    /// axes), and the largest radius: the lowest any sphere reaches, for a link as flat as
    /// hex18's body, is far above the lowest of its bounding sphere (see [`lowest_of_box`]).
    half: DVec3,
    largest: f64,
    /// Range in [`GroundContacts::spheres`].
    first: usize,
    end: usize,
    /// Some sphere of it touched last step (its states need resetting once it lifts).
    touched: bool,
}

/// Every contact's state between steps, and scratch.
pub(super) struct GroundContacts {
    /// [`MAX_FACES`] per sphere: the feet's, then every link sphere's.
    slots: Vec<Slot>,
    /// Per sphere (the feet's, then every link sphere's): where its last closest-point search
    /// ended, from its centre, while it touches ([`ContactModel::sphere_faces_from`]).
    last_search: Vec<Option<(f64, f64)>>,
    links: Vec<LinkSpheres>,
    spheres: Vec<ContactSphere>,
    /// Per sphere in `spheres`: the leg whose foot's sole it is part of (see
    /// `contact_set::soles`), whose contact it is reported as.
    soles: Vec<Option<usize>>,
    /// The highest the terrain's surface reaches anywhere.
    ceiling: f64,
    /// This step's touching contacts: their index in `slots`, rapier point, solver input.
    ids: Vec<usize>,
    points: Vec<ContactPoint>,
    inputs: Vec<JointContact>,
    velocities: Vec<DVec3>,
    mobility: Vec<DMat3>,
    forces: Vec<Option<ContactForce>>,
    solver: JointSolver,
}

impl GroundContacts {
    pub fn new(model: &RobotModel, terrain: &HeightGrid) -> Self {
        let mut links = Vec::new();
        let mut spheres = Vec::new();
        let mut soles = Vec::new();
        for (k, link) in model.links.iter().enumerate() {
            if let Some(bound) = contact_set::bound(&link.contacts) {
                let half = link
                    .contacts
                    .iter()
                    .map(|c| (c.center - bound.center).abs())
                    .fold(DVec3::ZERO, DVec3::max);
                let largest = link.contacts.iter().map(|c| c.radius).fold(0.0, f64::max);
                links.push(LinkSpheres {
                    link: k,
                    bound,
                    half,
                    largest,
                    first: spheres.len(),
                    end: spheres.len() + link.contacts.len(),
                    touched: false,
                });
                spheres.extend_from_slice(&link.contacts);
                soles.extend(contact_set::soles(model, k));
            }
        }
        let [x0, x1] = terrain.x_range();
        let [y0, y1] = terrain.y_range();
        let ceiling =
            terrain.ceiling_near(0.5 * (x0 + x1), 0.5 * (y0 + y1), (x1 - x0).max(y1 - y0));
        GroundContacts {
            slots: vec![Slot::default(); (6 + spheres.len()) * MAX_FACES],
            last_search: vec![None; 6 + spheres.len()],
            links,
            spheres,
            soles,
            ceiling,
            ids: Vec::new(),
            points: Vec::new(),
            inputs: Vec::new(),
            velocities: Vec::new(),
            mobility: Vec::new(),
            forces: Vec::new(),
            solver: JointSolver::default(),
        }
    }

    /// Finds the feet and link spheres touching `terrain`, solves their forces under `contact`,
    /// applies them to the links, and writes each leg's foot force (None: in the air) into `feet`
    /// (in place: a copy of the six was 150 instructions) and the other links' contacts into
    /// `link_contacts`. `frames` are the world poses of every model link; `bodies` the rapier
    /// body per model link.
    #[allow(clippy::too_many_arguments)]
    pub fn apply(
        &mut self,
        engine: &mut Engine,
        joints: &mut dyn Joints,
        model: &RobotModel,
        bodies: &[RigidBodyHandle],
        terrain: &HeightGrid,
        contact: &ContactModel,
        frames: &[DAffine3],
        link_contacts: &mut Vec<LinkContact>,
        feet: &mut [Option<ContactForce>; 6],
    ) {
        self.ids.clear();
        self.points.clear();
        self.inputs.clear();
        // the feet near the ground: their closest-point searches taken together (in turns, so
        // that one waits on its latencies while another computes: `closest_from_each`), then
        // each one's faces, in the feet's order
        let mut near = [(0, (DVec3::ZERO, 0.0, (0.0, 0.0))); 6];
        let mut n_near = 0;
        for (k, leg) in model.legs.iter().enumerate() {
            let frame = &frames[leg.foot_link];
            let center = frame.transform_point3(leg.foot.center);
            let r = leg.foot.radius;
            if !self.near_ground(k, center, r, terrain) {
                continue;
            }
            if contact.searches_from_below() {
                let start = search_start(terrain, center, self.last_search[k]);
                near[n_near] = (k, (center, r, start));
                n_near += 1;
            } else {
                let faces = contact.sphere_faces_from(terrain, center, r, &mut self.last_search[k]);
                self.add_faces(k, leg.foot_link, faces.as_slice(), frame, bodies, model);
            }
        }
        let spheres: [_; 6] = std::array::from_fn(|m| near[m].1);
        let below = closest_from_each(terrain, contact.orientation, &spheres[..n_near]);
        // each foot's faces written over the last foot's
        let mut faces = Faces::EMPTY;
        for (&(k, (center, r, _)), below) in near[..n_near].iter().zip(below) {
            let below = below.expect("one answer a sphere");
            let orientation = contact.orientation;
            let last = &mut self.last_search[k];
            faces_from_below_into(terrain, center, r, orientation, below, last, &mut faces);
            let leg = &model.legs[k];
            let frame = &frames[leg.foot_link];
            self.add_faces(k, leg.foot_link, faces.as_slice(), frame, bodies, model);
        }
        // the links' spheres, those near the ground
        for l in 0..self.links.len() {
            let LinkSpheres {
                link,
                bound,
                half,
                largest,
                first,
                end,
                touched,
            } = self.links[l];
            let frame = &frames[link];
            let centre = frame.transform_point3(bound.center).z;
            if centre - bound.radius > self.ceiling
                || lowest_of_box(frame, centre, half, largest) > self.ceiling
            {
                if touched {
                    free(&mut self.slots[(6 + first) * MAX_FACES..(6 + end) * MAX_FACES]);
                    self.last_search[6 + first..6 + end].fill(None);
                    self.links[l].touched = false;
                }
                continue;
            }
            let mut any = false;
            for s in first..end {
                let sphere = self.spheres[s];
                any |= self.find(6 + s, link, &sphere, frame, terrain, contact, bodies, model);
            }
            self.links[l].touched = any;
        }
        let n = self.ids.len();
        // contacts sharing a link damp it together (see `JointContact::sharing`)
        for i in 0..n {
            let link = self.points[i].link;
            self.inputs[i].sharing = self.points.iter().filter(|p| p.link == link).count();
        }
        self.velocities.clear();
        self.velocities.resize(n, DVec3::ZERO);
        // every block written by `contact_mobility`: not cleared first
        self.mobility.resize(n * n, DMat3::ZERO);
        joints.contact_mobility(
            engine,
            &self.points,
            &mut self.velocities,
            &mut self.mobility,
        );
        for (input, velocity) in self.inputs.iter_mut().zip(&self.velocities) {
            input.velocity = *velocity;
        }
        self.forces.clear();
        self.forces.resize(n, None);
        if contact.variant == Variant::Paper {
            // the paper's: each contact alone, its sphere's centre velocity, the force there
            for i in 0..n {
                let normal_mass =
                    1.0 / self.mobility[i * n + i].z_axis.z / self.inputs[i].sharing as f64;
                self.forces[i] = contact.respond_paper(
                    &self.inputs[i].geometry,
                    self.inputs[i].velocity,
                    normal_mass,
                    engine.dt(),
                    &mut self.slots[self.ids[i]].state,
                );
            }
        } else {
            let mobility = &self.mobility;
            self.solver.respond(
                contact,
                &self.inputs,
                |i, j| mobility[i * n + j],
                engine.dt(),
                &mut SlotStates {
                    slots: &mut self.slots,
                    ids: &self.ids,
                },
                &mut self.forces,
            );
        }
        *feet = [None; 6];
        link_contacts.clear();
        for i in 0..n {
            let id = self.ids[i];
            let Some(c) = &self.forces[i] else { continue };
            let point = &self.points[i];
            let torque = (c.point - point.com).cross(c.force);
            engine.add_force_and_torque(point.body, c.force.as_vec3(), torque.as_vec3(), true);
            let sphere = id / MAX_FACES;
            let foot = match sphere {
                0..6 => Some(sphere),
                _ => self.soles[sphere - 6],
            };
            if let Some(foot) = foot {
                // a foot pressing into several faces, or with its sole, reports them as one
                // contact
                match &mut feet[foot] {
                    Some(foot) => foot.merge(c),
                    none => *none = Some(*c),
                }
            } else {
                link_contacts.push(LinkContact {
                    link: point.link,
                    radius: self.spheres[sphere - 6].radius,
                    force: *c,
                });
            }
        }
    }

    /// Whether every free slot holds the default state, as [`free`] takes it to.
    #[cfg(test)]
    pub fn free_slots_are_default(&self) -> bool {
        self.slots
            .iter()
            .all(|s| !s.is_free() || s.state == crate::contact::ContactState::default())
    }

    /// Adds sphere `sphere` of link `link` (posed by `frame`) to this step's contacts, one per
    /// face it presses into, if it touches the terrain, as sphere `id`; false (its faces' states
    /// reset) if it is clear.
    #[allow(clippy::too_many_arguments)]
    fn find(
        &mut self,
        id: usize,
        link: usize,
        sphere: &ContactSphere,
        frame: &DAffine3,
        terrain: &HeightGrid,
        contact: &ContactModel,
        bodies: &[RigidBodyHandle],
        model: &RobotModel,
    ) -> bool {
        let center = frame.transform_point3(sphere.center);
        let r = sphere.radius;
        if !self.near_ground(id, center, r, terrain) {
            return false;
        }
        let faces = contact.sphere_faces_from(terrain, center, r, &mut self.last_search[id]);
        self.add_faces(id, link, faces.as_slice(), frame, bodies, model)
    }

    /// Whether sphere `id` (centre `center`, radius `r`) may touch the terrain; if not, its
    /// slots and search state are reset. A sphere well clear of the ground needs no
    /// closest-point search; one that touched last step (a stance foot: nearly always it still
    /// does) is searched without asking the cells around it: were it clear of their bounds, the
    /// search would find the same, a gap (no surface point within its radius), and the same
    /// slots and search state are reset.
    fn near_ground(&mut self, id: usize, center: DVec3, r: f64, terrain: &HeightGrid) -> bool {
        if center.z - r > self.ceiling
            || (self.last_search[id].is_none()
                && terrain.ceiling_below(center.x, center.y, r, center.z - r))
        {
            free(&mut self.slots[id * MAX_FACES..(id + 1) * MAX_FACES]);
            self.last_search[id] = None;
            return false;
        }
        true
    }

    /// Adds sphere `id`'s `faces` (of link `link`, posed by `frame`) to this step's contacts, if
    /// it touches; false (its faces' states reset) if the nearest is a gap.
    fn add_faces(
        &mut self,
        id: usize,
        link: usize,
        faces: &[SphereGeometry],
        frame: &DAffine3,
        bodies: &[RigidBodyHandle],
        model: &RobotModel,
    ) -> bool {
        let slots = id * MAX_FACES..(id + 1) * MAX_FACES;
        if faces[0].penetration <= 0.0 {
            free(&mut self.slots[slots]);
            return false;
        }
        let taken = match_faces(&mut self.slots[slots.clone()], faces);
        let com = frame.transform_point3(model.links[link].com);
        for (geometry, slot) in faces.iter().zip(taken) {
            self.ids.push(slots.start + slot);
            self.points.push(ContactPoint {
                link,
                body: bodies[link],
                point: geometry.point,
                com,
                frame: geometry.frame,
            });
            self.inputs.push(JointContact {
                geometry: *geometry,
                velocity: DVec3::ZERO,
                sharing: 1,
            });
        }
        true
    }
}

/// The lowest a link's spheres reach, bounded from the box of their centres (`half` about a
/// centre at height `centre`, posed by `frame`) and their largest radius, less a nanometre for
/// the rounding that places each sphere on its own: a link above the terrain's highest point by
/// this bound has every sphere clear of it, as each sphere's own test would find, and is passed
/// over whole. For hex18's body (32 spheres of 25 mm on its 0.24 × 0.14 m mid-plane) the
/// bounding sphere reaches 0.13 m below its centre and this bound, level, 25 mm.
fn lowest_of_box(frame: &DAffine3, centre: f64, half: DVec3, largest: f64) -> f64 {
    let m = &frame.matrix3;
    let reach = m.x_axis.z.abs() * half.x + m.y_axis.z.abs() * half.y + m.z_axis.z.abs() * half.z;
    centre - reach - largest - 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The box bound never passes over a sphere that reaches lower: each sphere's lowest point,
    /// placed as the step places it, is above the bound in every pose.
    #[test]
    fn the_box_bound_is_below_every_sphere() {
        let spheres: Vec<ContactSphere> = (0..12)
            .map(|k| ContactSphere {
                center: DVec3::new(
                    0.02 * (k % 4) as f64 - 0.03,
                    0.015 * (k / 4) as f64,
                    0.004 * k as f64,
                ),
                radius: 0.005 + 0.001 * k as f64,
            })
            .collect();
        let bound = contact_set::bound(&spheres).unwrap();
        let half = spheres
            .iter()
            .map(|c| (c.center - bound.center).abs())
            .fold(DVec3::ZERO, DVec3::max);
        let largest = spheres.iter().map(|c| c.radius).fold(0.0, f64::max);
        for k in 0..200 {
            let t = k as f64;
            let rotation = glam::DQuat::from_euler(
                glam::EulerRot::ZYX,
                0.37 * t,
                0.91 * t.sin(),
                1.3 * t.cos(),
            );
            let frame = DAffine3::from_rotation_translation(rotation, DVec3::new(0.1, -0.2, 0.07));
            let centre = frame.transform_point3(bound.center).z;
            let lowest = spheres
                .iter()
                .map(|c| frame.transform_point3(c.center).z - c.radius)
                .fold(f64::INFINITY, f64::min);
            let bounded = lowest_of_box(&frame, centre, half, largest);
            assert!(
                bounded <= lowest,
                "pose {k}: bound {bounded}, lowest {lowest}"
            );
        }
    }
}
