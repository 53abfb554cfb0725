//! The ground's local orientation: the frame in which a contact splits velocity into a normal and
//! an in-plane part.
//!
//! Two methods, chosen by [`Orientation`]:
//! - [`Orientation::Exact`] (default): the exact normal of the interpolated surface,
//!   n = (−∂h/∂x, −∂h/∂y, 1)/‖·‖, with the in-plane x axis the world x axis projected onto the plane.
//!   It is the gradient of the very surface the penetration is measured against, so the normal force
//!   is the gradient of the spring's potential and does no spurious work.
//! - [`Orientation::Paper`]: Burkus & Odry's method. Roll and pitch come from central differences
//!   (eq. 1–2): α = arctan((h(x, y+YE) − h(x, y−YE)) / 2·YE), β = arctan((h(x+XE, y) − h(x−XE, y)) / 2·XE),
//!   and the ground frame is the rotation Rx(α)·Ry(β) of eq. 3–4. Positive α and β mean ground rising
//!   towards +y and +x; in our right-handed convention a rise towards +x is a rotation of −β about y,
//!   so the frame is Rx(α)·Ry(−β). It is exact on a plane that slopes along one axis and approximate
//!   (rotation order, finite step) elsewhere.

use super::HeightGrid;
use glam::{DMat3, DVec2, DVec3};

/// The plane z = level + slope·((x, y) − centre) fitted by least squares to points (x, y, z): the
/// ground under a robot's feet or hips, seen as one plane. `centre` and `level` are the points'
/// means; a slope that the points do not determine (fewer than three, or in a line) is zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedPlane {
    pub centre: DVec2,
    pub level: f64,
    pub slope: DVec2,
}

impl FittedPlane {
    pub fn fit(points: &[DVec3]) -> Self {
        let n = points.len() as f64;
        let centre = points.iter().map(|p| p.truncate()).sum::<DVec2>() / n;
        let level = points.iter().map(|p| p.z).sum::<f64>() / n;
        let (mut xx, mut xy, mut yy, mut xz, mut yz) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for p in points {
            let (x, y, z) = (p.x - centre.x, p.y - centre.y, p.z - level);
            (xx, xy, yy, xz, yz) = (xx + x * x, xy + x * y, yy + y * y, xz + x * z, yz + y * z);
        }
        let det = xx * yy - xy * xy;
        let slope = if det.abs() > 1e-12 {
            DVec2::new(yy * xz - xy * yz, xx * yz - xy * xz) / det
        } else {
            DVec2::ZERO
        };
        FittedPlane {
            centre,
            level,
            slope,
        }
    }

    /// The plane's upward unit normal.
    pub fn normal(&self) -> DVec3 {
        DVec3::new(-self.slope.x, -self.slope.y, 1.0).normalize()
    }
}

/// How the contact finds the ground's orientation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Orientation {
    /// Exact normal of the interpolated surface.
    #[default]
    Exact,
    /// The paper's central-difference angles with half-steps XE and YE (metres).
    Paper { xe: f64, ye: f64 },
}

/// An orthonormal ground frame in world coordinates: two in-plane axes and the outward normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundFrame {
    pub tangent_x: DVec3,
    pub tangent_y: DVec3,
    pub normal: DVec3,
}

impl GroundFrame {
    /// The frame whose normal is `n` (unit) and whose first tangent is world x projected onto the plane.
    pub fn from_normal(n: DVec3) -> Self {
        // On a height field's surface n.z > 0 and the projection of x never vanishes; on a wall
        // facing ±x (a cliff, `cliff.rs`) it does, and the in-plane x axis is the vertical.
        let projected = DVec3::X - n.x * n;
        let length_squared = projected.length_squared();
        // (`normalize`'s own arithmetic, without computing the length twice: the hot path)
        let tangent_x = if length_squared > 1e-12 {
            projected * length_squared.sqrt().recip()
        } else {
            cold_vertical_tangent(n)
        };
        GroundFrame {
            tangent_x,
            tangent_y: n.cross(tangent_x),
            normal: n,
        }
    }

    /// The paper's frame Rx(α)·Ry(−β) (eq. 3–4): its columns are the ground's axes in world coordinates.
    pub fn from_paper_angles(alpha: f64, beta: f64) -> Self {
        let rotation = DMat3::from_rotation_x(alpha) * DMat3::from_rotation_y(-beta);
        GroundFrame {
            tangent_x: rotation.x_axis,
            tangent_y: rotation.y_axis,
            normal: rotation.z_axis,
        }
    }

    /// World vector → ground components (in-plane x, in-plane y, normal).
    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(
            self.tangent_x.dot(v),
            self.tangent_y.dot(v),
            self.normal.dot(v),
        )
    }

    /// Ground components → world vector.
    pub fn to_world(&self, l: DVec3) -> DVec3 {
        l.x * self.tangent_x + l.y * self.tangent_y + l.z * self.normal
    }
}

/// The in-plane x axis of a wall facing ±x: the vertical.
#[cold]
fn cold_vertical_tangent(n: DVec3) -> DVec3 {
    (DVec3::Z - n.z * n).normalize()
}

impl HeightGrid {
    /// The paper's roll α and pitch β at (x, y) from central differences of the height (eq. 1–2).
    pub fn paper_angles(&self, x: f64, y: f64, xe: f64, ye: f64) -> (f64, f64) {
        let alpha = ((self.height(x, y + ye) - self.height(x, y - ye)) / (2.0 * ye)).atan();
        let beta = ((self.height(x + xe, y) - self.height(x - xe, y)) / (2.0 * xe)).atan();
        (alpha, beta)
    }

    /// The surface height at (x, y) and the ground frame there, from one evaluation of the
    /// interpolant for the exact normal (the contact's closest-point search calls this per foot
    /// and iteration, so it is on the hot path).
    pub fn height_and_frame(&self, x: f64, y: f64, orientation: Orientation) -> (f64, GroundFrame) {
        match orientation {
            Orientation::Exact => {
                let s = self.surface(x, y);
                (s.height, GroundFrame::from_normal(s.normal()))
            }
            Orientation::Paper { .. } => (self.height(x, y), self.ground_frame(x, y, orientation)),
        }
    }

    /// The ground frame at (x, y) by the chosen method.
    pub fn ground_frame(&self, x: f64, y: f64, orientation: Orientation) -> GroundFrame {
        match orientation {
            Orientation::Exact => GroundFrame::from_normal(self.normal(x, y)),
            Orientation::Paper { xe, ye } => {
                let (alpha, beta) = self.paper_angles(x, y, xe, ye);
                GroundFrame::from_paper_angles(alpha, beta)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_orthonormal(f: &GroundFrame) {
        let m = DMat3::from_cols(f.tangent_x, f.tangent_y, f.normal);
        assert!((m.transpose() * m).abs_diff_eq(DMat3::IDENTITY, 1e-12));
        assert!((m.determinant() - 1.0).abs() < 1e-12, "right-handed");
    }

    #[test]
    fn frames_are_right_handed_and_orthonormal() {
        assert_orthonormal(&GroundFrame::from_normal(
            DVec3::new(0.3, -0.4, 1.0).normalize(),
        ));
        assert_orthonormal(&GroundFrame::from_paper_angles(0.3, -0.7));
    }

    #[test]
    fn paper_frame_matches_exact_on_single_axis_slopes() {
        let along_y = GroundFrame::from_paper_angles(0.25, 0.0);
        let exact = DVec3::new(0.0, -(0.25f64).tan(), 1.0).normalize();
        assert!(along_y.normal.abs_diff_eq(exact, 1e-12));
        let along_x = GroundFrame::from_paper_angles(0.0, 0.25);
        let exact = DVec3::new(-(0.25f64).tan(), 0.0, 1.0).normalize();
        assert!(along_x.normal.abs_diff_eq(exact, 1e-12));
    }

    #[test]
    fn local_world_round_trip() {
        let f = GroundFrame::from_normal(DVec3::new(0.1, 0.2, 1.0).normalize());
        let v = DVec3::new(0.3, -1.2, 2.5);
        assert!(f.to_world(f.to_local(v)).abs_diff_eq(v, 1e-12));
    }
}
