//! Which legs stand when: a leg's cycle phase φ = frac(t/T − offset); it is in stance for
//! φ < duty factor, and in swing for the rest of the cycle.

/// Where a leg is in its cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LegPhase {
    /// On the ground; progress through the stance in [0, 1).
    Stance(f64),
    /// In the air; progress through the swing in [0, 1).
    Swing(f64),
}

impl LegPhase {
    pub fn is_stance(&self) -> bool {
        matches!(self, LegPhase::Stance(_))
    }
}

/// The phase of a leg with stance start `offset` (cycle fraction) at gait time `t`.
pub fn leg_phase(t: f64, period: f64, duty: f64, offset: f64) -> LegPhase {
    let phase = (t / period - offset).rem_euclid(1.0);
    if phase < duty {
        LegPhase::Stance(phase / duty)
    } else {
        LegPhase::Swing((phase - duty) / (1.0 - duty))
    }
}

/// The fewest legs in stance at any time of the cycle, sampled finely (a gait that leaves fewer
/// than three on the ground cannot stand statically).
pub fn minimum_support(offsets: &[f64; 6], duty: f64) -> usize {
    (0..1000)
        .map(|k| {
            let t = k as f64 / 1000.0;
            offsets
                .iter()
                .filter(|&&o| leg_phase(t, 1.0, duty, o).is_stance())
                .count()
        })
        .min()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tripod_alternates_two_groups() {
        let offsets = [0.0, 0.5, 0.0, 0.5, 0.0, 0.5];
        for &t in &[0.1, 0.3, 0.6, 0.9] {
            let stance: Vec<bool> = offsets
                .iter()
                .map(|&o| leg_phase(t, 1.0, 0.5, o).is_stance())
                .collect();
            assert_eq!(stance[0], stance[2]);
            assert_ne!(stance[0], stance[1]);
        }
        assert_eq!(minimum_support(&offsets, 0.5), 3);
    }
}
