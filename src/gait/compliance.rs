//! Leg compliance: a leg that presses the ground with more than three times its robot's weight
//! gives way.
//!
//! The servos are stiff position servos, and a foot target the ground does not let the foot reach
//! — a foot wedged in a pit, a shin against a stone's edge, a stance foot on a step its plan did
//! not know — is pressed towards up to the servos' effort. Through a leg folded to a short lever
//! that is many times the robot's weight (hex18 on stepping stones: 100–170 N on one foot, 4–7×
//! its weight), and the ground, a spring, gives way by F/k: 5–10 mm, past the foot's radius
//! (a "divergence"). Legged robots' controllers bound what a leg presses by force feedback
//! (Syropod's impedance control; an admittance on a foot's force sensor). Here each leg's ground
//! force — its foot's and its links' — past [`CAP`] × the robot's weight moves the leg's foot
//! target along that force, at a rate proportional to the excess (an integral admittance:
//! ẏ = γ·(|F| − F_cap)·F̂), and the displacement returns to the plan over [`RELEASE_TIME`] once
//! the force is below the cap. A walk whose legs stay under the cap is not touched: the default
//! walk's feet peak at 2.7 weights as they land, and it is the same bit for bit with or without.
//!
//! Moving the foot target does not free a leg whose *links* are pressed: a shin against a
//! stone's side with the foot hanging in the pit, a leg gripping a stone between its foot and
//! its shin (the forces cancel in the sum, not in the ground), a hip pressed into a wall. On
//! the ladders' stepping stones and stairs such legs pressed with 5–24 weights, their links
//! 5–9 mm into the ground. So each leg also *yields* in joint space, as a servo with a torque
//! limit backs off: past the cap, the leg's load — the magnitudes of its contacts' forces summed,
//! so that a grip counts — moves a yield fraction y ∈ [0, 1] up at [`YIELD_RATE`] per weight of
//! excess, and the leg's joint targets are sent that fraction of the way to the joints' angles
//! (y = 1: the servos' springs hold nothing beyond the load feed-forward). Under the cap y decays
//! over [`RELEASE_TIME`].
//!
//! A leg fully yielded can still be pressed by the others, through the body: two feet pinching
//! a stone, three legs shoving the body onto a fourth whose force runs along its joints or into
//! a joint limit (PhantomX on 8 cm stones: 6.0 mm with y = 1). So the legs' *squeeze* — the
//! part of their loads that cancels in their net force, Σ|Fᵢ| − |ΣFᵢ| — past [`SQUEEZE_CAP`]
//! weights yields every leg that bears load at the rate of its excess (each at the larger of its
//! own excess and the squeeze's); a leg in the air presses nothing, and yielded it hung limp
//! while its swing went on, to be snapped back at 10–30 rad/s when the squeeze ended (a
//! MushroomRL foot driven onto a stone at 2.4 m/s, 8 mm deep). A landing, however hard,
//! squeezes nothing. A foot pressing several faces at
//! once (wedged in a crack) counts each face's force ([`crate::contact::ContactForce::load`]).
//! The body's own contacts count in the squeeze too: legs that shove the body against a wall
//! press it there with forces no leg feels as its own (harika perceptive over 8 cm gaps, its
//! belly against the far wall: 16 N, 4.2 of its weights, 5.3 mm into the wall, while every leg
//! stayed under its cap).
//!
//! The release is bounded too while the leg bears load. A leg yielded for a while has let its
//! joints fall behind the gait's angles (MushroomRL's rear leg on 4 cm stepping stones, limp for
//! 0.3 s: its knee 0.6 rad from its target), and sent back over [`RELEASE_TIME`] alone the
//! target swept that gap in a tenth of a second: the foot, on a stone, threw the 2.3 kg robot
//! up at 0.9 m/s, and another foot landed from the hop 6.7 mm deep. So a loaded leg's yield
//! falls no faster than it takes its targets back to the gait's at `release` (a joint speed:
//! the gait's landing speed over the leg's length), and its foot target's displacement comes
//! back no faster than the landing speed; a leg in the air is released over [`RELEASE_TIME`].

use glam::DVec3;

/// The force a leg may press the ground with, in robot weights: above the default walk's
/// landing peaks (2.7), below the 4 at which the reference ground (2·10⁴ N/m under hex18's
/// 24.7 N) gives way by 5 mm.
pub const CAP: f64 = 3.0;
/// How fast a leg gives way per unit of excess force: the excess, in robot weights, moves the
/// foot target at this speed (m/s). With the ground's stiffness fitted to the weight (the
/// reference's 2·10⁴ N/m for hex18's 24.7 N: 810 weights per metre) the excess decays at about
/// 80/s on the ground alone, slower through a leg softer than it.
pub const SPEED_PER_WEIGHT: f64 = 0.1;
/// The time over which a leg's displacement goes back to its plan once under the cap (s).
pub const RELEASE_TIME: f64 = 0.1;
/// How fast a leg yields per unit of excess load: each weight over the cap raises its yield
/// fraction by this much per second (a leg pressing with 5 weights, 2 over, yields fully in
/// 2.5 ms, a quarter of the fitted ground's own time √(M/k) = 11.2 ms, as a servo's torque limit
/// acts at once). At 10 a second a leg pressing the stepping stones' walls with 5 weights still
/// sank a foot 5.7 mm before it had yielded a quarter of the way; at 50, yielding over 5–10 ms,
/// MushroomRL's legs pressing stones' and treads' edges with 4–7 of its weights sank a coxa or a
/// femur 5.06–5.32 mm.
pub const YIELD_RATE: f64 = 200.0;
/// How hard the legs may squeeze the ground between them, in robot weights: the part of their
/// loads that cancels in their net force (Σ|Fᵢ| − |ΣFᵢ|). Past it every leg bearing load
/// yields, as one leg past [`CAP`] does: legs that push against each other through the body (two feet pinching a
/// stone, the body shoved by three legs onto a fourth pressed against a stone's side) carry
/// forces no single leg's servos hold. A landing, all forces up, squeezes nothing.
pub const SQUEEZE_CAP: f64 = 2.0;

/// The ground's forces on the robot over a step, as leg compliance reads them (body frame).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GroundForces {
    /// Each leg's: its foot's and its links' summed.
    pub legs: [DVec3; 6],
    /// Each leg's load: the magnitudes of its contacts' forces summed.
    pub leg_loads: [f64; 6],
    /// The body's (every link off the legs), summed.
    pub body: DVec3,
    /// The body's load.
    pub body_load: f64,
}

impl GroundForces {
    /// Legs' forces and loads alone, the body touching nothing.
    pub fn of_legs(legs: [DVec3; 6], leg_loads: [f64; 6]) -> Self {
        GroundForces {
            legs,
            leg_loads,
            ..Default::default()
        }
    }
}

/// How fast a leg bearing load takes back what it gave way: its joints' targets and its foot's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Release {
    /// Per leg, the fastest its joint targets go back to the gait's angles (rad/s).
    pub joint_speed: [f64; 6],
    /// The fastest a foot target's displacement comes back (m/s).
    pub foot_speed: f64,
}

impl Release {
    /// Unbounded: released over [`RELEASE_TIME`] alone.
    pub const FREE: Release = Release {
        joint_speed: [f64::INFINITY; 6],
        foot_speed: f64::INFINITY,
    };
}

/// Per leg, how far its foot target has given way (body frame).
#[derive(Debug, Clone, PartialEq)]
pub struct Compliance {
    offset: [DVec3; 6],
    /// Per leg, the fraction of the way its joint targets are sent to its joints' angles.
    yielded: [f64; 6],
    weight: f64,
    /// The most a target gives way (m).
    longest: f64,
    release: Release,
}

impl Compliance {
    /// `weight`: the robot's weight (N); `longest`: the most a foot target may be moved (m);
    /// `release`: how fast a loaded leg takes it back.
    pub fn new(weight: f64, longest: f64, release: Release) -> Self {
        Compliance {
            offset: [DVec3::ZERO; 6],
            yielded: [0.0; 6],
            weight,
            longest,
            release,
        }
    }

    /// Each leg's ground force over the last step (`ground.legs`, body frame; its foot's and its
    /// links' summed) moves its displacement on by `dt`, and its load (`ground.leg_loads`: the
    /// magnitudes of those forces summed) its yield; the body's contacts count in the squeeze.
    /// `gaps`: per leg, its joints' largest distance from the gait's angles (rad), which bounds
    /// how fast a loaded leg's yield falls.
    pub fn feel(&mut self, ground: &GroundForces, gaps: &[f64; 6], dt: f64) {
        let (forces, loads) = (&ground.legs, &ground.leg_loads);
        let cap = CAP * self.weight;
        let decay = (-dt / RELEASE_TIME).exp();
        let net = (forces.iter().sum::<DVec3>() + ground.body).length();
        let squeezed = loads.iter().sum::<f64>() + ground.body_load - net;
        let robot_excess = squeezed - SQUEEZE_CAP * self.weight;
        for (k, yielded) in self.yielded.iter_mut().enumerate() {
            // the squeeze yields the legs that bear load: a leg in the air presses nothing,
            // and yielded it hangs while its swing goes on without it
            let squeeze = if loads[k] > 0.0 { robot_excess } else { 0.0 };
            let excess = (loads[k] - cap).max(squeeze);
            if excess > 0.0 {
                *yielded = (*yielded + YIELD_RATE * excess / self.weight * dt).min(1.0);
            } else if *yielded != 0.0 {
                let mut next = *yielded * decay;
                if loads[k] > 0.0 && gaps[k] > 0.0 {
                    // the targets sent y·gap from the gait's: y falls by at most speed·dt/gap
                    next = next.max(*yielded - self.release.joint_speed[k] * dt / gaps[k]);
                }
                *yielded = if next < 1e-6 { 0.0 } else { next };
            }
        }
        for (k, (offset, force)) in self.offset.iter_mut().zip(forces).enumerate() {
            let magnitude = force.length();
            if magnitude > cap {
                let rate = SPEED_PER_WEIGHT * (magnitude - cap) / self.weight;
                *offset += *force / magnitude * (rate * dt);
                *offset = offset.clamp_length_max(self.longest);
            } else if *offset != DVec3::ZERO {
                let (length, most) = (offset.length(), self.release.foot_speed * dt);
                if loads[k] > 0.0 && length * (1.0 - decay) > most {
                    *offset *= (length - most) / length;
                } else {
                    *offset *= decay;
                }
                if offset.length() < 1e-7 {
                    *offset = DVec3::ZERO;
                }
            }
        }
    }

    /// How far leg `k`'s foot target gives way (body frame).
    pub fn offset(&self, k: usize) -> DVec3 {
        self.offset[k]
    }

    /// The fraction of the way leg `k`'s joint targets go to its joints' angles.
    pub fn yielded(&self, k: usize) -> f64 {
        self.yielded[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NO_GAPS: [f64; 6] = [0.0; 6];

    #[test]
    fn a_leg_under_the_cap_is_not_moved() {
        let mut c = Compliance::new(10.0, 0.05, Release::FREE);
        let forces = [DVec3::new(3.0, -2.0, 29.7); 6];
        for _ in 0..1000 {
            c.feel(
                &GroundForces::of_legs(forces, forces.map(|f| f.length())),
                &NO_GAPS,
                1e-3,
            );
        }
        assert!((0..6).all(|k| c.offset(k) == DVec3::ZERO && c.yielded(k) == 0.0));
    }

    #[test]
    fn a_gripping_leg_yields_though_its_net_force_is_under_the_cap() {
        let mut c = Compliance::new(10.0, 0.05, Release::FREE);
        // a stone gripped between foot and shin: 40 N each way, net zero; the load is 80 N,
        // 5 weights over the leg's cap of 30 N, and all of it squeezed, 6 weights over the
        // squeeze's cap of 20 N: its yield rises at 6·YIELD_RATE a second; the other legs, in
        // the air, bear nothing and do not yield
        let forces = [DVec3::ZERO; 6];
        let mut loads = [0.0; 6];
        loads[4] = 80.0;
        c.feel(&GroundForces::of_legs(forces, loads), &NO_GAPS, 1e-4);
        assert!((c.yielded(4) - 6.0 * YIELD_RATE * 1e-4).abs() < 1e-12);
        assert!((0..6).all(|k| k == 4 || c.yielded(k) == 0.0));
        assert_eq!(c.offset(4), DVec3::ZERO);
        // bounded at 1: the servos' springs hold nothing
        for _ in 0..100 {
            c.feel(&GroundForces::of_legs(forces, loads), &NO_GAPS, 1e-3);
        }
        assert_eq!(c.yielded(4), 1.0);
        // under both caps it decays over RELEASE_TIME
        loads[4] = 19.0;
        for _ in 0..100 {
            c.feel(&GroundForces::of_legs(forces, loads), &NO_GAPS, 1e-3);
        }
        assert!((c.yielded(4) - (-1.0f64).exp()).abs() < 1e-9);
    }

    #[test]
    fn legs_squeezing_the_ground_all_yield_though_each_is_under_the_cap() {
        let w = 10.0;
        let mut c = Compliance::new(w, 0.05, Release::FREE);
        // two feet pinching a stone (25 N each, mostly inwards) and four standing with 4 N:
        // each leg under its cap of 30 N; the loads, 66 N, against a net force of 30 N up:
        // 36 N squeezed, 1.6 weights over the squeeze cap of 20 N
        let mut forces = [DVec3::new(0.0, 0.0, 4.0); 6];
        forces[0] = DVec3::new(24.0, 0.0, 7.0);
        forces[1] = DVec3::new(-24.0, 0.0, 7.0);
        let loads = forces.map(|f| f.length());
        assert!(loads.iter().all(|&l| l < CAP * w));
        c.feel(&GroundForces::of_legs(forces, loads), &NO_GAPS, 1e-3);
        let rate = (66.0 - 30.0 - SQUEEZE_CAP * w) / w * YIELD_RATE;
        assert!((0..6).all(|k| (c.yielded(k) - rate * 1e-3).abs() < 1e-12));
        // a hard landing, every foot with 2.5 weights up (15 in all): nothing squeezed, no yield
        let mut c = Compliance::new(w, 0.05, Release::FREE);
        let forces = [DVec3::new(0.0, 0.0, 25.0); 6];
        c.feel(
            &GroundForces::of_legs(forces, forces.map(|f| f.length())),
            &NO_GAPS,
            1e-3,
        );
        assert!((0..6).all(|k| c.yielded(k) == 0.0));
        // a leg over its own cap yields at the larger of its excess and the squeeze's: a grip
        // (60 N of load, no net force) is 3 weights over the leg's cap, 4 over the squeeze's;
        // a leg standing with 1 N yields at the squeeze's rate, the legs in the air not at all
        let mut c = Compliance::new(w, 0.05, Release::FREE);
        let mut loads = [0.0; 6];
        loads[0] = 60.0;
        loads[3] = 1.0;
        let mut forces = [DVec3::ZERO; 6];
        forces[3] = DVec3::Z;
        c.feel(&GroundForces::of_legs(forces, loads), &NO_GAPS, 1e-3);
        let rate = (60.0 - SQUEEZE_CAP * w) / w * YIELD_RATE;
        assert!((c.yielded(0) - 4.0 * YIELD_RATE * 1e-3).abs() < 1e-12);
        assert!((c.yielded(3) - rate * 1e-3).abs() < 1e-12);
        assert!([1, 2, 4, 5].iter().all(|&k| c.yielded(k) == 0.0));
    }

    #[test]
    fn legs_shoving_the_body_against_a_wall_yield() {
        let w = 10.0;
        // the body pressed against a wall with 25 N by three legs pushing it forwards (each
        // 8.33 N forwards, 10 N up, under its cap of 30 N), three more standing with 0 N:
        // the legs' own squeeze is nothing (their forces run the same way), but with the wall's
        // the loads, 3·13.0 + 25 = 64.1 N, against a net force of 30 N up, squeeze 3.4 weights
        let leg = DVec3::new(25.0 / 3.0, 0.0, 10.0);
        let mut legs = [DVec3::ZERO; 6];
        legs[..3].fill(leg);
        let leg_loads = legs.map(|f| f.length());
        let wall = DVec3::new(-25.0, 0.0, 0.0);
        let alone = GroundForces::of_legs(legs, leg_loads);
        let mut c = Compliance::new(w, 0.05, Release::FREE);
        c.feel(&alone, &NO_GAPS, 1e-3);
        assert!((0..6).all(|k| c.yielded(k) == 0.0));
        let shoved = GroundForces {
            body: wall,
            body_load: wall.length(),
            ..alone
        };
        c.feel(&shoved, &NO_GAPS, 1e-3);
        let squeezed = 3.0 * leg.length() + 25.0 - 30.0;
        let rate = (squeezed - SQUEEZE_CAP * w) / w * YIELD_RATE;
        assert!(rate > 0.0);
        // the three legs pressing yield, the three in the air do not
        assert!((0..3).all(|k| (c.yielded(k) - rate * 1e-3).abs() < 1e-12));
        assert!((3..6).all(|k| c.yielded(k) == 0.0));
        // the body resting on the ground beside its legs squeezes nothing
        let mut c = Compliance::new(w, 0.05, Release::FREE);
        let resting = GroundForces {
            body: DVec3::new(0.0, 0.0, 50.0),
            body_load: 50.0,
            ..GroundForces::of_legs([DVec3::new(0.0, 0.0, 5.0); 6], [5.0; 6])
        };
        c.feel(&resting, &NO_GAPS, 1e-3);
        assert!((0..6).all(|k| c.yielded(k) == 0.0));
    }

    #[test]
    fn a_leg_over_the_cap_gives_way_along_its_force_and_comes_back() {
        let mut c = Compliance::new(10.0, 0.05, Release::FREE);
        let mut forces = [DVec3::ZERO; 6];
        // 2 weights over the cap along +x: 0.2 m/s
        forces[2] = DVec3::new(50.0, 0.0, 0.0);
        for _ in 0..100 {
            c.feel(
                &GroundForces::of_legs(forces, forces.map(|f| f.length())),
                &NO_GAPS,
                1e-3,
            );
        }
        let o = c.offset(2);
        assert!((o.x - 0.02).abs() < 1e-9 && o.y == 0.0 && o.z == 0.0, "{o}");
        assert_eq!(c.offset(0), DVec3::ZERO);
        // bounded
        for _ in 0..1000 {
            c.feel(
                &GroundForces::of_legs(forces, forces.map(|f| f.length())),
                &NO_GAPS,
                1e-3,
            );
        }
        assert!((c.offset(2).length() - 0.05).abs() < 1e-12);
        // released over RELEASE_TIME
        forces[2] = DVec3::ZERO;
        for _ in 0..100 {
            c.feel(
                &GroundForces::of_legs(forces, forces.map(|f| f.length())),
                &NO_GAPS,
                1e-3,
            );
        }
        let expected = 0.05 * (-1.0f64).exp();
        assert!((c.offset(2).length() - expected).abs() < 1e-9);
    }

    /// A loaded leg's yield and foot displacement come back at the release's speeds, so its
    /// targets return to the gait's no faster than that; a leg in the air, and a gap too small
    /// to bind, are released over RELEASE_TIME.
    #[test]
    fn a_loaded_leg_takes_back_what_it_gave_way_no_faster_than_its_release() {
        let w = 10.0;
        let release = Release {
            joint_speed: [1.0; 6],
            foot_speed: 0.2,
        };
        let mut c = Compliance::new(w, 0.05, release);
        // legs 0, 1 and 2 gripping stones until fully yielded, leg 2 also pushed along +x
        // until its foot target has given way its longest
        let mut forces = [DVec3::ZERO; 6];
        forces[2] = DVec3::new(50.0, 0.0, 0.0);
        let mut loads = forces.map(|f| f.length());
        loads[0] = 80.0;
        loads[1] = 80.0;
        for _ in 0..1000 {
            c.feel(&GroundForces::of_legs(forces, loads), &NO_GAPS, 1e-3);
        }
        assert!((0..3).all(|k| c.yielded(k) == 1.0));
        assert!((c.offset(2).length() - 0.05).abs() < 1e-12);
        // under the caps: leg 0 standing (15 N) 0.5 rad from the gait's angles, leg 1 in the
        // air as far off, leg 2 standing 0.001 rad off with its foot target still displaced
        forces = [DVec3::ZERO; 6];
        forces[0] = DVec3::new(0.0, 0.0, 15.0);
        forces[2] = DVec3::new(0.0, 0.0, 15.0);
        let loads = forces.map(|f| f.length());
        let gaps = [0.5, 0.5, 0.001, 0.0, 0.0, 0.0];
        for _ in 0..100 {
            c.feel(&GroundForces::of_legs(forces, loads), &gaps, 1e-3);
        }
        // leg 0: 1 rad/s over 0.5 rad, 2 a second of its yield, for 0.1 s
        assert!((c.yielded(0) - 0.8).abs() < 1e-9, "{}", c.yielded(0));
        let by_time = (-1.0f64).exp();
        assert!((c.yielded(1) - by_time).abs() < 1e-9, "{}", c.yielded(1));
        assert!((c.yielded(2) - by_time).abs() < 1e-9, "{}", c.yielded(2));
        // leg 2's foot target: 0.2 m/s for 0.1 s, along its displacement
        let o = c.offset(2);
        assert!((o.x - 0.03).abs() < 1e-9 && o.y == 0.0 && o.z == 0.0, "{o}");
        // the slower of the two: held to the speed down to y = 0.2, where y·(1 − e^(−dt/T))
        // falls within it (0.3 s more), then by time (0.1 s more)
        for _ in 0..400 {
            c.feel(&GroundForces::of_legs(forces, loads), &gaps, 1e-3);
        }
        let tail = 0.2 * (-1.0f64).exp();
        assert!((c.yielded(0) / tail - 1.0).abs() < 0.01, "{}", c.yielded(0));
    }
}
