//! Normal force laws: the paper's linear spring-damper (eq. 5–6) and Hunt–Crossley.
//!
//! ## Stable damping on light bodies
//! An explicit damper force −c·v over a step of length h changes a mass m's velocity by the factor
//! (1 − c·h/m), which overshoots for c·h/m > 1 and diverges past 2 — and a 0.05 kg foot with the
//! reference c = 150 N·s/m at h = 1 ms has c·h/m = 3. Instead the damper's velocity change over the
//! step is the exact solution of m·v̇ = −c·v, v(h) = v·e^(−c·h/m), so the force applied is
//! −c·φ(c·h/m)·v with φ(z) = (1 − e^(−z))/z. φ → 1 as z → 0 (the explicit force for heavy bodies,
//! φ = 0.93 for the 1 kg ball), and the damper can never reverse the normal velocity (it only takes
//! energy out: passive) however light the body. The spring stays explicit; semi-implicit Euler keeps
//! it stable while √(k/m)·h < 2, which [`NormalLaw::stable_time_step`] reports.
//!
//! ## A light body pushed by a heavy one
//! That decay alone is right for a body the damper stops by itself (a ball, a swinging foot). A
//! stance foot is different: the body comes down on it through a stiff leg, and its own mass m
//! (1/W_nn) is a small part of what the damper has to stop. Under a push P (every other force
//! along the normal on it, its own spring included) m·ẋ' = P − c·ẋ has ẋ(t) = P/c + (ẋ₀ − P/c)·
//! e^(−c·t/m), and the damper's exact average over the step is
//!
//! F_d = P·(1 − φ) + c·ẋ₀·φ,  φ = φ(c·h/m).
//!
//! Without the push (P = 0) the damper gives only c·φ·ẋ: a foot pushed steadily sinks at
//! P/(c·φ), not P/c, so the body meets c·φ ≤ m/h of damping — on a 39 g foot at 1 ms, 39 N·s/m
//! against the 93 asked (docs/rough-ground-log.md, *Where a fall's depth comes from*). The
//! caller estimates P from the last step ([`crate::contact::ContactModel::begin`]); F_d is kept
//! between 0 and the law's own c·ẋ₀, so the damper only ever takes energy out and never more
//! than the law as written asks.

/// A normal force law on the penetration x ≥ 0 and its rate ẋ (positive when sinking in).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NormalLaw {
    /// F = k·x + c·ẋ, clamped at ≥ 0 (the ground pushes, never pulls).
    SpringDamper { stiffness: f64, damping: f64 },
    /// F = k·xⁿ·(1 + d·ẋ), clamped at ≥ 0: zero at touch-down, so no sticky tension.
    HuntCrossley {
        stiffness: f64,
        exponent: f64,
        damping: f64,
    },
}

/// The reference contact's stiffness (N/m) and damping (N·s/m), docs/validation.md: set for
/// hex18, a 2.52 kg robot whose feet sink 0.41 mm standing on three.
pub const REFERENCE_STIFFNESS: f64 = 2.0e4;
pub const REFERENCE_DAMPING: f64 = 150.0;

impl Default for NormalLaw {
    /// The reference contact: k = 2·10⁴ N/m, c = 150 N·s/m.
    fn default() -> Self {
        NormalLaw::SpringDamper {
            stiffness: REFERENCE_STIFFNESS,
            damping: REFERENCE_DAMPING,
        }
    }
}

/// φ(z) = (1 − e^(−z))/z, the exact-decay factor of a damper over one step.
pub fn exact_decay_factor(z: f64) -> f64 {
    if z < 1e-8 {
        1.0 - 0.5 * z
    } else {
        -(-z).exp_m1() / z
    }
}

impl NormalLaw {
    /// The law for a body `ratio` times as heavy on as many feet: the same static sink and the
    /// same damping ratio. The spring carries `ratio` times the load, so k scales by `ratio`; the
    /// spring–damper's ζ = c / (2·√(k·m)) then keeps with c scaled by `ratio` too, while
    /// Hunt–Crossley's damping k·xⁿ·d already grows with k, so its d stays.
    pub fn scaled(&self, ratio: f64) -> NormalLaw {
        match *self {
            NormalLaw::SpringDamper { stiffness, damping } => NormalLaw::SpringDamper {
                stiffness: stiffness * ratio,
                damping: damping * ratio,
            },
            NormalLaw::HuntCrossley {
                stiffness,
                exponent,
                damping,
            } => NormalLaw::HuntCrossley {
                stiffness: stiffness * ratio,
                exponent,
                damping,
            },
        }
    }

    /// The static penetration under a load `force` (N).
    pub fn static_sink(&self, force: f64) -> f64 {
        match *self {
            NormalLaw::SpringDamper { stiffness, .. } => force / stiffness,
            NormalLaw::HuntCrossley {
                stiffness,
                exponent,
                ..
            } => (force / stiffness).powf(1.0 / exponent),
        }
    }

    /// The stiffness that holds a load `force` (N) at a penetration `sink` (m).
    pub fn stiffness_for(&self, force: f64, sink: f64) -> f64 {
        match *self {
            NormalLaw::SpringDamper { .. } => force / sink,
            NormalLaw::HuntCrossley { exponent, .. } => force / sink.powf(exponent),
        }
    }

    pub fn stiffness(&self) -> f64 {
        match *self {
            NormalLaw::SpringDamper { stiffness, .. }
            | NormalLaw::HuntCrossley { stiffness, .. } => stiffness,
        }
    }

    pub fn damping(&self) -> f64 {
        match *self {
            NormalLaw::SpringDamper { damping, .. } | NormalLaw::HuntCrossley { damping, .. } => {
                damping
            }
        }
    }

    /// The spring's part alone: k·x (Hunt–Crossley k·xⁿ); 0 out of contact.
    pub fn elastic(&self, x: f64) -> f64 {
        if x <= 0.0 {
            return 0.0;
        }
        match *self {
            NormalLaw::SpringDamper { stiffness, .. } => stiffness * x,
            NormalLaw::HuntCrossley {
                stiffness,
                exponent,
                ..
            } => stiffness * x.powf(exponent),
        }
    }

    /// The normal force for penetration `x` (> 0 in contact) and penetration rate `rate` (ẋ = −v_n),
    /// on a body whose effective mass along the normal is `mass`, over a step `dt`, pushed into
    /// the ground by `push` (P: every other normal force on it, its own spring included; 0 for
    /// a body the damper stops alone). The spring k·x plus the damper's exact average over the
    /// step, P·(1 − φ) + c·ẋ·φ, kept between 0 and c·ẋ (module doc); the sum clamped at ≥ 0.
    pub fn force(&self, x: f64, rate: f64, mass: f64, dt: f64, push: f64) -> f64 {
        if x <= 0.0 {
            return 0.0;
        }
        let elastic = self.elastic(x);
        let damping = match *self {
            NormalLaw::SpringDamper { damping, .. } => damping,
            NormalLaw::HuntCrossley { damping, .. } => elastic * damping,
        };
        let phi = exact_decay_factor(damping * dt / mass);
        let explicit = damping * rate;
        let damper =
            (push * (1.0 - phi) + explicit * phi).clamp(explicit.min(0.0), explicit.max(0.0));
        (elastic + damper).max(0.0)
    }

    /// The law as written, its damper explicit: k·x + c·ẋ (Hunt–Crossley k·xⁿ·(1 + d·ẋ)),
    /// clamped at ≥ 0 — the paper's eq. 6, which [`Self::force`] improves on for light bodies.
    pub fn explicit_force(&self, x: f64, rate: f64) -> f64 {
        if x <= 0.0 {
            return 0.0;
        }
        let force = match *self {
            NormalLaw::SpringDamper { stiffness, damping } => stiffness * x + damping * rate,
            NormalLaw::HuntCrossley {
                stiffness,
                exponent,
                damping,
            } => stiffness * x.powf(exponent) * (1.0 + damping * rate),
        };
        force.max(0.0)
    }

    /// Elastic energy stored at penetration `x`: ½·k·x² or k·xⁿ⁺¹/(n+1).
    pub fn stored_energy(&self, x: f64) -> f64 {
        if x <= 0.0 {
            return 0.0;
        }
        match *self {
            NormalLaw::SpringDamper { stiffness, .. } => 0.5 * stiffness * x * x,
            NormalLaw::HuntCrossley {
                stiffness,
                exponent,
                ..
            } => stiffness * x.powf(exponent + 1.0) / (exponent + 1.0),
        }
    }

    /// The largest step for which the explicit spring is stable on `mass`, 2/√(k/m), for the
    /// linear law; for Hunt–Crossley the tangent stiffness at penetration `x` is used.
    pub fn stable_time_step(&self, mass: f64, x: f64) -> f64 {
        let stiffness = match *self {
            NormalLaw::SpringDamper { stiffness, .. } => stiffness,
            NormalLaw::HuntCrossley {
                stiffness,
                exponent,
                ..
            } => stiffness * exponent * x.max(1e-6).powf(exponent - 1.0),
        };
        2.0 / (stiffness / mass).sqrt()
    }

    /// Checks the parameters, returning the name of the bad field and what was expected.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let check = |name: &'static str, v: f64, min: f64| {
            if v.is_finite() && v >= min {
                Ok(())
            } else {
                Err((
                    name,
                    if min > 0.0 {
                        format!("expected a finite number > 0, got {v}")
                    } else {
                        format!("expected a finite number ≥ {min}, got {v}")
                    },
                ))
            }
        };
        match *self {
            NormalLaw::SpringDamper { stiffness, damping } => {
                check("stiffness", stiffness, f64::MIN_POSITIVE)?;
                check("damping", damping, 0.0)
            }
            NormalLaw::HuntCrossley {
                stiffness,
                exponent,
                damping,
            } => {
                check("stiffness", stiffness, f64::MIN_POSITIVE)?;
                check("exponent", exponent, 1.0)?;
                check("damping", damping, 0.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body `ratio` times as heavy on the scaled law sinks as deep, in both laws.
    #[test]
    fn a_scaled_law_holds_a_heavier_body_at_the_same_sink() {
        let hunt = NormalLaw::HuntCrossley {
            stiffness: 1e6,
            exponent: 1.5,
            damping: 0.5,
        };
        for law in [NormalLaw::default(), hunt] {
            let sink = law.static_sink(8.0);
            let heavy = law.scaled(30.0);
            assert!((heavy.static_sink(240.0) / sink - 1.0).abs() < 1e-12);
            assert!((law.stiffness_for(8.0, sink) / law.stiffness() - 1.0).abs() < 1e-12);
        }
        assert_eq!(
            NormalLaw::default().scaled(30.0).damping(),
            30.0 * REFERENCE_DAMPING
        );
        assert_eq!(hunt.scaled(30.0).damping(), 0.5);
    }

    #[test]
    fn spring_damper_is_the_papers_law_for_heavy_bodies() {
        let law = NormalLaw::SpringDamper {
            stiffness: 2e4,
            damping: 150.0,
        };
        // effectively explicit when c·h/m is tiny
        let f = law.force(0.001, 0.2, 1e6, 1e-3, 0.0);
        assert!((f - (20.0 + 30.0)).abs() < 1e-3, "{f}");
    }

    #[test]
    fn never_pulls() {
        let law = NormalLaw::default();
        assert_eq!(law.force(0.001, -10.0, 1.0, 1e-3, 0.0), 0.0);
        assert_eq!(law.force(-0.001, 1.0, 1.0, 1e-3, 0.0), 0.0);
        let hc = NormalLaw::HuntCrossley {
            stiffness: 2e6,
            exponent: 1.5,
            damping: 1.0,
        };
        assert_eq!(hc.force(0.001, -5.0, 1.0, 1e-3, 0.0), 0.0);
    }

    #[test]
    fn hunt_crossley_is_continuous_at_touch_down() {
        let hc = NormalLaw::HuntCrossley {
            stiffness: 2e6,
            exponent: 1.5,
            damping: 1.0,
        };
        assert!(hc.force(1e-12, 3.0, 1.0, 1e-3, 0.0) < 1e-8);
        // F = k·x^n·(1 + d·ẋ) for a heavy body
        let f = hc.force(1e-3, 0.5, 1e9, 1e-3, 0.0);
        assert!((f - 2e6 * 1e-3f64.powf(1.5) * 1.5).abs() < 1e-6);
    }

    #[test]
    fn damper_cannot_reverse_a_light_body() {
        // c·h/m = 3 (0.05 kg foot, c = 150, h = 1 ms): the impulse is below m·v
        let law = NormalLaw::SpringDamper {
            stiffness: 0.0,
            damping: 150.0,
        };
        let (m, v, h) = (0.05, 1.0, 1e-3);
        let impulse = law.force(1e-3, v, m, h, 0.0) * h;
        assert!(impulse < m * v);
        assert!((impulse - m * v * (1.0 - (-3.0f64).exp())).abs() < 1e-12);
    }

    #[test]
    fn decay_factor_is_smooth_at_zero() {
        assert!((exact_decay_factor(1e-9) - exact_decay_factor(1.1e-8)).abs() < 1e-8);
        assert!((exact_decay_factor(3.0) - (1.0 - (-3.0f64).exp()) / 3.0).abs() < 1e-15);
    }
}
