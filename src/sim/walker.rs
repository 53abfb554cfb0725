//! A hexapod driven by a gait: settle in the standing pose, then walk to a velocity command.

use super::hexapod::{Hexapod, HexapodSample};
use crate::gait::{GaitController, GaitTargets, VelocityCommand};

/// The walking robot: a [`Hexapod`] and the [`GaitController`] that sets its servo targets.
pub struct Walker {
    hexapod: Hexapod,
    controller: GaitController,
    command: VelocityCommand,
    /// Seconds standing still before the gait starts.
    settle_time: f64,
    targets_by_joint: Vec<f64>,
    last_targets: Option<GaitTargets>,
    /// Steps in which some leg's target was out of reach (IK clamped).
    pub clamped_steps: u64,
}

/// A step of the walker: the robot's state and the gait's targets for it.
pub struct WalkSample {
    pub robot: HexapodSample,
    /// None while settling.
    pub gait: Option<GaitTargets>,
}

impl Walker {
    pub fn new(
        hexapod: Hexapod,
        controller: GaitController,
        command: VelocityCommand,
        settle_time: f64,
    ) -> Self {
        let n = hexapod.model().joints.len();
        Walker {
            hexapod,
            controller,
            command,
            settle_time,
            targets_by_joint: vec![0.0; n],
            last_targets: None,
            clamped_steps: 0,
        }
    }

    pub fn hexapod(&self) -> &Hexapod {
        &self.hexapod
    }

    pub fn controller(&self) -> &GaitController {
        &self.controller
    }

    pub fn set_command(&mut self, command: VelocityCommand) {
        self.command = command;
    }

    /// Seconds since the gait started (negative while settling).
    pub fn gait_time(&self) -> f64 {
        self.hexapod.time() - self.settle_time
    }

    pub fn step(&mut self) -> WalkSample {
        let t = self.gait_time();
        if t >= 0.0 {
            let period = self.controller.spec().period;
            // ramp the stride up over the first cycle so the feet leave the standing pose smoothly
            let blend = (t / period).min(1.0);
            let targets = self.controller.targets(t, self.command, blend);
            for (leg, angles) in self.hexapod.model().legs.iter().zip(targets.joint_angles) {
                for (j, a) in leg.joints.iter().zip(angles) {
                    self.targets_by_joint[*j] = a;
                }
            }
            if targets.clamped.iter().any(|&c| c) {
                self.clamped_steps += 1;
            }
            let targets_by_joint = std::mem::take(&mut self.targets_by_joint);
            self.hexapod.set_targets(&targets_by_joint);
            self.targets_by_joint = targets_by_joint;
            self.last_targets = Some(targets);
        }
        let robot = self.hexapod.step();
        WalkSample {
            robot,
            gait: self.last_targets,
        }
    }
}
