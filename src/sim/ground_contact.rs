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

use super::articulation::{ContactPoint, Joints};
use super::engine::Engine;
use crate::contact::joint::{JointContact, JointSolver};
use crate::contact::{ContactForce, ContactModel, ContactState, Variant};
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

/// A link's contact spheres and the sphere around them, for the broad phase.
struct LinkSpheres {
    link: usize,
    bound: ContactSphere,
    /// Range in [`GroundContacts::spheres`].
    first: usize,
    end: usize,
    /// Some sphere of it touched last step (its states need resetting once it lifts).
    touched: bool,
}

/// Every contact's state between steps (stick anchors, Karnopp's sticking flag), and scratch.
pub(super) struct GroundContacts {
    /// The feet's, then every link sphere's.
    states: Vec<ContactState>,
    links: Vec<LinkSpheres>,
    spheres: Vec<ContactSphere>,
    /// The highest the terrain's surface reaches anywhere.
    ceiling: f64,
    /// This step's touching contacts: their index in `states`, rapier point, solver input.
    ids: Vec<usize>,
    points: Vec<ContactPoint>,
    inputs: Vec<JointContact>,
    velocities: Vec<DVec3>,
    mobility: Vec<DMat3>,
    forces: Vec<Option<ContactForce>>,
    scratch_states: Vec<ContactState>,
    solver: JointSolver,
}

impl GroundContacts {
    pub fn new(model: &RobotModel, terrain: &HeightGrid) -> Self {
        let mut links = Vec::new();
        let mut spheres = Vec::new();
        for (k, link) in model.links.iter().enumerate() {
            if let Some(bound) = contact_set::bound(&link.contacts) {
                links.push(LinkSpheres {
                    link: k,
                    bound,
                    first: spheres.len(),
                    end: spheres.len() + link.contacts.len(),
                    touched: false,
                });
                spheres.extend_from_slice(&link.contacts);
            }
        }
        let [x0, x1] = terrain.x_range();
        let [y0, y1] = terrain.y_range();
        let ceiling =
            terrain.ceiling_near(0.5 * (x0 + x1), 0.5 * (y0 + y1), (x1 - x0).max(y1 - y0));
        GroundContacts {
            states: vec![ContactState::default(); 6 + spheres.len()],
            links,
            spheres,
            ceiling,
            ids: Vec::new(),
            points: Vec::new(),
            inputs: Vec::new(),
            velocities: Vec::new(),
            mobility: Vec::new(),
            forces: Vec::new(),
            scratch_states: Vec::new(),
            solver: JointSolver::default(),
        }
    }

    /// Finds the feet and link spheres touching `terrain`, solves their forces under `contact`,
    /// applies them to the links, and returns each leg's foot force (None: in the air) and the
    /// other links' contacts into `link_contacts`. `frames` are the world poses of every model
    /// link; `bodies` the rapier body per model link.
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
    ) -> [Option<ContactForce>; 6] {
        self.ids.clear();
        self.points.clear();
        self.inputs.clear();
        // the feet
        for (k, leg) in model.legs.iter().enumerate() {
            let frame = &frames[leg.foot_link];
            let sphere = ContactSphere {
                center: leg.foot.center,
                radius: leg.foot.radius,
            };
            if !self.find(
                k,
                leg.foot_link,
                &sphere,
                frame,
                terrain,
                contact,
                bodies,
                model,
            ) {
                self.states[k] = ContactState::default();
            }
        }
        // the links' spheres, those near the ground
        for l in 0..self.links.len() {
            let LinkSpheres {
                link,
                bound,
                first,
                end,
                touched,
            } = self.links[l];
            let frame = &frames[link];
            if frame.transform_point3(bound.center).z - bound.radius > self.ceiling {
                if touched {
                    self.states[6 + first..6 + end].fill(ContactState::default());
                    self.links[l].touched = false;
                }
                continue;
            }
            let mut any = false;
            for s in first..end {
                let sphere = self.spheres[s];
                if self.find(6 + s, link, &sphere, frame, terrain, contact, bodies, model) {
                    any = true;
                } else {
                    self.states[6 + s] = ContactState::default();
                }
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
        self.mobility.clear();
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
        self.scratch_states.clear();
        self.scratch_states
            .extend(self.ids.iter().map(|&id| self.states[id]));
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
                    &mut self.scratch_states[i],
                );
            }
        } else {
            let mobility = &self.mobility;
            self.solver.respond(
                contact,
                &self.inputs,
                |i, j| mobility[i * n + j],
                engine.dt(),
                &mut self.scratch_states,
                &mut self.forces,
            );
        }
        let mut feet = [None; 6];
        link_contacts.clear();
        for i in 0..n {
            let id = self.ids[i];
            self.states[id] = self.scratch_states[i];
            let Some(c) = self.forces[i] else { continue };
            let point = &self.points[i];
            let body = &mut engine.bodies[point.body];
            body.add_force(c.force.as_vec3(), true);
            body.add_torque((c.point - point.com).cross(c.force).as_vec3(), true);
            if id < 6 {
                feet[id] = Some(c);
            } else {
                link_contacts.push(LinkContact {
                    link: point.link,
                    radius: self.spheres[id - 6].radius,
                    force: c,
                });
            }
        }
        feet
    }

    /// Adds sphere `sphere` of link `link` (posed by `frame`) to this step's contacts if it
    /// touches the terrain, as contact `id`; false if it is clear.
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
        // a sphere well clear of the ground needs no closest-point search
        if center.z - r > self.ceiling || center.z - r > terrain.ceiling_near(center.x, center.y, r)
        {
            return false;
        }
        let geometry = contact.sphere_geometry(terrain, center, r);
        if geometry.penetration <= 0.0 {
            return false;
        }
        self.ids.push(id);
        self.points.push(ContactPoint {
            link,
            body: bodies[link],
            point: geometry.point,
            com: frame.transform_point3(model.links[link].com),
            frame: geometry.frame,
        });
        self.inputs.push(JointContact {
            geometry,
            velocity: DVec3::ZERO,
            sharing: 1,
        });
        true
    }
}
