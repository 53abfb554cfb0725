//! Observers of the step loop: the rerun recording, the trajectory CSV and the metrics. Physics
//! hands each step's sample to the observers and knows nothing of what they write.

pub mod background;
pub mod ball;
pub mod blueprint;
pub mod camera;
pub mod hexapod;
pub mod output;
pub mod rerun;
pub mod table;

/// Something that watches a simulation step by step.
pub trait Observer<S> {
    fn observe(&mut self, sample: &S) -> anyhow::Result<()>;
}

/// Steps between logged samples for a wanted rate (Hz) at step `dt` (at least every step).
pub fn decimation(rate_hz: f64, dt: f64) -> u64 {
    if rate_hz <= 0.0 {
        u64::MAX
    } else {
        ((1.0 / (rate_hz * dt)).round() as u64).max(1)
    }
}
