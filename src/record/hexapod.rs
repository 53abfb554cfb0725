//! A walk's outputs: its rerun recording and its trajectory's columns (its metrics:
//! `crate::metrics`).

use super::background::Background;
use super::blueprint::{History, Layout, View};
use super::camera::{self, FollowCamera};
use super::links::LinkTree;
use super::rerun::Recording;
use super::table::RowOf;
use super::{Observer, Scene};
use crate::robot::{LEG_NAMES, RobotModel};
use crate::sim::{WalkSample, Walker};
use crate::terrain::HeightGrid;
use anyhow::Result;
use glam::{DAffine3, DVec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Records the robot (links with their URDF shapes), its foot forces, the feet's stance trails,
/// the body's path, the footfall diagram and time series, with a camera that follows the body.
pub struct HexapodRecorder {
    recording: Recording,
    every: u64,
    /// The links' entities.
    links: LinkTree,
    /// Whether links can drift from their joints (impulse joints): then each link's full pose
    /// relative to its joint frame is logged, not only the rotation.
    joints_drift: bool,
    /// Metres of drawn arrow per newton: a foot carrying its share of the weight gets an arrow
    /// as long as its leg in the starting stance (measured at the first sample).
    force_scale: Option<f64>,
    camera: FollowCamera,
    /// Samples between frames of the 3D scene (links, camera, forces, trails): the scene is drawn
    /// at up to [`SCENE_RATE`], the plots and the footfall diagram at every sample.
    scene_every: u64,
    /// The body position last added to the path.
    path_end: Option<[f32; 3]>,
    /// The footfall lanes' last logged states.
    footfall: [Option<&'static str>; 6],
    /// The entities a sample logs to, parsed once (a path given as text is parsed at every log).
    entities: Entities,
    /// A leg's plotted values, written over for each.
    values: Vec<f64>,
}

/// The entities of [`HexapodRecorder::observe_with`]'s logs.
struct Entities {
    body_path: rerun::EntityPath,
    camera: rerun::EntityPath,
    foot_forces: rerun::EntityPath,
    link_forces: rerun::EntityPath,
    height: rerun::EntityPath,
    attitude: rerun::EntityPath,
    forward_speed: rerun::EntityPath,
    normal_force: rerun::EntityPath,
    slip_speed: rerun::EntityPath,
    /// Per leg: its footfall lane, its stance trail, its joints' angle and torque plots.
    legs: Vec<[rerun::EntityPath; 4]>,
}

impl Entities {
    fn new(model: &RobotModel) -> Self {
        Entities {
            body_path: "world/body_path".into(),
            camera: "world/camera".into(),
            foot_forces: "world/foot_forces".into(),
            link_forces: "world/link_forces".into(),
            height: "plots/body/height_above_ground".into(),
            attitude: "plots/body/attitude_deg".into(),
            forward_speed: "plots/body/forward_speed".into(),
            normal_force: "plots/feet/normal_force".into(),
            slip_speed: "plots/feet/slip_speed".into(),
            legs: model
                .legs
                .iter()
                .map(|leg| {
                    [
                        format!("footfall/{}", leg.name).into(),
                        format!("world/feet/{}/trail", leg.name).into(),
                        format!("plots/joints/{}/angle", leg.name).into(),
                        format!("plots/joints/{}/torque", leg.name).into(),
                    ]
                })
                .collect(),
        }
    }
}

/// Samples between points of the body's path (at the default 50 Hz: 10 points a second).
const PATH_EVERY: u64 = 5;

/// Frames a second of the 3D scene at most: a film's rate, smooth in playback. Its 19 link poses
/// are most of a sample's bytes; at the 50 Hz default this halves them, and keeps a walk under
/// 6 MB a minute (5.1 MB with the scene at 50 Hz, plus 1 MB of terrain, robot and layout).
const SCENE_RATE: f64 = 25.0;

/// Seconds of history shown for the feet's stance trails.
const TRAIL_SECONDS: f64 = 3.0;

/// The footfall diagram's states, one lane per leg (an entity `footfall/{leg}`, so the viewer
/// heads its row with the leg's name; two lanes as a leg's instances were headed `footfall/lf[]`,
/// and as entities of their own took twelve rows, more than the view holds): the foot on the
/// ground as scheduled (white), in the air while scheduled down (blue: a late touchdown or an
/// early lift-off), on the ground while scheduled to swing (orange: a late lift-off, a stumble),
/// and in the air as scheduled (a gap).
const FOOTFALL_STATES: [(&str, [u8; 3]); 4] = [
    ("stance", [235, 235, 235]),
    ("scheduled, in the air", [60, 130, 200]),
    ("down, scheduled to swing", [240, 140, 40]),
    ("swing", [0, 0, 0]),
];

/// The footfall state of a foot on the ground (`down`) or not, scheduled in stance or not.
fn footfall_state(down: bool, scheduled: bool) -> &'static str {
    let k = match (down, scheduled) {
        (true, true) => 0,
        (false, true) => 1,
        (true, false) => 2,
        (false, false) => 3,
    };
    FOOTFALL_STATES[k].0
}

/// The viewer's default layout for a walk: the robot in 3D above its footfall diagram, beside tabs
/// of time series (body; feet; each leg's joints).
fn layout(model: &RobotModel) -> Layout {
    let mut scene = View::spatial_3d("robot", "world")
        .through_camera("world/camera")
        .with_history("world/body_path", History::Whole);
    for leg in &model.legs {
        scene = scene.with_history(
            &format!("world/feet/{}/trail", leg.name),
            History::Last(TRAIL_SECONDS),
        );
    }
    let mut tabs = vec![
        Layout::plots(
            "body",
            &[
                "plots/body/height_above_ground",
                "plots/body/attitude_deg",
                "plots/body/forward_speed",
            ],
        ),
        Layout::plots(
            "feet",
            &["plots/feet/normal_force", "plots/feet/slip_speed"],
        ),
    ];
    for leg in &model.legs {
        let angle = format!("plots/joints/{}/angle", leg.name);
        let torque = format!("plots/joints/{}/torque", leg.name);
        tabs.push(Layout::plots(leg.name, &[&angle, &torque]));
    }
    Layout::horizontal(
        vec![
            scene.into(),
            Layout::vertical(
                vec![
                    View::state_timeline(
                        "footfall: stance (white), airborne in stance (blue), down in swing (orange)",
                        "footfall",
                    )
                    .into(),
                    Layout::tabs(tabs),
                ],
                vec![0.5, 0.5],
            ),
        ],
        vec![0.55, 0.45],
    )
}

impl HexapodRecorder {
    /// Creates the recording at `path` with its layout, the terrain, the robot's shapes and the
    /// plots' series names; `every` is the steps between samples; `joints_drift` for an
    /// articulation whose links are not held to their joints exactly (impulse joints).
    pub fn create(
        path: &Path,
        name: String,
        dt: f64,
        terrain: &HeightGrid,
        model: &RobotModel,
        every: u64,
        joints_drift: bool,
    ) -> Result<Self> {
        let recording = Recording::create(path, name, dt, &layout(model))?;
        recording.log_terrain("world/terrain", terrain)?;
        let rec = recording.stream();
        let links = LinkTree::log(rec, model, "world/robot")?;
        recording.name_series("plots/body/attitude_deg", &["roll", "pitch", "yaw"])?;
        recording.name_series("plots/feet/normal_force", &LEG_NAMES)?;
        recording.name_series("plots/feet/slip_speed", &LEG_NAMES)?;
        for leg in &model.legs {
            let names: Vec<String> = leg
                .joints
                .iter()
                .map(|&j| model.joints[j].name.clone())
                .collect();
            let mut series = names.clone();
            series.extend(names.iter().map(|n| format!("{n} target")));
            let refs: Vec<&str> = series.iter().map(String::as_str).collect();
            recording.name_series(&format!("plots/joints/{}/angle", leg.name), &refs)?;
            let refs: Vec<&str> = names.iter().map(String::as_str).collect();
            recording.name_series(&format!("plots/joints/{}/torque", leg.name), &refs)?;
            // a classic footfall (Hildebrand) diagram: a bar while the foot is down, a gap while
            // it swings, coloured where the foot is not where the gait schedules it
            rec.log_static(
                format!("footfall/{}", leg.name),
                &rerun::StateConfiguration::new()
                    .with_values(FOOTFALL_STATES.map(|(state, _)| state))
                    // a blank label: the states are named once, in the view's title, not in
                    // every bar (an empty label shows the state's name, cut to fit the bar)
                    .with_labels([" "; 4])
                    .with_colors(FOOTFALL_STATES.map(|(_, color)| color))
                    .with_visible([true, true, true, false]),
            )?;
        }
        rec.log_static("world/camera", &camera::pinhole(0.05f32))?;
        // colours and sizes once, static, rather than in every sample's row
        rec.log_static(
            "world/foot_forces",
            &rerun::Arrows3D::update_fields().with_colors([[40, 120, 255]]),
        )?;
        // a link other than a foot on the ground (a shin on a riser, the belly) in orange
        rec.log_static(
            "world/link_forces",
            &rerun::Arrows3D::update_fields().with_colors([[255, 140, 0]]),
        )?;
        rec.log_static(
            "world/body_path",
            &rerun::LineStrips3D::update_fields().with_colors([[240, 200, 60]]),
        )?;
        for leg in &model.legs {
            rec.log_static(
                format!("world/feet/{}/trail", leg.name),
                &rerun::Points3D::update_fields()
                    .with_colors([[230, 60, 60]])
                    .with_radii([0.002f32]),
            )?;
        }
        Ok(HexapodRecorder {
            recording,
            every,
            links,
            joints_drift,
            scene_every: ((1.0 / (SCENE_RATE * dt * every as f64)).round() as u64).max(1),
            force_scale: None,
            camera: FollowCamera::new(robot_radius(model), true),
            path_end: None,
            footfall: [None; 6],
            entities: Entities::new(model),
            values: Vec::new(),
        })
    }

    pub fn finish(self) -> Result<PathBuf> {
        self.recording.finish()
    }

    /// The recorder as an observer of a walk, writing on its own thread (see
    /// [`super::background`]): the loop hands it each `every`-th sample with the links' poses.
    pub fn in_background(
        self,
        model: Arc<RobotModel>,
    ) -> Background<WalkSample, Walker, (WalkSample, Vec<DAffine3>)> {
        Background::spawn(
            self.every,
            |sample: &WalkSample, walker: &Walker| (sample.clone(), walker.hexapod().link_frames()),
            self,
            move |r: &mut HexapodRecorder, (sample, frames): (WalkSample, Vec<DAffine3>)| {
                r.observe_with(&sample, &model, &frames)
            },
            HexapodRecorder::finish,
        )
    }
}

/// The robot's horizontal radius, which sets the follow camera's distance: its farthest foot
/// with each leg stretched out level from its hip along the leg's heading at rest — hex18's zero
/// pose; a URDF whose zero pose hangs the tibias down (a PhantomX) is measured the same way.
pub fn robot_radius(model: &RobotModel) -> f64 {
    let radius = model
        .legs
        .iter()
        .map(|leg| {
            let chain = crate::robot::kinematics::LegChain::new(model, leg);
            let length: f64 = crate::robot::statics::segment_lengths(model, leg)
                .iter()
                .sum();
            let (s, c) = chain.rest_yaw().sin_cos();
            (chain.hip().truncate() + length * glam::DVec2::new(c, s)).length()
        })
        .fold(0.0, f64::max);
    radius.max(0.05)
}

/// The whole robot's centre of mass (world), its links at `link_frames`.
fn centre_of_mass(model: &RobotModel, link_frames: &[DAffine3]) -> DVec3 {
    let (moment, mass) = model.links.iter().zip(link_frames).fold(
        (DVec3::ZERO, 0.0),
        |(moment, mass), (link, frame)| {
            (
                moment + link.mass * frame.transform_point3(link.com),
                mass + link.mass,
            )
        },
    );
    if mass > 0.0 {
        moment / mass
    } else {
        link_frames[0].translation
    }
}

/// Metres of arrow per newton so that a foot carrying a third of the weight (a tripod's stance
/// foot) gets an arrow half as long as the mean hip-to-foot distance in the pose `link_frames`:
/// it stays within the legs' own scale (a sixth of the weight to a whole leg drew a tripod's
/// stance arrows twice a leg's length).
fn force_scale(model: &RobotModel, link_frames: &[DAffine3]) -> f64 {
    let reach: f64 = model
        .legs
        .iter()
        .map(|leg| {
            let hip = &model.joints[leg.joints[0]];
            let hip = (link_frames[hip.parent] * hip.origin).translation;
            let foot = link_frames[leg.foot_link].transform_point3(leg.foot.center);
            (foot - hip).length()
        })
        .sum::<f64>()
        / model.legs.len().max(1) as f64;
    let weight_share = model.total_mass() * crate::sim::STANDARD_GRAVITY / 3.0;
    0.5 * reach.max(0.01) / weight_share.max(1e-9)
}

impl HexapodRecorder {
    /// Logs a sample (one of every `every` steps); `link_frames` are the world poses of the
    /// model's links.
    pub fn observe_with(
        &mut self,
        s: &WalkSample,
        model: &RobotModel,
        link_frames: &[DAffine3],
    ) -> Result<()> {
        let sample = self.recording.set_step(s.robot.step);
        if sample.is_multiple_of(self.scene_every) {
            self.log_scene(s, model, link_frames)?;
        }
        let r = &self.recording;
        let rec = r.stream();
        let (roll, pitch, yaw) = s.robot.roll_pitch_yaw();
        let body = s.robot.body.translation;
        // the path grows by one segment at a time; the view draws them all (History::Whole), so
        // the file grows linearly with the run
        let point = body.as_vec3().to_array();
        if sample.is_multiple_of(PATH_EVERY) {
            if let Some(end) = self.path_end {
                rec.log(
                    self.entities.body_path.clone(),
                    &rerun::LineStrips3D::new([[end, point]]),
                )?;
            }
            self.path_end = Some(point);
        }
        let entities = &self.entities;
        for k in 0..model.legs.len() {
            let contact = s.robot.foot_contacts[k];
            // while settling every foot is scheduled down
            let scheduled = s.gait.as_ref().is_none_or(|g| g.phases[k].is_stance());
            let state = footfall_state(contact.is_some(), scheduled);
            // logged when it changes
            if self.footfall[k].replace(state) != Some(state) {
                rec.log(
                    entities.legs[k][0].clone(),
                    &rerun::StateChange::new().with_state([state]),
                )?;
            }
        }
        r.scalars(entities.height.clone(), &[s.robot.body_height])?;
        r.scalars(
            entities.attitude.clone(),
            &[roll.to_degrees(), pitch.to_degrees(), yaw.to_degrees()],
        )?;
        let forward = s.robot.body.matrix3.x_axis.dot(s.robot.body_velocity);
        r.scalars(entities.forward_speed.clone(), &[forward])?;
        let normal = s
            .robot
            .foot_contacts
            .map(|c| c.map_or(0.0, |c| c.normal_force));
        r.scalars(entities.normal_force.clone(), &normal)?;
        let slip = s
            .robot
            .foot_contacts
            .map(|c| c.map_or(0.0, |c| c.slip.length()));
        r.scalars(entities.slip_speed.clone(), &slip)?;
        // one buffer for every leg's plots, not two allocated a leg
        let values = &mut self.values;
        for (leg, entities) in model.legs.iter().zip(&entities.legs) {
            values.clear();
            values.extend(leg.joints.iter().map(|&j| s.robot.joint_angles[j]));
            values.extend(leg.joints.iter().map(|&j| s.robot.joint_targets[j]));
            r.scalars(entities[2].clone(), values)?;
            values.clear();
            values.extend(leg.joints.iter().map(|&j| s.robot.joint_torques[j]));
            r.scalars(entities[3].clone(), values)?;
        }
        Ok(())
    }

    /// Logs a frame of the 3D scene: the links, the camera, the foot forces and the stance trails.
    fn log_scene(
        &mut self,
        s: &WalkSample,
        model: &RobotModel,
        link_frames: &[DAffine3],
    ) -> Result<()> {
        let rec = self.recording.stream();
        self.links
            .log_frames(rec, model, link_frames, self.joints_drift, false)?;
        let (_, _, yaw) = s.robot.roll_pitch_yaw();
        let frame_dt = self.recording.dt() * (self.every * self.scene_every) as f64;
        // aimed at the robot's centre of mass: a base link's origin can sit anywhere (Kraby's is
        // below its feet, which framed the robot in the top third of the view)
        let view = self
            .camera
            .follow(centre_of_mass(model, link_frames), yaw, frame_dt);
        camera::log_pose(rec, self.entities.camera.clone(), &view)?;
        let force_scale = *self
            .force_scale
            .get_or_insert_with(|| force_scale(model, link_frames));
        let (origins, vectors): (Vec<[f32; 3]>, Vec<[f32; 3]>) = s
            .robot
            .foot_contacts
            .iter()
            .flatten()
            .map(|c| {
                (
                    c.point.as_vec3().to_array(),
                    (c.force * force_scale).as_vec3().to_array(),
                )
            })
            .unzip();
        rec.log(
            self.entities.foot_forces.clone(),
            &rerun::Arrows3D::from_vectors(vectors).with_origins(origins),
        )?;
        let (origins, vectors): (Vec<[f32; 3]>, Vec<[f32; 3]>) = s
            .robot
            .link_contacts
            .iter()
            .map(|c| {
                (
                    c.force.point.as_vec3().to_array(),
                    (c.force.force * force_scale).as_vec3().to_array(),
                )
            })
            .unzip();
        rec.log(
            self.entities.link_forces.clone(),
            &rerun::Arrows3D::from_vectors(vectors).with_origins(origins),
        )?;
        // a dot per frame while a foot is down: a footprint, or a streak where it slips
        for (leg, contact) in self.entities.legs.iter().zip(&s.robot.foot_contacts) {
            if let Some(c) = contact {
                rec.log(
                    leg[1].clone(),
                    &rerun::Points3D::new([c.point.as_vec3().to_array()]),
                )?;
            }
        }
        Ok(())
    }
}

/// A walk as its outputs see it: the recorder's set-up and the trajectory's columns.
pub struct WalkScene {
    pub name: String,
    pub dt: f64,
    pub terrain: Arc<HeightGrid>,
    pub robot: Arc<RobotModel>,
    pub every: u64,
    /// Whether links can drift from their joints (impulse joints): the recording then logs each
    /// link's full pose.
    pub joints_drift: bool,
}

/// A sample's trajectory row: time, body pose and velocity, joint angles, targets and torques,
/// and per foot its force, contact state and slip speed (the columns of [`WalkScene`]).
fn row(s: &WalkSample, row: &mut Vec<f64>) {
    let r = &s.robot;
    let (roll, pitch, yaw) = r.roll_pitch_yaw();
    let p = r.body.translation;
    row.extend([
        r.time,
        p.x,
        p.y,
        p.z,
        roll,
        pitch,
        yaw,
        r.body_velocity.x,
        r.body_velocity.y,
        r.body_velocity.z,
        r.body_angular_velocity.x,
        r.body_angular_velocity.y,
        r.body_angular_velocity.z,
    ]);
    row.extend(&r.joint_angles);
    row.extend(&r.joint_targets);
    row.extend(&r.joint_torques);
    for c in &r.foot_contacts {
        match c {
            Some(c) => row.extend([
                c.force.x,
                c.force.y,
                c.force.z,
                c.normal_force,
                1.0,
                c.slip.length(),
            ]),
            None => row.extend([0.0; 6]),
        }
    }
}

impl Scene for WalkScene {
    type Sample = WalkSample;
    type World = Walker;

    fn recorder(&self, path: &Path) -> Result<Box<dyn Observer<WalkSample, Walker>>> {
        let recorder = HexapodRecorder::create(
            path,
            self.name.clone(),
            self.dt,
            &self.terrain,
            &self.robot,
            self.every,
            self.joints_drift,
        )?;
        Ok(Box::new(recorder.in_background(self.robot.clone())))
    }

    fn columns(&self) -> (Vec<String>, RowOf<WalkSample>) {
        let mut columns: Vec<String> = [
            "time", "x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz", "wx", "wy", "wz",
        ]
        .map(String::from)
        .to_vec();
        // named by leg and role, in the model's joint order
        let joints = super::joint_columns::joint_columns(&self.robot);
        for suffix in ["angle", "target", "torque"] {
            columns.extend(joints.iter().map(|j| format!("{j}_{suffix}")));
        }
        for leg in LEG_NAMES {
            columns.extend(
                ["fx", "fy", "fz", "normal", "contact", "slip"].map(|q| format!("{leg}_{q}")),
            );
        }
        (columns, row)
    }

    fn every(&self) -> u64 {
        self.every
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// hex18's zero pose stretches its legs out level: the follow camera's radius is its farthest
    /// foot in that pose (0.33 m), as it was measured before legs folded otherwise were handled.
    #[test]
    fn hex18s_camera_radius_is_its_farthest_stretched_foot() {
        let model = crate::robot::urdf::from_str(
            include_str!("../../robots/hex18.urdf"),
            Path::new("robots/hex18.urdf"),
        )
        .unwrap();
        let poses = model.link_poses(&vec![0.0; model.joints.len()]);
        let stretched = model
            .legs
            .iter()
            .map(|leg| {
                poses[leg.foot_link]
                    .transform_point3(leg.foot.center)
                    .truncate()
                    .length()
            })
            .fold(0.0, f64::max);
        let radius = robot_radius(&model);
        assert!(
            (radius - stretched).abs() < 1e-9,
            "{radius} against {stretched}"
        );
        assert!((0.3..0.4).contains(&radius), "{radius}");
    }

    /// A tripod's stance foot (a third of the weight) draws an arrow half the mean hip-to-foot
    /// distance; the camera aims at the centre of mass, which for hex18 standing is inside its
    /// body box, not at the base link's origin alone by accident of the URDF.
    #[test]
    fn force_arrows_are_half_a_leg_and_the_camera_aims_at_the_centre_of_mass() {
        let model = crate::scenario::builtin::hex18();
        let pose = crate::gait::fit(&model, &crate::gait::tripod_for_tests())
            .unwrap()
            .standing_pose;
        let frames = model.link_poses(&pose);
        let reach: f64 = model
            .legs
            .iter()
            .map(|leg| {
                let hip = &model.joints[leg.joints[0]];
                let hip = (frames[hip.parent] * hip.origin).translation;
                (frames[leg.foot_link].transform_point3(leg.foot.center) - hip).length()
            })
            .sum::<f64>()
            / 6.0;
        let third = model.total_mass() * crate::sim::STANDARD_GRAVITY / 3.0;
        let arrow = third * force_scale(&model, &frames);
        assert!(
            (arrow - 0.5 * reach).abs() < 1e-12,
            "{arrow} m against {reach} m"
        );
        // the legs are mirror images about the body's x axis: the centre of mass is on it, and
        // between the body's origin and the feet, below the origin (the legs hang lower)
        let com = centre_of_mass(&model, &frames);
        let origin = frames[0].translation;
        assert!((com.y - origin.y).abs() < 1e-9, "{com} against {origin}");
        assert!(
            com.z < origin.z && com.z > origin.z - 0.05,
            "{com} against {origin}"
        );
        let total: f64 = model.links.iter().map(|l| l.mass).sum();
        assert!((total - 2.52).abs() < 1e-9);
    }

    /// Every plot the recorders lay out has a title with its unit, and a legend only where it
    /// draws several series.
    #[test]
    fn plot_titles_carry_units() {
        for entity in [
            "height_above_ground",
            "attitude_deg",
            "forward_speed",
            "normal_force",
            "slip_speed",
            "angle",
            "torque",
            "energy",
            "height",
            "force",
            "penetration_mm",
            "speed",
        ] {
            let (title, _) = Layout::plot_title(entity);
            assert!(
                title.ends_with(')') && title.contains(" ("),
                "{entity}: {title}"
            );
        }
        assert!(!Layout::plot_title("forward_speed").1);
        assert!(Layout::plot_title("normal_force").1);
    }
}
