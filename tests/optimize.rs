//! `hexsim optimize`: a tiny search end to end, and clear errors for a broken specification.

mod common;
use common::{assert_input_error, hexsim, scratch};
use hexsim::record::rerun::read_back;

const SPEC: &str = r#"
seeds = [3]
check_seeds = [4]
generations = 1
population = 2
[scenario]
terrain = "TERRAINS/natural.toml"
duration = 1.0
[scenario.start]
x = -1.25
y = 0.0
[parameters]
"gait.period" = [0.8, 1.2]
"gait.stride_length" = [0.04, 0.08]
[objective]
forward_distance = 1.0
[constraints]
max_tilt_deg = 20
"#;

fn spec(extra: &str, replace: Option<(&str, &str)>) -> String {
    let terrains = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains");
    let mut text = SPEC.replace("TERRAINS", &terrains.to_string_lossy());
    if let Some((from, to)) = replace {
        text = text.replace(from, to);
    }
    text + extra
}

/// A search of two candidates after the start: every evaluation logged, the best gait written
/// as a gait file that `hexsim run --gait` walks, and the summary.
#[test]
fn a_tiny_search_runs_end_to_end() {
    let dir = scratch("optimize");
    let file = dir.join("tiny.toml");
    std::fs::write(&file, spec("", None)).unwrap();
    let out_dir = dir.join("out");
    let out = hexsim()
        .arg("optimize")
        .arg(&file)
        .arg("--output")
        .arg(&out_dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("generation 1/1"), "{stdout}");
    let log = std::fs::read_to_string(out_dir.join("evaluations.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = log
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3, "the start and two candidates");
    for line in &lines {
        assert_eq!(line["status"], "ok", "{line}");
        let period = line["parameters"]["gait.period"].as_f64().unwrap();
        assert!((0.8..=1.2).contains(&period), "{period}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    let best = summary["best"]["objective"].as_f64().unwrap();
    let all_best = lines
        .iter()
        .filter_map(|l| l["objective"].as_f64())
        .fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(best, all_best);
    // the start and the best checked on the searched and the unsearched seed, both articulations
    let per_seed = summary["per_terrain"].as_array().unwrap();
    assert_eq!(per_seed.len(), 2);
    assert_eq!(per_seed[1]["searched"], false);
    for key in [
        "start_impulse",
        "best_impulse",
        "start_multibody",
        "best_multibody",
    ] {
        assert!(
            per_seed.iter().all(|s| s[key].is_number()),
            "{key}: {per_seed:?}"
        );
    }
    assert_eq!(
        per_seed[0]["best_impulse"].as_f64(),
        Some(best),
        "one seed: its objective"
    );
    // the search's recording: every evaluation's objective and parameters over the evaluations
    let search = read_back(&out_dir.join("search.rrd")).unwrap();
    assert_eq!(search.activations, [(true, true)]);
    let evaluations = search.at(false, "plots/objective/evaluations");
    assert!(evaluations.is_some_and(|e| e.rows == 3), "{evaluations:?}");
    for name in ["gait_period", "gait_stride_length"] {
        let p = search.at(false, &format!("plots/parameters/{name}"));
        assert!(p.is_some_and(|p| p.rows == 3), "{name}: {p:?}");
    }
    assert!(search.at(false, "summary").is_some());
    let failures = search.at(false, "plots/failures/failed");
    assert!(failures.is_some_and(|f| f.rows == 3), "{failures:?}");
    // each seed's: the start and the best walking it, superposed
    for seed in [3, 4] {
        let walk = read_back(&out_dir.join(format!("natural-seed-{seed}.rrd"))).unwrap();
        for name in ["start", "best"] {
            let links = walk
                .under(false, &format!("world/{name}/robot"))
                .filter(|(_, l)| l.rows > 10)
                .count();
            assert!(links > 6, "seed {seed}, {name}: {links} links moving");
        }
    }
    let gait = out_dir.join("best_gait.toml");
    let run = hexsim()
        .args([
            "run",
            "--no-record",
            "--duration",
            "1",
            "--terrain",
            "terrains/flat.toml",
            "--gait",
        ])
        .arg(&gait)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// A broken specification is an input error (exit 2) naming the file and the field.
#[test]
fn a_broken_specification_says_where() {
    let dir = scratch("optimize-bad");
    let cases = [
        (
            spec("", Some(("\"gait.period\"", "\"gait.perod\""))),
            "parameters.gait.perod: unknown parameter",
        ),
        (
            spec("", Some(("[0.8, 1.2]", "[1.2, 0.8]"))),
            "parameters.gait.period: expected [low, high] with low < high",
        ),
        (
            spec(
                "",
                Some((
                    "\"gait.stride_length\" = [0.04, 0.08]",
                    "\"gait.duty_factor\" = [0.5, 1.2]",
                )),
            ),
            "parameters.gait.duty_factor: [0.5, 1.2] leaves what the field accepts",
        ),
        (
            spec(
                "",
                Some(("forward_distance = 1.0", "forward_distanse = 1.0")),
            ),
            "objective.forward_distanse: unknown metric",
        ),
        (
            spec("", Some(("check_seeds = [4]", "check_seeds = [4, 3]"))),
            "check_seeds: seed 3 is also searched (in seeds)",
        ),
        (
            spec("", Some(("seeds = [3]", "seeds = []"))),
            "seeds: expected at least one terrain seed",
        ),
        (
            spec("", Some(("seeds = [3]", "seeds = [3]\nterrains = []"))),
            "terrains: expected at least one terrain file",
        ),
        (
            spec(
                "",
                Some(("seeds = [3]", "seeds = [3]\nterrains = [\"nowhere.toml\"]")),
            ),
            "terrains: nowhere.toml: ",
        ),
        (
            spec("", Some(("[0.8, 1.2]", "[\"sine\", \"cycloid\"]"))),
            "parameters.gait.period: a number; expected bounds [low, high]",
        ),
        (
            spec(
                "",
                Some((
                    "\"gait.period\" = [0.8, 1.2]",
                    "\"gait.period\" = [0.8, 1.2]\n\"gait.swing\" = [0, 1]",
                )),
            ),
            "parameters.gait.swing: a choice; expected a list of names among sine, cycloid, rectangle",
        ),
        (
            spec(
                "",
                Some((
                    "\"gait.period\" = [0.8, 1.2]",
                    "\"gait.period\" = [0.8, 1.2]\n\"gait.swing\" = [\"sine\", \"zigzag\"]",
                )),
            ),
            "parameters.gait.swing: unknown choice \"zigzag\"",
        ),
        (
            spec(
                "",
                Some((
                    "\"gait.period\" = [0.8, 1.2]",
                    "\"gait.period\" = [0.8, 1.2]\n\"gait.phase_offsets.lf\" = [0.5, 1.5]",
                )),
            ),
            "parameters.gait.phase_offsets.lf: [0.5, 1.5] leaves what the field accepts",
        ),
        (
            spec(
                "",
                Some((
                    "\"gait.period\" = [0.8, 1.2]",
                    "\"gait.period\" = [0.8, 1.2]\n\"command.forward\" = [0.05, 0.2]",
                )),
            ),
            "parameters.gait.stride_length: the speed is commanded",
        ),
    ];
    for (k, (text, expected)) in cases.iter().enumerate() {
        let file = dir.join(format!("case_{k}.toml"));
        std::fs::write(&file, text).unwrap();
        let mut cmd = hexsim();
        cmd.arg("optimize")
            .arg(&file)
            .arg("--output")
            .arg(dir.join("out"));
        assert_input_error(cmd, &file, &[expected]);
    }
}

/// The same specification and seed give the same search, evaluation for evaluation.
#[test]
fn a_search_is_deterministic() {
    let dir = scratch("optimize-twice");
    let file = dir.join("tiny.toml");
    std::fs::write(&file, spec("", None)).unwrap();
    let logs: Vec<String> = ["a", "b"]
        .iter()
        .map(|run| {
            let out_dir = dir.join(run);
            let out = hexsim()
                .arg("optimize")
                .arg(&file)
                .arg("--output")
                .arg(&out_dir)
                .arg("--no-record")
                .output()
                .unwrap();
            assert!(out.status.success());
            std::fs::read_to_string(out_dir.join("evaluations.jsonl")).unwrap()
        })
        .collect();
    assert_eq!(logs[0], logs[1]);
}

/// Resume: a search cut short (its log truncated after the first generation, as Ctrl-C leaves it,
/// or a real Ctrl-C) and continued with --resume replays what is logged and ends with the same
/// log, line for line, as a search never interrupted.
#[test]
fn an_interrupted_search_resumes_to_the_same_result() {
    let dir = scratch("optimize-resume");
    let file = dir.join("two.toml");
    std::fs::write(
        &file,
        spec("", Some(("generations = 1", "generations = 3"))),
    )
    .unwrap();
    let run = |out: &std::path::Path, resume: bool| {
        let mut cmd = hexsim();
        cmd.arg("optimize")
            .arg(&file)
            .arg("--output")
            .arg(out)
            .arg("--no-record");
        if resume {
            cmd.arg("--resume");
        }
        let o = cmd.output().unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stdout).into_owned(),
        )
    };
    let whole = dir.join("whole");
    assert_eq!(run(&whole, false).0, Some(0));
    let expected = std::fs::read_to_string(whole.join("evaluations.jsonl")).unwrap();
    // the start and generation 1 (two candidates) kept, the rest lost
    let cut = dir.join("cut");
    std::fs::create_dir_all(&cut).unwrap();
    let kept: Vec<&str> = expected.lines().take(3).collect();
    std::fs::write(cut.join("evaluations.jsonl"), kept.join("\n") + "\n").unwrap();
    let (code, stdout) = run(&cut, true);
    assert_eq!(code, Some(0), "{stdout}");
    assert!(
        stdout.contains("generation 1/3") && stdout.contains("(replayed from the log)"),
        "{stdout}"
    );
    assert_eq!(
        std::fs::read_to_string(cut.join("evaluations.jsonl")).unwrap(),
        expected
    );
    // a real Ctrl-C in the middle of a longer search: sent once the log shows it running, it
    // must stop it (exit 130, saying so, the log short of the whole), and --resume completes it
    // to the same log as a search never interrupted
    let long = dir.join("long.toml");
    std::fs::write(
        &long,
        spec("", Some(("generations = 1", "generations = 40"))),
    )
    .unwrap();
    let search = |out: &std::path::Path, resume: bool| {
        let mut cmd = hexsim();
        cmd.arg("optimize")
            .arg(&long)
            .arg("--output")
            .arg(out)
            .arg("--no-record");
        if resume {
            cmd.arg("--resume");
        }
        cmd
    };
    let whole_long = dir.join("whole-long");
    assert_eq!(
        search(&whole_long, false).output().unwrap().status.code(),
        Some(0)
    );
    let expected = std::fs::read_to_string(whole_long.join("evaluations.jsonl")).unwrap();
    let real = dir.join("real");
    let child = search(&real, false)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let log = real.join("evaluations.jsonl");
    let started = std::time::Instant::now();
    while std::fs::read_to_string(&log).map_or(0, |t| t.lines().count()) < 3 {
        assert!(started.elapsed().as_secs() < 60, "the search never logged");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let kill = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success(), "kill -INT failed");
    let out = child.wait_with_output().unwrap();
    let said =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{said}");
    assert!(said.contains("interrupted"), "{said}");
    let logged = std::fs::read_to_string(&log).unwrap().lines().count();
    assert!(
        logged < expected.lines().count(),
        "the interrupt came after the search's end: {logged} lines logged"
    );
    assert_eq!(search(&real, true).output().unwrap().status.code(), Some(0));
    assert_eq!(std::fs::read_to_string(&log).unwrap(), expected);
}

/// A search spread over shards, as a cluster's array jobs run it (each step every shard's slice
/// of one generation, then --resume), logs exactly what one process does, line for line; a
/// choice (the swing shape) and a phase offset are searched along, and logged by value.
#[test]
fn a_sharded_search_joins_to_the_same_log() {
    let dir = scratch("optimize-shards");
    let file = dir.join("sharded.toml");
    let terrains = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains");
    let searched = concat!(
        "\"gait.period\" = [0.8, 1.2]\n",
        "\"gait.swing\" = [\"sine\", \"cycloid\", \"rectangle\"]\n",
        "\"gait.phase_offsets.rf\" = [0.3, 0.7]",
    );
    let text = spec(
        "",
        Some((
            "\"gait.period\" = [0.8, 1.2]\n\"gait.stride_length\" = [0.04, 0.08]",
            searched,
        )),
    )
    .replace("generations = 1", "generations = 2")
    .replace("population = 2", "population = 3")
    .replace(
        "seeds = [3]",
        &format!(
            "seeds = [3]\nterrains = [{:?}, {:?}]",
            terrains.join("natural.toml"),
            terrains.join("flat.toml")
        ),
    );
    std::fs::write(&file, text).unwrap();
    let run = |out: &std::path::Path, extra: &[&str]| {
        let o = hexsim()
            .arg("optimize")
            .arg(&file)
            .arg("--output")
            .arg(out)
            .arg("--no-record")
            .args(extra)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{extra:?}: {stdout}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        stdout
    };
    let whole = dir.join("whole");
    run(&whole, &[]);
    let expected = std::fs::read_to_string(whole.join("evaluations.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = expected
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 1 + 2 * 3);
    for line in &lines {
        // each candidate walks the natural terrain's seed and the flat ground (no seed: once)
        let walked: Vec<&str> = line["metrics"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m["terrain"].as_str().unwrap())
            .collect();
        assert_eq!(walked, ["natural seed 3", "flat"], "{line}");
        let p = &line["parameters"];
        let swing = p["gait.swing"].as_str().unwrap();
        assert!(["sine", "cycloid", "rectangle"].contains(&swing), "{line}");
        let rf = p["gait.phase_offsets.rf"].as_f64().unwrap();
        assert!((0.3..=0.7).contains(&rf), "{line}");
    }
    // two shards, one generation per step; a step ahead of its generation has nothing to run
    let sharded = dir.join("sharded");
    let mut done = false;
    for _step in 0..4 {
        let first = run(&sharded, &["--shard", "1/2"]);
        let second = run(&sharded, &["--shard", "2/2"]);
        if first.contains("are all logged") && second.contains("are all logged") {
            done = true;
            break;
        }
        assert!(first.contains("shard 1/2: ran"), "{first}");
        assert!(second.contains("shard 2/2: ran"), "{second}");
    }
    assert!(done, "two generations take two steps");
    assert!(
        !sharded.join("evaluations.jsonl").exists() || {
            std::fs::read_to_string(sharded.join("evaluations.jsonl"))
                .unwrap()
                .is_empty()
        }
    );
    let end = run(&sharded, &["--resume"]);
    assert!(end.contains("(replayed from the log)"), "{end}");
    assert_eq!(
        std::fs::read_to_string(sharded.join("evaluations.jsonl")).unwrap(),
        expected
    );
    let best = std::fs::read_to_string(sharded.join("best_gait.toml")).unwrap();
    assert!(
        best.contains("swing = ") && best.contains("rf = "),
        "{best}"
    );
}

/// A folder's log belongs to the specification that wrote it: resuming with the objective, the
/// duration or the seeds changed is refused, naming what changed (it would replay the old
/// objectives as the new ones), and so is a stale shard file of another specification.
#[test]
fn a_changed_specification_does_not_replay_another_ones_log() {
    let dir = scratch("optimize-fingerprint");
    let out = dir.join("out");
    let run = |text: String, resume: bool| {
        let file = dir.join("search.toml");
        std::fs::write(&file, text).unwrap();
        let mut cmd = hexsim();
        cmd.arg("optimize")
            .arg(&file)
            .arg("--output")
            .arg(&out)
            .arg("--no-record");
        if resume {
            cmd.arg("--resume");
        }
        let o = cmd.output().unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, stderr) = run(spec("", None), false);
    assert_eq!(code, Some(0), "{stderr}");
    let (code, stderr) = run(spec("", None), true);
    assert_eq!(code, Some(0), "the same specification resumes: {stderr}");
    for (change, named) in [
        (
            ("forward_distance = 1.0", "forward_distance = 2.0"),
            "objective",
        ),
        (("duration = 1.0", "duration = 1.5"), "duration"),
        (("seeds = [3]", "seeds = [5]"), "terrains and seeds"),
    ] {
        let (code, stderr) = run(spec("", Some(change)), true);
        assert_eq!(code, Some(2), "{change:?}: {stderr}");
        assert!(
            stderr.contains("holds evaluations of another specification")
                && stderr.contains(&format!("its {named} changed")),
            "{change:?}: {stderr}"
        );
    }
    // a shard file left by another search in the folder
    let main = std::fs::read_to_string(out.join("evaluations.jsonl")).unwrap();
    let first = main.lines().next().unwrap();
    let v: serde_json::Value = serde_json::from_str(first).unwrap();
    let stale = first.replace(v["specification"].as_str().unwrap(), "0123456789abcdef");
    std::fs::write(out.join("shard-0-of-2.jsonl"), stale + "\n").unwrap();
    let (code, stderr) = run(spec("", None), true);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("shard-0-of-2.jsonl: evaluations of another specification"),
        "{stderr}"
    );
}

/// The scenario names its robot by path: a search's log belongs to the robot's content too.
/// With the body's mass doubled in the URDF, resuming is refused naming the URDF (it replayed
/// the old log as the new robot's, whose best differs).
#[test]
fn a_changed_robot_does_not_replay_the_old_robots_log() {
    let dir = scratch("optimize-robot");
    for file in ["hex18.urdf", "hex18.toml"] {
        std::fs::copy(
            common::project_file(&format!("robots/{file}")),
            dir.join(file),
        )
        .unwrap();
    }
    let file = dir.join("search.toml");
    let text = spec(
        "",
        Some(("[scenario]\n", "[scenario]\nrobot = \"hex18.urdf\"\n")),
    );
    std::fs::write(&file, text).unwrap();
    let out = dir.join("out");
    let run = |resume: bool| {
        let mut cmd = hexsim();
        cmd.arg("optimize")
            .arg(&file)
            .arg("--output")
            .arg(&out)
            .arg("--no-record");
        if resume {
            cmd.arg("--resume");
        }
        let o = cmd.output().unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, stderr) = run(false);
    assert_eq!(code, Some(0), "{stderr}");
    let urdf = dir.join("hex18.urdf");
    let body = std::fs::read_to_string(&urdf).unwrap();
    let doubled = body.replacen(r#"<mass value="1.5"/>"#, r#"<mass value="3.0"/>"#, 1);
    assert_ne!(body, doubled);
    std::fs::write(&urdf, doubled).unwrap();
    let (code, stderr) = run(true);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("holds evaluations of another specification")
            && stderr.contains("its robot hex18.urdf changed"),
        "{stderr}"
    );
}
