//! Validation case V19 of docs/validation.md: every link touches the ground, not only
//! the feet — hex18 dropped on its belly with its legs folded up comes to rest on its underside.

mod common;
use common::*;
use hexsim::contact::ContactModel;
use hexsim::robot::{self, RobotModel};
use hexsim::sim::{Articulation, Hexapod, HexapodSample, HexapodSettings, Placement};
use hexsim::terrain;
use std::sync::Arc;

fn hex18() -> Arc<RobotModel> {
    Arc::new(robot::load(&project_file("robots/hex18.urdf")).unwrap())
}

/// Every leg raised: the femur 60° up, the tibia folded a further 60° up (hex18's positive
/// femur and tibia angles bend a leg down).
fn legs_folded_up(model: &RobotModel) -> Vec<f64> {
    let up = -60f64.to_radians();
    model.pose_from_legs(&[[0.0, up, up]; 6])
}

/// The weight every contact carries together, and the deepest any sank, from a sample.
fn load_and_depth(s: &HexapodSample) -> (f64, f64) {
    let feet = s.foot_contacts.iter().flatten();
    let links = s.link_contacts.iter().map(|c| &c.force);
    feet.chain(links).fold((0.0, 0.0), |(load, depth), c| {
        (load + c.normal_force, f64::max(depth, c.penetration))
    })
}

fn v19_resting_on_the_belly(articulation: Articulation) {
    let model = hex18();
    let pose = legs_folded_up(&model);
    // the legs clear the belly's underside (z = −25 mm in the body frame) by a margin: no foot
    // can touch before the body does
    let poses = model.link_poses(&pose);
    for leg in &model.legs {
        let foot = poses[leg.foot_link].transform_point3(leg.foot.center);
        assert!(foot.z - leg.foot.radius > 0.0, "{}: {foot}", leg.name);
    }
    let ground = terrain::flat([2.0, 2.0], [0.0, 0.0], 0.0).unwrap();
    let mut hexapod = Hexapod::dropped(
        model.clone(),
        Arc::new(ground),
        ContactModel::default(),
        HexapodSettings {
            articulation,
            ..Default::default()
        },
        Placement {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        &pose,
        0.05,
    );
    let samples: Vec<HexapodSample> = (0..3000).map(|_| hexapod.step()).collect();
    let deepest = samples
        .iter()
        .map(|s| load_and_depth(s).1)
        .fold(0.0, f64::max);
    let tail = &samples[samples.len() - 500..];
    let load = tail.iter().map(|s| load_and_depth(s).0).sum::<f64>() / tail.len() as f64;
    let last = samples.last().unwrap();
    let body_links = last.link_contacts.iter().filter(|c| c.link == 0).count();
    let foot_load: f64 = samples[1000..]
        .iter()
        .flat_map(|s| s.foot_contacts.iter().flatten())
        .map(|c| c.normal_force)
        .fold(0.0, f64::max);
    let (roll, pitch, _) = last.roll_pitch_yaw();
    let weight = model.total_mass() * G;
    println!(
        "V19 {articulation:?}: load {load:.4} N against {weight:.4} N, deepest {:.3} mm, \
         {body_links} of the body's spheres down, body centre {:.4} m, roll {:.3}°, pitch \
         {:.3}°, largest foot load after 1 s {foot_load} N",
        deepest * 1e3,
        last.body.translation.z,
        roll.to_degrees(),
        pitch.to_degrees()
    );
    assert!(
        (load - 24.72).abs() <= 0.01 * 24.72,
        "the contacts carry {load} N, the robot weighs 24.72 N"
    );
    assert!(deepest <= 2e-3, "a contact sank {} mm", deepest * 1e3);
    assert_eq!(foot_load, 0.0, "a foot carries load");
    // it rests on the body's underside: the box's half-height above the ground, level, on the
    // spheres of its bottom face
    assert!(
        (last.body.translation.z - 0.025).abs() < 1e-3,
        "{}",
        last.body.translation.z
    );
    assert!(roll.abs() < 1f64.to_radians() && pitch.abs() < 1f64.to_radians());
    // every sphere of the body's bottom face is down (the box lies flat on all of them), not a
    // few corners: those whose lowest point is the body's lowest
    let body = &model.links[0].contacts;
    let lowest = body
        .iter()
        .map(|c| c.center.z - c.radius)
        .fold(f64::INFINITY, f64::min);
    let bottom = body
        .iter()
        .filter(|c| c.center.z - c.radius < lowest + 1e-9)
        .count();
    assert!(bottom >= 4, "the body's bottom face has {bottom} spheres");
    assert_eq!(body_links, bottom, "of the bottom face's {bottom} spheres");
}

#[test]
fn v19_resting_on_the_belly_multibody() {
    v19_resting_on_the_belly(Articulation::Multibody);
}

#[test]
fn v19_resting_on_the_belly_impulse() {
    v19_resting_on_the_belly(Articulation::Impulse);
}

/// The collapse: hex18 on servos too weak to stand (0.3 N·m/rad against the reference's
/// 20) used to end with its body 12.6 cm below the ground, every foot "in contact", and nothing
/// said. It now comes down on its links — its belly, or as measured since kinetic friction
/// resists a reversing slip along the stopping force, its knees (femurs 0.26–0.70 s each) — and
/// stays above the ground, and the run says so (and exits 1: not the walk commanded).
#[test]
fn a_robot_too_weak_to_stand_rests_on_its_links_and_the_run_says_so() {
    let dir = scratch("collapse");
    let metrics = dir.join("m.json");
    let out = hexsim()
        .args([
            "run",
            "--terrain",
            "terrains/flat.toml",
            "--servo-stiffness",
            "0.3",
            "--duration",
            "4",
            "--no-record",
            "--metrics",
        ])
        .arg(&metrics)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // and it is no walk: its feet slide far more than it creeps, and it goes off its course —
    // how it comes down decides which way (measured: turned, and since the body leans as it
    // tilts, drifted sideways)
    assert_eq!(out.status.code(), Some(1), "{stdout}{stderr}");
    assert!(
        stderr.contains("error: not the walk commanded (skated, ")
            && (stderr.contains("turned)") || stderr.contains("drifted sideways)")),
        "{stderr}"
    );
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&metrics).unwrap()).unwrap();
    let touched = m["link_contact_time"].as_object().unwrap();
    let lowest = m["body_height_min"].as_f64().unwrap();
    let deepest = m["max_link_penetration"].as_f64().unwrap();
    println!(
        "collapse: links on the ground {touched:?}, hips at least {lowest} m up, links {deepest} m deep"
    );
    let longest = touched
        .values()
        .filter_map(|t| t.as_f64())
        .fold(0.0, f64::max);
    assert!(longest > 0.1, "{m}");
    // the hips' plane stays above the box's half-height less what the spheres sink
    assert!(lowest > 0.02, "{lowest}");
    assert!(deepest < 5e-3, "{deepest}");
    assert!(
        stdout.contains("links other than the feet touched the ground"),
        "{stdout}"
    );
}

/// A foot in a crack its own width: hex18 walking blind over 2 cm trenches and between stones
/// 2 cm apart (its feet are 2 cm across) drops feet in and gets them wedged. Where each face of
/// the crack was summed into one contact, and kinetic friction acted against the slip a step
/// began with, a wedged foot swung from wall to wall, growing each step, and the runs ended
/// "diverged" at 12.76 s and 11.16 s with a foot 11.7 and 10.2 mm deep. Each face is its own
/// contact now, and friction acts against the velocity a step ends with, never jamming the foot
/// in: the runs finish, no foot or link deeper than 5 mm.
#[test]
fn a_foot_wedged_in_a_crack_its_own_width_stays_in_the_physics() {
    let dir = scratch("crack");
    for (name, source, start) in [
        (
            "gaps",
            "kind = \"gaps\"\nwidth = 0.02\nspacing = 0.4\ndepth = 0.1\nfirst_gap = 0.5\n\
             size = [6.0, 4.0]\ncell = 0.01\n",
            ["-0.5", "0"],
        ),
        (
            "stones",
            "kind = \"stepping_stones\"\nstone = 0.15\ngap = 0.02\ndepth = 0.1\n\
             platform = 1.0\nsize = [6.0, 6.0]\ncell = 0.01\n",
            ["0", "0"],
        ),
    ] {
        let terrain = dir.join(format!("{name}.toml"));
        std::fs::write(&terrain, format!("[source]\n{source}")).unwrap();
        let metrics = dir.join(format!("{name}.json"));
        let out = hexsim()
            .arg("run")
            .arg("--terrain")
            .arg(&terrain)
            .args([
                "--start",
                start[0],
                start[1],
                "--duration",
                "14",
                "--no-record",
            ])
            .arg("--metrics")
            .arg(&metrics)
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        // the blind tripod wedges its feet and drags them (measured: the worst foot slid 1.04 m
        // of 1.19 m on the gaps, 1.08 of 0.87 m on the stones, where it also turned 15°):
        // flagged as skating, exit 1
        assert_eq!(out.status.code(), Some(1), "{name}: {text}");
        assert!(
            text.contains("error: not the walk commanded (skated"),
            "{name}: {text}"
        );
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&metrics).unwrap()).unwrap();
        let foot = m["max_penetration"].as_f64().unwrap();
        let link = m["max_link_penetration"].as_f64().unwrap();
        println!(
            "{name}: deepest foot {:.2} mm, link {:.2} mm",
            foot * 1e3,
            link * 1e3
        );
        assert!(foot < 5e-3 && link < 5e-3, "{name}: {foot} {link}");
    }
}

/// Legs that give way (`gait::compliance`): perceptive on stepping stones 2 cm apart, a foot of
/// hex18 goes into a pit its own width and its leg, stiff, presses it into the walls with
/// 100–300 N (4–12 weights) until it is deeper than its radius: "diverged" at 16.46 s, 10.1 mm.
/// A leg that gives way past 3 weights keeps it out: the run goes on, no foot deeper than 5 mm.
/// That held for one chaotic trajectory, not as a property: from this start and seven 0.4–1.4 mm
/// from it the stiff run diverged twice and the compliant once (12.3 mm), its others 3.4–6.7 mm
/// deep (docs/rough-ground.md, *Legs that give way*); with the Coriolis forces explicit (rapier
/// patch 0013, on since) the stiff run from this start stays at 5.9 mm. Kept as a measurement;
/// a claim about legs that give way needs a press that is not chaotic or many starts.
#[test]
#[ignore = "measured: one chaotic trajectory; explicit Coriolis: stiff 5.9 mm (not diverged), giving way 4.95 mm; over 16 nearby starts stiff diverges 0, giving way misses 5 mm in 7"]
fn a_leg_pressing_into_a_pit_gives_way() {
    let dir = scratch("give-way");
    let terrain = dir.join("stones.toml");
    std::fs::write(
        &terrain,
        "[source]\nkind = \"stepping_stones\"\nstone = 0.15\ngap = 0.02\ndepth = 0.1\n\
         platform = 1.0\nsize = [6.0, 6.0]\ncell = 0.01\n",
    )
    .unwrap();
    let run = |stiff: bool| {
        let metrics = dir.join(format!("stiff-{stiff}.json"));
        let mut command = hexsim();
        command
            .arg("run")
            .arg("--terrain")
            .arg(&terrain)
            .args(["--start", "0", "0", "--duration", "17", "--follow-terrain"])
            .args(["--allow-flags", "--no-record", "--metrics"])
            .arg(&metrics);
        if stiff {
            command.arg("--stiff-legs");
        }
        let out = command.output().unwrap();
        let text = String::from_utf8_lossy(&out.stderr).into_owned();
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&metrics).unwrap()).unwrap();
        (text, m["max_penetration"].as_f64().unwrap())
    };
    let (stiff, stiff_depth) = run(true);
    assert!(stiff.contains("diverged"), "{stiff}");
    assert!(stiff_depth > 0.010, "stiff legs: {stiff_depth}");
    let (compliant, depth) = run(false);
    println!(
        "deepest foot: stiff {:.2} mm, giving way {:.2} mm",
        stiff_depth * 1e3,
        depth * 1e3
    );
    assert!(!compliant.contains("diverged"), "{compliant}");
    assert!(depth < 5e-3, "giving way: {depth}");
}
