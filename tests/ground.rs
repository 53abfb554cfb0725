//! The ground fitted to the robot's weight: a walk whose scenario leaves the contact's stiffness
//! and damping out gets the reference contact scaled to the robot's mass against hex18's (the
//! same static sink and damping ratio); one that sets a stiffness its feet would sink through
//! is refused up front.

mod common;
use common::{hexsim, scratch};

/// hex18 with every mass, inertia and effort ×30: a 75.6 kg robot of hex18's size.
const HEAVY: &str = "tests/data/robots/hex18_x30.urdf";

fn walk(robot: Option<&str>, extra: &[&str], name: &str) -> serde_json::Value {
    let dir = scratch("ground");
    let json = dir.join(format!("{name}.json"));
    let mut cmd = hexsim();
    cmd.args(["run", "--terrain", "terrains/flat.toml", "--duration", "5"]);
    if let Some(robot) = robot {
        cmd.args(["--robot", robot]);
    }
    let out = cmd
        .args(extra)
        .args(["--no-record", "--metrics"])
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
}

/// Every force in the heavy robot is 30 times hex18's — weight, servos (their gains fitted to
/// inertias 30 times as large), and the fitted ground — so it must move as hex18 does: the same
/// distance and the same sink. On the reference contact it would sink 12.4 mm on three feet,
/// past its 10 mm feet.
#[test]
fn a_robot_thirty_times_as_heavy_walks_as_hex18_on_a_ground_fitted_to_it() {
    let hex18 = walk(None, &[], "hex18");
    let heavy = walk(Some(HEAVY), &[], "heavy");
    assert_eq!(hex18["ground"]["stiffness"], 2.0e4);
    assert_eq!(hex18["ground"]["damping"], 150.0);
    assert_eq!(hex18["ground"]["mass_ratio"], 1.0);
    let ratio = heavy["ground"]["mass_ratio"].as_f64().unwrap();
    assert!((ratio - 30.0).abs() < 1e-9, "{ratio}");
    for (field, reference) in [("stiffness", 2.0e4), ("damping", 150.0)] {
        let fitted = heavy["ground"][field].as_f64().unwrap();
        assert!(
            (fitted / (30.0 * reference) - 1.0).abs() < 1e-9,
            "{field} {fitted}"
        );
        assert_eq!(heavy["ground"]["origins"][field], "fitted");
    }
    for metric in ["forward_distance", "max_penetration", "body_height_mean"] {
        let (a, b) = (
            hex18[metric].as_f64().unwrap(),
            heavy[metric].as_f64().unwrap(),
        );
        println!("{metric}: hex18 {a:.5}, heavy {b:.5}");
        assert!(
            (b - a).abs() < 0.02 * a,
            "{metric}: {b} against hex18's {a}"
        );
    }
}

/// A stiffness given that lets the feet sink past their radius on the gait's fewest feet is
/// refused before the run, naming the stiffness that would hold them: 75.6 kg·g / 3 = 247.2 N per
/// foot over 10 mm is 2.472·10⁴ N/m.
#[test]
fn a_ground_the_feet_would_sink_through_is_refused() {
    let out = hexsim()
        .args([
            "run",
            "--robot",
            HEAVY,
            "--stiffness",
            "20000",
            "--no-record",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    for expected in [
        "contact.stiffness: 20000 lets the feet sink 12.4 mm",
        "fewest 3 feet (247.2 N each), past their 10.0 mm radius",
        "at least 2.472e4",
        "fitted to this robot: 6.000e5",
    ] {
        assert!(stderr.contains(expected), "no {expected:?} in {stderr}");
    }
}

/// A stiffness and damping given are used as given, and said so.
#[test]
fn a_ground_given_is_kept() {
    let m = walk(
        Some(HEAVY),
        &["--stiffness", "3e5", "--damping", "3000"],
        "given",
    );
    assert_eq!(m["ground"]["stiffness"], 3e5);
    assert_eq!(m["ground"]["damping"], 3000.0);
    assert_eq!(m["ground"]["origins"]["stiffness"], "given");
    assert_eq!(m["ground"]["origins"]["damping"], "given");
}
