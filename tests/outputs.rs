//! Outputs never clobber inputs or special files, a failed write is never called written, and
//! an interruption ends every command with exit code 130 (docs/running.md).

mod common;
use common::{hexsim, scratch};
use std::path::Path;

fn text(out: &std::process::Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// A short walk's arguments, with `extra` after them.
fn walk<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["run", "--duration", "0.05", "--settle", "0"];
    args.extend_from_slice(extra);
    args
}

#[test]
fn an_output_that_is_an_input_or_another_output_is_refused_and_the_input_kept() {
    let dir = scratch("clobber");
    let terrain = dir.join("terrain.toml");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains/bell.toml"),
        &terrain,
    )
    .unwrap();
    let before = std::fs::read(&terrain).unwrap();
    std::fs::create_dir(dir.join("sub")).unwrap();
    let via = dir.join("sub/../terrain.toml");
    let link = dir.join("link.csv");
    std::os::unix::fs::symlink(&terrain, &link).unwrap();
    for (flag, path) in [
        ("--trajectory", &terrain),
        ("--trajectory", &via),
        ("--metrics", &link),
    ] {
        let out = hexsim()
            .args(walk(&["--no-record"]))
            .arg("--terrain")
            .arg(&terrain)
            .arg(flag)
            .arg(path)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{}", text(&out));
        assert!(
            text(&out).contains("it is the terrain file"),
            "{}",
            text(&out)
        );
    }
    let export = hexsim()
        .args(["terrain", "export"])
        .arg(&terrain)
        .arg("--csv")
        .arg(&terrain)
        .output()
        .unwrap();
    assert_eq!(export.status.code(), Some(2), "{}", text(&export));
    assert!(text(&export).contains("--csv"), "{}", text(&export));
    assert_eq!(
        std::fs::read(&terrain).unwrap(),
        before,
        "the input changed"
    );

    let same = dir.join("same.out");
    let out = hexsim()
        .args(walk(&["--no-record"]))
        .arg("--trajectory")
        .arg(&same)
        .arg("--metrics")
        .arg(&same)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        text(&out).contains("metrics file")
            && text(&out).contains("the same file as the trajectory"),
        "{}",
        text(&out)
    );
}

#[test]
fn a_symlink_is_written_through_and_a_device_is_never_replaced() {
    let dir = scratch("special");
    let target = dir.join("metrics.json");
    let link = dir.join("link.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let out = hexsim()
        .args(walk(&[
            "--no-record",
            "--trajectory",
            "/dev/null",
            "--metrics",
        ]))
        .arg(&link)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(
        std::fs::read_to_string(&target)
            .unwrap()
            .contains("\"complete\": true")
    );

    // a full disk: the file is named, never "wrote", the metrics say incomplete, the device stays
    let metrics = dir.join("m.json");
    for flag in ["--record", "--trajectory"] {
        let mut cmd = hexsim();
        cmd.args(walk(&[flag, "/dev/full", "--metrics"]))
            .arg(&metrics);
        if flag == "--trajectory" {
            cmd.arg("--no-record");
        }
        let out = cmd.output().unwrap();
        let said = text(&out);
        assert_eq!(out.status.code(), Some(2), "{said}");
        assert!(said.contains("/dev/full"), "{said}");
        assert!(!said.contains("wrote /dev/full"), "{said}");
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::metadata("/dev/full")
                .unwrap()
                .file_type()
                .is_char_device()
        );
        if flag == "--trajectory" {
            let m = std::fs::read_to_string(&metrics).unwrap();
            assert!(m.contains("\"complete\": false"), "{m}");
        }
    }
}

#[test]
fn record_and_no_record_together_are_refused() {
    let out = hexsim()
        .args(walk(&["--record", "x.rrd", "--no-record"]))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(text(&out).contains("cannot be used with"), "{}", text(&out));
}

#[test]
fn ctrl_c_ends_terrain_generation_and_compare_with_130() {
    let dir = scratch("interrupt");
    // some 15 s of waves: interrupted after 1 s
    let rough = dir.join("rough.toml");
    std::fs::write(
        &rough,
        "[source]\nkind = \"rough\"\npeak_to_peak = 0.05\nwavelength_min = 0.1\n\
         wavelength_max = 1.0\nwaves = 100\nsize = [30.0, 30.0]\n",
    )
    .unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let comparison = dir.join("long.toml");
    std::fs::write(
        &comparison,
        format!(
            "scenario = \"{}\"\nduration = 1000.0\n[[setting]]\nname = \"a\"\n[[setting]]\nname = \"b\"\ncontact = {{ stiffness = 3e4 }}\n",
            root.join("scenarios/natural_tripod.toml").display()
        ),
    )
    .unwrap();
    let metrics = dir.join("compare.json");
    for args in [
        vec![
            "terrain".to_string(),
            "info".into(),
            rough.display().to_string(),
        ],
        vec![
            "compare".to_string(),
            comparison.display().to_string(),
            "--no-record".into(),
            "-j".into(),
            "2".into(),
            "--metrics".into(),
            metrics.display().to_string(),
        ],
    ] {
        let child = hexsim()
            .args(&args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(1500));
        let started = std::time::Instant::now();
        // SIGINT, as Ctrl-C sends
        std::process::Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap();
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(130), "{args:?}: {}", text(&out));
        assert!(
            started.elapsed().as_secs_f64() < 10.0,
            "{args:?} took its time"
        );
        assert!(text(&out).contains("interrupted"), "{}", text(&out));
    }
    let json = std::fs::read_to_string(&metrics).unwrap();
    assert!(json.contains("\"complete\": false"), "{json}");
}

#[test]
fn optimize_and_robot_refuse_to_write_over_what_they_read() {
    let dir = scratch("optimize-clobber");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // a second round of a search, from the first's best gait, into the same folder
    let spec = std::fs::read_to_string(root.join("optimizations/hex18_cost_of_transport.toml"))
        .unwrap()
        .replace(
            "\"../terrains/natural.toml\"",
            &format!("{:?}", root.join("terrains/natural.toml")),
        )
        .replace("[scenario]", "[scenario]\ngait = \"best_gait.toml\"");
    std::fs::write(dir.join("o.toml"), spec).unwrap();
    let gait = dir.join("best_gait.toml");
    std::fs::copy(root.join("gaits/tripod.toml"), &gait).unwrap();
    let before = std::fs::read(&gait).unwrap();
    let out = hexsim()
        .arg("optimize")
        .arg(dir.join("o.toml"))
        .arg("--output")
        .arg(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(text(&out).contains("it is the gait file"), "{}", text(&out));
    assert_eq!(std::fs::read(&gait).unwrap(), before);

    let out = hexsim()
        .args([
            "robot",
            "robots/hex18.urdf",
            "--record",
            "robots/../robots/hex18.toml",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        text(&out).contains("it is the robot file"),
        "{}",
        text(&out)
    );
}

/// A full disk under `terrain export` and `batch -o`: exit 2 naming the file, never "wrote" —
/// the exports are streamed, and a failed write used to be reported as "cannot read".
#[test]
fn exports_and_results_on_a_full_disk_name_the_file() {
    let dir = scratch("full-disk");
    let terrain = dir.join("flat.toml");
    std::fs::write(
        &terrain,
        "[source]\nkind = \"sine\"\nsize = [2.0, 2.0]\ncell = 0.02\namplitude = 0.01\nwavelength = 0.5\n",
    )
    .unwrap();
    for flag in ["--csv", "--stl", "--png"] {
        let out = hexsim()
            .args(["terrain", "export"])
            .arg(&terrain)
            .args([flag, "/dev/full"])
            .output()
            .unwrap();
        let said = text(&out);
        assert_eq!(out.status.code(), Some(2), "{flag}: {said}");
        assert!(
            said.contains("cannot write /dev/full: No space left"),
            "{flag}: {said}"
        );
        assert!(!said.contains("wrote"), "{flag}: {said}");
    }
    let scenario = dir.join("drop.toml");
    std::fs::write(
        &scenario,
        "kind = \"ball\"\nduration = 0.05\n[terrain.source]\nkind = \"flat\"\nsize = [4.0, 4.0]\n",
    )
    .unwrap();
    let out = hexsim()
        .arg("batch")
        .arg(&scenario)
        .args(["-q", "-o", "/dev/full"])
        .output()
        .unwrap();
    let said = text(&out);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(said.contains("/dev/full"), "{said}");
}
