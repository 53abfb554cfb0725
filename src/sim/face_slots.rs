//! A sphere's faces from step to step: in a concave corner a sphere presses into several faces at
//! once, each a contact of its own with its own state (stick anchor, Karnopp's sticking flag,
//! last damper), and each step's faces are matched to last step's by their normals, so that a
//! contact keeps its state while it stays on its face. The robot's spheres
//! ([`super::ground_contact`]) and the ball ([`super::ball`]) keep theirs so.

use crate::contact::joint::ContactStates;
use crate::contact::{ContactState, MAX_FACES, SphereGeometry};
use glam::DVec3;

/// A face a sphere pressed into last step: its contact's state between steps (stick anchor,
/// Karnopp's sticking flag) and its normal, by which this step's faces are matched to it.
#[derive(Clone, Copy, Default)]
pub(super) struct Slot {
    pub(super) state: ContactState,
    /// None: free.
    normal: Option<DVec3>,
}

impl Slot {
    /// Whether the slot holds no face: then it holds the default state too ([`free`]).
    pub(super) fn is_free(&self) -> bool {
        self.normal.is_none()
    }
}

/// Frees `slots`, each to [`Slot::default`]. A free slot holds that already: every write of a
/// slot either gives it a face's normal or frees it (a taken slot's state is written back only
/// while it holds its face), so only the slots taken are written. A swing foot's four slots,
/// freed every step it is in the air, were 200 bytes each written again.
pub(super) fn free(slots: &mut [Slot]) {
    for slot in slots {
        if !slot.is_free() {
            *slot = Slot::default();
        }
        // (checked wherever a build is tested: the unit tests that step a robot walk it)
        #[cfg(any(test, debug_assertions))]
        assert!(
            slot.state == ContactState::default(),
            "a free slot holds the default state"
        );
    }
}

/// This step's contacts' states, each in its face's slot: the solver's `i`th contact is slot
/// `ids[i]` (read and written in place, not copied out and back).
pub(super) struct SlotStates<'a> {
    pub(super) slots: &'a mut [Slot],
    pub(super) ids: &'a [usize],
}

impl ContactStates for SlotStates<'_> {
    #[inline]
    fn state(&mut self, i: usize) -> &mut ContactState {
        &mut self.slots[self.ids[i]].state
    }
}

/// Faces whose normals differ by less than this (cos 45°) from one step to the next are taken to
/// be the same face, its contact state carried on.
const SAME_FACE: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Gives each of this step's `faces` (all touching) one of a sphere's `slots`: the slot of last
/// step's face with the nearest normal, within [`SAME_FACE`] — so a contact keeps its stick
/// anchor while it stays on its face — or a free one, its state fresh. A sphere on one face
/// before and after keeps its slot, and its state while the normal turns less than
/// [`SAME_FACE`] in the step (a foot rolling over an edge turns it a few degrees a step). A
/// single face whose normal jumped further is another surface: a foot bouncing across a groove
/// between two boxes' edges, touching one edge a step, then the other. Carried on, the first
/// face's friction and slip were read on the second as a tangential load
/// (L = M·(v − v_prev)/h − F_prev) three times the slip, friction slid at μ·Fn along the push
/// the wall had just given, and the foot swung from edge to edge ×1.35 a step until it sank
/// 10.1 mm (`ladder/obstacles.toml` at 2 cm, blind). Slots left over are freed. Returns the
/// slot of each face.
pub(super) fn match_faces(slots: &mut [Slot], faces: &[SphereGeometry]) -> [usize; MAX_FACES] {
    let mut taken = [usize::MAX; MAX_FACES];
    let before = slots.iter().filter(|s| s.normal.is_some()).count();
    if faces.len() == 1 && before <= 1 {
        let slot = slots.iter().position(|s| s.normal.is_some()).unwrap_or(0);
        if slots[slot]
            .normal
            .is_some_and(|n| n.dot(faces[0].frame.normal) <= SAME_FACE)
        {
            slots[slot].state = ContactState::default();
        }
        taken[0] = slot;
    } else {
        let mut claimed = [false; MAX_FACES];
        for (f, face) in faces.iter().enumerate() {
            let n = face.frame.normal;
            let same = (0..slots.len())
                .filter(|&k| !claimed[k])
                .filter_map(|k| Some((k, slots[k].normal?.dot(n))))
                .filter(|&(_, cos)| cos > SAME_FACE)
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(k, _)| k);
            let slot = same.unwrap_or_else(|| {
                (0..slots.len())
                    .find(|&k| !claimed[k] && slots[k].normal.is_none())
                    .or_else(|| (0..slots.len()).find(|&k| !claimed[k]))
                    .expect("as many slots as faces")
            });
            if same.is_none() {
                slots[slot].state = ContactState::default();
            }
            claimed[slot] = true;
            taken[f] = slot;
        }
    }
    let used = &taken[..faces.len()];
    for (k, slot) in slots.iter_mut().enumerate() {
        match used.iter().position(|&t| t == k) {
            Some(f) => slot.normal = Some(faces[f].frame.normal),
            None => free(std::slice::from_mut(slot)),
        }
    }
    taken
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{ContactModel, EffectiveMass};
    use crate::terrain::GroundFrame;
    use glam::DMat3;

    fn face(normal: DVec3) -> SphereGeometry {
        SphereGeometry {
            penetration: 1e-3,
            point: DVec3::ZERO,
            frame: GroundFrame::from_normal(normal),
        }
    }

    /// A face keeps its slot — its stick anchor — while it stays the same face, whatever order
    /// the faces come in; a new face gets a fresh state; a face gone frees its slot.
    #[test]
    fn faces_keep_their_contact_state_from_step_to_step() {
        let mut slots = [Slot::default(); MAX_FACES];
        let (floor, wall) = (DVec3::Z, DVec3::X);
        let taken = match_faces(&mut slots, &[face(floor), face(wall)]);
        assert_ne!(taken[0], taken[1]);
        // the faces the other way round
        let again = match_faces(&mut slots, &[face(wall), face(floor)]);
        assert_eq!((again[0], again[1]), (taken[1], taken[0]));
        // the wall gone, the floor tilted 30°: still the floor's slot; the wall's is free
        let tilted = DVec3::new(0.5, 0.0, 0.75f64.sqrt());
        let last = match_faces(&mut slots, &[face(tilted), face(-wall)]);
        assert_eq!(last[0], taken[0]);
        assert_ne!(last[1], taken[0]);
        assert_eq!(slots.iter().filter(|s| s.normal.is_some()).count(), 2);
        // one face before and one after keeps its slot, and its state while the normal turns
        // less than 45° in a step (an edge rolled over)
        let mut slots = [Slot::default(); MAX_FACES];
        let first = match_faces(&mut slots, &[face(floor)])[0];
        let sliding = ContactModel::default().respond(
            &face(floor),
            DVec3::new(0.3, 0.0, -0.1),
            &EffectiveMass::rigid_body(
                0.05,
                DMat3::from_diagonal(DVec3::splat(1e4)),
                -0.01 * floor,
                &face(floor).frame,
            ),
            1e-3,
            &mut slots[first].state,
        );
        assert!(sliding.is_some() && slots[first].state != ContactState::default());
        let held = slots[first].state;
        assert_eq!(match_faces(&mut slots, &[face(tilted)])[0], first);
        assert_eq!(slots[first].state, held);
        // … but a jump to a face turned 45° or more is another surface (the far wall of a groove
        // the sphere bounced across): its state is fresh — carried on, the other face's friction
        // and slip read as a tangential load
        assert_eq!(match_faces(&mut slots, &[face(-wall)])[0], first);
        assert_eq!(slots[first].state, ContactState::default());
    }
}
