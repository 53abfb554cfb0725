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
    let phase = fraction(t / period - offset);
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

/// `x.rem_euclid(1.0)` bit for bit, without the call to libm's `fmod` it makes (six legs a
/// step): below 2⁵² in size, `x % 1.0` is x less its integer part, exactly, with x's sign.
fn fraction(x: f64) -> f64 {
    if x.abs() >= 4_503_599_627_370_496.0 {
        return x.rem_euclid(1.0);
    }
    let r = (x - (x as i64) as f64).copysign(x);
    if r < 0.0 { r + 1.0 } else { r }
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

    /// The same bits as `rem_euclid(1.0)`: gait times, whole numbers of either sign (a zero's
    /// sign included), the neighbours of each, and beyond 2⁵².
    #[test]
    fn fraction_is_rem_euclid() {
        let mut xs: Vec<f64> = (0..100_000).map(|k| -3.0 + k as f64 * 0.000_137).collect();
        for x in [
            -3.0f64,
            -1.0,
            -0.0,
            0.0,
            1.0,
            2.0,
            1e15,
            4_503_599_627_370_496.0,
            1e300,
        ] {
            xs.extend([x, -x, x.next_down(), x.next_up()]);
        }
        for x in xs {
            assert_eq!(fraction(x).to_bits(), x.rem_euclid(1.0).to_bits(), "{x}");
        }
        assert!(fraction(f64::NAN).is_nan());
        assert!(fraction(f64::INFINITY).is_nan());
    }
}
