//! Property tests: the contact model stays physical for any finite input, and the readers of
//! robots, terrains, gaits and scenarios answer anything with a value or an error, never a panic.

use glam::DVec3;
use hexsim::contact::{
    ContactModel, ContactState, EffectiveMass, FrictionLaw, NormalLaw, sphere_geometry,
};
use hexsim::terrain::{HeightGrid, Orientation};
use proptest::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

fn ground() -> &'static HeightGrid {
    static GROUND: OnceLock<HeightGrid> = OnceLock::new();
    GROUND.get_or_init(|| hexsim::terrain::sine([2.0, 2.0], [0.0, 0.0], 0.05, 0.5, 0.01).unwrap())
}

fn vector(limit: f64) -> impl Strategy<Value = DVec3> {
    (-limit..limit, -limit..limit, -limit..limit).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Any finite state: finite force, normal force ≥ 0, friction within μs·Fn (Karnopp) or μ·Fn
    /// (Coulomb), over several steps so the friction's memory is exercised too.
    #[test]
    fn contact_forces_are_finite_nonnegative_and_within_the_friction_cone(
        x in -0.9..0.9f64, y in -0.9..0.9f64, depth in -0.02..0.08f64, radius in 0.005..0.1f64,
        velocities in prop::collection::vec(vector(10.0), 4),
        mass in 0.01..10.0f64, dt in 1e-4..2e-3f64,
        stiffness in 1e3..1e6f64, damping in 0.0..500.0f64,
        mu_static in 0.05..1.5f64, ratio in 0.1..1.0f64, coulomb in any::<bool>(),
        paper in any::<bool>(),
    ) {
        let terrain = ground();
        let friction = if coulomb {
            FrictionLaw::Coulomb { mu: mu_static, width: 1e-3 }
        } else {
            FrictionLaw::Karnopp { mu_static, mu_kinetic: ratio * mu_static, stick_band: 1e-3 }
        };
        let orientation = if paper { Orientation::Paper { xe: 0.01, ye: 0.01 } } else { Orientation::Exact };
        let model = ContactModel {
            normal: NormalLaw::SpringDamper { stiffness, damping },
            friction,
            orientation,
            ..ContactModel::default()
        };
        let center = DVec3::new(x, y, terrain.height(x, y) + radius - depth);
        let geometry = sphere_geometry(terrain, center, radius, orientation);
        let effective = EffectiveMass::particle(mass);
        let mut state = ContactState::default();
        for v in velocities {
            let Some(c) = model.respond(&geometry, v, &effective, dt, &mut state) else {
                prop_assert!(geometry.penetration <= 0.0);
                continue;
            };
            prop_assert!(c.force.is_finite() && c.friction.is_finite(), "{c:?}");
            prop_assert!(c.normal_force >= 0.0, "normal force {}", c.normal_force);
            let bound = mu_static * c.normal_force * (1.0 + 1e-9) + 1e-12;
            prop_assert!(
                c.friction.length() <= bound,
                "friction {} above μs·Fn = {}", c.friction.length(), bound
            );
        }
    }

    /// Any number in any numeric attribute of the reference URDF: a robot or an error.
    #[test]
    fn the_urdf_reader_never_panics(which in 0usize..2000, value in prop_oneof![
        Just("NaN".to_string()), Just("-inf".to_string()), Just("".to_string()), Just("x".to_string()),
        any::<f64>().prop_map(|v| v.to_string()), (-2.0..2.0f64).prop_map(|v| v.to_string()),
    ]) {
        let text = include_str!("../robots/hex18.urdf");
        let numbers: Vec<(usize, usize)> = text
            .match_indices('"')
            .collect::<Vec<_>>()
            .chunks(2)
            .filter(|q| q.len() == 2)
            .map(|q| (q[0].0 + 1, q[1].0))
            .filter(|&(a, b)| text[a..b].chars().all(|c| c.is_ascii_digit() || " .-e".contains(c)) && b > a)
            .collect();
        let (a, b) = numbers[which % numbers.len()];
        let mutated = format!("{}{}{}", &text[..a], value, &text[b..]);
        let _ = hexsim::robot::urdf::from_str(&mutated, Path::new("mutated.urdf"));
    }

    /// Arbitrary text as a terrain, gait or scenario file: parsed or refused, never a panic.
    #[test]
    fn the_file_readers_never_panic(text in "[a-z_\\[\\]\"=.,0-9 \n{}-]{0,200}") {
        let _ = hexsim::terrain::TerrainSpec::from_toml(&text, Path::new("t.toml"));
        let _ = hexsim::gait::GaitSpec::from_toml(&text, Path::new("g.toml"));
        let _ = toml::from_str::<hexsim::scenario::ScenarioSpec>(&text);
    }

    /// Arbitrary CSV content as a height file: a grid or an error.
    #[test]
    fn the_csv_height_reader_never_panics(rows in prop::collection::vec(
        prop::collection::vec(prop_oneof![
            any::<f64>().prop_map(|v| v.to_string()), Just("nan".to_string()), Just("".to_string()),
            Just("1e999".to_string()), Just("a".to_string())
        ], 0..5), 0..5)
    ) {
        let text: Vec<String> = rows.iter().map(|r| r.join(",")).collect();
        let file = tempfile::Builder::new().prefix("hexsim-prop-").suffix(".csv").tempfile().unwrap();
        let path = file.path();
        std::fs::write(path, text.join("\n")).unwrap();
        if let Ok((cols, rows, heights)) = hexsim::terrain::io::read_csv(path) {
            prop_assert_eq!(cols * rows, heights.len());
            prop_assert!(heights.iter().all(|h| h.is_finite()));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Scenario fields with extreme values: the file parses, and resolves exactly when every value
    /// is in its range (checked here independently: the ranges the scenario format documents, and
    /// the explicit spring's stability limit 2/√(k/m) for the lightest foot or the ball); a refusal
    /// names the file and one of the fields out of range; a scenario resolved takes the steps its
    /// times ask for.
    #[test]
    fn scenarios_resolve_exactly_when_their_values_are_in_range(
        dt in prop_oneof![Just(f64::NAN), Just(0.0), Just(-1.0), 1e-5..0.02f64],
        duration in prop_oneof![Just(f64::INFINITY), -1.0..100.0f64],
        stiffness in prop_oneof![Just(0.0), Just(-1.0), 1.0..1e9f64],
        mu in -1.0..2.0f64, settle in -1.0..5.0f64, iterations in 0usize..10,
        ball in any::<bool>(),
    ) {
        let text = if ball {
            format!("kind = \"ball\"\nduration = {duration}\ndt = {dt}\n[contact]\nstiffness = {stiffness}\nmu_kinetic = {mu}\n")
        } else {
            format!("duration = {duration}\ndt = {dt}\nsettle = {settle}\nsolver_iterations = {iterations}\n[contact]\nstiffness = {stiffness}\nmu_static = {mu}\n")
        };
        // TOML spells them nan and inf
        let text = text.replace("NaN", "nan");
        let spec = toml::from_str::<hexsim::scenario::ScenarioSpec>(&text);
        prop_assert!(spec.is_ok(), "{text}: {:?}", spec.err());
        // what is out of range, by the fragment of the message that names it
        let mut invalid = Vec::new();
        if !(dt.is_finite() && dt > 0.0 && dt <= 0.01) {
            invalid.push("dt");
        }
        if !(duration.is_finite() && duration >= 0.0) {
            invalid.push("duration");
        }
        if stiffness <= 0.0 {
            invalid.push("stiffness");
        } else {
            // the reference ball (1 kg), or hex18's lightest foot link
            let mass = if ball { 1.0 } else { lightest_foot() };
            if dt.is_finite() && dt >= 2.0 / (stiffness / mass).sqrt() {
                invalid.push("dt");
            }
        }
        // the other coefficient keeps its default: μs = 0.9, μk = 0.8
        let friction_ok = if ball { (0.0..=0.9).contains(&mu) } else { mu >= 0.8 };
        if !friction_ok {
            invalid.push("mu_");
        }
        if !ball && settle < 0.0 {
            invalid.push("settle");
        }
        if !ball && iterations == 0 {
            invalid.push("solver_iterations");
        }
        match hexsim::scenario::Scenario::resolve(spec.unwrap(), "p".into(), Path::new("p.toml")) {
            Ok(s) => {
                prop_assert!(invalid.is_empty(), "resolved despite {invalid:?}: {text}");
                let time = if ball { duration } else { settle + duration };
                prop_assert_eq!(s.total_steps(), (time / dt).round() as u64);
            }
            Err(e) => {
                let message = e.to_string();
                prop_assert!(!invalid.is_empty(), "refused in range: {message}\n{text}");
                prop_assert!(message.starts_with("p.toml: "), "{message}");
                prop_assert!(
                    invalid.iter().any(|field| message.contains(field)),
                    "{message} names none of {invalid:?}"
                );
            }
        }
    }
}

/// The mass of hex18's lightest foot link (kg), which bounds the contact spring's stable step.
fn lightest_foot() -> f64 {
    static MASS: OnceLock<f64> = OnceLock::new();
    *MASS.get_or_init(|| {
        let model = hexsim::robot::urdf::from_str(
            include_str!("../robots/hex18.urdf"),
            Path::new("robots/hex18.urdf"),
        )
        .unwrap();
        model
            .legs
            .iter()
            .map(|leg| model.links[leg.foot_link].mass)
            .fold(f64::INFINITY, f64::min)
    })
}
