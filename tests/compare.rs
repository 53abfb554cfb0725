//! `hexsim compare`: one scenario under several contact settings, end to end — the metrics
//! table and JSON, the superposed recording, and clear errors for a broken comparison file.

mod common;
use common::{assert_input_error, hexsim, scratch};
use hexsim::record::rerun::read_back;

/// The shipped ball comparison runs every setting, reports each one's metrics and draws each
/// ball with its path and plots; the paper's ball, which cannot roll, stops where hexsim's rolls.
#[test]
fn a_comparison_reports_and_records_every_setting() {
    let dir = scratch("compare");
    let (json, rrd) = (dir.join("ball.json"), dir.join("ball.rrd"));
    let out = hexsim()
        .args(["compare", "comparisons/ball_bell.toml", "--metrics"])
        .arg(&json)
        .arg("--record")
        .arg(&rrd)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let names = ["hexsim", "paper", "rolling 2 mm", "soft Hunt-Crossley"];
    let header = stdout.lines().find(|l| l.starts_with("metric")).unwrap();
    assert!(names.iter().all(|n| header.contains(n)), "{header}");
    // the final position by coordinate, not a sum of coordinates
    for axis in ["x", "y", "z"] {
        let row = format!("final_position {axis}");
        assert!(
            stdout.lines().any(|l| l.starts_with(&row)),
            "no {row}: {stdout}"
        );
    }
    assert!(!stdout.contains("final_position (sum"), "{stdout}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let settings = report["settings"].as_array().unwrap();
    assert_eq!(settings.len(), 4);
    let speed = |k: usize| settings[k]["metrics"]["final_speed"].as_f64().unwrap();
    assert!(speed(0) > 0.1, "hexsim's ball rolls on: {}", speed(0));
    assert!(
        speed(1) < 1e-3 && speed(2) < 1e-3,
        "{} {}",
        speed(1),
        speed(2)
    );
    let contents = read_back(&rrd).unwrap();
    assert_eq!(contents.activations, [(true, true)]);
    for name in names.map(|n| n.replace(' ', "_")) {
        let ball = contents.at(false, &format!("world/{name}/ball"));
        assert!(ball.is_some_and(|b| b.rows > 100), "{name}: {ball:?}");
        for plot in [
            "height",
            "speed",
            "total_energy",
            "normal_force",
            "penetration_mm",
            "slip",
        ] {
            let series = contents.at(false, &format!("plots/{plot}/{name}"));
            assert!(series.is_some_and(|s| s.rows > 100), "{plot}/{name}");
        }
        assert!(contents.at(false, &format!("world/paths/{name}")).is_some());
    }
}

/// A walk comparison draws each setting's robot, tinted, and plots their bodies (entity paths
/// spell a setting's spaces as underscores).
#[test]
fn a_walk_comparison_draws_every_robot() {
    let dir = scratch("compare");
    let rrd = dir.join("walk.rrd");
    let out = hexsim()
        .args(["compare", "comparisons/hex18_natural.toml", "--record"])
        .arg(&rrd)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("forward_distance"), "{stdout}");
    let contents = read_back(&rrd).unwrap();
    for name in [
        "hexsim",
        "stiff",
        "slippery",
        "Coulomb",
        "no_drift_recovery",
    ] {
        let links = contents
            .under(false, &format!("world/{name}/robot"))
            .filter(|(_, l)| l.rows > 0)
            .count();
        assert!(links >= 18, "{name}: {links} moving links");
        assert!(
            contents
                .at(false, &format!("plots/forward_x/{name}"))
                .is_some()
        );
    }
}

/// A broken comparison is an input error (exit 2) naming the file, the setting and the field.
#[test]
fn a_broken_comparison_says_where() {
    let dir = scratch("compare-bad");
    let cases = [
        (
            "scenario = \"SCENARIOS/ball_bell.toml\"\n[[setting]]\nname = \"a\"\ncontact = { stifness = 1e4 }\n",
            vec!["setting \"a\"", "stifness"],
        ),
        (
            "scenario = \"SCENARIOS/ball_bell.toml\"\n[[setting]]\nname = \"a\"\n[[setting]]\nname = \"a\"\n",
            vec!["setting \"a\" is named twice"],
        ),
        (
            "scenario = \"SCENARIOS/sweep_contact.toml\"\n[[setting]]\nname = \"a\"\n",
            vec!["has a [sweep]"],
        ),
        (
            "scenario = \"SCENARIOS/ball_bell.toml\"\n",
            vec!["expected at least one [[setting]]"],
        ),
        (
            "scenario = \"SCENARIOS/ball_bell.toml\"\n[[setting]]\nname = \"a\"\ncontact = { variant = \"paper\", rolling_resistance = 0.002 }\n",
            vec!["setting \"a\"", "contact.rolling_resistance"],
        ),
    ];
    for (k, (text, expected)) in cases.iter().enumerate() {
        let scenarios = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let file = dir.join(format!("case_{k}.toml"));
        let text = text.replace("SCENARIOS", &scenarios.to_string_lossy());
        std::fs::write(&file, text).unwrap();
        let mut cmd = hexsim();
        cmd.arg("compare")
            .arg(&file)
            .arg("--record")
            .arg(dir.join("x.rrd"));
        assert_input_error(cmd, &file, expected);
    }
}

/// A setting that diverges (hex18 on a contact spring far too stiff for the 1 ms step, √(k/m)·h ≈
/// 9 on a foot link, run though the set-up refuses it: `allow_unstable_dt`; it diverges within
/// the first steps, whatever the gait does) is reported with why, exit 1, and the others are
/// still recorded, the diverged one up to where it stopped.
#[test]
fn a_diverging_setting_is_reported_and_the_rest_recorded() {
    let dir = scratch("compare-diverge");
    let terrain =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains/natural_matlab.toml");
    let scenario = dir.join("unstable.toml");
    std::fs::write(
        &scenario,
        format!(
            "terrain = {:?}\nduration = 20.0\ndt = 0.001\nallow_unstable_dt = true\n[start]\nx = -1.25\ny = 0.0\n",
            terrain.to_string_lossy()
        ),
    )
    .unwrap();
    let file = dir.join("diverge.toml");
    std::fs::write(
        &file,
        format!(
            "scenario = {:?}\nduration = 6.0\n[[setting]]\nname = \"hexsim\"\n[[setting]]\nname = \"stiff\"\ncontact = {{ stiffness = 4e6 }}\n",
            scenario.to_string_lossy()
        ),
    )
    .unwrap();
    let rrd = dir.join("diverge.rrd");
    let out = hexsim()
        .arg("compare")
        .arg(&file)
        .arg("--record")
        .arg(&rrd)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("stiff: the simulation diverged"),
        "{stdout}"
    );
    let contents = read_back(&rrd).unwrap();
    for (name, least) in [("hexsim", 100), ("stiff", 1)] {
        let rows = contents
            .at(false, &format!("plots/forward_x/{name}"))
            .map_or(0, |s| s.rows);
        assert!(rows >= least, "{name}: {rows} samples");
    }
}
