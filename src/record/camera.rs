//! A camera that follows a body from behind and above, for the 3D view: the recording logs it as a
//! `Pinhole` camera and the view's blueprint looks through it (rerun's eye tracking of a camera
//! entity), so the robot stays in view, at a size that shows its legs, however far it walks.
//!
//! The camera follows the body's position and heading through first-order lags, so the body's
//! rocking within a gait cycle does not shake the view; it ignores roll and pitch.

use glam::{DMat3, DVec3};

/// Vertical field of view of the follow camera (rad).
const FIELD_OF_VIEW: f64 = 0.87; // 50°

/// The image the camera's projection is defined on (pixels); its aspect is the 3D view's usual.
const RESOLUTION: [f32; 2] = [1200.0, 800.0];

/// The follow camera's projection, as rerun logs a camera: a `Pinhole` whose frustum is drawn
/// `frustum_depth` metres deep (small: the view looks through it).
pub fn pinhole(frustum_depth: f32) -> rerun::Pinhole {
    let focal = 0.5 * RESOLUTION[1] / (0.5 * FIELD_OF_VIEW as f32).tan();
    rerun::Pinhole::from_focal_length_and_resolution([focal, focal], RESOLUTION)
        .with_image_plane_distance(frustum_depth)
}

/// Logs the camera's pose at the current time (the `Pinhole` itself is logged once, static).
pub fn log_pose(
    stream: &rerun::RecordingStream,
    entity: impl Into<rerun::EntityPath>,
    pose: &CameraPose,
) -> anyhow::Result<()> {
    stream.log(entity, &transform(pose))?;
    Ok(())
}

/// The camera's pose as rerun logs it.
pub fn transform(pose: &CameraPose) -> rerun::Transform3D {
    rerun::Transform3D::from_translation_rotation(
        pose.eye.as_vec3().to_array(),
        rerun::Quaternion::from_xyzw(
            glam::DQuat::from_mat3(&pose.axes)
                .normalize()
                .as_quat()
                .to_array(),
        ),
    )
}

/// Where the camera is, and its axes in the world, in the `Pinhole` convention RDF
/// (columns: image right, image down, viewing direction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    pub eye: DVec3,
    pub axes: DMat3,
}

#[derive(Debug, Clone)]
pub struct FollowCamera {
    /// Horizontal distance behind the target and height above it (m).
    back: f64,
    up: f64,
    /// Lag time constants for position and heading (s).
    position_lag: f64,
    heading_lag: f64,
    /// Whether the camera turns with the body (a walking robot) or keeps its heading (a ball).
    turns: bool,
    state: Option<(DVec3, f64)>,
}

impl FollowCamera {
    /// A camera for a body of horizontal radius `size` (m): the body fills about half the view's
    /// height, with the ground around it in view.
    pub fn new(size: f64, turns: bool) -> Self {
        FollowCamera {
            back: 2.2 * size,
            up: 1.3 * size,
            position_lag: 0.3,
            heading_lag: 1.0,
            turns,
            state: None,
        }
    }

    /// Moves the camera after `dt` seconds towards the body at `target` heading `heading`
    /// (rad about z; ignored for a camera that does not turn) and returns its pose.
    pub fn follow(&mut self, target: DVec3, heading: f64, dt: f64) -> CameraPose {
        let heading = if self.turns { heading } else { 0.0 };
        let (position, yaw) = match self.state {
            None => (target, heading),
            Some((position, yaw)) => {
                let a = 1.0 - (-dt / self.position_lag).exp();
                let b = 1.0 - (-dt / self.heading_lag).exp();
                // turn the shorter way round
                let mut turn = heading - yaw;
                turn -= (turn / std::f64::consts::TAU).round() * std::f64::consts::TAU;
                (position + (target - position) * a, yaw + turn * b)
            }
        };
        self.state = Some((position, yaw));
        let behind = DVec3::new(yaw.cos(), yaw.sin(), 0.0) * -self.back;
        let eye = position + behind + DVec3::Z * self.up;
        let forward = (position - eye).normalize();
        let right = forward.cross(DVec3::Z).normalize();
        let down = forward.cross(right);
        CameraPose {
            eye,
            axes: DMat3::from_cols(right, down, forward),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn looks_at_the_body_from_behind_and_above() {
        let size = 0.25;
        let mut camera = FollowCamera::new(size, true);
        let target = DVec3::new(1.0, 2.0, 0.1);
        let heading = 0.5;
        let pose = camera.follow(target, heading, 0.02);
        let to_target = (target - pose.eye).normalize();
        assert!((pose.axes.z_axis - to_target).length() < 1e-12);
        let ahead = DVec3::new(heading.cos(), heading.sin(), 0.0);
        // a few body sizes behind it and above it, looking down at about 30°
        assert!(
            (target - pose.eye).dot(ahead) > 2.0 * size,
            "behind the body"
        );
        assert!(pose.eye.z > target.z + size, "above it");
        let down = (-pose.axes.z_axis.z).asin().to_degrees();
        assert!((25.0..40.0).contains(&down), "looks down at {down}°");
        // image down points down in the world, image right to the body's right
        assert!(pose.axes.y_axis.z < 0.0);
        assert!(
            pose.axes
                .x_axis
                .dot(DVec3::new(heading.sin(), -heading.cos(), 0.0))
                > 0.99
        );
        assert!((pose.axes.determinant() - 1.0).abs() < 1e-12, "a rotation");
    }

    #[test]
    fn lags_behind_a_turn_and_catches_up() {
        let mut camera = FollowCamera::new(0.25, true);
        let start = camera.follow(DVec3::ZERO, 0.0, 0.02);
        // a half turn: the camera swings round the shorter way and arrives behind the body
        let mut pose = start;
        for _ in 0..50 {
            pose = camera.follow(DVec3::ZERO, 3.0, 0.02);
        }
        let swung = pose.eye.truncate().angle_to(start.eye.truncate()).abs();
        assert!(
            swung > 0.3 && swung < 2.9,
            "part of the way after 1 s: {swung}"
        );
        for _ in 0..1000 {
            pose = camera.follow(DVec3::ZERO, 3.0, 0.02);
        }
        let behind = -DVec3::new(3.0f64.cos(), 3.0f64.sin(), 0.0);
        assert!(pose.eye.truncate().normalize().dot(behind.truncate()) > 0.999);
    }

    #[test]
    fn a_camera_that_does_not_turn_keeps_its_heading() {
        let mut camera = FollowCamera::new(0.05, false);
        let a = camera.follow(DVec3::ZERO, 0.0, 0.01);
        let b = camera.follow(DVec3::ZERO, 2.0, 0.01);
        assert_eq!(a, b);
    }
}
