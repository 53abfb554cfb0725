//! Hexapods written by others (tests/data/third_party, with their sources and licences): loaded as
//! their users would bring them, and walked with the built-in tripod where it fits them.

mod common;
use common::{hexsim, scratch};

/// Walks `robot` for 10 s with the built-in tripod on `terrain` and returns its metrics.
fn walk(robot: &str, terrain: &str, name: &str) -> serde_json::Value {
    let json = scratch("third_party").join(format!("{name}.json"));
    let out = hexsim()
        .args([
            "run",
            "--robot",
            robot,
            "--terrain",
            terrain,
            "--duration",
            "10",
        ])
        .args(["--no-record", "--metrics"])
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{robot} on {terrain}: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
}

/// The PhantomX (rectangular) and the huaibovip hexapod (hexagonal) walk out of the box: on flat
/// ground at least 80 % of the tripod's nominal 1.2 m in 10 s with a heading change under 10°,
/// and over the paper's natural terrain without tilting past 20°.
#[test]
fn third_party_hexapods_walk_with_the_built_in_tripod() {
    let nominal = 0.06 / (0.5 * 1.0) * 10.0;
    for (name, robot) in [
        (
            "phantomx",
            "tests/data/third_party/phantomx_description/urdf/phantomx.urdf",
        ),
        (
            "huaibovip",
            "tests/data/third_party/hexapod_description/urdf/hexapod.urdf",
        ),
    ] {
        let flat = walk(robot, "terrains/flat.toml", &format!("{name}_flat"));
        let forward = flat["forward_distance"].as_f64().unwrap();
        let heading = flat["heading_change_deg"].as_f64().unwrap();
        println!("{name}: {forward:.3} m of {nominal:.3} m nominal, heading {heading:+.2}°");
        assert!(forward >= 0.8 * nominal, "{name} walked {forward:.3} m");
        assert!(heading.abs() < 10.0, "{name} turned {heading:.1}°");
        let natural = walk(robot, "terrains/natural.toml", &format!("{name}_natural"));
        let tilt = natural["max_roll_deg"]
            .as_f64()
            .unwrap()
            .max(natural["max_pitch_deg"].as_f64().unwrap());
        println!("{name} on the natural terrain: tilt ≤ {tilt:.2}°");
        assert!(tilt < 20.0, "{name} tilted {tilt:.1}°");
        assert_eq!(natural["complete"], true);
    }
}

/// The MushroomRL hexapod loads (six legs found from its structure); the tripod's fixed stance is
/// out of its long legs' reach, which `hexsim robot` says (fitting the gait to it is to come).
#[test]
fn the_mushroom_hexapod_loads_and_says_why_the_tripod_does_not_fit() {
    let out = hexsim()
        .args([
            "robot",
            "tests/data/third_party/mushroom_hexapod/hexapod.urdf",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("19 links, 18 joints, 6 legs"), "{stdout}");
    assert!(
        stdout.contains("standing in tripod's pose: does not fit: leg lf cannot reach its standing foot position"),
        "{stdout}"
    );
}
