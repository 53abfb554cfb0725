//! The `hexsim` binary end to end: outputs written, errors reported with exit code 2.

mod common;
use common::{hexsim, project_file, scratch};
use std::process::Command;

#[test]
fn ball_writes_recording_trajectory_and_metrics() {
    let dir = scratch("ball");
    let (rrd, csv, json) = (dir.join("b.rrd"), dir.join("b.csv"), dir.join("b.json"));
    let out = hexsim()
        .args([
            "ball",
            "--terrain",
            "terrains/bell.toml",
            "--at",
            "0.7",
            "0.3",
            "--duration",
            "1",
        ])
        .arg("--record")
        .arg(&rrd)
        .arg("--trajectory")
        .arg(&csv)
        .arg("--metrics")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rrd_bytes = std::fs::read(&rrd).unwrap();
    assert!(
        rrd_bytes.len() > 10_000 && rrd_bytes.starts_with(b"RRF"),
        "not an .rrd file"
    );
    let trajectory = std::fs::read_to_string(&csv).unwrap();
    assert!(trajectory.starts_with("time,x,y,z,"));
    assert_eq!(
        trajectory.lines().count(),
        1 + 101,
        "header + 100 Hz for 1 s + the initial row"
    );
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(metrics["complete"], true);
    assert_eq!(metrics["steps"], 1000);
    assert!(metrics["touchdowns"].as_u64().unwrap() >= 1);
    assert!(!dir.join("b.rrd.partial").exists());
}

#[test]
fn terrain_export_writes_stl_and_png_that_read_back() {
    let dir = scratch("export");
    let out = hexsim()
        .args(["terrain", "export", "terrains/natural.toml", "--stl"])
        .arg(dir.join("n.stl"))
        .arg("--png")
        .arg(dir.join("n.png"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stl = std::fs::read(dir.join("n.stl")).unwrap();
    assert_eq!(
        stl.len(),
        84 + 50 * 2 * 99 * 99,
        "binary STL with two triangles per cell"
    );
    let png = image::open(dir.join("n.png")).unwrap();
    assert_eq!(png.color(), image::ColorType::L16);
    assert_eq!((png.width(), png.height()), (100, 100));
    // an STL given where a terrain file is expected is its `[source]` (kind "stl", 1 cm cells)
    let out = hexsim()
        .args(["terrain", "info"])
        .arg(dir.join("n.stl"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("401 × 401 samples, cell 0.0100") && text.contains("x ∈ [-2.0, 2.0]"),
        "{text}"
    );
}

#[test]
fn bad_input_is_a_clear_error_with_exit_code_2() {
    let dir = scratch("bad");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[source]\nkind = \"bell\"\nsamples = 1\n").unwrap();
    let out = hexsim()
        .args(["ball", "--no-record", "--terrain"])
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("bad.toml") && stderr.contains("source.samples"),
        "{stderr}"
    );
    let out = hexsim()
        .args(["ball", "--no-record", "--terrain", "no/such/file.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/file.toml"));
    let out = hexsim()
        .args([
            "ball",
            "--duration",
            "0.1",
            "--record",
            "/nonexistent-dir/x.rrd",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent-dir/x.rrd"));
}

#[test]
fn run_walks_and_writes_recording_trajectory_and_metrics() {
    let dir = scratch("run");
    let (rrd, csv, json) = (dir.join("h.rrd"), dir.join("h.csv"), dir.join("h.json"));
    let out = hexsim()
        .args([
            "run",
            "--gait",
            "gaits/wave.toml",
            "--duration",
            "4",
            "--settle",
            "0.5",
            // its 4 s walk 0.12 m, the start's 17 mm of slip 14 % of it: flagged as skating (at
            // the default 20 s, 3.7 %); this test is of the files written
            "--allow-flags",
        ])
        .arg("--record")
        .arg(&rrd)
        .arg("--trajectory")
        .arg(&csv)
        .arg("--metrics")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("wave") && stdout.contains("distance"),
        "{stdout}"
    );
    // walking forward as told: no warning of going backwards
    assert!(!stdout.contains("backwards"), "{stdout}");
    assert!(std::fs::read(&rrd).unwrap().starts_with(b"RRF"));
    let trajectory = std::fs::read_to_string(&csv).unwrap();
    let header = trajectory.lines().next().unwrap();
    assert!(
        header.starts_with("time,x,y,z,roll,pitch,yaw")
            && header.contains(",lf_coxa_angle,")
            && header.contains("rr_tibia_torque")
            && header.ends_with("rr_contact,rr_slip")
    );
    assert_eq!(
        trajectory.lines().count(),
        1 + 225,
        "header + 50 Hz over 4.5 s"
    );
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(metrics["complete"], true);
    assert!(
        metrics["forward_distance"].as_f64().unwrap() > 0.1, // wave: 0.04 m/s nominal, ramping up over its first 1.8 s cycle
        "{metrics}"
    );
}

/// Ctrl-C mid-run: the run stops at the next step, and the recording (decodable to its end), the
/// trajectory and the metrics (marked incomplete) hold the run so far; exit code 130.
#[test]
fn sigint_leaves_a_readable_recording_and_incomplete_metrics() {
    let dir = scratch("sigint");
    let (rrd, csv, json) = (dir.join("i.rrd"), dir.join("i.csv"), dir.join("i.json"));
    let child = hexsim()
        .args(["run", "--duration", "600", "--settle", "0.2"])
        .arg("--record")
        .arg(&rrd)
        .arg("--trajectory")
        .arg(&csv)
        .arg("--metrics")
        .arg(&json)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // wait until it is stepping (the partial trajectory has rows), then interrupt it
    let partial = dir.join("i.csv.partial");
    let started = std::time::Instant::now();
    while std::fs::read(&partial).map_or(0, |b| b.len()) < 50_000 {
        assert!(
            started.elapsed().as_secs() < 120,
            "the run never started writing"
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    // the shell's own `kill`, so no procps is needed
    let status = Command::new("sh")
        .args(["-c", &format!("kill -INT {}", child.id())])
        .status()
        .unwrap();
    assert!(status.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(metrics["complete"], false);
    let steps = metrics["steps"].as_u64().unwrap();
    assert!(steps > 200 && steps < 600_000, "{steps} steps");
    let rows = std::fs::read_to_string(&csv).unwrap().lines().count();
    assert!(rows > 10, "{rows} trajectory rows");
    let messages = hexsim::record::rerun::read_back(&rrd).unwrap().messages;
    assert!(messages > 10, "{messages} messages in the recording");
    for leftover in ["i.rrd.partial", "i.csv.partial", "i.json.partial"] {
        assert!(!dir.join(leftover).exists(), "{leftover} left behind");
    }
}

/// A reader that closes the pipe (`hexsim run | head -1`) does not stop the run: its report
/// lines are dropped, not a panic, and the files it was asked for are written.
#[test]
fn a_closed_stdout_is_no_panic_and_the_files_are_written() {
    let dir = scratch("closed_stdout");
    let json = dir.join("m.json");
    let mut child = hexsim()
        .args(["run", "--duration", "0.3", "--settle", "0.1", "--no-record"])
        .arg("--metrics")
        .arg(&json)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // the read end closed before the first line is written
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(metrics["complete"], true);
}

/// An absurd stiffness with a large step (allowed on purpose) diverges: the run stops with when,
/// where and the likely cause, exits 1, and still writes its metrics marked incomplete.
#[test]
fn a_diverging_run_is_caught_with_when_where_and_why() {
    let dir = scratch("diverge");
    let json = dir.join("d.json");
    let out = hexsim()
        .args([
            "run",
            "--terrain",
            "terrains/flat.toml",
            "--stiffness",
            "2e6",
            "--dt",
            "0.004",
            "--allow-unstable-dt",
            "--no-record",
            "--duration",
            "5",
        ])
        .arg("--metrics")
        .arg(&json)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    for fragment in [
        "the simulation diverged at t = ",
        "likely cause: dt = 0.004 s",
        "stability limit",
        "reduce dt or the stiffness",
    ] {
        assert!(stderr.contains(fragment), "no {fragment:?} in {stderr}");
    }
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(metrics["complete"], false);
    // without the flag the step is refused before anything runs, with the limit
    let out = hexsim()
        .args(["run", "--stiffness", "2e6", "--dt", "0.004", "--no-record"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("dt < 3.16e-4 s"), "{stderr}");
}

/// `hexsim robot` says what hexsim found: legs by name with their hips, the walking direction,
/// the masses, and what each servo holds standing; a robot it cannot use is an input error.
#[test]
fn robot_inspection_shows_legs_direction_masses_and_standing_torques() {
    let out = hexsim()
        .args(["robot", "robots/hex18.urdf"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    for fragment in [
        "walking direction +x (the URDF's)",
        "mass 2.520 kg: body 1.500 kg",
        "lf  hip (+0.120, +0.060, +0.000) m; joints lf_coxa_joint lf_femur_joint lf_tibia_joint; segments 0.050 0.080 0.120 m",
        "rr  hip (-0.120, -0.060, +0.000) m",
        "stance height 0.100 m (robot file), reach 0.150 m (robot file), step height 0.030 m (robot file), stride 0.060 m (robot file)",
        "fitted to the legs alone (without the robot file's [gait]):",
        "m (fitted), reach ",
        "standing on six feet (hips 0.100 m above the ground)",
        "the most loaded servo: ",
        "walking tripod's cycle at 0.120 m/s on level ground: least room ",
        "planned on level ground step by step as the run plans it: every foot target reached in all 20000 steps",
    ] {
        assert!(stdout.contains(fragment), "no {fragment:?} in\n{stdout}");
    }
    let out = hexsim()
        .args(["robot", "tests/data/round_hexapod_y.urdf"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout
            .contains("walking direction +y (chosen: the legs do not split three a side about x; -y splits them as well: a robot file's `forward = \"-y\"` walks that way)"),
        "{stdout}"
    );
    let out = hexsim()
        .args(["robot", "tests/data/bad/urdf/five_legs.urdf"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("found 5 legs"));
}

/// A URDF named relative to the working directory finds its `package://` meshes the same as
/// named in full: from its own folder, `hexsim robot hexapod.urdf` reads ant_bot's feet from its
/// tibia meshes in the package folder above (before, the search for the package stopped at the
/// working directory, and the robot was refused for feet it could not find).
#[test]
fn a_urdf_named_from_its_own_folder_finds_its_package_meshes() {
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/third_party/ant_bot/ant_bot/urdf");
    let out = hexsim()
        .current_dir(&folder)
        .args(["robot", "hexapod.urdf"])
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("lf  hip"), "{stdout}");
}

/// A robot file can set the walking direction (`forward = "-y"`); the run says it and walks
/// that way (the body frame's x, so forward distance is positive and sideways small).
#[test]
fn a_robot_file_sets_the_walking_direction() {
    let dir = scratch("forward");
    std::fs::copy(
        project_file("tests/data/round_hexapod_y.urdf"),
        dir.join("round.urdf"),
    )
    .unwrap();
    // the robot file's stance too: hex18's stride and step, a stance for the round robot's size
    std::fs::write(
        dir.join("round.toml"),
        "forward = \"-y\"\n[gait]\nstance_height = 0.11\nreach = 0.16\nstride_length = 0.06\nstep_height = 0.03\n",
    )
    .unwrap();
    let json = dir.join("m.json");
    let out = hexsim()
        .args([
            "run",
            "--terrain",
            "terrains/flat.toml",
            "--duration",
            "3",
            "--no-record",
        ])
        .arg("--robot")
        .arg(dir.join("round.urdf"))
        .arg("--metrics")
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("walking direction -y (set in the robot file)"),
        "{stdout}"
    );
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(metrics["stance"]["stance_height"], 0.11);
    assert_eq!(metrics["stance"]["origins"]["reach"], "robot file");
    let forward = metrics["forward_distance"].as_f64().unwrap();
    let sideways = metrics["sideways_distance"].as_f64().unwrap();
    // nominal 0.06 m / 0.5 s = 0.12 m/s for 3 s, the first cycle ramping up
    assert!(forward > 0.25, "walked {forward} m forward");
    assert!(sideways.abs() < 0.05, "{sideways} m sideways");
}

/// The ball goes through the same step loop as the walk: when it diverges, every file asked for
/// is still written, the trajectory ends with the step that diverged, and the metrics say the run
/// is incomplete.
#[test]
fn a_diverging_ball_leaves_every_file_ending_at_the_diverged_step() {
    let dir = scratch("diverge_ball");
    let (rrd, csv, json) = (dir.join("b.rrd"), dir.join("b.csv"), dir.join("b.json"));
    let out = hexsim()
        .args([
            "ball",
            "--terrain",
            "terrains/flat.toml",
            "--stiffness",
            "1e9",
            "--dt",
            "0.005",
            "--log-rate",
            "200",
            "--allow-unstable-dt",
            "--duration",
            "3",
        ])
        .arg("--record")
        .arg(&rrd)
        .arg("--trajectory")
        .arg(&csv)
        .arg("--metrics")
        .arg(&json)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let at = stderr
        .split("diverged at t = ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or_else(|| panic!("no time of divergence in {stderr}"));
    let at: f64 = at.parse().unwrap();
    let table = std::fs::read_to_string(&csv).unwrap();
    let last: f64 = table
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (last - at).abs() < 1e-9,
        "the trajectory ends at {last} s, the run diverged at {at} s"
    );
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(metrics["complete"], false);
    assert!(hexsim::record::rerun::read_back(&rrd).unwrap().messages > 3);
}

#[test]
fn bench_measures_both_articulations_and_says_what_it_measured() {
    let dir = scratch("bench");
    let json = dir.join("bench.json");
    let out = hexsim()
        .args([
            "bench",
            "--duration",
            "0.3",
            "--repeats",
            "1",
            "--jobs",
            "2",
            "--json",
        ])
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for needle in [
        "articulation",
        "multibody",
        "impulse",
        "contact",
        "steps/s",
        "ball",
    ] {
        assert!(stdout.contains(needle), "no {needle:?} in:\n{stdout}");
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let figures = report["figures"].as_array().unwrap();
    // walk, walk recorded, batch — per articulation — and the ball
    assert_eq!(figures.len(), 7, "{figures:?}");
    for f in figures {
        let median = f["steps_per_second"].as_f64().unwrap();
        assert!(median > 0.0);
        assert!(
            f["best_steps_per_second"].as_f64().unwrap() >= median,
            "{f}"
        );
    }
    // each single-thread walk says how much of its time was rapier's step
    for f in figures.iter().filter(|f| f["workload"] == "walk") {
        let share = f["rapier_share"].as_f64().unwrap();
        assert!(share > 0.0 && share < 1.0, "{f}");
    }
    assert!(stdout.contains("rapier's step"), "{stdout}");
    let batch = figures
        .iter()
        .find(|f| f["workload"].as_str().unwrap().starts_with("batch"))
        .unwrap();
    assert_eq!(batch["threads"], 2);
    assert_eq!(batch["steps"], 2 * 1300, "two worlds of 1.3 s at 1 ms");
}

/// `bench --mujoco PYTHON` runs the built-in MuJoCo script with that Python, as many steps as
/// the walk, once a round beside one walk, and prints the walk as a multiple of MuJoCo's figure:
/// the median of the rounds' ratios. A stand-in "Python" that checks its arguments and writes
/// the figures the real script writes keeps the test free of MuJoCo; a Python that cannot run is
/// an error that says how to get one.
#[test]
#[cfg(unix)]
fn bench_times_mujoco_beside_itself() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("bench_mujoco");
    let python = dir.join("python");
    std::fs::write(
        &python,
        "#!/bin/sh\n\
         case \"$1\" in *hex18_mujoco.py) ;; *) exit 3;; esac\n\
         test -s \"$2\" || exit 4\n\
         while [ $# -gt 0 ]; do\n\
           case \"$1\" in\n\
             --steps) steps=$2;;\n\
             --urdf) grep -q '<robot' \"$2\" || exit 5;;\n\
             --json) json=$2;;\n\
           esac; shift\n\
         done\n\
         echo run >> \"$(dirname \"$0\")/calls\"\n\
         printf '{\"mujoco_version\":\"9.9\",\"steps\":%s,\"repeats\":1,\"loop_steps_per_second\":1000.0,\"rollout_steps_per_second\":2000.0,\"base_end\":[0,0,0.1],\"tilt_deg\":1.0}' \"$steps\" > \"$json\"\n",
    )
    .unwrap();
    std::fs::set_permissions(&python, std::fs::Permissions::from_mode(0o755)).unwrap();
    let out = hexsim()
        .args(["bench", "--articulation", "multibody", "--duration", "0.3"])
        .args(["--repeats", "2", "--jobs", "1", "--mujoco"])
        .arg(&python)
        .arg("--json")
        .arg(dir.join("bench.json"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("MuJoCo 9.9 on this machine, the same walk's 1300 steps: rollout 2000"),
        "{stdout}"
    );
    let ratio = stdout
        .lines()
        .find_map(|l| l.strip_prefix("multibody walk: "))
        .unwrap_or_else(|| panic!("no ratio in:\n{stdout}"));
    let times: f64 = ratio.split('×').next().unwrap().parse().unwrap();
    assert!(
        times > 1.0,
        "hexsim's walk against a stand-in 2000 steps/s: {ratio}"
    );
    assert!(ratio.contains("median of 2 rounds"), "{ratio}");
    // one MuJoCo run a round, each beside one walk
    let calls = std::fs::read_to_string(dir.join("calls")).unwrap();
    assert_eq!(calls.lines().count(), 2, "{calls}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("bench.json")).unwrap()).unwrap();
    let pairs = json["mujoco"]["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 2, "{pairs:?}");
    for pair in pairs {
        assert_eq!(pair["articulation"], "multibody");
        assert_eq!(pair["mujoco"], 2000.0);
        assert!(pair["hexsim"].as_f64().unwrap() > 2000.0, "{pair}");
    }
    assert_eq!(json["mujoco"]["figures"]["repeats"], 2);
    let missing = hexsim()
        .args(["bench", "--articulation", "multibody", "--duration", "0.1"])
        .args(["--repeats", "1", "--mujoco"])
        .arg(dir.join("no-such-python"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&missing.stderr);
    assert!(!missing.status.success());
    assert!(stderr.contains("pip install mujoco"), "{stderr}");
}

/// `hexsim` without a subcommand is `hexsim run` with the options given: the same metrics, bit
/// for bit; a subcommand's name after run's options is refused rather than mixed.
#[test]
fn hexsim_alone_takes_runs_options() {
    let dir = scratch("alone");
    let metrics = |prefix: &[&str], name: &str| {
        let out = hexsim()
            .args(prefix)
            .args(["--duration", "0.5", "--no-record", "--metrics"])
            .arg(dir.join(name))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read_to_string(dir.join(name)).unwrap()
    };
    assert_eq!(metrics(&[], "alone.json"), metrics(&["run"], "run.json"));
    let mixed = hexsim()
        .args(["--duration", "0.5", "ball"])
        .output()
        .unwrap();
    assert_eq!(mixed.status.code(), Some(2));
}

/// `joint_limit_time` (and its `max_joint_limit_s` expectation): hex18's tripod at its nominal
/// speed keeps every joint off its stops; asked for 0.6 m/s (5× the gait's speed), its strides
/// outrun the legs and a joint stays pressed against a limit for a good part of a step (0.40 s of
/// 4 at 0.5 ms, 0.55 s at 1 ms). At 0.4 m/s the strides overreach by so little that the feet's
/// rolling offset (gait::controller) keeps every target in reach; without it, 0.38 s at a limit.
/// The half step keeps the overdriven, pitching body well inside the contact's stability.
#[test]
fn time_at_a_joint_limit_is_measured() {
    let dir = scratch("joint_limit");
    let run = |speed: Option<&str>, name: &str| {
        let json = dir.join(name);
        let mut cmd = hexsim();
        cmd.args(["run", "--no-record", "--duration", "4", "--metrics"])
            .arg(&json);
        if let Some(v) = speed {
            // overdriven on purpose: at 0.6 m/s the feet skate (19 % of the distance)
            cmd.args(["--speed", v, "--dt", "0.0005", "--allow-flags"]);
        }
        let out = cmd.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        m["joint_limit_time"].as_f64().unwrap()
    };
    assert_eq!(run(None, "nominal.json"), 0.0);
    let fast = run(Some("0.6"), "fast.json");
    assert!(fast > 0.1, "{fast} s at a limit");
}

/// A walk that leaves the terrain's grid (here started 0.3 m from its +x edge) is flagged: the
/// time off it in the metrics and a warning in the summary; one that stays on reports 0.
#[test]
fn a_walk_off_the_terrain_grid_is_flagged() {
    let dir = scratch("off-terrain");
    let walk = |start: &str, name: &str| {
        let json = dir.join(format!("{name}.json"));
        let out = hexsim()
            .args([
                "run",
                "--terrain",
                "terrains/natural.toml",
                "--duration",
                "6",
            ])
            .args(["--start", start, "0", "--no-record", "--metrics"])
            .arg(&json)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(out.status.success(), "{stdout}");
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        (m["time_off_terrain"].as_f64().unwrap(), stdout)
    };
    let (off, stdout) = walk("1.7", "edge");
    // 0.3 m at about 0.12 m/s: off the grid after about 2.5 s of the 6
    assert!(off > 2.0 && off < 4.5, "{off} s off the terrain");
    assert!(stdout.contains("beyond the terrain's grid"), "{stdout}");
    // the paper's terrain is 4 m long: the warning names its continuation
    assert!(stdout.contains("`--terrain natural_long`"), "{stdout}");
    let (on, stdout) = walk("-1.0", "inside");
    assert_eq!(on, 0.0);
    assert!(!stdout.contains("beyond the terrain's grid"), "{stdout}");
}

/// A walk that goes backwards against its command says so: uphill on 20° with μs = μk = 0.3,
/// past the feet's friction angle (tan 20° = 0.36), no stance holds and the robot slides down
/// while told to climb; the summary warns, the metrics carry the negative progress, and the run
/// exits 1.
#[test]
fn a_walk_sliding_back_against_its_command_says_so() {
    let dir = scratch("slide_back");
    let terrain = dir.join("slope45.toml");
    std::fs::write(
        &terrain,
        "[source]\nkind = \"slope\"\nangle_deg = 20.0\nsize = [20.0, 4.0]\n",
    )
    .unwrap();
    let json = dir.join("m.json");
    let out = hexsim()
        .args(["run", "--no-record", "--duration", "2", "--start", "0", "0"])
        .args(["--mu-static", "0.3", "--mu-kinetic", "0.3", "--terrain"])
        .arg(&terrain)
        .arg("--metrics")
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // not the walk commanded: exit 1, naming why
    assert_eq!(out.status.code(), Some(1), "{stdout}{stderr}");
    assert!(
        stderr.contains("error: not the walk commanded (skated, went backwards)"),
        "{stderr}"
    );
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let progress = metrics["command_progress"].as_f64().unwrap();
    println!("{stdout}");
    assert!(progress < -0.1, "progress {progress} m");
    assert!(
        stdout.contains(&format!(
            "warning: the body went {:.3} m backwards against the command",
            -progress
        )),
        "{stdout}"
    );
}

/// The paper's variant says which of its parts are hexsim's reading, not the paper's (issue 42):
/// Karnopp's stick force and friction on the ball.
#[test]
fn the_paper_variant_names_what_is_hexsims_reading() {
    for command in ["ball", "run"] {
        let out = hexsim().args([command, "--help"]).output().unwrap();
        let help = String::from_utf8_lossy(&out.stdout);
        assert!(
            help.contains("Two parts are hexsim's reading, not the paper's")
                && help.contains("Karnopp's stick force")
                && help.contains("friction on the ball"),
            "{command} --help: {help}"
        );
    }
}

/// `hexsim robot` and `hexsim run` judge reach by one tally (`gait::reach`), the report planning
/// the run's walk step by step on level ground: hex18 with a 0.19 m stride, which the report once
/// called out of reach (a cycle sampled without the feet's rolling offset) while the run reached
/// every target, and with 0.21 m, out of reach in 4582 steps of 20000 (18525 while a solve that
/// missed stayed on the branch it had slid to, `gait::controller::solve_on_branch`): the report's
/// count is the run's `clamped_ik_steps` on flat ground, exactly.
#[test]
fn the_robot_report_and_the_run_count_the_same_steps_out_of_reach() {
    let dir = scratch("reach");
    let tripod = std::fs::read_to_string("gaits/tripod.toml").unwrap();
    for stride in ["0.19", "0.21"] {
        let gait = dir.join(format!("tripod_{stride}.toml"));
        let text = tripod.replace(
            "swing = \"sine\"",
            &format!("swing = \"sine\"\nstride_length = {stride}"),
        );
        std::fs::write(&gait, text).unwrap();
        let out = hexsim()
            .args(["robot", "robots/hex18.urdf", "--gait"])
            .arg(&gait)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{stdout}");
        let line = stdout
            .lines()
            .find(|l| l.contains("as the run plans it: "))
            .unwrap_or_else(|| panic!("no reach line in {stdout}"));
        let verdict = line.split("as the run plans it: ").nth(1).unwrap();
        let reported: u64 = if verdict.starts_with("every foot target reached") {
            0
        } else {
            verdict.split(" of ").next().unwrap().parse().unwrap()
        };
        let metrics = dir.join(format!("run_{stride}.json"));
        let out = hexsim()
            .args(["run", "--robot", "robots/hex18.urdf", "--gait"])
            .arg(&gait)
            .args([
                "--terrain",
                "terrains/flat.toml",
                "--no-record",
                // strides beyond the legs' reach: the walk drifts and turns, and is flagged
                "--allow-flags",
                // the report plans without the ground's forces, which legs that give way
                // answer (`gait::compliance`: a leg past its reach presses 3 weights)
                "--stiff-legs",
                // nor the body's attitude, which the lean answers (`gait::lean`: a stride
                // beyond the legs' reach pitches the body past its onset)
                "--no-lean",
                "--metrics",
            ])
            .arg(&metrics)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&metrics).unwrap()).unwrap();
        assert_eq!(
            m["clamped_ik_steps"].as_u64().unwrap(),
            reported,
            "stride {stride}: {line}"
        );
        if stride == "0.21" {
            assert!(reported > 2_000, "{line}");
        }
    }
}

/// A walk judged against its command (issue 40): hex18 on a 0.08 s tripod cannot keep up with
/// its gait and skates (measured: the worst foot slid 2.3 m on the ground while the body went
/// 0.14 m in 4 s, hex18's own tripod 0.8 % of its distance); the run says it skated, the metrics flag it (`walk_flags`, `slip_share`),
/// and it exits 1 unless `--allow-flags`. In a batch the same walk fails without any
/// expectation (`walk_as_commanded`, set for every walk), and passes where its file accepts it
/// (`walk_as_commanded = false`); a scenario bounding `slip_share_max` fails on that bound too.
#[test]
fn a_walk_on_skating_feet_is_flagged_and_fails() {
    let dir = scratch("skate");
    let tripod = std::fs::read_to_string("gaits/tripod.toml").unwrap();
    let fast = dir.join("fast.toml");
    std::fs::write(&fast, tripod.replace("period = 1.0", "period = 0.08")).unwrap();
    let judged = |gait: &std::path::Path, name: &str, extra: &[&str]| {
        let metrics = dir.join(format!("{name}.json"));
        let out = hexsim()
            .args(["run", "--gait"])
            .arg(gait)
            .args(["--terrain", "terrains/flat.toml", "--duration", "4"])
            .args(["--no-record", "--metrics"])
            .arg(&metrics)
            .args(extra)
            .output()
            .unwrap();
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&metrics).unwrap()).unwrap();
        (
            out.status.code(),
            format!(
                "{}{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            ),
            m,
        )
    };
    let (code, output, m) = judged(&fast, "fast", &[]);
    assert_eq!(code, Some(1), "{output}");
    assert!(
        output.contains("warning: not the walk commanded: it skated: its worst foot slid"),
        "{output}"
    );
    assert!(
        output.contains("error: not the walk commanded (skated")
            && output.contains("); --allow-flags accepts it"),
        "{output}"
    );
    assert!(
        m["slip_share"].as_f64().unwrap() > 0.10,
        "{}",
        m["slip_share"]
    );
    assert!(m["walk_flags"][0].as_str().unwrap().starts_with("skated"));
    // the share is the worst foot's slip on the ground: its swings' scuffs (some, at this pace)
    // left out
    let per_foot = |key: &str| -> Vec<f64> {
        m[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (slip, scuff) = (per_foot("foot_slip"), per_foot("foot_scuff"));
    assert!(scuff.iter().any(|&s| s > 0.0), "{scuff:?}");
    let on_ground = slip
        .iter()
        .zip(&scuff)
        .map(|(s, c)| s - c)
        .fold(0.0, f64::max);
    let share = on_ground / m["distance"].as_f64().unwrap();
    assert!(
        (m["slip_share"].as_f64().unwrap() - share).abs() < 1e-12,
        "{} against {share}",
        m["slip_share"]
    );
    let (code, output, _) = judged(&fast, "allowed", &["--allow-flags"]);
    assert_eq!(code, Some(0), "{output}");
    assert!(
        output.contains("warning: not the walk commanded"),
        "{output}"
    );
    let (code, output, m) = judged(std::path::Path::new("gaits/tripod.toml"), "nominal", &[]);
    assert_eq!(code, Some(0), "{output}");
    assert!(!output.contains("not the walk commanded"), "{output}");
    assert!(
        m["slip_share"].as_f64().unwrap() < 0.02,
        "{}",
        m["slip_share"]
    );
    assert_eq!(m["walk_flags"], serde_json::json!([]));
    let scenarios = dir.join("scenarios");
    std::fs::create_dir_all(&scenarios).unwrap();
    let skate = "gait = \"../fast.toml\"\nduration = 4.0\n[terrain.source]\nkind = \"flat\"\nsize = [30.0, 4.0]\n";
    let batch = |expect: &str| {
        std::fs::write(scenarios.join("skate.toml"), format!("{skate}{expect}")).unwrap();
        let out = hexsim()
            .current_dir(dir.path())
            .args(["batch", "scenarios", "-o", "r.jsonl"])
            .output()
            .unwrap();
        std::fs::remove_file(dir.join("r.jsonl")).unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    let (code, stdout) = batch("");
    assert_eq!(code, Some(1), "{stdout}");
    assert!(
        stdout.contains("walk_as_commanded: it skated: its worst foot slid"),
        "{stdout}"
    );
    let (code, stdout) = batch("[expect]\nwalk_as_commanded = false\n");
    assert_eq!(code, Some(0), "{stdout}");
    let (code, stdout) = batch("[expect]\nwalk_as_commanded = false\nslip_share_max = 0.05\n");
    assert_eq!(code, Some(1), "{stdout}");
    assert!(
        stdout.contains("slip_share_max: ") && stdout.contains(" > 0.05"),
        "{stdout}"
    );
}

/// Built-in gaits, terrains and hex18 by name from any folder (`--gait wave --terrain flat`);
/// a name that is none of them says which are; a file of that name in the folder wins.
#[test]
fn built_in_files_by_name_from_any_folder() {
    let dir = scratch("named");
    let run = |args: &[&str]| {
        hexsim()
            .current_dir(&dir)
            .args(["run", "--duration", "0.3", "--no-record"])
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&["--robot", "hex18", "--gait", "wave", "--terrain", "flat"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run(&["--gait", "wavy"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("built-in gaits, by name: tripod, ripple, wave"),
        "{stderr}"
    );
    // `hexsim terrain` and `hexsim robot` take the same names
    let inspect = |args: &[&str]| {
        let out = hexsim().current_dir(&dir).args(args).output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "{args:?}: {stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        stdout
    };
    assert!(inspect(&["terrain", "info", "flat"]).contains("x ∈ [-10.0, 10.0]"));
    assert!(inspect(&["robot", "hex18", "--gait", "wave"]).starts_with("hex18: hex18, 19 links"));
    // and a name that is none of them says which are, whichever command reads it
    let refused = |args: &[&str], names: &str| {
        let out = hexsim().current_dir(&dir).args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(names), "{args:?}: {stderr}");
    };
    let terrains = "built-in terrains, by name: bell, discrete_obstacles, flat,";
    refused(&["terrain", "info", "flatt"], terrains);
    refused(
        &["terrain", "export", "flatt", "--csv", "out.csv"],
        terrains,
    );
    refused(
        &["robot", "hex18", "--gait", "wavy"],
        "built-in gaits, by name: tripod,",
    );
    refused(&["robot", "hex19"], "built-in robots, by name: hex18");
    refused(
        &["run", "--robot", "hex19", "--no-record"],
        "built-in robots, by name: hex18",
    );
    assert!(!dir.join("out.csv").exists());
    // a file called `flat` here is the user's, and this one is not a terrain
    std::fs::write(dir.join("flat"), "not = \"a terrain\"\n").unwrap();
    let out = run(&["--terrain", "flat"]);
    assert_eq!(out.status.code(), Some(2));
}

/// `hexsim run SCENARIO.toml` runs and records the one walk a scenario file holds, with the
/// output flags; a sweep, a ball scenario or a walk flag beside the file is refused, naming why.
#[test]
fn run_takes_a_scenario_file() {
    let dir = scratch("run-scenario");
    let file = dir.join("short.toml");
    std::fs::write(
        &file,
        "duration = 0.3\nsettle = 0.2\n[terrain.source]\nkind = \"flat\"\nsize = [4.0, 4.0]\n",
    )
    .unwrap();
    let (rrd, json) = (dir.join("short.rrd"), dir.join("short.json"));
    let out = hexsim()
        .arg("run")
        .arg(&file)
        .arg("--record")
        .arg(&rrd)
        .arg("--metrics")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(rrd.metadata().unwrap().len() > 0);
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(
        (m["walk_time"].as_f64().unwrap() - 0.3).abs() < 1e-9,
        "{}",
        m["walk_time"]
    );
    let refused = |args: &[&str], expected: &str| {
        let out = hexsim().arg("run").args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(expected), "{stderr}");
    };
    // the file's expectations are judged as `hexsim batch` judges them
    let expecting = dir.join("expecting.toml");
    std::fs::write(
        &expecting,
        "duration = 0.3\nsettle = 0.2\n[terrain.source]\nkind = \"flat\"\nsize = [4.0, 4.0]\n\
         [expect]\ndistance_min = 5.0\nmax_tilt_deg = 45\n",
    )
    .unwrap();
    let out = hexsim()
        .args(["run", expecting.to_str().unwrap(), "--no-record"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("error: expectation not met: distance_min: ") && stderr.contains(" < 5"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("max_tilt_deg"),
        "a met one is not named: {stderr}"
    );
    refused(&["ladder/gaps.toml"], "a sweep of 12 scenarios");
    refused(&["scenarios/ball_bell.toml"], "a ball scenario");
    refused(
        &[file.to_str().unwrap(), "--duration", "2"],
        "cannot be used with '--duration",
    );
}
