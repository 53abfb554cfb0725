//! The recordings as the viewer will read them: the layout (blueprint) that opens, the follow
//! camera, the footfall diagram, and a file that grows linearly with the run. What the viewer
//! draws from them is checked by looking (README, "Recordings"); here, what it is given.

mod common;
use common::{hexsim, scratch};
use hexsim::record::rerun::{Contents, read_back};
use std::path::Path;

const LEGS: [&str; 6] = ["lf", "lm", "lr", "rf", "rm", "rr"];

/// Runs `hexsim ARGS --record FILE` and returns what it printed.
fn record(args: &[&str], file: &Path) -> String {
    let out = hexsim()
        .args(args)
        .arg("--record")
        .arg(file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The blueprint entity whose component `component` holds the text `value`.
fn blueprint_with(contents: &Contents, component: &str, value: &str) -> Option<String> {
    contents
        .under(true, "")
        .find(|(_, l)| l.components.contains(component) && l.texts.contains(value))
        .map(|(path, _)| path.to_string())
}

/// The layout every recording must open with: activated (not only a default, which the viewer's
/// saved layout or an early frame overrides), complete before activation, time on `sim_time`, and
/// a 3D view looking through the follow camera.
fn check_layout(contents: &Contents) {
    assert_eq!(contents.activations, [(true, true)], "activate and default");
    assert!(
        !contents.activated_early,
        "activated before it was complete"
    );
    let panel = contents.at(true, "time_panel").expect("a time panel");
    assert!(panel.texts.contains("sim_time"), "{:?}", panel.texts);
    assert!(
        blueprint_with(contents, "ViewBlueprint:class_identifier", "3D").is_some(),
        "no 3D view"
    );
    let eye = blueprint_with(contents, "EyeControls3D:tracking_entity", "world/camera");
    assert!(
        eye.is_some(),
        "the 3D view does not look through the camera"
    );
    let camera = contents.at(false, "world/camera").expect("a camera");
    assert!(camera.components.contains("Pinhole:image_from_camera"));
    assert!(camera.static_rows >= 1 && camera.rows > 10, "{camera:?}");
}

#[test]
fn a_walk_opens_with_its_layout_camera_footfall_diagram_and_trails() {
    let dir = scratch("walk");
    let file = dir.join("walk.rrd");
    let printed = record(&["run", "--duration", "3", "--settle", "0.5"], &file);
    assert!(
        printed.contains(&format!("rerun {}", file.display())),
        "says how to open it: {printed}"
    );
    let contents = read_back(&file).unwrap();
    check_layout(&contents);
    let samples = 175; // 3.5 s at 50 Hz
    let frames = 88; // the 3D scene at 25 Hz
    assert_eq!(contents.at(false, "world/camera").unwrap().rows, frames);
    assert_eq!(
        contents.at(false, "plots/feet/normal_force").unwrap().rows,
        samples
    );
    assert!(
        blueprint_with(&contents, "ViewBlueprint:class_identifier", "StateTimeline").is_some(),
        "no footfall diagram"
    );
    // footfall: one lane per leg, an entity named by the leg (the viewer heads its row
    // `/footfall/lf`, not `/footfall/lf[]`), swing as gaps; logged on change
    for leg in LEGS {
        let lane = contents
            .at(false, &format!("footfall/{leg}"))
            .unwrap_or_else(|| panic!("no footfall lane for {leg}"));
        for state in ["stance", "swing"] {
            assert!(lane.texts.contains(state), "{leg}: {:?}", lane.texts);
        }
        assert!(lane.rows > 4 && lane.rows < samples / 4, "{leg}: {lane:?}");
        // the foot's trail is drawn with 3 s of history, from a point per frame in stance
        let trail = format!("world/feet/{leg}/trail");
        let history = contents.under(true, "view/").find(|(path, l)| {
            path.contains(&format!("overrides/{trail}"))
                && l.components.contains("VisibleTimeRanges:ranges")
        });
        assert!(history.is_some(), "{trail} has no history in the 3D view");
        let points = contents.at(false, &trail).unwrap().rows;
        assert!(points > frames / 3 && points < frames, "{trail}: {points}");
    }
    // the body's path: a segment at a time (10 a second), drawn with its whole history
    let path = contents.at(false, "world/body_path").unwrap();
    assert!((path.rows as i64 - 35).abs() <= 1, "{path:?}");
    assert!(
        contents
            .under(true, "view/")
            .any(|(p, _)| p.contains("overrides/world/body_path")),
        "the path is drawn with its history"
    );
    // the links nest as the kinematic tree: a tibia under its femur under its coxa
    let tibia = contents
        .under(false, "world/robot/")
        .find(|(p, l)| p.ends_with("/lf_tibia") && l.rows == frames);
    let tibia = tibia.expect("lf_tibia moves every frame").0;
    assert!(
        tibia.contains("/lf_coxa/") && tibia.contains("/lf_femur/"),
        "{tibia}"
    );
}

#[test]
fn a_ball_opens_with_its_layout_camera_and_path() {
    let dir = scratch("ball");
    let file = dir.join("ball.rrd");
    record(
        &["ball", "--terrain", "terrains/bell.toml", "--duration", "2"],
        &file,
    );
    let contents = read_back(&file).unwrap();
    check_layout(&contents);
    assert_eq!(contents.at(false, "world/ball").unwrap().rows, 201);
    assert!(contents.at(false, "world/contact_force").is_some());
    assert!(contents.at(false, "plots/energy").unwrap().rows == 201);
    assert!(
        contents
            .under(true, "view/")
            .any(|(p, _)| p.contains("overrides/world/path")),
        "the path is drawn with its history"
    );
}

/// Nothing in a recording is re-logged as the run grows (the body's path once was, whole, every
/// tenth sample: 624 MB for 10 minutes): each further stretch of walking adds the same bytes,
/// and at the default 50 Hz under 6 MB a minute.
#[test]
fn a_walk_recording_grows_linearly_with_the_run() {
    let dir = scratch("size");
    let size = |seconds: u32| {
        let file = dir.join(format!("w{seconds}.rrd"));
        let duration = seconds.to_string();
        record(&["run", "--duration", &duration, "--settle", "0.5"], &file);
        std::fs::metadata(&file).unwrap().len() as f64
    };
    let (a, b, c) = (size(15), size(30), size(45));
    assert!(b <= 2.2 * a, "2× the run, {:.2}× the file", b / a);
    let (first, second) = (b - a, c - b);
    assert!(
        second <= 1.15 * first && second >= first / 1.15,
        "15 s more walking added {first:.0} B, then {second:.0} B"
    );
    let per_minute = (c - a) / 30.0 * 60.0;
    assert!(per_minute < 6e6, "{per_minute:.0} B a minute");
}

/// A URDF's mesh visuals are drawn from the file its `package://` URI names (found in a
/// ROS-style package folder above the URDF), at the URDF's `scale` (a mesh in millimetres).
#[test]
fn mesh_visuals_are_found_by_package_and_drawn_at_their_scale() {
    let dir = scratch("mesh_visuals");
    let package = dir.join("round_description");
    std::fs::create_dir_all(package.join("urdf")).unwrap();
    std::fs::create_dir_all(package.join("meshes")).unwrap();
    std::fs::write(
        package.join("meshes/body.stl"),
        "solid body\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 100 0 0\nvertex 0 100 0\nendloop\nendfacet\nendsolid body\n",
    )
    .unwrap();
    let urdf = std::fs::read_to_string(common::project_file("tests/data/round_hexapod.urdf"))
        .unwrap()
        .replacen(
            r#"<visual><geometry><cylinder radius="0.1" length="0.04"/></geometry></visual>"#,
            r#"<visual><geometry><mesh filename="package://round_description/meshes/body.stl" scale="0.001 0.001 0.001"/></geometry></visual>"#,
            1,
        );
    assert!(urdf.contains("package://round_description"));
    let robot = package.join("urdf/round.urdf");
    std::fs::write(&robot, urdf).unwrap();
    let rrd = dir.join("mesh.rrd");
    let out = record(
        &[
            "run",
            "--robot",
            robot.to_str().unwrap(),
            "--terrain",
            "terrains/flat.toml",
            "--duration",
            "0.2",
            "--settle",
            "0.2",
            // --strict refuses every warning (a step hexsim chooses is a note, not one)
            "--strict",
        ],
        &rrd,
    );
    assert!(!out.contains("warning"), "{out}");
    let contents = read_back(&rrd).unwrap();
    let body = contents
        .at(false, "world/robot/chassis/visual_0")
        .expect("the body's visual");
    assert!(
        body.components.contains("Asset3D:blob"),
        "{:?}",
        body.components
    );
    assert!(
        body.components.contains("Transform3D:scale"),
        "{:?}",
        body.components
    );
}

/// `hexsim robot --record`: a still picture that opens as designed — the robot standing beside
/// the printed report, through a camera, with its feet named as gait files name them, the walking
/// direction and (asked for) each leg's workspace; everything static, no timeline to look for.
#[test]
fn a_robot_standing_is_recorded_beside_its_report() {
    let dir = scratch("recording");
    let file = dir.join("kraby_standing.rrd");
    let stdout = record(
        &[
            "robot",
            "tests/data/third_party/kraby/hexapod.urdf",
            "--workspace",
        ],
        &file,
    );
    let contents = read_back(&file).unwrap();
    assert_eq!(contents.activations, [(true, true)], "activate and default");
    assert!(!contents.activated_early);
    let panel = contents.at(true, "time_panel").expect("a time panel");
    assert!(!panel.texts.contains("sim_time"), "{:?}", panel.texts);
    for class in ["3D", "TextDocument"] {
        assert!(
            blueprint_with(&contents, "ViewBlueprint:class_identifier", class).is_some(),
            "no {class} view"
        );
    }
    assert!(
        blueprint_with(&contents, "EyeControls3D:tracking_entity", "world/camera").is_some(),
        "the 3D view does not look through the camera"
    );
    // the report shown is the one printed (less the line naming the recording)
    let report = contents.at(false, "report").expect("the report");
    let shown = report.texts.iter().next().unwrap();
    let printed = stdout.lines().next().unwrap();
    assert!(shown.contains(printed), "{shown}");
    assert!(shown.contains("walking direction +y"), "{shown}");
    let feet = contents.at(false, "world/feet").expect("the feet");
    assert!(LEGS.iter().all(|l| feet.texts.contains(*l)), "{feet:?}");
    for leg in LEGS {
        let workspace = contents.at(false, &format!("world/workspace/{leg}"));
        assert!(workspace.is_some(), "no workspace for {leg}");
    }
    assert!(contents.at(false, "world/ground").is_some());
    let moving: Vec<&str> = contents
        .under(false, "")
        .filter(|(_, l)| l.rows > 0)
        .map(|(path, _)| path)
        .collect();
    assert!(moving.is_empty(), "not a still picture: {moving:?}");
    // every link is drawn: Kraby's 19 links (its merged servo horns and feet among them)
    let links = contents
        .under(false, "world/robot")
        .filter(|(path, _)| path.ends_with("visual_0"))
        .count();
    assert!(links >= 19, "{links} links drawn");
}

/// `--spawn` where the viewer cannot open fails (exit 2) and says where the recording is, rather
/// than ending 0 after the viewer's error: with no display it does not start the viewer; a viewer
/// that stops at once (here a stand-in `rerun` that exits 1) is reported.
#[cfg(unix)]
#[test]
fn spawn_without_a_display_fails_and_says_so() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("spawn");
    let bin = dir.join("bin");
    std::fs::create_dir(&bin).unwrap();
    let viewer = bin.join("rerun");
    std::fs::write(&viewer, "#!/bin/sh\nexit 1\n").unwrap();
    std::fs::set_permissions(&viewer, std::fs::Permissions::from_mode(0o755)).unwrap();
    let file = dir.join("ball.rrd");
    for (display, expected) in [
        (None, "no display to open the viewer on"),
        (Some(":99"), "the rerun viewer stopped at once"),
    ] {
        let mut cmd = hexsim();
        cmd.args(["ball", "--duration", "0.1", "--spawn", "--record"])
            .arg(&file)
            .env("PATH", &bin)
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("WAYLAND_SOCKET");
        match display {
            Some(d) => cmd.env("DISPLAY", d),
            None => cmd.env_remove("DISPLAY"),
        };
        let out = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(expected) && stderr.contains(&format!("rerun {}", file.display())),
            "{stderr}"
        );
        assert!(file.is_file(), "the recording is written");
    }
}
