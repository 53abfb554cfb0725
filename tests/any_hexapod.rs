//! Hexapods with more than six legs of three joints (issue 40): a head, an arm and eyes on the
//! body; legs of four and five joints (on three, the others held; or driven whole, on redundant
//! inverse kinematics); passive, massless feet. Each is hex18 (robots/hex18.urdf)
//! with the trait added (tests/data/robots/hex18_*.urdf), so hex18 is the reference it is held
//! to, and each walks 10 s on flat ground with the built-in tripod and no robot file.

mod common;
use common::{hexsim, metrics_of, scratch};
use std::path::Path;

/// `hexsim robot`'s report on `robot`.
fn report(robot: &str) -> String {
    let out = hexsim().args(["robot", robot]).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{robot}: {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// Walks `robot` 10 s on flat ground and returns its metrics.
fn walk(robot: &Path, dir: &Path, name: &str) -> serde_json::Value {
    let json = dir.join(format!("{name}.json"));
    let mut cmd = hexsim();
    cmd.args(["run", "--robot"])
        .arg(robot)
        .args(["--terrain", "terrains/flat.toml", "--duration", "10"])
        .args(["--no-record", "--metrics"])
        .arg(&json);
    metrics_of(cmd, &json, name)
}

/// The forward distance and the tripod's nominal distance over 10 s (duty 0.5, period 1 s).
fn forward_of_nominal(metrics: &serde_json::Value) -> (f64, f64) {
    let stride = metrics["stance"]["stride_length"].as_f64().unwrap();
    (
        metrics["forward_distance"].as_f64().unwrap(),
        stride / 0.5 * 10.0,
    )
}

/// hex18 without its robot file (its stance fitted, as the variants' are).
fn bare_hex18(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("hex18.urdf");
    std::fs::copy("robots/hex18.urdf", &path).unwrap();
    path
}

/// A pan-tilt head, a two-joint arm whose gripper ends in a collision sphere, and two eye spheres
/// fixed to the body: the legs are hex18's six (the arm, on the walking axis, is no leg's pair;
/// the head does not reach the ground), every joint off them is held at zero, the spheres on the
/// body and the gripper are contact geometry, not feet, and it walks as hex18 does (measured:
/// 1.175 m of 1.237 m nominal; hex18 bare 1.166 m).
#[test]
fn a_head_an_arm_and_eyes_ride_on_the_body() {
    let robot = "tests/data/robots/hex18_head_arm.urdf";
    let text = report(robot);
    assert!(text.contains("4 joints held still"), "{text}");
    for joint in [
        "head_pan_joint 0°",
        "head_tilt_joint 0°",
        "arm_shoulder_joint 0°",
        "arm_elbow_joint 0°",
    ] {
        assert!(text.contains(joint), "{joint}: {text}");
    }
    for leg in ["lf", "lm", "lr", "rf", "rm", "rr"] {
        let line = format!("joints {leg}_coxa_joint {leg}_femur_joint {leg}_tibia_joint");
        assert!(text.contains(&line), "{line}: {text}");
    }
    let dir = scratch("any_hexapod_head");
    let metrics = walk(Path::new(robot), &dir, "head_arm");
    let (forward, nominal) = forward_of_nominal(&metrics);
    println!("head and arm: {forward:.3} m of {nominal:.3} m nominal");
    assert!(forward >= 0.9 * nominal, "{forward:.3} m of {nominal:.3}");
    let heading = metrics["heading_change_deg"].as_f64().unwrap();
    assert!(heading.abs() < 1.0, "turned {heading:.2}°");
}

/// Legs of four joints (coxa, femur, tibia, tarsus) and of five (a hip roll besides) walk on the
/// three joints that sweep the largest workspace — coxa, femur, tibia — the others held at zero,
/// where each leg is hex18's: they walk as far as hex18 (measured: 1.166 m each of 1.237 m
/// nominal, as hex18 bare).
#[test]
fn legs_of_four_and_five_joints_walk_on_three() {
    let dir = scratch("any_hexapod_joints");
    let reference = walk(&bare_hex18(&dir), &dir, "hex18");
    let (hex18, _) = forward_of_nominal(&reference);
    for (name, held) in [
        ("tarsus", vec!["lf_tarsus_joint 0°", "rr_tarsus_joint 0°"]),
        (
            "five_joint",
            vec!["lf_roll_joint 0°", "lf_tarsus_joint 0°", "rm_roll_joint 0°"],
        ),
    ] {
        let robot = format!("tests/data/robots/hex18_{name}.urdf");
        let text = report(&robot);
        assert!(text.contains("on the legs, beyond the three"), "{text}");
        for joint in held {
            assert!(text.contains(joint), "{joint}: {text}");
        }
        assert!(
            text.contains("joints lf_coxa_joint lf_femur_joint lf_tibia_joint"),
            "{text}"
        );
        walks_as_far_as_hex18(Path::new(&robot), &dir, name, hex18);
    }
}

/// Walks `robot` (see [`walk`]) and checks it goes at least 90 % of its nominal distance and
/// within 2 % of bare hex18's `hex18`; returns its metrics.
fn walks_as_far_as_hex18(robot: &Path, dir: &Path, name: &str, hex18: f64) -> serde_json::Value {
    let metrics = walk(robot, dir, name);
    let (forward, nominal) = forward_of_nominal(&metrics);
    println!("{name}: {forward:.3} m of {nominal:.3} m nominal (hex18: {hex18:.3} m)");
    assert!(
        forward >= 0.9 * nominal,
        "{name}: {forward:.3} m of {nominal:.3}"
    );
    assert!(
        (forward - hex18).abs() < 0.02 * hex18,
        "{name}: {forward:.3} m, hex18 {hex18:.3} m"
    );
    metrics
}

/// A copy of `tests/data/robots/NAME.urdf` in `dir` with a robot file driving its legs whole.
fn driven(name: &str, dir: &Path) -> std::path::PathBuf {
    let path = dir.join(format!("{name}.urdf"));
    std::fs::copy(format!("tests/data/robots/{name}.urdf"), &path).unwrap();
    std::fs::write(
        dir.join(format!("{name}.toml")),
        "redundant_legs = \"driven\"\n",
    )
    .unwrap();
    path
}

/// With `redundant_legs = "driven"` in the robot file, legs of four and five joints are driven
/// whole, on redundant inverse kinematics (`robot::redundant`): coxa, femur and tibia — the three
/// that sweep the largest workspace — place the foot, the others pulled towards rest. Where each
/// leg is hex18's, the three reach the built-in tripod's feet alone, the extra joints stay near
/// zero, and they walk as far as hex18 (measured: tarsus 1.169 m, five joints 1.170 m of
/// 1.237 m nominal; hex18 bare 1.166 m).
#[test]
fn driven_legs_of_four_and_five_joints_walk_on_all_their_joints() {
    let dir = scratch("any_hexapod_joints");
    let reference = walk(&bare_hex18(&dir), &dir, "hex18");
    let (hex18, _) = forward_of_nominal(&reference);
    for (name, joints, extra) in [
        (
            "tarsus",
            "joints lf_coxa_joint lf_femur_joint lf_tibia_joint lf_tarsus_joint;",
            "lf_tarsus_joint 0° driven too",
        ),
        (
            "five_joint",
            "joints lf_coxa_joint lf_roll_joint lf_femur_joint lf_tibia_joint lf_tarsus_joint;",
            "lf_roll_joint 0°, lf_tarsus_joint 0° driven too",
        ),
    ] {
        let robot = driven(&format!("hex18_{name}"), &dir);
        let robot = robot.to_str().unwrap();
        let text = report(robot);
        assert!(!text.contains("held still"), "{text}");
        assert!(text.contains(joints), "{joints}: {text}");
        assert!(
            text.contains("redundant: lf_coxa_joint lf_femur_joint lf_tibia_joint place the foot"),
            "{text}"
        );
        assert!(text.contains(extra), "{extra}: {text}");
        let metrics = walks_as_far_as_hex18(Path::new(robot), &dir, name, hex18);
        assert_eq!(metrics["clamped_ik_steps"], 0, "{name}");
    }
}

/// A driven extra joint is used where the three cannot reach: on folded legs (stance 0.05 m
/// high, feet 0.10 m out: tests/data/gaits/tripod_folded.toml) hex18_tarsus's coxa, femur and
/// tibia miss the standing feet by 0.9 mm with the tarsus held at zero — the run is refused, and
/// says how to drive it — and with the tarsus driven and bent, up to 34° in the walk, it walks
/// 0.757 m of 0.8 m nominal with every target reached.
#[test]
fn a_tarsus_bends_to_reach_what_coxa_femur_and_tibia_cannot() {
    let dir = scratch("any_hexapod_folded");
    let gait = "tests/data/gaits/tripod_folded.toml";
    let held = hexsim()
        .args([
            "run",
            "--robot",
            "tests/data/robots/hex18_tarsus.urdf",
            "--gait",
            gait,
        ])
        .args([
            "--terrain",
            "terrains/flat.toml",
            "--duration",
            "1",
            "--no-record",
        ])
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&held.stderr);
    assert_eq!(held.status.code(), Some(2), "{said}");
    assert!(
        said.contains("cannot reach its standing foot position")
            && said.contains("redundant_legs = \"driven\""),
        "{said}"
    );
    let robot = driven("hex18_tarsus", &dir);
    let json = dir.join("folded.json");
    let csv = dir.join("folded.csv");
    let mut cmd = hexsim();
    cmd.args(["run", "--robot"])
        .arg(&robot)
        .args(["--gait", gait])
        .args(["--terrain", "terrains/flat.toml", "--duration", "10"])
        .args(["--no-record", "--metrics"])
        .arg(&json)
        .arg("--trajectory")
        .arg(&csv);
    let metrics = metrics_of(cmd, &json, "folded");
    let forward = metrics["forward_distance"].as_f64().unwrap();
    println!("folded tarsus: {forward:.3} m of 0.8 m nominal");
    assert!(forward >= 0.9 * 0.8, "{forward:.3} m of 0.8 m");
    assert_eq!(metrics["clamped_ik_steps"], 0);
    // the tarsus joints turn in the walk
    let mut reader = csv::Reader::from_path(&csv).unwrap();
    let headers = reader.headers().unwrap().clone();
    let columns: Vec<usize> = headers
        .iter()
        .enumerate()
        .filter(|(_, h)| h.contains("tarsus") && h.ends_with("_angle"))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(columns.len(), 6, "{headers:?}");
    let bent = reader
        .records()
        .map(|r| r.unwrap())
        .flat_map(|r| {
            columns
                .iter()
                .map(move |&i| r[i].parse::<f64>().unwrap().abs())
        })
        .fold(0.0f64, f64::max);
    println!("the tarsus bends up to {:.1}°", bent.to_degrees());
    assert!(bent > 20f64.to_radians(), "tarsus bent at most {bent} rad");
}

/// Feet on massless links hung by revolute ankles fold into their tibias (the ankle held at zero,
/// with a warning): the robot is then hex18, and walks bit for bit as hex18 does. So does a
/// ball-joint foot written as two revolute joints (roll, pitch) between massless links with the
/// sphere on a massless frame below them (Lynxmotion's LSS hexapod's feet; issue 40): before, its
/// roll link, not a leaf, was refused as a moving link without mass.
#[test]
fn passive_massless_feet_fold_into_their_legs() {
    let dir = scratch("any_hexapod_passive");
    let reference = walk(&bare_hex18(&dir), &dir, "hex18");
    for (file, warned, joint) in [
        (
            "tests/data/robots/hex18_passive_feet.urdf",
            "6 revolute joints carry a massless link",
            "lf_ankle_joint",
        ),
        (
            "tests/data/robots/hex18_ball_feet.urdf",
            "12 revolute joints carry a massless link",
            "lf_ankle_pitch_joint",
        ),
    ] {
        let text = report(file);
        assert!(
            text.contains(warned) && text.contains(joint) && text.contains("18 joints, 6 legs"),
            "{text}"
        );
        let metrics = walk(Path::new(file), &dir, "passive");
        for key in [
            "forward_distance",
            "sideways_distance",
            "heading_change_deg",
            "servo_energy",
        ] {
            assert_eq!(metrics[key], reference[key], "{file}: {key}");
        }
    }
}
