//! A perceptive swing's height over known terrain.
//!
//! Following the terrain under the swinging foot's current point, a foot target steps by a
//! whole riser, a stone's rim or a pit's depth the instant that point crosses an edge: on
//! `stones` at 4 cm a tibia target jumped 1.85 rad in one step and the foot landed at 17 m/s.
//! Planned instead over the whole swing, the ground under the foot goes from where it lifted off
//! to where it will land, and on its way it passes over everything between the two as over a
//! cone: a point of the terrain at height g, d away horizontally, asks for g − SLOPE·(d − m). The
//! highest such ask is continuous in the foot's position, so the target rises ahead of a riser
//! and descends after a drop, never in one step.
//!
//! The cone's flat top, m wide, is the foot's radius plus the samples' spacing. A spherical foot
//! whose bottom is below a nose touches it unless its centre is a radius past it, and the last
//! sample on the nose's tread may lie a spacing short of the wall. Without it PhantomX's foot,
//! 7 mm in radius, came down 5 mm past a stair's wall onto its nose at 100 N, and the swing,
//! driven on down, threw the body 6 cm up.

use glam::DVec3;

/// How steeply a swing rises towards an obstacle ahead and falls after it (height per distance).
const SLOPE: f64 = 2.0;
/// Spacing of the samples along the ground a swing passes over (m).
const SAMPLE: f64 = 0.01;

/// The terrain a swing crosses: heights sampled from its lift-off point to its touch-down point
/// (body frame, now).
pub struct SwingGround {
    points: Vec<DVec3>,
    heights: Vec<f64>,
    /// The cone's flat top: how far from a terrain point the foot stays at its height (m).
    margin: f64,
}

impl SwingGround {
    /// The terrain under a foot of `radius` swinging from `from` to `to`.
    pub fn new(ground: &impl Fn(DVec3) -> f64, from: DVec3, to: DVec3, radius: f64) -> Self {
        let n = ((to - from).truncate().length() / SAMPLE).ceil().max(1.0) as usize;
        let points: Vec<DVec3> = (0..=n)
            .map(|i| from.lerp(to, i as f64 / n as f64))
            .collect();
        let heights = points.iter().map(|&p| ground(p)).collect();
        SwingGround {
            points,
            heights,
            margin: radius + SAMPLE,
        }
    }

    /// The height (terrain units of `ground`) that a foot at horizontal point `p` must be above
    /// to pass over the crossed terrain.
    pub fn envelope(&self, p: DVec3) -> f64 {
        self.points
            .iter()
            .zip(&self.heights)
            .map(|(q, h)| h - SLOPE * ((*q - p).truncate().length() - self.margin).max(0.0))
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// The ground height under a swinging foot at swing progress `s` ∈ [0, 1): from `from` (the
/// ground it lifted off) to `to` (the ground it will land on) along the swing's horizontal
/// `progress`, raised to the crossed terrain's `envelope` wherever it lies above; the raise is
/// faded in over the swing's first sixth and out over its last, so the foot leaves and lands on
/// its own ground.
pub fn swing_ground(from: f64, to: f64, progress: f64, envelope: f64, s: f64) -> f64 {
    let line = from + (to - from) * progress;
    let fade = (2.0 * (std::f64::consts::PI * s).sin()).min(1.0);
    line + fade * (envelope - line).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over a riser 8 cm high between lift-off and touch-down, the swing's ground climbs before
    /// the riser and by no more than a bounded amount per unit of progress: no jump.
    #[test]
    fn a_swing_over_a_riser_rises_before_it_without_a_jump() {
        let riser = |p: DVec3| if p.x < 0.05 { 0.0 } else { 0.08 };
        let (from, to) = (DVec3::new(0.0, 0.0, -0.1), DVec3::new(0.1, 0.0, -0.1));
        let crossed = SwingGround::new(&riser, from, to, 0.0);
        let n = 1000;
        let heights: Vec<f64> = (0..n)
            .map(|i| {
                let s = i as f64 / n as f64;
                let p = from.lerp(to, s);
                swing_ground(0.0, 0.08, s, crossed.envelope(p), s)
            })
            .collect();
        // at the riser (s = 0.5) the ground is its top
        assert!(heights[n / 2] >= 0.08 - 1e-12, "{}", heights[n / 2]);
        let steepest = heights
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        assert!(steepest < 0.002, "{steepest}");
        assert_eq!(heights[0], 0.0);
    }

    /// Past a drop, a foot's bottom stays at the nose's height until its centre is a radius
    /// beyond the wall, wherever the wall falls between the samples; then it descends.
    #[test]
    fn a_swing_clears_a_nose_by_the_foot_radius() {
        let radius = 0.007;
        for i in 0..10 {
            let wall = 0.05 + 0.001 * i as f64;
            let drop = move |p: DVec3| if p.x < wall { 0.0 } else { -0.08 };
            let (from, to) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.15, 0.0, 0.0));
            let crossed = SwingGround::new(&drop, from, to, radius);
            for j in 0..=1000 {
                let x = 0.15 * j as f64 / 1000.0;
                let bottom = crossed.envelope(DVec3::new(x, 0.0, 0.0));
                if x < wall + radius {
                    assert!(
                        bottom >= -1e-12,
                        "wall {wall}: at {x} the bottom is {bottom}"
                    );
                }
            }
            // and down on the lower tread once the cone's slope has brought it there
            let down = wall + SAMPLE + radius + SAMPLE + 0.08 / SLOPE;
            let far = crossed.envelope(DVec3::new(down, 0.0, 0.0));
            assert!(far <= -0.08 + 1e-12, "wall {wall}: {far}");
        }
    }
}
