//! Friction laws in the ground plane, exchangeable by configuration (paper §IV.C): regularised
//! Coulomb, viscous, Stribeck (static + Coulomb + viscous, the paper's Fig. 7) and Karnopp.
//!
//! ## Discrete time, and why Karnopp does not creep
//! Each law is evaluated once per step of length h, on a contact whose in-plane effective mass is
//! the 2×2 matrix M (the body's inertia seen at the contact point). Two quantities tie a law to the
//! step:
//! - the **tangential load** L: every in-plane force on the contact but friction. It is measured
//!   from the last step, L = M·(v − v_prev)/h − F_prev (what accelerated the contact, minus what
//!   friction contributed);
//! - the **stopping force** F_stop = −L − M·v/h: the friction that brings the contact point to rest
//!   at the end of this step.
//!
//! Karnopp (1985): inside the stick band |v| < Δv friction *cancels the tangential load* — it is
//! F_stop, as long as |F_stop| ≤ μs·Fn, and μs·Fn along it otherwise (the contact breaks away).
//! Outside the band it is the kinetic force μk·Fn, unless the kinetic friction can stop the
//! contact within the step (|F_stop| ≤ μk·Fn), in which case it stops there instead of overshooting.
//! Kinetic friction acts against the slip the step begins with, as the law is written, except
//! where the step would end with the slip reversed (the load alone carries the contact past rest
//! within the step): there it is F_stop projected onto the kinetic disc, as a projected
//! Gauss–Seidel solver projects its impulse — against the velocity the step ends with. Against
//! the old slip, friction would push the same way as the load: a light foot bouncing between the
//! walls of a pit its own width, pushed 3 m/s sideways a step by each wall (its leg turns a push
//! across into a slide along), had its slip grow ×1.2–3.7 a step to a divergence
//! (`ladder/stones.toml` at 2 cm). Always along F_stop (the implicit choice) would serve there
//! too, but where the load is estimated poorly (WORMS's 9.7 kg feet landing at 0.76 m/s) friction
//! then resists the estimate rather than the slip: a foot slid 0.16 m where it slid 0.2 mm.
//! Because the stick force holds the velocity at zero rather than letting a residual velocity
//! inside the band persist, a foot on a slope below its friction angle does not creep — the failure
//! of regularised models (MuJoCo's, Drake's) that need a velocity to make a force.
//!
//! The load is measured one step late, so under a load that keeps changing (a walking robot's
//! foot) a sticking contact still drifts a little; the stick force therefore also undoes a fraction
//! (`ContactModel::drift_recovery`, default ½; 0 turns it off) of the drift accumulated since the
//! contact last stuck (the material point's slip integrated while sticking — not the geometric
//! contact point, so a rolling ball is not held back).
//!
//! The other laws are continuous functions of the slip; they are evaluated as written, and only
//! limited to F_stop when they would otherwise reverse the slip within one step (which explicit
//! friction on a light foot does at once). That limit only ever removes energy.

use glam::DVec2;

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionLaw {
    /// No friction (the paper's non-slip ball needs none; a frictionless check needs it).
    None,
    /// Regularised Coulomb: F = −μ·Fn·v / max(|v|, width); linear below `width` (m/s).
    Coulomb { mu: f64, width: f64 },
    /// Viscous: F = −b·v.
    Viscous { coefficient: f64 },
    /// Stribeck (Fig. 7): F = −[Fc + (Fs − Fc)·exp(−(|v|/vs)²)]·v/max(|v|, width) − b·v,
    /// Fs = μs·Fn, Fc = μc·Fn.
    Stribeck {
        mu_static: f64,
        mu_coulomb: f64,
        viscous: f64,
        stribeck_velocity: f64,
        width: f64,
    },
    /// Karnopp: stick band |v| < `stick_band` (m/s) with static μs, kinetic μk outside.
    Karnopp {
        mu_static: f64,
        mu_kinetic: f64,
        stick_band: f64,
    },
}

impl Default for FrictionLaw {
    /// The reference contact: Karnopp, μs = 0.9, μk = 0.8, stick band 1 mm/s.
    fn default() -> Self {
        FrictionLaw::Karnopp {
            mu_static: 0.9,
            mu_kinetic: 0.8,
            stick_band: 1e-3,
        }
    }
}

/// What friction did in one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionOutcome {
    /// In-plane friction force (ground-frame components).
    pub force: DVec2,
    /// The contact is held at rest this step (Karnopp stick, or any law stopping the slip).
    pub sticking: bool,
}

impl FrictionLaw {
    /// The friction force for in-plane slip `slip` under normal force `normal_force`.
    /// `stop` is the stopping force F_stop (see the module docs).
    pub fn force(&self, slip: DVec2, normal_force: f64, stop: DVec2) -> FrictionOutcome {
        let speed = slip.length();
        let direction = |width: f64| slip / speed.max(width);
        let law = match *self {
            FrictionLaw::None => DVec2::ZERO,
            FrictionLaw::Coulomb { mu, width } => -mu * normal_force * direction(width),
            FrictionLaw::Viscous { coefficient } => -coefficient * slip,
            FrictionLaw::Stribeck {
                mu_static,
                mu_coulomb,
                viscous,
                stribeck_velocity,
                width,
            } => {
                let coulomb = mu_coulomb * normal_force;
                let stat = mu_static * normal_force;
                let level =
                    coulomb + (stat - coulomb) * (-(speed / stribeck_velocity).powi(2)).exp();
                -level * direction(width) - viscous * slip
            }
            FrictionLaw::Karnopp {
                mu_static,
                mu_kinetic,
                stick_band,
            } => return karnopp(slip, normal_force, stop, mu_static, mu_kinetic, stick_band),
        };
        if stop.length_squared() <= law.length_squared() {
            FrictionOutcome {
                force: stop,
                sticking: true,
            }
        } else {
            FrictionOutcome {
                force: law,
                sticking: false,
            }
        }
    }

    /// The friction force magnitude for steady sliding at `speed` under `normal_force` — the law's
    /// curve (as in the paper's Fig. 7), without the per-step stopping limit.
    pub fn sliding_force(&self, speed: f64, normal_force: f64) -> f64 {
        match *self {
            FrictionLaw::Karnopp {
                mu_static,
                mu_kinetic,
                stick_band,
            } => {
                if speed < stick_band {
                    mu_static * normal_force
                } else {
                    mu_kinetic * normal_force
                }
            }
            _ => {
                let out = self.force(
                    DVec2::new(speed, 0.0),
                    normal_force,
                    DVec2::splat(f64::INFINITY),
                );
                -out.force.x
            }
        }
    }

    /// Checks the parameters, returning the name of the bad field and what was expected.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let nonneg = |name: &'static str, v: f64| {
            crate::limits::check_number(v, crate::limits::Range::NonNegative, "")
                .map_err(|e| (name, e))
        };
        let positive = |name: &'static str, v: f64| {
            crate::limits::check_number(v, crate::limits::Range::Positive, "")
                .map_err(|e| (name, e))
        };
        match *self {
            FrictionLaw::None => Ok(()),
            FrictionLaw::Coulomb { mu, width } => {
                nonneg("mu", mu)?;
                positive("width", width)
            }
            FrictionLaw::Viscous { coefficient } => nonneg("coefficient", coefficient),
            FrictionLaw::Stribeck {
                mu_static,
                mu_coulomb,
                viscous,
                stribeck_velocity,
                width,
            } => {
                nonneg("mu_static", mu_static)?;
                nonneg("mu_coulomb", mu_coulomb)?;
                nonneg("viscous", viscous)?;
                positive("stribeck_velocity", stribeck_velocity)?;
                positive("width", width)
            }
            FrictionLaw::Karnopp {
                mu_static,
                mu_kinetic,
                stick_band,
            } => {
                nonneg("mu_static", mu_static)?;
                nonneg("mu_kinetic", mu_kinetic)?;
                positive("stick_band", stick_band)?;
                if mu_kinetic > mu_static {
                    return Err((
                        "mu_kinetic",
                        format!("expected ≤ mu_static ({mu_static}), got {mu_kinetic}"),
                    ));
                }
                Ok(())
            }
        }
    }
}

fn karnopp(
    slip: DVec2,
    normal_force: f64,
    stop: DVec2,
    mu_static: f64,
    mu_kinetic: f64,
    stick_band: f64,
) -> FrictionOutcome {
    let speed = slip.length();
    let stop_needed = stop.length();
    if speed < stick_band {
        let limit = mu_static * normal_force;
        if stop_needed <= limit {
            FrictionOutcome {
                force: stop,
                sticking: true,
            }
        } else {
            // break-away: static friction at its limit, along the load it resists
            FrictionOutcome {
                force: stop * (limit / stop_needed),
                sticking: false,
            }
        }
    } else if stop_needed <= mu_kinetic * normal_force {
        FrictionOutcome {
            force: stop,
            sticking: true,
        }
    } else {
        FrictionOutcome {
            force: kinetic_or_projected(
                -mu_kinetic * normal_force * slip / speed,
                stop,
                mu_kinetic * normal_force,
                slip,
            ),
            sticking: false,
        }
    }
}

/// Karnopp's kinetic force `kinetic` (−μk·Fn·v/|v|), unless the step would end with the slip
/// reversed — the stopping force `stop` lies beyond it along the slip, (F − F_stop)·v < 0: the
/// load alone carries the contact past rest — where it is the stopping force projected onto the
/// kinetic disc of radius `limit`, against the velocity the step ends with. Against the slip the
/// step began with, friction would push the same way as the load and the slip would grow.
fn kinetic_or_projected(kinetic: DVec2, stop: DVec2, limit: f64, slip: DVec2) -> DVec2 {
    if (kinetic - stop).dot(slip) >= 0.0 {
        kinetic
    } else {
        stop * (limit / stop.length())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat2;

    const FN: f64 = 10.0;

    #[test]
    fn coulomb_curve_saturates_at_mu_fn() {
        let law = FrictionLaw::Coulomb {
            mu: 0.5,
            width: 0.01,
        };
        assert!((law.sliding_force(1.0, FN) - 5.0).abs() < 1e-12);
        assert!(
            (law.sliding_force(0.005, FN) - 2.5).abs() < 1e-12,
            "linear inside the width"
        );
        assert_eq!(law.sliding_force(0.0, FN), 0.0);
    }

    #[test]
    fn viscous_curve_is_linear() {
        let law = FrictionLaw::Viscous { coefficient: 3.0 };
        assert!((law.sliding_force(0.7, FN) - 2.1).abs() < 1e-12);
    }

    #[test]
    fn stribeck_curve_falls_from_static_to_coulomb_then_rises_viscously() {
        let law = FrictionLaw::Stribeck {
            mu_static: 0.9,
            mu_coulomb: 0.6,
            viscous: 2.0,
            stribeck_velocity: 0.05,
            width: 1e-4,
        };
        let near_zero = law.sliding_force(1e-4, FN);
        assert!(
            (near_zero - 9.0).abs() < 0.01,
            "static level at break-away: {near_zero}"
        );
        let at_vs = law.sliding_force(0.05, FN);
        let expected = 6.0 + 3.0 * (-1.0f64).exp() + 0.1;
        assert!((at_vs - expected).abs() < 1e-9);
        let fast = law.sliding_force(1.0, FN);
        assert!(
            (fast - (6.0 + 2.0)).abs() < 1e-6,
            "Coulomb + viscous: {fast}"
        );
        assert!(law.sliding_force(0.2, FN) < near_zero);
    }

    #[test]
    fn karnopp_curve_is_static_in_the_band_and_kinetic_outside() {
        let law = FrictionLaw::default();
        assert!((law.sliding_force(5e-4, FN) - 9.0).abs() < 1e-12);
        assert!((law.sliding_force(0.5, FN) - 8.0).abs() < 1e-12);
    }

    #[test]
    fn karnopp_cancels_a_load_below_the_static_limit() {
        let law = FrictionLaw::default();
        // at rest, under a load of 5 N along x that friction held last step:
        // F_stop = F_prev − M·(2v − v_prev)/h = F_prev = −L
        let stop = DVec2::new(-5.0, 0.0);
        let out = law.force(DVec2::ZERO, FN, stop);
        assert!(out.sticking);
        assert!((out.force - DVec2::new(-5.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn karnopp_breaks_away_above_the_static_limit() {
        let law = FrictionLaw::default();
        let out = law.force(DVec2::ZERO, FN, DVec2::new(0.0, -12.0));
        assert!(!out.sticking);
        assert!((out.force.length() - 9.0).abs() < 1e-12);
    }

    #[test]
    fn karnopp_slides_kinetically_outside_the_band() {
        let law = FrictionLaw::default();
        let slip = DVec2::new(0.3, 0.4);
        // a contact's first step: F_stop = −M·v/h
        let stop = -(DMat2::from_diagonal(DVec2::splat(2.0)) * slip) / 1e-3;
        let out = law.force(slip, FN, stop);
        assert!(!out.sticking);
        assert!((out.force + 8.0 * slip / 0.5).length() < 1e-12);
    }

    /// Sliding at 1 m/s along +x while the load (a wall's push through the leg) would carry the
    /// contact to −2 m/s by the end of the step: kinetic friction, too weak to stop it, acts
    /// against that end velocity (+x), not against the start's (−x, which would add to the load).
    #[test]
    fn karnopp_slides_against_the_velocity_the_step_ends_with() {
        let law = FrictionLaw::default();
        let mass = DMat2::from_diagonal(DVec2::splat(0.05));
        let (slip, h) = (DVec2::new(1.0, 0.0), 1e-3);
        let load = DVec2::new(-150.0, 0.0);
        // F_stop = −L − M·v/h
        let stop = -load - mass * slip / h;
        assert!(stop.x > 0.0 && stop.length() > 8.0);
        let out = law.force(slip, FN, stop);
        assert!(!out.sticking);
        assert!(
            (out.force - DVec2::new(8.0, 0.0)).length() < 1e-12,
            "{}",
            out.force
        );
        // the end velocity is smaller than without friction: friction took energy out
        let end = |f: DVec2| slip + mass.inverse() * (load + f) * h;
        assert!(end(out.force).length() < end(DVec2::ZERO).length());
    }

    #[test]
    fn no_law_reverses_a_light_contact_within_a_step() {
        // 20 g contact sliding at 1 cm/s, no load: every law may at most stop it.
        let mass = DMat2::from_diagonal(DVec2::splat(0.02));
        let slip = DVec2::new(0.01, 0.0);
        let stop = -(mass * slip) / 1e-3;
        for law in [
            FrictionLaw::Coulomb {
                mu: 0.8,
                width: 1e-4,
            },
            FrictionLaw::Viscous { coefficient: 1e3 },
            FrictionLaw::default(),
        ] {
            let f = law.force(slip, FN, stop).force;
            let next = slip + mass.inverse() * f * 1e-3;
            assert!(next.x >= -1e-12, "{law:?} reversed the slip: {next}");
        }
    }

    #[test]
    fn validation_names_the_field() {
        let bad = FrictionLaw::Karnopp {
            mu_static: 0.5,
            mu_kinetic: 0.8,
            stick_band: 1e-3,
        };
        assert_eq!(bad.validate().unwrap_err().0, "mu_kinetic");
    }
}
