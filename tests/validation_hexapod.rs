//! Validation cases V11–V15 of docs/validation.md: the hexapod hex18.

mod common;
use common::*;
use hexsim::contact::ContactModel;
use hexsim::gait::VelocityCommand;
use hexsim::gait::{Gait, GaitController, GaitSpec};
use hexsim::robot::{self, RobotModel};
use hexsim::sim::{
    Articulation, Attitude, Hexapod, HexapodSample, HexapodSettings, Placement, Walker,
};
use hexsim::terrain::{self, HeightGrid};
use std::sync::Arc;

fn hex18() -> Arc<RobotModel> {
    Arc::new(robot::load(&project_file("robots/hex18.urdf")).unwrap())
}

/// The built-in tripod on hex18: its robot file's stance (V11's 0.10 m) and V12's stride and step.
fn tripod() -> Gait {
    let spec = GaitSpec::from_file(&project_file("gaits/tripod.toml")).unwrap();
    hexsim::gait::fit(&hex18(), &spec).unwrap().gait
}

fn settings(articulation: Articulation) -> HexapodSettings {
    HexapodSettings {
        articulation,
        ..Default::default()
    }
}

fn standing(
    model: &Arc<RobotModel>,
    ground: HeightGrid,
    placement: Placement,
    articulation: Articulation,
) -> (Hexapod, GaitController) {
    standing_on(
        model,
        ground,
        placement,
        articulation,
        ContactModel::default(),
    )
}

/// [`standing`] with a contact model of its own.
fn standing_on(
    model: &Arc<RobotModel>,
    ground: HeightGrid,
    placement: Placement,
    articulation: Articulation,
    contact: ContactModel,
) -> (Hexapod, GaitController) {
    let controller = GaitController::new(model, tripod()).unwrap();
    let pose: Vec<f64> = standing_pose(model, &controller);
    let hexapod = Hexapod::new(
        model.clone(),
        Arc::new(ground),
        contact,
        settings(articulation),
        placement,
        &pose,
    );
    (hexapod, controller)
}

/// hex18 standing at the origin of flat ground.
fn standing_on_flat_ground(model: &Arc<RobotModel>, articulation: Articulation) -> Hexapod {
    let ground = terrain::flat([4.0, 4.0], [0.0, 0.0], 0.0).unwrap();
    let place = Placement {
        x: 0.0,
        y: 0.0,
        yaw: 0.0,
        ..Default::default()
    };
    standing(model, ground, place, articulation).0
}

/// The standing pose as per-joint angles.
fn standing_pose(model: &RobotModel, controller: &GaitController) -> Vec<f64> {
    model.pose_from_legs(&controller.standing_angles())
}

fn run(hexapod: &mut Hexapod, seconds: f64) -> Vec<HexapodSample> {
    (0..(seconds / DT).round() as usize)
        .map(|_| hexapod.step())
        .collect()
}

#[test]
fn hex18_loads_as_the_reference_robot() {
    let model = hex18();
    assert!(
        (model.total_mass() - 2.52).abs() < 1e-9,
        "mass {}",
        model.total_mass()
    );
    assert_eq!(model.legs.len(), 6);
    assert_eq!(model.joints.len(), 18);
    let names: Vec<&str> = model.legs.iter().map(|l| l.name).collect();
    assert_eq!(names, ["lf", "lm", "lr", "rf", "rm", "rr"]);
    assert_eq!(model.links[model.legs[0].foot_link].name, "lf_tibia");
}

fn v11_standing_load_equals_weight(articulation: Articulation) {
    let model = hex18();
    let ground = terrain::flat([4.0, 4.0], [0.0, 0.0], 0.0).unwrap();
    let (mut hexapod, _) = standing(
        &model,
        ground,
        Placement {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        articulation,
    );
    let samples = run(&mut hexapod, 3.0);
    let last = samples.last().unwrap();
    let height = last.body.translation.z;
    let forces: Vec<f64> = last
        .foot_contacts
        .iter()
        .map(|c| c.map_or(0.0, |c| c.normal_force))
        .collect();
    // average the vertical load over the last 0.5 s (the contact springs ring slightly)
    let tail = &samples[samples.len() - 500..];
    let load: f64 = tail
        .iter()
        .map(|s| {
            s.foot_contacts
                .iter()
                .map(|c| c.map_or(0.0, |c| c.force.z))
                .sum::<f64>()
        })
        .sum::<f64>()
        / tail.len() as f64;
    println!(
        "V11: body height {height:.4} m, foot normal forces {forces:.3?} N, mean vertical load {load:.4} N"
    );
    assert!(
        (height - 0.10).abs() <= 0.01,
        "V11: body height {height:.4} m, expected 0.10 ± 0.01"
    );
    // loaded: each foot carries a real share of the weight (an even share is 4.12 N), not a
    // foot resting on the ground with a newton's fraction while the robot stands on the others
    let weight = model.total_mass() * G;
    assert!(
        forces.iter().all(|&f| f > 0.25 * weight / 6.0),
        "V11: not all feet loaded (each at least a quarter of an even share): {forces:?}"
    );
    assert!(
        (load - weight).abs() <= 0.01 * weight,
        "V11: load {load:.4} N, expected {weight:.2} N ± 1 %"
    );
}

/// A walker with the gait's nominal forward speed, standing for `settle` seconds first.
fn walker(
    model: Arc<RobotModel>,
    ground: HeightGrid,
    placement: Placement,
    gait: Gait,
    settle: f64,
    articulation: Articulation,
) -> Walker {
    let controller = GaitController::new(&model, gait).unwrap();
    walker_with(model, ground, placement, controller, settle, articulation)
}

/// hex18 with the tripod on `ground`, set down level at (x, 0) heading +x, settling 1 s, on the
/// multibody.
fn hex18_from(ground: HeightGrid, x: f64) -> Walker {
    let place = Placement {
        x,
        ..Default::default()
    };
    walker(
        hex18(),
        ground,
        place,
        tripod(),
        1.0,
        Articulation::Multibody,
    )
}

/// [`walker`] with a controller of its own.
fn walker_with(
    model: Arc<RobotModel>,
    ground: HeightGrid,
    placement: Placement,
    controller: GaitController,
    settle: f64,
    articulation: Articulation,
) -> Walker {
    walker_on(
        model,
        ground,
        placement,
        controller,
        settle,
        settings(articulation),
    )
}

/// [`walker_with`] with settings of its own.
fn walker_on(
    model: Arc<RobotModel>,
    ground: HeightGrid,
    placement: Placement,
    controller: GaitController,
    settle: f64,
    settings: HexapodSettings,
) -> Walker {
    let command = VelocityCommand {
        forward: controller.gait().nominal_speed(),
        ..Default::default()
    };
    let pose = standing_pose(&model, &controller);
    let hexapod = Hexapod::new(
        model,
        Arc::new(ground),
        ContactModel::default(),
        settings,
        placement,
        &pose,
    );
    Walker::new(hexapod, controller, command, settle)
}

/// Rolling feet (gait::controller's doc): the body walks at the commanded speed over feet that
/// roll as the tibias turn. Planned as if each sphere's centre were its contact, the feet scrub,
/// and the body rides on them 3.5 % faster than commanded.
#[test]
fn rolling_feet_walk_at_the_commanded_speed() {
    let gait = v12_gait();
    let command = gait.nominal_speed();
    // from 2 s into the walk (the stride ramps up over the first period) to 12 s
    let speed = |rolling: bool| {
        let ground = terrain::flat([20.0, 20.0], [0.0, 0.0], 0.0).unwrap();
        let placement = Placement {
            x: -5.0,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        };
        let model = hex18();
        let controller = GaitController::new(&model, gait.clone())
            .unwrap()
            .with_rolling_feet(rolling);
        let mut walker = walker_with(
            model,
            ground,
            placement,
            controller,
            1.0,
            Articulation::Multibody,
        );
        let at = |s: f64| ((1.0 + s) / DT).round() as usize;
        let samples: Vec<HexapodSample> = (0..=at(12.0)).map(|_| walker.step().robot).collect();
        (samples[at(12.0)].body.translation.x - samples[at(2.0)].body.translation.x) / 10.0
    };
    let (rolling, planned) = (speed(true), speed(false));
    let off = |v: f64| v / command - 1.0;
    println!(
        "commanded {command:.4} m/s: rolling feet {rolling:.5} m/s ({:+.2} %), planned as the contact {planned:.5} m/s ({:+.2} %)",
        100.0 * off(rolling),
        100.0 * off(planned)
    );
    assert!(
        off(rolling).abs() < 0.01,
        "rolling feet walk {rolling:.5} m/s, commanded {command:.4}"
    );
    assert!(off(rolling).abs() < 0.5 * off(planned).abs());
}

/// Walks `seconds` after 1 s of settling; returns the samples from the gait's start.
fn walk(
    ground: HeightGrid,
    placement: Placement,
    gait: Gait,
    seconds: f64,
    articulation: Articulation,
) -> Vec<HexapodSample> {
    let mut walker = walker(hex18(), ground, placement, gait, 1.0, articulation);
    let total = ((1.0 + seconds) / DT).round() as usize;
    let samples: Vec<HexapodSample> = (0..total).map(|_| walker.step().robot).collect();
    samples[(1.0 / DT) as usize - 1..].to_vec()
}

/// V12's gait, as docs/validation.md states it: the tripod with period 1 s, duty 0.5, stride
/// 0.06 m and step height 0.03 m (hex18's robot file and the tripod give exactly that).
fn v12_gait() -> Gait {
    let gait = tripod();
    assert_eq!(
        (
            gait.period,
            gait.duty_factor,
            gait.stride_length,
            gait.step_height
        ),
        (1.0, 0.5, 0.06, 0.03),
        "the fitted tripod is not V12's"
    );
    gait
}

fn v12_tripod_walks_on_flat_ground(articulation: Articulation) {
    let ground = terrain::flat([20.0, 20.0], [0.0, 0.0], 0.0).unwrap();
    let gait = v12_gait();
    let seconds = 20.0;
    // stride / (duty · period) · t, and each leg's stances over the walk
    let nominal = gait.nominal_speed() * seconds;
    let stances = seconds / gait.period;
    let samples = walk(
        ground,
        Placement {
            x: -5.0,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        gait.clone(),
        seconds,
        articulation,
    );
    let (start, end) = (samples.first().unwrap(), samples.last().unwrap());
    let moved = end.body.translation - start.body.translation;
    let heading = (end.roll_pitch_yaw().2 - start.roll_pitch_yaw().2).to_degrees();
    println!(
        "V12: forward {:.4} m, sideways {:.4} m, heading change {heading:.3}°",
        moved.x, moved.y
    );
    assert!(
        moved.x >= 0.9 * nominal,
        "V12: walked {:.3} m, expected ≥ 90 % of {nominal:.3} m",
        moved.x
    );
    assert!(
        moved.y.abs() < 0.05 * moved.x,
        "V12: drifted {:.3} m sideways",
        moved.y
    );
    assert!(heading.abs() < 5.0, "V12: heading changed {heading:.2}°");
    // feet hold in stance: what each slides over its stances, per stance, against the stride
    for leg in 0..6 {
        let slid: f64 = samples
            .iter()
            .filter_map(|s| s.foot_contacts[leg].map(|c| c.slip.length() * DT))
            .sum();
        let per_stance = slid / stances;
        println!(
            "V12: leg {leg} slides {:.2} mm per stance",
            per_stance * 1e3
        );
        assert!(
            per_stance < 0.05 * gait.stride_length,
            "leg {leg} slides {:.2} mm per stance, over 5 % of the {:.0} mm stride",
            per_stance * 1e3,
            gait.stride_length * 1e3
        );
    }
}

fn v13_tripod_walks_on_the_natural_terrain(articulation: Articulation) {
    let ground = terrain::load(&project_file("terrains/natural_matlab.toml")).unwrap();
    let gait = v12_gait();
    let seconds = 20.0;
    let nominal = gait.nominal_speed() * seconds;
    let samples = walk(
        ground,
        Placement {
            x: -1.25,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        gait,
        seconds,
        articulation,
    );
    let (start, end) = (samples.first().unwrap(), samples.last().unwrap());
    let forward = end.body.translation.x - start.body.translation.x;
    let tilt = samples
        .iter()
        .map(|s| {
            let (roll, pitch, _) = s.roll_pitch_yaw();
            roll.abs().max(pitch.abs()).to_degrees()
        })
        .fold(0.0, f64::max);
    let deepest = samples
        .iter()
        .flat_map(|s| s.foot_contacts.iter().flatten().map(|c| c.penetration))
        .fold(0.0, f64::max);
    println!(
        "V13: forward {forward:.4} m, max roll/pitch {tilt:.2}°, deepest foot {:.3} mm",
        deepest * 1e3
    );
    assert!(
        forward >= 0.7 * nominal,
        "V13: walked {forward:.3} m, expected ≥ 70 % of {nominal:.3} m"
    );
    assert!(tilt < 25.0, "V13: tilted {tilt:.1}°");
    assert!(deepest <= 0.005, "V13: a foot sank {:.2} mm", deepest * 1e3);
}

fn v14_stands_on_a_15_degree_slope(articulation: Articulation) {
    let moved = creep_on_a_15_degree_slope(articulation, ContactModel::default());
    println!("V14: body moved {:.4} mm in 10 s on 15°", moved * 1e3);
    assert!(moved < 0.005, "V14: the body moved {:.3} mm", moved * 1e3);
}

/// How far hex18's body moves in 10 s standing on a 15° slope (after 1 s to land), m.
fn creep_on_a_15_degree_slope(articulation: Articulation, contact: ContactModel) -> f64 {
    let model = hex18();
    let ground = terrain::slope([4.0, 4.0], [0.0, 0.0], 15f64.to_radians(), 0.0).unwrap();
    let (mut hexapod, _) = standing_on(
        &model,
        ground,
        Placement {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        articulation,
        contact,
    );
    // let it land, then measure 10 s
    let landing = run(&mut hexapod, 1.0);
    let start = landing.last().unwrap().body.translation;
    let samples = run(&mut hexapod, 10.0);
    samples
        .iter()
        .map(|s| (s.body.translation - start).length())
        .fold(0.0, f64::max)
}

/// V14 does not rest on the stick force's drift recovery: with it off (each friction law as its
/// equation) the robot still stands on the 15° slope (measured: 0.052 mm in 10 s on the
/// multibody, 0.85 mm on impulse joints; with the default 0.5: 0.029 mm and 0.63 mm).
#[test]
fn v14_holds_without_drift_recovery() {
    for articulation in [Articulation::Multibody, Articulation::Impulse] {
        let off = ContactModel {
            drift_recovery: 0.0,
            ..ContactModel::default()
        };
        let moved = creep_on_a_15_degree_slope(articulation, off);
        println!(
            "V14 without drift recovery, {articulation:?}: {:.4} mm in 10 s",
            moved * 1e3
        );
        assert!(moved < 0.005, "V14: the body moved {:.3} mm", moved * 1e3);
    }
}

/// V21: how far hex18's body moves in 10 s standing on a 30° slope (μs = 0.9) after 1 s to land,
/// m: the walker standing (its settle) with the load feed-forward, set down parallel to the slope
/// (`Attitude::Ground`: every foot touches at once) and standing so or, `levelled`, following the
/// terrain as far as the legs reach (`GaitController::levelling`: on 30° it levels 11° of the
/// slope's 30°).
fn creep_on_a_30_degree_slope(articulation: Articulation, levelled: bool) -> f64 {
    creep_on_a_30_degree_slope_with(
        HexapodSettings {
            articulation,
            ..Default::default()
        },
        levelled,
        0.0,
    )
}

/// [`creep_on_a_30_degree_slope`] with settings of its own, the body heading `yaw` (rad) from
/// straight up the slope.
fn creep_on_a_30_degree_slope_with(settings: HexapodSettings, levelled: bool, yaw: f64) -> f64 {
    let model = hex18();
    let ground = terrain::slope([4.0, 4.0], [0.0, 0.0], 30f64.to_radians(), 0.0).unwrap();
    let place = Placement {
        attitude: Attitude::Ground,
        yaw,
        ..Default::default()
    };
    // standing all the while: the gait would start after 60 s
    let controller = GaitController::new(&model, tripod()).unwrap();
    let mut walker = walker_on(model, ground, place, controller, 60.0, settings);
    walker.terrain_following = levelled;
    let landing: Vec<HexapodSample> = (0..1000).map(|_| walker.step().robot).collect();
    let start = landing.last().unwrap().body.translation;
    (0..10_000)
        .map(|_| (walker.step().robot.body.translation - start).length())
        .fold(0.0, f64::max)
}

/// Set down on the ground (`Attitude::Ground`), hex18 on a 30° slope (heading 40° across it)
/// stands with its body parallel to the slope and every foot on it at once: the feet's gaps all
/// within 1.1 mm (the placement's 1 mm clearance) and the body's up axis the slope's normal;
/// set down level, the uphill feet touch and the downhill ones hang 0.2 m and more.
#[test]
fn a_robot_set_down_on_a_slope_stands_on_all_its_feet() {
    let angle = 30f64.to_radians();
    let ground = terrain::slope([4.0, 4.0], [0.0, 0.0], angle, 0.0).unwrap();
    let normal = glam::DVec3::new(-angle.sin(), 0.0, angle.cos());
    let model = hex18();
    let controller = GaitController::new(&model, tripod()).unwrap();
    let pose = standing_pose(&model, &controller);
    let gaps = |attitude: Attitude| {
        let hexapod = Hexapod::new(
            model.clone(),
            Arc::new(ground.clone()),
            ContactModel::default(),
            settings(Articulation::Multibody),
            Placement {
                yaw: 40f64.to_radians(),
                attitude,
                ..Default::default()
            },
            &pose,
        );
        let s = hexapod.sample();
        let gaps: Vec<f64> = model
            .legs
            .iter()
            .zip(&s.foot_positions)
            // the vertical gap to a plane times cos(angle) is the gap along its normal
            .map(|(leg, p)| (p.z - ground.height(p.x, p.y)) * angle.cos() - leg.foot.radius)
            .collect();
        (gaps, s.body.matrix3.z_axis)
    };
    let (on_ground, up) = gaps(Attitude::Ground);
    println!("set down on the ground: foot gaps {on_ground:?} m, up {up}");
    assert!(
        on_ground.iter().all(|g| (0.0..1.1e-3).contains(g)),
        "{on_ground:?}"
    );
    assert!(up.abs_diff_eq(normal, 1e-6), "{up}");
    let (level, _) = gaps(Attitude::Level);
    assert!(level.iter().any(|&g| g > 0.2), "{level:?}");
}

fn v21_stands_on_a_30_degree_slope(articulation: Articulation, levelled: bool) {
    let moved = creep_on_a_30_degree_slope(articulation, levelled);
    println!(
        "V21 ({articulation:?}, {}): body moved {:.4} mm in 10 s on 30°",
        if levelled { "levelled" } else { "parallel" },
        moved * 1e3
    );
    assert!(moved < 0.005, "V21: the body moved {:.3} mm", moved * 1e3);
}

#[test]
fn v21_multibody_parallel_to_a_30_degree_slope() {
    v21_stands_on_a_30_degree_slope(Articulation::Multibody, false);
}

#[test]
fn v21_multibody_levelled_on_a_30_degree_slope() {
    v21_stands_on_a_30_degree_slope(Articulation::Multibody, true);
}

/// Set down level, the robot used to fall 0.26 m onto its rear feet and land sliding at 0.8 m/s;
/// the impulse joints' feet, which do not share their stopping forces as the multibody's do,
/// slid 589 mm (levelled: 1500 mm) before they held. Set down on the ground it stands.
#[test]
fn v21_impulse_parallel_to_a_30_degree_slope() {
    v21_stands_on_a_30_degree_slope(Articulation::Impulse, false);
}

/// Levelled on impulse joints it holds on their default 5 solver sweeps. On 3, their default
/// before rapier patches 0014–0015 made 5 cheaper than 3 had been, it slid 2.39 m in 10 s: not
/// the friction but a lightly loaded foot falling into a period-2 oscillation with the joints,
/// its velocity reversing every step (±0.1 m/s along the ground, ±0.03 m/s normal, its load 1.1
/// and 5.7 N in turn) while the body stood, so it slid, and the levelled stance's downhill feet,
/// which carry 0.8–0.87 of their load in friction (μk = 0.8), broke away after it. Parallel to
/// the slope they carry 0.73 at most and held on 3 too.
#[test]
fn v21_impulse_levelled_on_a_30_degree_slope() {
    v21_stands_on_a_30_degree_slope(Articulation::Impulse, true);
}

/// V21 levelled on impulse joints holds at every heading on the slope. Measured, the body's
/// largest displacement in 10 s at headings 0°, 45°, …, 315° from straight up the slope (mm): 5
/// sweeps, the default, 0.11–0.37; 4 sweeps hold all but facing up and down the slope (0°: 103
/// mm, 180°: 230 mm; the others 0.08–0.14 mm); 3 sweeps slide 1.10–2.39 m at every heading.
#[test]
fn v21_impulse_levelled_holds_at_every_heading() {
    let settings = HexapodSettings {
        articulation: Articulation::Impulse,
        ..Default::default()
    };
    let moved: Vec<f64> = (0..8)
        .map(|k| {
            let yaw = (45.0 * k as f64).to_radians();
            creep_on_a_30_degree_slope_with(settings, true, yaw) * 1e3
        })
        .collect();
    println!("V21 impulse, levelled, headings 0°, 45°, …: body moved {moved:.3?} mm");
    assert!(moved.iter().all(|&m| m < 5.0), "{moved:.3?} mm");
}

/// Set down level on a 25° slope and following the terrain, the robot first stands as it was set
/// down and leaves for the levelled stance at a landing's pace: its first targets are the blind
/// settle's (within a landing's step), and no target moves 0.05 rad in a step. Taken at once,
/// the ground moved hex18's first targets 0.55 rad from the pose it was set down
/// in (WORMS's by 0.5 rad on the ladder's stairs, throwing its body at 3.8 m/s).
#[test]
fn a_perceptive_settle_leaves_the_pose_set_down_at_a_landings_pace() {
    let first_targets = |following: bool| {
        let ground = terrain::slope([14.0, 4.0], [0.0, 0.0], 25f64.to_radians(), 0.0).unwrap();
        let mut walker = hex18_from(ground, -4.0);
        walker.terrain_following = following;
        let samples: Vec<Vec<f64>> = (0..300)
            .map(|_| walker.step().robot.joint_targets)
            .collect();
        samples
    };
    let (blind, following) = (first_targets(false), first_targets(true));
    let apart = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let first = apart(&blind[0], &following[0]);
    let steepest = following
        .windows(2)
        .map(|w| apart(&w[0], &w[1]))
        .fold(0.0, f64::max);
    let travelled = apart(&following[0], following.last().unwrap());
    println!(
        "first targets {first:.4} rad from the blind settle's; at most {steepest:.4} rad a step; {travelled:.3} rad in 0.3 s"
    );
    assert!(
        first < 0.01,
        "first targets {first} rad from the pose set down"
    );
    assert!(steepest < 0.05, "a target moved {steepest} rad in a step");
    assert!(
        travelled > 0.05,
        "never left the pose set down: {travelled} rad"
    );
}

/// Up and down a 25° slope (μs = 0.9), blind and following the terrain, 20 s: the stance holds
/// its ground — forward at least V13's 70 % of nominal and no more than nominal (sliding down
/// would add to it), no foot sliding 0.1 m (the third-party robots' bar). Measured: up 2.092 m
/// blind, 2.108 m following (0.085 / 0.091 m worst slip); down 2.136 / 2.155 m (0.029 /
/// 0.019 m). Before the feed-forward took gravity's direction and the levelling its reach, up
/// 1.767 m blind (0.271 m slip) and −1.019 m following — it slid back — and down 3.058 m
/// following (1.546 m slip). Multibody: on impulse joints the level start's fall onto the slope
/// lands sliding (see V21).
#[test]
fn walks_up_and_down_a_25_degree_slope() {
    let gait = tripod();
    let nominal = gait.nominal_speed() * 20.0;
    for (ascent, way) in [(0.0, "up"), (std::f64::consts::PI, "down")] {
        for following in [false, true] {
            let ground =
                terrain::slope([14.0, 4.0], [0.0, 0.0], 25f64.to_radians(), ascent).unwrap();
            let mut walker = hex18_from(ground, -4.0);
            walker.terrain_following = following;
            let samples: Vec<HexapodSample> = (0..21_000).map(|_| walker.step().robot).collect();
            let forward =
                samples.last().unwrap().body.translation.x - samples[999].body.translation.x;
            let mut slid = [0.0f64; 6];
            for s in &samples[1000..] {
                for (k, c) in s.foot_contacts.iter().enumerate() {
                    if let Some(c) = c.filter(|c| c.normal_force > 0.0) {
                        slid[k] += c.slip.length() * DT;
                    }
                }
            }
            let worst = slid.iter().copied().fold(0.0, f64::max);
            println!(
                "25° {way}, following {following}: forward {forward:.3} m of {nominal:.2}, worst slip {worst:.3} m"
            );
            assert!(
                (0.7 * nominal..=nominal).contains(&forward),
                "25° {way}, following {following}: forward {forward:.3} m"
            );
            assert!(
                worst < 0.1,
                "25° {way}, following {following}: slid {worst:.3} m"
            );
        }
    }
}

/// What a walk over rough ground did: the body's rise, where it ended (x), the largest change
/// of any joint's gait target from one step to the next (rad; the servo's target adds the load
/// feed-forward, which steps as a foot lands), the deepest foot (m), the body's steepest
/// nose-up pitch (degrees) and the worst foot's slip in contact (∫|v_t| dt, as the metrics'
/// `foot_slip`) over the distance the body travelled (its `slip_share`).
struct RoughWalk {
    rise: f64,
    end_x: f64,
    target_step: f64,
    deepest: f64,
    pitch: f64,
    slip_share: f64,
}

/// hex18 walked `seconds` (after a 1 s settle) over `ground` from x = `from`, blind or reactive
/// or perceptive.
fn walk_over(
    ground: HeightGrid,
    from: f64,
    seconds: f64,
    reactive: bool,
    following: bool,
) -> RoughWalk {
    let mut walker = hex18_from(ground, from);
    walker.reactive = reactive;
    walker.terrain_following = following;
    let mut targets = vec![];
    let samples: Vec<HexapodSample> = (0..((1.0 + seconds) / DT).round() as usize)
        .map(|_| {
            let step = walker.step();
            targets.extend(step.gait.map(|g| g.joint_angles));
            step.robot
        })
        .collect();
    let walking = &samples[(1.0 / DT) as usize - 1..];
    let target_step = targets
        .windows(2)
        .flat_map(|w| (0..18).map(move |i| (w[1][i / 3][i % 3] - w[0][i / 3][i % 3]).abs()))
        .fold(0.0, f64::max);
    let pitch = walking
        .iter()
        .map(|s| s.body.matrix3.x_axis.z.asin().to_degrees())
        .fold(f64::NEG_INFINITY, f64::max);
    let deepest = walking
        .iter()
        .flat_map(|s| s.foot_contacts.iter().flatten().map(|c| c.penetration))
        .fold(0.0, f64::max);
    let end = samples.last().unwrap().body.translation;
    let mut slip = [0.0f64; 6];
    for s in walking {
        for (k, c) in s.foot_contacts.iter().enumerate() {
            slip[k] += c.map_or(0.0, |c| c.slip.length() * DT);
        }
    }
    let travelled = (end - walking[0].body.translation).truncate().length();
    RoughWalk {
        slip_share: slip.iter().copied().fold(0.0, f64::max) / travelled,
        rise: end.z - walking[0].body.translation.z,
        end_x: end.x,
        target_step,
        deepest,
        pitch,
    }
}

/// Stairs of `rise` per 30 cm tread, the first riser at x = 0.3 m.
fn stairs(rise: f64) -> HeightGrid {
    terrain::steps([8.0, 2.0], [1.5, 0.0], 0.3, 0.3, rise, 0.01).unwrap()
}

/// Issue #39: hex18 blind (the reactive gait, as the ladder walks blind) climbs 6 cm risers and
/// descends them — two of each in 12 s from 0.2 m before the first — where the rigid tripod
/// stalls against the first riser. Measured: up +0.202 m to x 1.29 m (rigid: +0.027 m, its
/// front feet up the riser and its body not); down −0.244 m to x 1.47 m; feet 1.8 mm deep.
/// Down, its feet hold the treads: the worst slid 4.2 % of the distance (the walk's flag is at
/// 10 %; before a touched-down foot moved with the ground and a blocked swing held its ground
/// and the lift was remembered, `gait::reactive`, such descents slid 12–15 % on the ladder).
/// Up, the worst foot still slides 17.8 %, mostly up the risers' faces as its swing lifts it.
#[test]
fn blind_hex18_climbs_and_descends_6_cm_risers() {
    let up = walk_over(stairs(0.06), 0.1, 12.0, true, false);
    let rigid = walk_over(stairs(0.06), 0.1, 12.0, false, false);
    let down = walk_over(stairs(-0.06), 0.1, 12.0, true, false);
    println!(
        "6 cm risers blind: up {:+.3} m to x {:.2} m (rigid {:+.3} m); down {:+.3} m to x {:.2} m; deepest foot {:.1}, {:.1} mm; worst foot slid {:.1} %, {:.1} % of the distance",
        up.rise,
        up.end_x,
        rigid.rise,
        down.rise,
        down.end_x,
        up.deepest * 1e3,
        down.deepest * 1e3,
        up.slip_share * 100.0,
        down.slip_share * 100.0
    );
    assert!(up.rise > 0.10, "climbed {:.3} m: not two risers", up.rise);
    assert!(
        rigid.rise < 0.05,
        "the rigid tripod climbed {:.3} m",
        rigid.rise
    );
    assert!(
        down.rise < -0.10,
        "descended {:.3} m: not two risers",
        down.rise
    );
    assert!(up.deepest.max(down.deepest) < 0.005);
    assert!(
        down.slip_share < 0.10,
        "down, a foot slid {:.1} % of the distance",
        down.slip_share * 100.0
    );
}

/// Issue #39: hex18 perceptive (`follow_terrain`) climbs 8 cm risers: the swings planned over
/// the risers, the footholds off their edges, the body pitched with the flight where its legs
/// cannot level it. Measured: +0.223 m to x 0.98 m in 12 s, pitched up to 29.6°, feet 2.8 mm
/// deep (before: stalled at the first 8 cm riser). Since each face of a tread and its riser is
/// a contact of its own (a foot against the riser has friction on it), the climb stops at the
/// first: +0.104 m to x 0.54 m; with the faces' springs summed into one contact it climbs
/// +0.183 m, but a foot in a 2 cm trench then diverges (`validation_whole_body`). With legs
/// that give way (`gait::compliance`): +0.130 m to x 0.69 m, pitched up to 20.0°, feet 2.9 mm
/// deep — the ladder's 1.5 m over three 8 cm risers it crosses in 25 s, not two risers in 12 s.
/// With the Coriolis forces explicit (rapier patch 0013, `docs/physics.md`): +0.190 m to x 0.83
/// m, pitched up to 23.6°, feet 3.8 mm deep — two risers, as asked. Since the body's reference
/// moves at the landing speed under every foot (`sim::walker`'s `BodyReference`): +0.308 m to
/// x 1.42 m, pitched up to 17.0°, feet 1.1 mm deep (just before: +0.291 m, 1.37 m, 17.1°,
/// 1.6 mm).
#[test]
fn perceptive_hex18_climbs_8_cm_risers() {
    let up = walk_over(stairs(0.08), 0.1, 12.0, false, true);
    println!(
        "8 cm risers perceptive: up {:+.3} m to x {:.2} m, pitched up to {:.1}°; largest target step {:.3} rad; deepest foot {:.1} mm",
        up.rise,
        up.end_x,
        up.pitch,
        up.target_step,
        up.deepest * 1e3
    );
    assert!(up.rise > 0.14, "climbed {:.3} m: not two risers", up.rise);
    assert!(up.pitch > 5.0, "pitched {:.1}°", up.pitch);
    assert!(up.deepest < 0.005);
}

/// Issue #39: a perceptive swing's target never jumps across an edge. On stepping stones (15 cm
/// stones, 4 cm pits 10 cm deep) a tibia target once jumped 1.85 rad in one step and its foot
/// landed at 17 m/s, sinking 11.7 mm; now every joint target moves at most a few times the
/// nominal swing's joint speed (gait::slew). Measured: 0.0101 rad a step at most, the deepest
/// foot 3.3 mm.
#[test]
fn perceptive_targets_do_not_jump_across_edges() {
    let stones =
        terrain::stepping_stones([6.0, 6.0], [0.0, 0.0], 0.15, 0.04, 0.1, 1.0, 0.01).unwrap();
    let walk = walk_over(stones, 0.0, 10.0, false, true);
    println!(
        "stones 4 cm perceptive: to x {:.2} m; largest target step {:.4} rad; deepest foot {:.1} mm",
        walk.end_x,
        walk.target_step,
        walk.deepest * 1e3
    );
    assert!(
        walk.target_step < 0.05,
        "a target jumped {:.3} rad",
        walk.target_step
    );
}

/// The same walk's deepest foot: 3.3 mm with the faces of a pit's corner summed into one
/// contact, 5.8 mm with a contact per face (feet landing against a stone's side and the pit's
/// floor at once, each face damped on its own); 5.9 mm with legs that give way (a landing, not
/// a press: `gait::compliance` bounds what a leg presses, not how fast a foot lands); 4.79 mm
/// with the Coriolis forces explicit, one chaotic walk at the bar's edge; 1.9 mm after the
/// footholds kept out of pits and the stance targets bounded, and 1.5 mm since the body's
/// reference moves at the landing speed (`sim::walker`'s `BodyReference`).
#[test]
fn perceptive_feet_on_stones_stay_within_5_mm() {
    let stones =
        terrain::stepping_stones([6.0, 6.0], [0.0, 0.0], 0.15, 0.04, 0.1, 1.0, 0.01).unwrap();
    let walk = walk_over(stones, 0.0, 10.0, false, true);
    println!(
        "stones 4 cm perceptive: deepest foot {:.2} mm",
        walk.deepest * 1e3
    );
    assert!(
        walk.deepest < 0.005,
        "a foot sank {:.1} mm",
        walk.deepest * 1e3
    );
}

/// On a 35° slope the robot, placed with its lowest foot 2 mm lower than touching, touches in
/// its very first step: the contact forces then must already be finite and bounded (the
/// multibody's contact mobility needs the mass matrix before rapier's first step).
fn touches_down_in_the_first_step_on_a_steep_slope(articulation: Articulation) {
    let model = hex18();
    let ground = terrain::slope([4.0, 4.0], [0.0, 0.0], 35f64.to_radians(), 0.0).unwrap();
    let controller = GaitController::new(&model, tripod()).unwrap();
    let mut hexapod = Hexapod::dropped(
        model.clone(),
        Arc::new(ground),
        ContactModel::default(),
        settings(articulation),
        Placement::default(),
        &standing_pose(&model, &controller),
        -0.002,
    );
    let first = hexapod.step();
    let touching: Vec<_> = first.foot_contacts.iter().flatten().collect();
    assert!(!touching.is_empty(), "no foot touches in the first step");
    let weight = model.total_mass() * G;
    for c in touching {
        assert!(c.force.is_finite(), "{c:?}");
        assert!(c.force.length() < 10.0 * weight, "{c:?}");
    }
    let samples = run(&mut hexapod, 0.5);
    assert!(samples.iter().all(|s| s.body.translation.is_finite()));
}

fn v15_same_scenario_same_result_bit_for_bit(articulation: Articulation) {
    let ground = || terrain::load(&project_file("terrains/natural_matlab.toml")).unwrap();
    let a = walk(
        ground(),
        Placement {
            x: -1.25,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        tripod(),
        3.0,
        articulation,
    );
    let b = walk(
        ground(),
        Placement {
            x: -1.25,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        tripod(),
        3.0,
        articulation,
    );
    assert_eq!(a, b, "V15: two identical runs differ");
    println!("V15: {} samples identical", a.len());
}

/// V15 as a user meets it: a scenario with a seed, run twice by two processes, writes the same
/// trajectory and metrics byte for byte (the generated terrain, not a height file), and another
/// seed another walk.
#[test]
fn v15_a_seeded_run_repeats_byte_for_byte_in_another_process() {
    let dir = scratch("v15");
    let run = |seed: &str, name: &str| {
        let (csv, json) = (
            dir.join(format!("{name}.csv")),
            dir.join(format!("{name}.json")),
        );
        let mut cmd = hexsim();
        cmd.args([
            "run",
            "--terrain",
            "natural",
            "--duration",
            "2",
            "--no-record",
        ])
        .args(["--seed", seed, "--trajectory"])
        .arg(&csv)
        .arg("--metrics")
        .arg(&json);
        let metrics = metrics_of(cmd, &json, &format!("V15, seed {seed}"));
        // the metrics' timing fields aside (they name the run, not its result)
        let mut metrics = metrics.as_object().unwrap().clone();
        metrics.remove("metadata");
        (std::fs::read(&csv).unwrap(), metrics)
    };
    let (a, b, other) = (run("7", "a"), run("7", "b"), run("8", "c"));
    assert!(
        a.0 == b.0,
        "V15: the trajectories of two runs with seed 7 differ"
    );
    assert_eq!(a.1, b.1, "V15: the metrics of two runs with seed 7 differ");
    assert!(
        a.0 != other.0,
        "seed 8 walked the same as seed 7: the seed is not read"
    );
}

#[test]
fn ik_round_trips_within_a_tenth_of_a_millimetre() {
    let model = hex18();
    let controller = GaitController::new(&model, tripod()).unwrap();
    let standing = controller.standing_angles();
    let mut rng = hexsim::terrain::MatlabRand::new(42);
    for (leg, chain) in controller.chains().iter().enumerate() {
        for _ in 0..200 {
            // a reachable target: forward kinematics of angles around the standing pose
            let q: [f64; 3] =
                std::array::from_fn(|k| standing[leg][k] + 0.8 * (rng.next_f64() - 0.5));
            let target = chain.foot_position(chain.clamp(q));
            let answer = chain.solve(target, standing[leg]);
            let reached = chain.foot_position(answer.angles);
            assert!(
                (reached - target).length() < 1e-4,
                "leg {leg}: missed {target} by {:.3e} m",
                (reached - target).length()
            );
        }
    }
}

#[test]
fn feet_touch_the_ground_when_the_gait_says_stance() {
    // the tripod's schedule, checked against where the simulated feet actually bear load
    let model = hex18();
    let spec = tripod();
    let ground = terrain::flat([20.0, 20.0], [0.0, 0.0], 0.0).unwrap();
    let mut walker = walker(
        model,
        ground,
        Placement {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        spec.clone(),
        0.5,
        Articulation::Multibody,
    );
    let (mut agree, mut total) = (0, 0);
    for _ in 0..5500 {
        let t = walker.gait_time(); // the time the step's targets are computed for
        let s = walker.step();
        let Some(gait) = s.gait else { continue };
        if t < 2.0 * spec.period {
            continue; // after the start-up ramp
        }
        for (k, phase) in gait.phases.iter().enumerate() {
            // the schedule from the gait file, independently of the controller
            let cycle = (t / spec.period - spec.offsets[k]).rem_euclid(1.0);
            assert_eq!(
                phase.is_stance(),
                cycle < spec.duty_factor,
                "leg {k} at t = {t}"
            );
            total += 1;
            agree += usize::from(
                phase.is_stance() == s.robot.foot_contacts[k].is_some_and(|c| c.normal_force > 0.5),
            );
        }
    }
    let fraction = agree as f64 / total as f64;
    println!(
        "feet loaded as scheduled {:.1} % of the time",
        100.0 * fraction
    );
    assert!(
        fraction > 0.9,
        "feet bear load as the schedule says only {:.1} % of the time",
        100.0 * fraction
    );
}

#[test]
fn a_hexapod_of_another_design_loads_and_walks() {
    let model = Arc::new(robot::load(&project_file("tests/data/round_hexapod.urdf")).unwrap());
    assert_eq!(model.legs.len(), 6);
    assert_eq!(
        model.links.len(),
        19,
        "the IMU and the toes are merged into their links"
    );
    assert!((model.total_mass() - (1.8 + 0.05 + 6.0 * (0.04 + 0.08 + 0.06 + 0.01))).abs() < 1e-9);
    let gait = Gait {
        reach: 0.16,
        stance_height: 0.11,
        ..tripod()
    };
    let speed = gait.nominal_speed();
    let ground = terrain::flat([20.0, 20.0], [0.0, 0.0], 0.0).unwrap();
    let mut walker = walker(
        model,
        ground,
        Placement {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            ..Default::default()
        },
        gait.clone(),
        1.0,
        Articulation::Multibody,
    );
    let samples: Vec<HexapodSample> = (0..6000).map(|_| walker.step().robot).collect();
    let start = samples[999].body.translation;
    let end = samples.last().unwrap().body.translation;
    println!(
        "round hexapod: {:.3} m in 5 s (nominal {:.3})",
        end.x - start.x,
        speed * 5.0
    );
    assert!(
        end.x - start.x > 0.8 * speed * 5.0,
        "walked only {:.3} m",
        end.x - start.x
    );
}

/// Walks `model` on flat ground with the tripod fitted by hand to the round hexapod's size (reach
/// 0.16 m, stance 0.11 m), 1 s standing then 5 s walking: the nominal speed, and the body's
/// position when the gait starts and at the end.
fn walk_round_gait(model: Arc<robot::RobotModel>) -> (f64, glam::DVec3, glam::DVec3) {
    let gait = Gait {
        reach: 0.16,
        stance_height: 0.11,
        ..tripod()
    };
    let speed = gait.nominal_speed();
    let ground = terrain::flat([20.0, 20.0], [0.0, 0.0], 0.0).unwrap();
    let placement = Placement {
        x: 0.0,
        y: 0.0,
        yaw: 0.0,
        ..Default::default()
    };
    let mut walker = walker(model, ground, placement, gait, 1.0, Articulation::Multibody);
    let samples: Vec<HexapodSample> = (0..6000).map(|_| walker.step().robot).collect();
    (
        speed,
        samples[999].body.translation,
        samples.last().unwrap().body.translation,
    )
}

/// A round hexapod whose legs sit at 0°, ±45°, 180° and ±135° (two of them on the URDF's x axis):
/// hexsim walks it along +y, the direction that splits its legs three a side, names the legs by
/// their angle about that direction, and it walks there with the same gait as the round hexapod.
#[test]
fn a_hexapod_whose_legs_straddle_x_walks_along_y() {
    use hexsim::robot::legs::ForwardFrom;
    let model = Arc::new(robot::load(&project_file("tests/data/round_hexapod_y.urdf")).unwrap());
    assert_eq!(model.forward.from, ForwardFrom::Legs);
    assert!((model.forward.yaw.to_degrees() - 90.0).abs() < 1e-9);
    // lf lm lr: the legs at 135°, 180°, 225° in the URDF; rf rm rr: 45°, 0°, 315°
    let hip_link = |leg: &hexsim::robot::Leg| model.joints[leg.joints[0]].name.clone();
    let names: Vec<String> = model.legs.iter().map(hip_link).collect();
    assert_eq!(
        names,
        [
            "leg2_hip_j",
            "leg3_hip_j",
            "leg4_hip_j",
            "leg1_hip_j",
            "leg0_hip_j",
            "leg5_hip_j"
        ]
    );
    // in hexsim's body frame the walking direction is x: lf ahead of lr, left legs at y > 0
    let hip = |k: usize| model.joints[model.legs[k].joints[0]].origin.translation;
    assert!(hip(0).x > hip(2).x && hip(0).y > 0.0 && hip(3).y < 0.0);
    let (speed, start, end) = walk_round_gait(model);
    println!(
        "round hexapod along y: {:.3} m in 5 s (nominal {:.3}), {:.3} m sideways",
        end.x - start.x,
        speed * 5.0,
        end.y - start.y
    );
    assert!(
        end.x - start.x > 0.8 * speed * 5.0,
        "walked only {:.3} m",
        end.x - start.x
    );
    assert!((end.y - start.y).abs() < 0.1 * speed * 5.0);
}

/// The stance is measured from the hips' plane: a robot whose base link origin sits 0.2 m below
/// its hips stands and walks with the same gait as the round hexapod it was made from (measured
/// from the base origin, no stance would fit: its feet would have to be 0.31 m below the hips).
#[test]
fn a_hexapod_whose_base_origin_is_below_its_hips_walks() {
    let model = Arc::new(robot::load(&project_file("tests/data/low_base_hexapod.urdf")).unwrap());
    let (speed, start, end) = walk_round_gait(model);
    // the hips' plane stands 0.11 m above the ground (the feet's centres a radius above it)
    let hips = end.z + 0.2;
    println!(
        "low base: {:.3} m in 5 s (nominal {:.3}); hips {hips:.3} m above the ground",
        end.x - start.x,
        speed * 5.0
    );
    assert!(
        end.x - start.x > 0.8 * speed * 5.0,
        "walked only {:.3} m",
        end.x - start.x
    );
    assert!(
        (hips - 0.11).abs() < 0.01,
        "hips {hips:.3} m above the ground, stance 0.11 m"
    );
}

/// Uphill on 10°: planned for level ground the body pitches with the slope; following the terrain
/// under the feet keeps it level.
#[test]
fn terrain_following_keeps_the_body_level_on_a_slope() {
    let max_pitch = |following: bool| {
        let model = hex18();
        let spec = tripod();
        let ground = terrain::slope([10.0, 4.0], [0.0, 0.0], 10f64.to_radians(), 0.0).unwrap();
        let mut walker = walker(
            model,
            ground,
            Placement {
                x: -1.0,
                y: 0.0,
                yaw: 0.0,
                ..Default::default()
            },
            spec.clone(),
            1.0,
            Articulation::Multibody,
        );
        walker.terrain_following = following;
        let samples: Vec<HexapodSample> = (0..6000).map(|_| walker.step().robot).collect();
        let climbed = samples.last().unwrap().body.translation.x - samples[999].body.translation.x;
        let pitch = samples[2000..]
            .iter()
            .map(|s| s.roll_pitch_yaw().1.abs().to_degrees())
            .fold(0.0, f64::max);
        (pitch, climbed)
    };
    let (tilted, _) = max_pitch(false);
    let (level, climbed) = max_pitch(true);
    println!(
        "10° uphill: max pitch {tilted:.2}° planned flat, {level:.2}° following the terrain ({climbed:.3} m in 5 s)"
    );
    assert!(
        tilted > 5.0,
        "planned for flat ground the body should follow the slope, pitched {tilted:.2}°"
    );
    assert!(
        level < 3.0,
        "following the terrain the body pitched {level:.2}°"
    );
    assert!(climbed > 0.4, "climbed only {climbed:.3} m");
}

/// hex18 without its foot spheres: its feet are found at the tips of its tibias' visual
/// geometry (a rod ending in a 10 mm sphere: the same sphere), and a robot file naming the feet
/// overrides what is found.
#[test]
fn feet_are_found_from_the_geometry_or_named_in_a_robot_file() {
    let dir = scratch("feet");
    let urdf = std::fs::read_to_string(project_file("robots/hex18.urdf")).unwrap();
    let bare: String = urdf
        .lines()
        .filter(|l| !l.contains("<collision name=\"foot\""))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(dir.join("bare.urdf"), &bare).unwrap();
    let reference = hex18();
    let found = robot::load(&dir.join("bare.urdf")).unwrap();
    for (leg, want) in found.legs.iter().zip(&reference.legs) {
        assert_eq!(leg.foot.from, robot::FootFrom::VisualTip);
        let apart = (leg.foot.center - want.foot.center).length();
        assert!(
            apart < 5e-4 && (leg.foot.radius - want.foot.radius).abs() < 5e-4,
            "{}: {:?} against {:?}",
            leg.name,
            leg.foot,
            want.foot
        );
    }
    std::fs::write(
        dir.join("bare.toml"),
        "[feet]\nlinks = [\"lf_tibia\", \"lm_tibia\", \"lr_tibia\", \"rf_tibia\", \"rm_tibia\", \"rr_tibia\"]\noffset = [0.12, 0.0, 0.0]\nradius = 0.01\n",
    )
    .unwrap();
    let model = robot::load(&dir.join("bare.urdf")).unwrap();
    for (leg, want) in model.legs.iter().zip(&reference.legs) {
        assert_eq!(leg.foot.from, robot::FootFrom::RobotFile);
        assert_eq!(
            (leg.foot.center, leg.foot.radius),
            (want.foot.center, want.foot.radius)
        );
        assert_eq!((leg.foot_link, &leg.joints), (want.foot_link, &want.joints));
    }
}

/// V11–V15 in each articulation: `multibody::v11_…` and `impulse::v11_…`.
macro_rules! in_both_articulations {
    ($($case:ident),* $(,)?) => {
        mod multibody {
            use super::*;
            $(#[test] fn $case() { super::$case(Articulation::Multibody) })*
        }
        mod impulse {
            use super::*;
            $(#[test] fn $case() { super::$case(Articulation::Impulse) })*
        }
    };
}

in_both_articulations!(
    v11_standing_load_equals_weight,
    v12_tripod_walks_on_flat_ground,
    v13_tripod_walks_on_the_natural_terrain,
    v14_stands_on_a_15_degree_slope,
    v15_same_scenario_same_result_bit_for_bit,
    servo_torques_hold_the_standing_robot,
    servo_torque_stops_at_the_effort_limit,
    touches_down_in_the_first_step_on_a_steep_slope,
);

/// A target far from the pose asks for k·Δq = 20 N·m/rad · 0.5 rad = 10 N·m, over hex18's 3 N·m
/// effort: the servos must apply exactly the effort (multibody: an explicit torque in place of the
/// spring; impulse joints: the explicit torque, clamped), and never more. The torque reported is
/// the saturation value by construction, so the torque applied is measured from the motion: the
/// robot hangs in the air (no contact), and about each joint's axis, through its anchor, the only
/// moment on the links outboard of it is the joint's torque (the joint's constraint force passes
/// through the anchor and its constraint moments are normal to the axis) and their weight's, so
///   τ = a · Σᵢ [Iᵢ·αᵢ + ωᵢ × Iᵢ·ωᵢ + mᵢ·(rᵢ − p) × (aᵢ − g)]
/// (Newton–Euler over the outboard links i: inertia about the centre of mass, angular velocity
/// and acceleration, centre of mass, its acceleration; p the anchor, a the axis), with velocities
/// and accelerations differenced from the links' poses step by step.
fn servo_torque_stops_at_the_effort_limit(articulation: Articulation) {
    use glam::{DQuat, DVec3};
    let model = hex18();
    let controller = GaitController::new(&model, tripod()).unwrap();
    let pose = standing_pose(&model, &controller);
    let ground = terrain::flat([4.0, 4.0], [0.0, 0.0], 0.0).unwrap();
    // 5 cm up: 0.1 s of free fall, of which 3 ms are measured, at a step short enough that the
    // joints turn little in one (the differences below are exact to O(ω·dt))
    let dt = 1e-4;
    let mut hexapod = Hexapod::dropped(
        model.clone(),
        Arc::new(ground),
        ContactModel::default(),
        HexapodSettings {
            dt,
            ..settings(articulation)
        },
        Placement::default(),
        &pose,
        0.05,
    );
    let targets: Vec<f64> = pose.iter().map(|q| q + 0.5).collect();
    hexapod.set_targets(&targets);
    // frames[n]: the links' poses after n steps; samples[n]: step n → n + 1
    let mut frames = vec![hexapod.link_frames()];
    let mut samples = Vec::new();
    for _ in 0..30 {
        samples.push(hexapod.step());
        frames.push(hexapod.link_frames());
    }
    for s in &samples {
        assert!(
            s.foot_contacts.iter().all(Option::is_none) && s.link_contacts.is_empty(),
            "the robot touched the ground"
        );
    }
    let gravity = DVec3::new(0.0, 0.0, -hexsim::sim::STANDARD_GRAVITY);
    // each link's angular velocity over step n → n + 1 (world), from its rotations
    let omega = |n: usize, link: usize| -> DVec3 {
        let turn = DQuat::from_mat3(&frames[n + 1][link].matrix3)
            * DQuat::from_mat3(&frames[n][link].matrix3).inverse();
        // the short way round (q and −q are one rotation)
        let turn = if turn.w < 0.0 { -turn } else { turn };
        turn.to_scaled_axis() / dt
    };
    let com = |n: usize, link: usize| frames[n][link].transform_point3(model.links[link].com);
    // outboard links of each joint: its child and every link below it
    let outboard = |joint: usize| -> Vec<usize> {
        let mut links = vec![model.joints[joint].child];
        let mut k = 0;
        while k < links.len() {
            let parent = links[k];
            links.extend(
                model
                    .joints
                    .iter()
                    .filter(|j| j.parent == parent)
                    .map(|j| j.child),
            );
            k += 1;
        }
        links
    };
    // the torque of step n → n + 1 shows in the motion differenced about n (n ≥ 1); single
    // steps carry the f32 poses' rounding (±3 % at 0.1 ms), their mean over the 3 ms does not
    let mut worst: f64 = 0.0;
    for (j, joint) in model.joints.iter().enumerate() {
        let mut applied = 0.0;
        for n in 1..samples.len() {
            let anchor = frames[n][joint.parent] * joint.origin;
            let (p, axis) = (anchor.translation, anchor.matrix3 * joint.axis);
            let moment: DVec3 = outboard(j)
                .into_iter()
                .map(|i| {
                    let link = &model.links[i];
                    let rotation = frames[n][i].matrix3;
                    let inertia = rotation * link.inertia * rotation.transpose();
                    let (w0, w1) = (omega(n - 1, i), omega(n, i));
                    let w = 0.5 * (w0 + w1);
                    let alpha = (w1 - w0) / dt;
                    let acceleration =
                        (com(n + 1, i) - 2.0 * com(n, i) + com(n - 1, i)) / dt.powi(2);
                    inertia * alpha
                        + w.cross(inertia * w)
                        + link.mass * (com(n, i) - p).cross(acceleration - gravity)
                })
                .sum();
            applied += moment.dot(axis) / (samples.len() - 1) as f64;
            let reported = samples[n].joint_torques[j];
            assert!(
                (reported - joint.effort).abs() < 1e-3 * joint.effort,
                "{articulation:?} {}: reported {reported:.5} N·m, expected the effort {}",
                joint.name,
                joint.effort
            );
        }
        worst = worst.max((applied - joint.effort).abs() / joint.effort);
        assert!(
            (applied - joint.effort).abs() < 5e-3 * joint.effort,
            "{articulation:?} {}: the motion shows {applied:.4} N·m applied over 3 ms, the \
             effort is {} N·m",
            joint.name,
            joint.effort
        );
    }
    println!(
        "{articulation:?}: applied torque within {:.3} % of the effort",
        worst * 100.0
    );
}

/// The servos' reported torques are the torques applied: standing still, each leg's joints carry
/// its foot's load, so both articulations (one reporting its implicit springs' law, the other the
/// explicit torques it applied) must report the same static torques, and the torques must balance
/// the foot forces' moments about each femur joint.
fn servo_torques_hold_the_standing_robot(articulation: Articulation) {
    let model = hex18();
    let mut hexapod = standing_on_flat_ground(&model, articulation);
    let samples = run(&mut hexapod, 3.0);
    let tail = &samples[samples.len() - 500..];
    let mean = |j: usize| tail.iter().map(|s| s.joint_torques[j]).sum::<f64>() / tail.len() as f64;
    for (k, leg) in model.legs.iter().enumerate() {
        let femur = leg.joints[1];
        let joint = &model.joints[femur];
        // the foot force's moment about the femur axis (statics: the servo holds it)
        let frames = hexapod.link_frames();
        let parent = frames[joint.parent] * joint.origin;
        let axis = parent.matrix3 * joint.axis;
        let moment: f64 = tail
            .iter()
            .map(|s| {
                let c = s.foot_contacts[k].expect("standing feet touch");
                (c.point - parent.translation).cross(c.force).dot(axis)
            })
            .sum::<f64>()
            / tail.len() as f64;
        // and the weight of the femur and tibia links
        let weight: f64 = [joint.child, leg.foot_link]
            .iter()
            .map(|&l| {
                let link = &model.links[l];
                let com = frames[l].transform_point3(link.com);
                let force = glam::DVec3::new(0.0, 0.0, -link.mass * G);
                (com - parent.translation).cross(force).dot(axis)
            })
            .sum();
        let moment = moment + weight;
        let torque = mean(femur);
        println!(
            "{articulation:?} leg {}: femur torque {torque:.4} N·m, foot force moment {moment:.4} N·m",
            leg.name
        );
        assert!(
            (torque + moment).abs() < 0.05 * moment.abs() + 2e-3,
            "leg {}: the servo reports {torque:.4} N·m, the foot's load needs {:.4}",
            leg.name,
            -moment
        );
    }
}

/// The load feed-forward (`Walker::load_feedforward`): a position servo of stiffness k holding
/// torque τ stands τ/k short of its target, so hex18 on the reference servo sags below the gait's
/// stance height, standing (0.9 mm) and more in the tripod's stance (2.2 mm: half the feet carry
/// the weight). With each target moved on by τ/k it stands within 0.5 mm of that height — the
/// ground spring's static sink (0.2 mm) and the feet's friction, which the statics of vertical
/// foot forces leave out, are what remains — and the sag is at least halved.
#[test]
fn the_load_feedforward_holds_the_stance_height() {
    // the hips' mean height over the 0.2 s before `seconds` (1 s standing first)
    let height = |feedforward: bool, seconds: f64| {
        let ground = terrain::flat([4.0, 4.0], [0.0, 0.0], 0.0).unwrap();
        let mut w = hex18_from(ground, 0.0);
        w.load_feedforward = feedforward;
        let samples: Vec<HexapodSample> = (0..(seconds / DT).round() as usize)
            .map(|_| w.step().robot)
            .collect();
        let tail = &samples[samples.len() - (0.2 / DT) as usize..];
        tail.iter().map(|s| s.body_height).sum::<f64>() / tail.len() as f64
    };
    let stance = tripod().stance_height;
    // standing at the end of the settle; the first half of a tripod's stance, 1.25 s into the walk
    for (what, seconds) in [("standing", 1.0), ("in the tripod's stance", 2.25)] {
        let (held, sagged) = (
            height(true, seconds) - stance,
            height(false, seconds) - stance,
        );
        println!(
            "{what}: {:+.3} mm with, {:+.3} mm without",
            held * 1e3,
            sagged * 1e3
        );
        assert!(
            held.abs() < 0.5e-3 && held.abs() < 0.5 * sagged.abs(),
            "{what}: {:+.3} mm off the stance height with the feed-forward, {:+.3} mm without",
            held * 1e3,
            sagged * 1e3
        );
    }
}
