//! The feet on the ground, each step: which feet touch the terrain, their ground frames and
//! penetrations (paper §2), their forces solved together through the articulation's contact
//! mobility (a stance foot's stopping force moves the others: see [`crate::contact::joint`]), and
//! those forces applied to the foot links. This is the only ground force on the robot.

use super::articulation::{ContactPoint, Joints};
use super::engine::Engine;
use crate::contact::joint::JointContact;
use crate::contact::{
    ContactForce, ContactModel, ContactState, SphereGeometry, Variant, respond_jointly,
};
use crate::robot::RobotModel;
use crate::terrain::{GroundFrame, HeightGrid};
use glam::{DAffine3, DMat3, DVec3};
use rapier3d::prelude::RigidBodyHandle;

/// Each foot's contact state between steps (stick anchors, Karnopp's sticking flag).
#[derive(Default)]
pub(super) struct FootContacts {
    states: [ContactState; 6],
}

impl FootContacts {
    /// Finds the feet touching `terrain`, solves their forces under `contact`, applies them to
    /// the foot links, and returns each leg's force (None: in the air). `foot_frames` are the
    /// world poses of each leg's foot link; `bodies` the rapier body per model link.
    #[allow(clippy::too_many_arguments)]
    pub fn apply(
        &mut self,
        engine: &mut Engine,
        joints: &mut dyn Joints,
        model: &RobotModel,
        bodies: &[RigidBodyHandle],
        terrain: &HeightGrid,
        contact: &ContactModel,
        foot_frames: &[DAffine3; 6],
    ) -> [Option<ContactForce>; 6] {
        let mut geometries = [None; 6];
        let mut points = [ContactPoint::default(); 6];
        let mut legs = [0; 6];
        let mut n = 0;
        for (k, (leg, frame)) in model.legs.iter().zip(foot_frames).enumerate() {
            let center = frame.transform_point3(leg.foot.center);
            let r = leg.foot.radius;
            // a swinging foot well clear of the ground needs no closest-point search
            if center.z - r > terrain.ceiling_near(center.x, center.y, r) {
                self.states[k] = ContactState::default();
                continue;
            }
            let geometry = contact.sphere_geometry(terrain, center, leg.foot.radius);
            if geometry.penetration <= 0.0 {
                self.states[k] = ContactState::default();
                continue;
            }
            points[n] = ContactPoint {
                link: leg.foot_link,
                body: bodies[leg.foot_link],
                point: geometry.point,
                com: frame.transform_point3(model.links[leg.foot_link].com),
                frame: geometry.frame,
            };
            geometries[n] = Some(geometry);
            legs[n] = k;
            n += 1;
        }
        let mut velocities = [DVec3::ZERO; 6];
        let mut mobility = [DMat3::ZERO; 36];
        joints.contact_mobility(engine, &points[..n], &mut velocities, &mut mobility);
        // (the entries past n are placeholders: only inputs[..n] is read)
        let placeholder = SphereGeometry {
            penetration: 0.0,
            point: DVec3::ZERO,
            frame: GroundFrame::from_normal(DVec3::Z),
        };
        let inputs: [JointContact; 6] = std::array::from_fn(|i| JointContact {
            geometry: geometries[i].as_ref().unwrap_or(&placeholder),
            velocity: velocities[i],
        });
        let mut states = [ContactState::default(); 6];
        for i in 0..n {
            states[i] = self.states[legs[i]];
        }
        let mut forces = [None; 6];
        if contact.variant == Variant::Paper {
            // the paper's: each foot alone, its sphere's centre velocity, the force there
            for i in 0..n {
                let normal_mass = 1.0 / mobility[i * n + i].z_axis.z;
                forces[i] = contact.respond_paper(
                    inputs[i].geometry,
                    velocities[i],
                    normal_mass,
                    engine.dt(),
                    &mut states[i],
                );
            }
        } else {
            respond_jointly(
                contact,
                &inputs[..n],
                |i, j| mobility[i * n + j],
                engine.dt(),
                &mut states[..n],
                &mut forces[..n],
            );
        }
        let mut contacts = [None; 6];
        for i in 0..n {
            self.states[legs[i]] = states[i];
            if let Some(c) = forces[i] {
                let body = &mut engine.bodies[points[i].body];
                body.add_force(c.force.as_vec3(), true);
                body.add_torque((c.point - points[i].com).cross(c.force).as_vec3(), true);
            }
            contacts[legs[i]] = forces[i];
        }
        contacts
    }
}
