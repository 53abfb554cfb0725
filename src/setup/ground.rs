//! A walk's ground: the reference contact (k = 2·10⁴ N/m, c = 150 N·s/m) was set for hex18; on a
//! robot 30 times as heavy the same spring lets the feet sink past their radius. So where the
//! scenario leaves the stiffness or damping out, it is the reference's scaled to the robot's mass
//! against hex18's ([`crate::contact::NormalLaw::scaled`]): the feet sink as hex18's do on the
//! reference contact, with the same damping ratio (hex18 gets the reference exactly).

use crate::contact::NormalLaw;
use crate::metrics::GroundMetrics;
use crate::robot::RobotModel;
use crate::robot::statics::foot_load;
use crate::sim::STANDARD_GRAVITY;
use std::path::Path;

/// Which of the normal law's parameters the scenario gives (the others are fitted).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Given {
    pub stiffness: bool,
    pub damping: bool,
}

/// hex18's mass (kg), against which a robot's ground is scaled.
pub fn hex18_mass() -> f64 {
    static MASS: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *MASS.get_or_init(|| {
        crate::robot::urdf::from_str_with(
            include_str!("../../robots/hex18.urdf"),
            Some(include_str!("../../robots/hex18.toml")),
            Path::new("robots/hex18.urdf"),
        )
        .expect("the built-in robot loads")
        .total_mass()
    })
}

/// The ground `normal` becomes on `robot`: the parameters not `given` fitted to its mass. A
/// stiffness given that lets the feet sink past their radius standing on the gait's fewest
/// (`support`) feet is refused, naming the stiffness that would hold them. Returns the law and
/// what the metrics say of it.
pub fn fit(
    normal: NormalLaw,
    given: Given,
    robot: &RobotModel,
    support: usize,
) -> Result<(NormalLaw, GroundMetrics), String> {
    let ratio = robot.total_mass() / hex18_mass();
    let fitted = normal.scaled(ratio);
    let mut normal = normal;
    let origin = |given: bool| if given { "given" } else { "fitted" }.to_string();
    if !given.stiffness || !given.damping {
        normal = match (normal, fitted) {
            (
                NormalLaw::SpringDamper { stiffness, damping },
                NormalLaw::SpringDamper {
                    stiffness: k,
                    damping: c,
                },
            ) => NormalLaw::SpringDamper {
                stiffness: if given.stiffness { stiffness } else { k },
                damping: if given.damping { damping } else { c },
            },
            (
                NormalLaw::HuntCrossley {
                    stiffness,
                    exponent,
                    damping,
                },
                NormalLaw::HuntCrossley {
                    stiffness: k,
                    damping: d,
                    ..
                },
            ) => NormalLaw::HuntCrossley {
                stiffness: if given.stiffness { stiffness } else { k },
                exponent,
                damping: if given.damping { damping } else { d },
            },
            (normal, _) => normal,
        };
    }
    if given.stiffness && support > 0 {
        let load = foot_load(robot, STANDARD_GRAVITY, support);
        let radius = robot
            .legs
            .iter()
            .map(|leg| leg.foot.radius)
            .fold(f64::INFINITY, f64::min);
        let sink = normal.static_sink(load);
        if sink >= radius {
            return Err(format!(
                "contact.stiffness: {} lets the feet sink {:.1} mm standing on the gait's fewest {support} feet ({load:.1} N each), past their {:.1} mm radius; a stiffness of at least {:.3e} holds them (left out, the contact is fitted to this robot: {:.3e})",
                normal.stiffness(),
                sink * 1e3,
                radius * 1e3,
                normal.stiffness_for(load, radius),
                fitted.stiffness()
            ));
        }
    }
    let metrics = GroundMetrics {
        stiffness: normal.stiffness(),
        damping: normal.damping(),
        origins: [
            ("stiffness".to_string(), origin(given.stiffness)),
            ("damping".to_string(), origin(given.damping)),
        ]
        .into_iter()
        .collect(),
        mass_ratio: ratio,
    };
    Ok((normal, metrics))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex18() -> RobotModel {
        crate::scenario::builtin::hex18()
    }

    /// hex18 times `factor` in every link's mass and inertia.
    fn heavier(factor: f64) -> RobotModel {
        let mut robot = hex18();
        for link in &mut robot.links {
            link.mass *= factor;
            link.inertia *= factor;
        }
        robot
    }

    #[test]
    fn hex18_gets_the_reference_contact_exactly() {
        let reference = NormalLaw::default();
        let (normal, metrics) = fit(reference, Given::default(), &hex18(), 3).unwrap();
        assert_eq!(normal, reference);
        assert_eq!(metrics.mass_ratio, 1.0);
        assert_eq!(metrics.origins["stiffness"], "fitted");
    }

    #[test]
    fn a_heavier_robot_sinks_as_hex18_does() {
        let reference = NormalLaw::default();
        let load = |r: &RobotModel| foot_load(r, STANDARD_GRAVITY, 3);
        let heavy = heavier(30.0);
        let (normal, metrics) = fit(reference, Given::default(), &heavy, 3).unwrap();
        assert!((metrics.mass_ratio - 30.0).abs() < 1e-9);
        let sink = normal.static_sink(load(&heavy));
        let hex18_sink = reference.static_sink(load(&hex18()));
        assert!(
            (sink / hex18_sink - 1.0).abs() < 1e-6,
            "{sink} vs {hex18_sink}"
        );
    }

    #[test]
    fn a_given_parameter_is_kept_and_the_other_fitted() {
        let given = NormalLaw::SpringDamper {
            stiffness: 5e5,
            damping: 150.0,
        };
        let only_k = Given {
            stiffness: true,
            damping: false,
        };
        let (normal, metrics) = fit(given, only_k, &heavier(4.0), 3).unwrap();
        assert_eq!(normal.stiffness(), 5e5);
        assert!(normal.damping() > 150.0, "{}", normal.damping());
        assert_eq!(metrics.origins["stiffness"], "given");
        assert_eq!(metrics.origins["damping"], "fitted");
    }

    #[test]
    fn a_stiffness_that_lets_the_feet_sink_past_their_radius_is_refused() {
        let soft = NormalLaw::SpringDamper {
            stiffness: 10.0,
            damping: 150.0,
        };
        let given = Given {
            stiffness: true,
            damping: true,
        };
        let error = fit(soft, given, &hex18(), 3).unwrap_err();
        assert!(
            error.starts_with("contact.stiffness: 10 lets the feet sink"),
            "{error}"
        );
        assert!(error.contains("a stiffness of at least"), "{error}");
    }
}
