//! `hexsim ladder`: a family's levels run blind and perceptive, each run's outcome read from its
//! record, the highest level crossed per family.

mod common;
use common::*;

/// `ladder/<name>.toml` as one scenario: its text before `[expect]` and `[sweep]` (each swept
/// value at the family's own, its first level; its gait the built-in tripod, by name), `header`
/// put first. The crossing's expectations are left out: `hexsim run` would judge them, and these
/// runs are shortened to test other things.
fn one_level(name: &str, header: &str) -> String {
    let family = std::fs::read_to_string(project_file(&format!("ladder/{name}.toml"))).unwrap();
    let end = family.find("[expect]").unwrap();
    assert!(
        end < family.find("[sweep]").unwrap(),
        "{name}: [expect] before [sweep]"
    );
    format!("{header}{}", &family[..end])
}

/// `hexsim run` of [`one_level`]`(family, header)` with each `(from, to)` of `edits` replaced,
/// written to a scratch folder, with `extra` flags, no recording (it would be written in the
/// project's folder) and its walk flags allowed: its metrics, the
/// test failing as `what` if the run does not succeed.
fn run_level(
    family: &str,
    header: &str,
    edits: &[(&str, &str)],
    extra: &[&str],
    what: &str,
) -> serde_json::Value {
    let dir = scratch(&format!("ladder-{family}"));
    let scenario = edits
        .iter()
        .fold(one_level(family, header), |text, (from, to)| {
            text.replace(from, to)
        });
    let file = dir.join(format!("{family}.toml"));
    std::fs::write(&file, scenario).unwrap();
    let json = dir.join("m.json");
    let mut cmd = hexsim();
    cmd.arg("run")
        .arg(&file)
        .args(extra)
        .arg("--no-record")
        .arg("--metrics")
        .arg(&json)
        .arg("--allow-flags");
    metrics_of(cmd, &json, what)
}

/// Runs `hexsim ladder FAMILY [extra] -o OUT -q`, which must exit 0, and returns its standard
/// output and its `ladder.json`.
fn run_ladder(
    family: &std::path::Path,
    extra: &[std::path::PathBuf],
    out_dir: &std::path::Path,
) -> (String, serde_json::Value) {
    let out = hexsim()
        .arg("ladder")
        .arg(family)
        .args(extra)
        .arg("-o")
        .arg(out_dir)
        .arg("-q")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = std::fs::read_to_string(out_dir.join("ladder.json")).unwrap();
    (stdout, serde_json::from_str(&json).unwrap())
}

/// A short ladder on slopes: 5° is walked up, 38° (friction holds to 42°, the gait does not
/// climb it) is not, and the table, the JSON and the batch's records say so.
#[test]
fn a_ladder_reports_the_highest_level_crossed_and_what_stopped_the_robot() {
    let dir = scratch("ladder");
    let family = dir.join("slope.toml");
    std::fs::write(
        &family,
        format!(
            "description = \"up a slope\"\ngait = {:?}\nduration = 6.0\n\
             [terrain.source]\nkind = \"slope\"\nangle_deg = 5.0\nsize = [10.0, 10.0]\n\
             [start]\nx = -1.0\ny = 0.0\n[expect]\nforward_min = 0.3\nmax_body_tilt_deg = 45\n\
             [sweep]\n\"terrain.source.angle_deg\" = [5.0, 38.0]\nfollow_terrain = [false, true]\n",
            project_file("gaits/tripod.toml")
        ),
    )
    .unwrap();
    let out_dir = dir.join("out");
    let (stdout, json) = run_ladder(&family, &[], &out_dir);
    let summary = &json["families"][0];
    assert_eq!(summary["family"], "slope");
    assert_eq!(summary["blind"], 5.0, "{summary}");
    assert_eq!(summary["perceptive"], 5.0, "{summary}");
    let stopped = summary["blind_stopped_by"].as_array().unwrap();
    assert_eq!(stopped[0], 38.0);
    assert_ne!(stopped[1], "crossed");
    let runs = json["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    for run in runs {
        let crossed = run["outcome"] == "crossed";
        assert_eq!(crossed, run["level"] == 5.0, "{run}");
        assert_eq!(crossed, run["forward"].as_f64().unwrap() >= 0.3, "{run}");
    }
    assert!(stdout.contains("| slope |"), "{stdout}");
    assert!(out_dir.join("ladder.md").is_file());
    assert!(out_dir.join("results.jsonl").is_file());
}

/// The ladder's families are built in: from a folder with no `ladder/` (a user's, after `cargo
/// install`), `hexsim ladder rough` runs the built-in family, its gait the built-in tripod, and a
/// name that is neither a file nor a family is refused, naming the families there are. Before,
/// the families were read from `./ladder` only, and anywhere else the ladder stopped with "no
/// such scenario file or folder".
#[test]
fn the_ladder_families_are_built_in() {
    let dir = scratch("ladder-built-in");
    // `hexsim ladder FAMILY -o OUT -q` in the empty folder: its exit code and standard error
    let ladder = |family: &str, out: &str| {
        let run = hexsim()
            .current_dir(&dir)
            .args(["ladder", family, "-o", out, "-q"])
            .output()
            .unwrap();
        (
            run.status.code(),
            String::from_utf8_lossy(&run.stderr).into_owned(),
        )
    };
    let (code, stderr) = ladder("rough", "out");
    assert_eq!(code, Some(0), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/ladder.json")).unwrap())
            .unwrap();
    assert_eq!(json["families"][0]["family"], "rough");
    assert_eq!(json["runs"].as_array().unwrap().len(), 10, "{json}");
    // every link of hex18 touches: nothing to caveat
    assert_eq!(json["caveats"], serde_json::json!([]), "{json}");
    let records = std::fs::read_to_string(dir.join("out/results.jsonl")).unwrap();
    assert!(
        records.contains("\"gaits/tripod.toml (built in)\""),
        "{records}"
    );
    let (code, stderr) = ladder("stair", "out2");
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("stair: no such scenario file or folder, nor a built-in family (gaps, "),
        "{stderr}"
    );
}

/// A robot some of whose links have no collision geometry (elkapod: only its feet touch) gets a
/// caveat under its ladder's table and in its JSON: its levels are those of a robot whose body
/// and legs pass through the terrain.
#[test]
fn a_ladder_says_which_links_do_not_touch() {
    let dir = scratch("ladder-caveat");
    let family = dir.join("flat.toml");
    std::fs::write(
        &family,
        "duration = 1.0\n[terrain.source]\nkind = \"slope\"\nangle_deg = 0.0\nsize = [4.0, 4.0]\n[expect]\nforward_min = 0.02\n[sweep]\n\"terrain.source.angle_deg\" = [0.0, 1.0]\n",
    )
    .unwrap();
    let elkapod = common::project_file(
        "tests/data/third_party/elkapod/elkapod_description/urdf/elkapod.urdf",
    );
    let out = hexsim()
        .arg("ladder")
        .arg(&family)
        .arg("--robot")
        .arg(&elkapod)
        .arg("-o")
        .arg(dir.join("out"))
        .arg("-q")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let caveat = "Caveat: 13 of elkapod's 19 links have no collision geometry hexsim could read";
    assert!(stdout.contains(caveat), "{stdout}");
    let table = std::fs::read_to_string(dir.join("out/ladder.md")).unwrap();
    assert!(table.contains(caveat), "{table}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/ladder.json")).unwrap())
            .unwrap();
    assert_eq!(json["caveats"].as_array().unwrap().len(), 1, "{json}");
}

/// A family that sweeps two difficulties at once is refused, naming the file.
#[test]
fn a_family_of_two_difficulties_is_refused() {
    let dir = scratch("ladder-bad");
    let family = dir.join("two.toml");
    std::fs::write(
        &family,
        "[expect]\nforward_min = 1.0\n[sweep]\n\"terrain.source.angle_deg\" = [5.0, 10.0]\nseed = [1, 2]\n",
    )
    .unwrap();
    let out = hexsim().arg("ladder").arg(&family).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("two.toml") && stderr.contains("one difficulty"),
        "{stderr}"
    );
}

/// Heading hold (`hold_heading`, docs/rough-ground.md): commanded to turn at 15°/s for 4 s and
/// then to walk straight (60° in all, the ramps included), the open-loop tripod on flat ground
/// turns only as far as its feet grip and falls short (measured 56.6°); holding its heading it
/// ends on the heading commanded (59.95°). On flat ground the walk is regular, not chaotic: over
/// the ladder's trenches the open loop turned −55° in one build and −15° in the next.
#[test]
fn a_walk_that_holds_its_heading_turns_as_far_as_commanded() {
    let dir = scratch("heading");
    let heading = |hold: bool| {
        let file = dir.join(format!("turn_{hold}.toml"));
        std::fs::write(
            &file,
            format!(
                "terrain = {:?}\ngait = {:?}\nduration = 8.0\nhold_heading = {hold}\n\
                 [[command]]\nforward = 0.1\nturn_deg_s = 15.0\n\
                 [[command]]\nat = 4.0\nforward = 0.1\nturn_deg_s = 0.0\n",
                project_file("terrains/flat.toml"),
                project_file("gaits/tripod.toml")
            ),
        )
        .unwrap();
        let json = dir.join(format!("turn_{hold}.json"));
        let mut cmd = hexsim();
        cmd.arg("run")
            .arg(&file)
            .args(["--no-record", "--allow-flags", "--metrics"])
            .arg(&json);
        metrics_of(cmd, &json, "turn")["heading_change_deg"]
            .as_f64()
            .unwrap()
    };
    let open_loop = heading(false);
    let held = heading(true);
    assert!(
        (open_loop - 60.0).abs() > 2.0,
        "open loop turned {open_loop:.2}°"
    );
    assert!((held - 60.0).abs() < 0.5, "held, it turned {held:.2}°");
}

/// hexaross stands tall: its centre of mass 0.2 m over its feet, 0.1 m inside its tripods'
/// rear edges on level ground. Walking up 30° with its body parallel to the slope (blind: it
/// follows its feet) or pitched with most of it (perceptive: its legs level 30° only in part),
/// its plumb line fell 0.12 m downhill — behind those edges — and it went over backwards in
/// both modes (hexsim 94a1d54: this ladder's runs ended 4.17 m and 4.35 m down the slope). The
/// lean (`gait::lean`) lowers its body by up to 6.4 cm, its legs' room to fold up (its feet
/// have 3.5 mm to move downhill), and it walks up: forward 2.48 m both ways (blind and perceptive),
/// its body within 31° of level. Since the fit prefers a steady stance (`gait::fit`) it stands
/// 19 mm lower on feet 25 mm farther out (its centre of mass 0.185 m over them, steady to
/// 30.7°), may crouch 7.2 cm, and walks up 2.51 and 2.53 m.
#[test]
fn a_tall_robot_leans_into_a_30_degree_slope_and_walks_up_it() {
    let dir = scratch("ladder-lean");
    let family = dir.join("slope_up.toml");
    let ladder = std::fs::read_to_string(project_file("ladder/slope_up.toml")).unwrap();
    let ladder = ladder.replace("[5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0]", "[30.0]");
    std::fs::write(&family, ladder).unwrap();
    let robot =
        project_file("tests/data/third_party/hexaross/hexapod_description/urdf/hexapod.urdf");
    let (_, json) = run_ladder(&family, &["--robot".into(), robot], &dir.join("out"));
    let runs = json["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2, "blind and perceptive");
    for run in runs {
        assert_eq!(run["level"], 30.0);
        assert_ne!(run["outcome"], "fell", "{run}");
        assert!(run["forward"].as_f64().unwrap() >= 1.5, "{run}");
        assert!(run["max_tilt_deg"].as_f64().unwrap() < 35.0, "{run}");
    }
}

/// hexaross perceptive down the ladder's 10 cm stairs: as its front hips pass the top's edge the
/// ground the legs reach for is planned afresh — the hips' plane tilts, the crouch eases — and
/// the body's reference steps. Its stance feet followed at the landing speed, its swinging feet
/// in full: two landed 4.6–8.1 mm under the top landing (8, 10 and 12 cm risers) and threw the
/// body up at 0.34–0.68 m/s, and at 10 and 12 cm it tumbled down the flight. The reference now
/// moves at the landing speed under every foot (`sim::walker`'s `BodyReference`). Measured to
/// 6.3 s, past the first edge: the late swings' targets at most 0.84 mm under the ground, the
/// body rising at 0.11 m/s at most.
#[test]
fn perceptive_swings_land_on_the_ground_as_the_body_pitches_over_an_edge() {
    use hexsim::gait::LegPhase;
    let dir = scratch("ladder-edge");
    let robot =
        project_file("tests/data/third_party/hexaross/hexapod_description/urdf/hexapod.urdf");
    let file = dir.join("stairs_down.toml");
    std::fs::write(
        &file,
        format!(
            "robot = {:?}\ngait = {:?}\nfollow_terrain = true\nduration = 5.3\n\
             [terrain.source]\nkind = \"steps\"\nstep_height = -0.1\nstep_length = 0.3\n\
             first_step = 0.3\nsize = [6.0, 4.0]\ncell = 0.01\n[start]\nx = -0.5\ny = 0.0\n",
            robot,
            project_file("gaits/tripod.toml")
        ),
    )
    .unwrap();
    let scenario = &hexsim::scenario::load_file(&file).unwrap()[0];
    let model = scenario.robot().unwrap().clone();
    let terrain = scenario.build_terrain().unwrap();
    let mut walk = scenario.start_walk(hexsim::record::Outputs::new()).unwrap();
    let (mut deepest, mut rise) = (0.0f64, 0.0f64);
    while walk.remaining() > 0 {
        walk.advance(1);
        let sample = walk.sample().unwrap();
        rise = rise.max(sample.robot.body_velocity.z);
        let Some(gait) = &sample.gait else { continue };
        for (k, phase) in gait.phases.iter().enumerate() {
            if matches!(phase, LegPhase::Swing(s) if *s > 0.5) {
                let target = sample.robot.body.transform_point3(gait.feet[k]);
                let ground = terrain.height(target.x, target.y) + model.legs[k].foot.radius;
                deepest = deepest.max(ground - target.z);
            }
        }
    }
    assert!(walk.failure().is_none());
    println!(
        "late swings' targets {:.2} mm under the ground at most; body rising {:.2} m/s at most",
        deepest * 1e3,
        rise
    );
    assert!(deepest < 0.002, "a target {:.1} mm under", deepest * 1e3);
    assert!(rise < 0.25, "the body rose at {rise:.2} m/s");
}

/// A 20 mm foot resting on the ground 12 mm from a 1.2 cm box of `ladder/obstacles.toml` at
/// 4 cm (pexod perceptive, 2026-12-04): on the 1 cm grid the box's side is a 50° ramp one cell
/// wide, not a cliff (a wall needs a jump steeper than 60°), and the sphere presses the ramp's
/// top edge 6.0 mm deep. The closest-point search found that edge only where the sphere also
/// pressed the ground (its crease probes at 0.7 r land on the ramp); 0.3 mm higher and 0.1 mm
/// along, floating clear of the ground, its probes at r started beyond the ramp and came back
/// to the ground, and it read the sphere clear. In the walk the force on that foot came and
/// went every step, at dt 0.33 and 0.17 ms alike, and one step's catch carried 108 N (a foot
/// 6.0 mm deep in a run that crossed). A contact's depth must not jump as its sphere moves
/// 0.3 mm; the search now also starts from the sample nearest the centre (the box's corner).
#[test]
fn a_foot_beside_a_low_box_finds_its_edge_wherever_it_stands() {
    let dir = scratch("ladder-ramp");
    let scenario =
        one_level("obstacles", "").replace("height = [0.01, 0.02]", "height = [0.01, 0.04]");
    let file = dir.join("obstacles.toml");
    std::fs::write(&file, scenario).unwrap();
    let terrain = hexsim::scenario::load_file(&file).unwrap()[0]
        .build_terrain()
        .unwrap();
    let depth = |x: f64, y: f64, z: f64| {
        let faces = hexsim::contact::sphere_faces(
            &terrain,
            glam::DVec3::new(x, y, z),
            0.02,
            Default::default(),
        );
        faces.as_slice()[0].penetration.max(0.0)
    };
    let pressing = depth(0.945_745_596, 0.263_386_544, 0.019_395_180);
    let floating = depth(0.945_635_820, 0.263_643_310, 0.019_582_363);
    println!(
        "depth {:.3} mm, 0.3 mm away {:.3} mm",
        pressing * 1e3,
        floating * 1e3
    );
    assert!(pressing > 5e-3, "the edge pressed: {pressing}");
    assert!(
        floating > pressing - 1e-3,
        "the same edge 0.3 mm away: {floating} against {pressing}"
    );
}

/// WORMS (79 kg, feet 56 mm spheres on pads 0.115 m across) settling perceptive over
/// `ladder/stones.toml` at its widest pits, 10 cm: the standing targets took each foot's ground
/// from under its centre alone, 10 cm down in a pit one step and on a stone the next as the
/// body swayed a millimetre, and the legs threw the body about until the run stopped for
/// runaway motion 0.19–0.28 s into the settle (2, 4 and 10 cm pits all did). A foot stands on
/// the ground its sole rests on (`foothold::resting_ground`): the pits' rims.
#[test]
fn a_heavy_robot_settles_over_pits_narrower_than_its_feet() {
    let header = format!(
        "robot = {:?}\nfollow_terrain = true\nreactive_gait = true\n",
        project_file("tests/data/third_party/worms/worms_assets/urdf/hexapod.urdf")
    );
    let m = run_level(
        "stones",
        &header,
        &[
            ("gap = 0.02", "gap = 0.10"),
            ("duration = 25.0", "duration = 0.5"),
        ],
        &[],
        "WORMS settling over 10 cm pits",
    );
    let tilt = m["max_roll_deg"]
        .as_f64()
        .unwrap()
        .max(m["max_pitch_deg"].as_f64().unwrap());
    println!(
        "walked {} s, tilt {tilt:.2}°, deepest foot {:.2} mm",
        m["walk_time"],
        m["max_penetration"].as_f64().unwrap() * 1e3
    );
    assert!(m["complete"].as_bool().unwrap(), "{m}");
    assert!(tilt < 10.0, "tilted {tilt}°");
}

/// harika (0.40 kg, its belly 18 mm above its feet) perceptive at the lip of `ladder/gaps.toml`'s
/// 8 cm trenches: its belly drops into the trench, and the legs, walking on, shove it against
/// the far wall. No leg presses past its cap (its loads run one way), so before the body's
/// contacts counted in the legs' squeeze (`gait::compliance`) the wall held the body with
/// 4 of its weights, 4.79 mm deep (5.32 mm on the ladder's run). Counted, the legs yield
/// once the squeeze passes its cap of 2 weights: the wall can be pressed no deeper than its
/// static sink under those, 2·W/k.
#[test]
fn legs_shoving_the_body_against_a_wall_give_way() {
    let urdf = project_file("tests/data/third_party/harika_hexapod/hexapod/urdf/hexapod.urdf");
    let m = run_level(
        "gaps",
        &format!("robot = {urdf:?}\nfollow_terrain = true\n"),
        &[
            ("width = 0.02", "width = 0.08"),
            ("x = -0.5", "x = 0.3"),
            ("duration = 25.0", "duration = 8.0"),
        ],
        &[],
        "harika at an 8 cm trench",
    );
    let weight = hexsim::robot::load(&urdf).unwrap().total_mass() * 9.80665;
    let k = m["ground"]["stiffness"].as_f64().unwrap();
    let squeezed = 2.0 * weight / k;
    let belly = m["link_contact_time"]["dummy_link"].as_f64().unwrap_or(0.0);
    let deepest = m["max_link_penetration"].as_f64().unwrap();
    println!(
        "belly down {belly:.2} s, deepest link {:.2} mm against {:.2} mm under 2 weights",
        deepest * 1e3,
        squeezed * 1e3
    );
    assert!(belly > 1.0, "the belly touched for {belly} s");
    assert!(
        deepest < squeezed,
        "{deepest} m deep, {squeezed} m under 2 weights"
    );
}

/// The MushroomRL hexapod (2.3 kg), blind over `ladder/stones.toml`'s 4 cm gaps, its feet in
/// the pits and its shins on the stones' edges: a rear leg yielded for 0.3 s (`gait::compliance`)
/// while the gait drew its knee 0.6 rad on, and the release, over 0.1 s alone, swept that back
/// with the foot on a stone, threw the robot up at 0.9 m/s and landed a front foot from the hop
/// 6.73 mm deep (its radius 9.5 mm), the run stalled at 1.25 m. A loaded leg now takes its
/// yield back no faster than its joints at the landing speed: no foot past the 5 mm asked of
/// every ladder run.
#[test]
fn a_yielded_leg_takes_its_load_back_without_a_kick() {
    let header = format!(
        "robot = {:?}\nfollow_terrain = false\nreactive_gait = true\n",
        project_file("tests/data/third_party/mushroom_hexapod/hexapod.urdf")
    );
    let m = run_level(
        "stones",
        &header,
        &[
            ("gap = 0.02", "gap = 0.04"),
            ("duration = 25.0", "duration = 14.9"),
        ],
        &[],
        "MushroomRL over 4 cm stones",
    );
    let foot = m["max_penetration"].as_f64().unwrap();
    let link = m["max_link_penetration"].as_f64().unwrap();
    println!(
        "forward {:.3} m, deepest foot {:.2} mm, link {:.2} mm",
        m["forward_distance"].as_f64().unwrap(),
        foot * 1e3,
        link * 1e3
    );
    assert!(foot.max(link) < 0.005, "{foot} m, links {link} m");
}

/// `hexsim run` of the scenario `text`, written to `dir` as `name`.toml, with its walk flags
/// allowed, whatever its exit: its summary and its metrics.
fn run_scenario(dir: &std::path::Path, name: &str, text: &str) -> (String, serde_json::Value) {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let json = dir.join(format!("{name}.json"));
    let out = hexsim()
        .arg("run")
        .arg(&file)
        .args(["--no-record", "--allow-flags", "--metrics"])
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let metrics = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    (stdout, metrics)
}

/// bullet set down on a plane of `angle_deg`, heading `heading_deg` from +x, at x = `x`, walking
/// 4 s: a scenario's text.
fn bullet_on_a_slope(angle_deg: f64, heading_deg: f64, x: f64, stop_at_fall: bool) -> String {
    format!(
        "robot = {:?}\ngait = {:?}\nduration = 4.0\nstop_at_fall = {stop_at_fall}\n\
         [terrain.source]\nkind = \"slope\"\nangle_deg = {angle_deg:?}\nsize = [10.0, 10.0]\n\
         [start]\nattitude = \"ground\"\nx = {x:?}\ny = 0.0\nheading_deg = {heading_deg:?}\n",
        project_file("tests/data/third_party/bullet_syropod/robot/bullet.urdf"),
        project_file("gaits/tripod.toml")
    )
}

/// A walk whose scenario stops at its fall (`stop_at_fall`, as the ladder's families do) ends on
/// the step its body first tilts past 45° from upright: complete (its result decided, not cut
/// short), the metrics' `fell_at` its last moment and its body's largest tilt just past 45°,
/// where the same walk without the stop tumbles on. bullet (steady to 8.9°: its body 0.41 m up
/// on feet close under it) walking up 20° falls backwards within a second of walking.
#[test]
fn a_walk_that_stops_at_its_fall_ends_on_the_step_it_fell() {
    let dir = scratch("fall");
    let walk = |stop: bool| {
        let scenario = bullet_on_a_slope(20.0, 0.0, -1.0, stop);
        run_scenario(&dir, &format!("fall_{stop}"), &scenario)
    };
    let (stdout, stopped) = walk(true);
    let fell_at = stopped["fell_at"].as_f64().expect("bullet falls up 20°");
    assert!(fell_at < 2.0, "{stopped}");
    assert_eq!(stopped["complete"], true, "{stdout}");
    assert_eq!(stopped["walk_time"].as_f64().unwrap(), fell_at, "{stopped}");
    let tilt = stopped["max_body_tilt_deg"].as_f64().unwrap();
    assert!(tilt > 45.0 && tilt < 46.0, "{tilt}");
    assert!(!stdout.contains("stopped early"), "{stdout}");
    assert!(stdout.contains("the walk stopped there"), "{stdout}");
    let (stdout, tumbling) = walk(false);
    assert_eq!(tumbling["fell_at"].as_f64(), Some(fell_at));
    assert_eq!(tumbling["walk_time"].as_f64(), Some(4.0));
    assert!(
        tumbling["max_body_tilt_deg"].as_f64().unwrap() > 60.0,
        "{tumbling}"
    );
    assert!(!stdout.contains("the walk stopped there"), "{stdout}");
    // the command line's flag: up the 15° slope file it falls later, and stops there too
    let json = dir.join("flag.json");
    let mut cmd = hexsim();
    cmd.arg("run")
        .arg("--robot")
        .arg(project_file(
            "tests/data/third_party/bullet_syropod/robot/bullet.urdf",
        ))
        .arg("--terrain")
        .arg(project_file("terrains/slope15.toml"))
        .args(["--on-ground", "--stop-at-fall", "--duration", "10"])
        .args(["--no-record", "--allow-flags", "--metrics"])
        .arg(&json);
    let flagged = metrics_of(cmd, &json, "--stop-at-fall");
    let fell_at = flagged["fell_at"].as_f64().expect("bullet falls up 15°");
    assert_eq!(flagged["walk_time"].as_f64(), Some(fell_at), "{flagged}");
    assert!(fell_at < 10.0 && flagged["complete"] == true, "{flagged}");
}

/// A robot set down where it cannot stand falls before its walk, and the run says so: bullet
/// (0.41 m tall over feet close under it) set down parallel to a 25° slope, facing down it,
/// slides and pitches over its front feet within its second of settling. Its `fell_at` is
/// before the walk (negative), its tilt the fall's, the walk stopped there (`stop_at_fall`) and
/// never begun, and the summary says it fell while it settled. Before, the fall went unseen
/// until the walk's first step: "fell at 0.00 s into the walk", its tilt 115° and its pitch 64°.
#[test]
fn a_robot_that_falls_while_it_settles_is_reported_falling_before_its_walk() {
    let dir = scratch("settle-fall");
    let (stdout, metrics) =
        run_scenario(&dir, "settle", &bullet_on_a_slope(25.0, 180.0, 1.0, true));
    let fell_at = metrics["fell_at"].as_f64().expect("bullet falls on 25°");
    // the settling lasts 1 s: the fall within it
    assert!((-1.0..0.0).contains(&fell_at), "{metrics}");
    assert_eq!(metrics["complete"], true, "{stdout}");
    assert_eq!(metrics["walk_time"].as_f64(), Some(0.0), "{metrics}");
    let tilt = metrics["max_body_tilt_deg"].as_f64().unwrap();
    assert!(tilt > 45.0 && tilt < 46.0, "{tilt}");
    assert!(stdout.contains("fell while it settled"), "{stdout}");
    assert!(stdout.contains("the walk stopped there"), "{stdout}");
}
