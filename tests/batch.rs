//! `hexsim batch` and `hexsim merge` end to end: exit codes, resume, shards, threads, baselines.
//! The scenarios are short (mostly balls, two 1-s walks) so the suite stays fast.

mod common;
use common::Scratch;
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn hexsim(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hexsim"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn scratch(name: &str) -> Scratch {
    let dir = Scratch::new(&format!("hexsim-batch-{name}-"));
    std::fs::create_dir_all(dir.join("scenarios")).unwrap();
    dir
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join("scenarios").join(name), text).unwrap();
}

const FLAT: &str = "[terrain.source]\nkind = \"flat\"\nsize = [4.0, 4.0]\n";

/// A sweep of 7 ball drops (uneven across 3 shards) and one that bounces too high for its
/// expectation.
fn balls(dir: &Path) {
    write(
        dir,
        "drops.toml",
        &format!(
            "kind = \"ball\"\nduration = 0.6\n{FLAT}[expect]\nmax_penetration_mm = 30\n[sweep]\n\"ball.drop_height\" = {{ from = 0.1, to = 0.4, count = 7 }}\n"
        ),
    );
    write(
        dir,
        "too_bouncy.toml",
        &format!(
            "kind = \"ball\"\nduration = 1.0\n{FLAT}[contact]\ndamping = 28.28\n[expect]\napex_max = 0.2\n"
        ),
    );
}

fn walks(dir: &Path) {
    for (name, gait) in [("tripod", "tripod"), ("wave", "wave")] {
        let gaits = Path::new(env!("CARGO_MANIFEST_DIR")).join("gaits");
        write(
            dir,
            &format!("walk_{name}.toml"),
            &format!(
                "gait = \"{}/{gait}.toml\"\nduration = 1.0\nsettle = 0.3\n{FLAT}[expect]\nmax_tilt_deg = 10\n",
                gaits.display()
            ),
        );
    }
}

fn records(path: &Path) -> Vec<Value> {
    let mut list: Vec<Value> = std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    list.sort_by_key(|r| r["index"].as_u64());
    list
}

/// What must not change between runs of the same scenarios (everything but timings).
fn results(path: &Path) -> Vec<Value> {
    records(path)
        .into_iter()
        .map(|mut r| {
            r["wall_time_s"] = Value::Null;
            r["steps_per_second"] = Value::Null;
            r
        })
        .collect()
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn a_failing_expectation_exits_1_and_says_which() {
    let dir = scratch("fail");
    balls(&dir);
    let out = hexsim(&["batch", "scenarios", "-o", "r.jsonl"], &dir);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    let t = text(&out);
    assert!(t.contains("too_bouncy") && t.contains("apex_max"), "{t}");
    assert!(t.contains("7 passed, 1 failed"), "{t}");
    let r = records(&dir.join("r.jsonl"));
    assert_eq!(r.len(), 8);
    let bouncy = r.iter().find(|r| r["name"] == "too_bouncy").unwrap();
    assert_eq!(bouncy["status"], "failed");
    let apex = &bouncy["expectations"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["expectation"] == "apex_max")
        .unwrap();
    assert_eq!(apex["passed"], false);
    assert!(apex["value"].as_f64().unwrap() > 0.2);
    // names come from the sweep's parameters
    assert!(r.iter().any(|r| r["name"] == "drops[drop_height=0.1]"));
}

#[test]
fn resume_keeps_finished_results_and_reruns_the_rest() {
    let dir = scratch("resume");
    balls(&dir);
    hexsim(&["batch", "scenarios", "-o", "r.jsonl"], &dir);
    let first = std::fs::read_to_string(dir.join("r.jsonl")).unwrap();
    // as if the batch had been killed while writing its last line, and had not run two others
    let lines: Vec<&str> = first.lines().collect();
    let cut = format!("{}\n{}", lines[..5].join("\n"), &lines[5][..20]);
    std::fs::write(dir.join("r.jsonl"), cut).unwrap();
    let out = hexsim(&["batch", "scenarios", "-o", "r.jsonl", "--resume"], &dir);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(text(&out).contains("5 results kept"), "{}", text(&out));
    let after = records(&dir.join("r.jsonl"));
    assert_eq!(after.len(), 8);
    // the kept ones are the very same lines (same wall time), the rest were run again
    for line in &lines[..5] {
        let kept: Value = serde_json::from_str(line).unwrap();
        assert!(after.contains(&kept), "{} was run again", kept["name"]);
    }
    assert_eq!(results(&dir.join("r.jsonl")).len(), 8);
}

/// A shard says what concerns its own scenarios only: the wave walk's note (the smaller time step
/// hexsim chose for its landing feet) in the shard that runs it, not in the tripod's.
#[test]
fn a_shard_notes_only_its_own_scenarios() {
    let dir = scratch("shard-notes");
    walks(&dir);
    let notes = |shard: &str| {
        let out = hexsim(
            &["batch", "scenarios", "--shard", shard, "-o", "s.jsonl"],
            &dir,
        );
        let all = text(&out);
        let ran: Vec<String> = records(&dir.join("s.jsonl"))
            .iter()
            .map(|r| r["name"].as_str().unwrap().to_string())
            .collect();
        std::fs::remove_file(dir.join("s.jsonl")).unwrap();
        let notes: Vec<String> = all
            .lines()
            .filter(|l| l.starts_with("note: "))
            .map(str::to_string)
            .collect();
        (ran, notes, all)
    };
    let whole = notes("1/1");
    assert!(
        whole
            .1
            .iter()
            .any(|n| n.contains("dt: ") && n.contains("(walk_wave)")),
        "{}",
        whole.2
    );
    for shard in ["1/2", "2/2"] {
        let (ran, notes, all) = notes(shard);
        assert_eq!(ran.len(), 1, "{all}");
        let wave = ran[0] == "walk_wave";
        assert_eq!(notes.iter().any(|n| n.contains("dt: ")), wave, "{all}");
        assert!(
            !all.contains(if wave { "walk_tripod)" } else { "walk_wave" }),
            "{all}"
        );
    }
}

#[test]
fn shards_merged_equal_the_whole_batch_and_merge_refuses_gaps_and_repeats() {
    let dir = scratch("shards");
    balls(&dir);
    hexsim(
        &["batch", "scenarios", "-o", "whole.jsonl", "-j", "1"],
        &dir,
    );
    for i in 1..=3 {
        let shard = format!("{i}/3");
        let file = format!("s{i}.jsonl");
        let out = hexsim(
            &["batch", "scenarios", "--shard", &shard, "-o", &file],
            &dir,
        );
        assert!(out.status.code().is_some(), "{}", text(&out));
        assert!(records(&dir.join(&file)).len() >= 2);
    }
    let out = hexsim(
        &[
            "merge",
            "s1.jsonl",
            "s2.jsonl",
            "s3.jsonl",
            "-o",
            "merged.jsonl",
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", text(&out));
    let strip_shard = |mut v: Vec<Value>| {
        for r in &mut v {
            r["shard"] = Value::Null;
        }
        v
    };
    assert_eq!(
        strip_shard(results(&dir.join("merged.jsonl"))),
        strip_shard(results(&dir.join("whole.jsonl")))
    );
    let missing = hexsim(&["merge", "s1.jsonl", "s3.jsonl", "-o", "m.jsonl"], &dir);
    assert_eq!(missing.status.code(), Some(2));
    assert!(
        text(&missing).contains("shard 2/3 is missing"),
        "{}",
        text(&missing)
    );
    let twice = hexsim(
        &["merge", "s1.jsonl", "s2.jsonl", "s3.jsonl", "s2.jsonl"],
        &dir,
    );
    assert_eq!(twice.status.code(), Some(2));
    assert!(text(&twice).contains("appears twice"), "{}", text(&twice));
}

#[test]
fn one_thread_or_two_give_identical_results() {
    let dir = scratch("jobs");
    balls(&dir);
    walks(&dir);
    let one = hexsim(&["batch", "scenarios", "-o", "one.jsonl", "-j", "1"], &dir);
    let two = hexsim(&["batch", "scenarios", "-o", "two.jsonl", "-j", "2"], &dir);
    assert_eq!(one.status.code(), Some(1), "{}", text(&one));
    assert_eq!(two.status.code(), Some(1), "{}", text(&two));
    let (a, b) = (
        results(&dir.join("one.jsonl")),
        results(&dir.join("two.jsonl")),
    );
    assert_eq!(a.len(), 10);
    let walk = a.iter().find(|r| r["name"] == "walk_tripod").unwrap();
    assert!(
        walk["metrics"]["distance"].as_f64().unwrap() > 0.02,
        "{walk}"
    );
    assert_eq!(a, b, "results differ between --jobs 1 and --jobs 2");
}

#[test]
fn a_moved_metric_fails_against_the_baseline() {
    let dir = scratch("baseline");
    balls(&dir);
    std::fs::remove_file(dir.join("scenarios/too_bouncy.toml")).unwrap();
    let out = hexsim(&["batch", "scenarios", "-o", "base.jsonl"], &dir);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let same = hexsim(
        &[
            "batch",
            "scenarios",
            "-o",
            "r.jsonl",
            "--baseline",
            "base.jsonl",
        ],
        &dir,
    );
    assert_eq!(same.status.code(), Some(0), "{}", text(&same));
    // an earlier build in which one drop bounced 2 cm higher and penetrated 3 mm less
    let mut base = records(&dir.join("base.jsonl"));
    let r = base
        .iter_mut()
        .find(|r| r["name"] == "drops[drop_height=0.3]")
        .unwrap();
    let apex = r["metrics"]["first_apex_height"].as_f64().unwrap();
    r["metrics"]["first_apex_height"] = (apex - 0.02).into();
    let lines: Vec<String> = base.iter().map(|r| r.to_string()).collect();
    std::fs::write(dir.join("old.jsonl"), lines.join("\n")).unwrap();
    let out = hexsim(
        &[
            "batch",
            "scenarios",
            "-o",
            "r.jsonl",
            "--baseline",
            "old.jsonl",
        ],
        &dir,
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    let t = text(&out);
    assert!(
        t.contains("REGRESSED")
            && t.contains("drops[drop_height=0.3]")
            && t.contains("first_apex_height"),
        "{t}"
    );
    assert!(t.contains("1 regressed"), "{t}");
    // the results file says so too: that record's status, what moved, from what to what
    let after = records(&dir.join("r.jsonl"));
    let moved = after
        .iter()
        .find(|r| r["name"] == "drops[drop_height=0.3]")
        .unwrap();
    assert_eq!(moved["status"], "regressed", "{moved}");
    let regression = &moved["regressions"][0];
    assert_eq!(regression["metric"], "first_apex_height", "{moved}");
    let (old, new) = (
        regression["baseline"].as_f64().unwrap(),
        regression["value"].as_f64().unwrap(),
    );
    assert!((new - old - 0.02).abs() < 1e-9, "{regression}");
    assert!(
        regression["allowed"].as_f64().unwrap() < 0.02,
        "{regression}"
    );
    for r in after
        .iter()
        .filter(|r| r["name"] != "drops[drop_height=0.3]")
    {
        assert_eq!(r["status"], "passed", "{r}");
        assert!(r.get("regressions").is_none(), "{r}");
    }
    // resumed against the true baseline, the mark goes: the record says what this comparison found
    let out = hexsim(
        &[
            "batch",
            "scenarios",
            "-o",
            "r.jsonl",
            "--resume",
            "--baseline",
            "base.jsonl",
        ],
        &dir,
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(
        records(&dir.join("r.jsonl"))
            .iter()
            .all(|r| r["status"] == "passed")
    );
    // without a baseline there is nothing to regress against, and no line says otherwise
    let out = hexsim(&["batch", "scenarios", "-o", "plain.jsonl"], &dir);
    assert!(!text(&out).contains("regressed"), "{}", text(&out));
}

#[test]
fn a_broken_scenario_is_an_input_error_naming_file_and_field() {
    let dir = scratch("broken");
    write(&dir, "typo.toml", "duration = 1.0\nsetle = 0.5\n");
    write(&dir, "bad_dt.toml", "duration = 1.0\ndt = 0.5\n");
    write(
        &dir,
        "wrong_kind.toml",
        "kind = \"ball\"\nduration = 1.0\ngait = \"x.toml\"\n",
    );
    write(
        &dir,
        "bad_sweep.toml",
        "duration = 1.0\nterrain = \"t.toml\"\n[sweep]\n\"terrain.source.peak_to_peak\" = [0.1]\n",
    );
    let out = hexsim(&["batch", "scenarios"], &dir);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let t = text(&out);
    for expected in [
        "typo.toml",
        "unknown field `setle`",
        "bad_dt.toml: dt: expected a time step in (0, 0.01] s, got 0.5",
        "wrong_kind.toml: gait: applies to walk scenarios",
        "bad_sweep.toml",
        "`terrain` is a string",
        "4 scenario file problems; nothing was run",
    ] {
        assert!(t.contains(expected), "missing {expected:?} in:\n{t}");
    }
    assert!(!dir.join("results.jsonl").exists());
    let none = hexsim(&["batch", "no/such/folder"], &dir);
    assert_eq!(none.status.code(), Some(2));
    assert!(text(&none).contains("no/such/folder: no such scenario file or folder"));
}

/// A robot's feet are read from its meshes: a mesh edited since a result makes `--resume` run
/// that scenario again, saying which file changed, and keep the others.
#[test]
fn resume_reruns_a_scenario_whose_mesh_changed() {
    let dir = scratch("resume-mesh");
    let kraby = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/third_party/kraby");
    std::fs::create_dir_all(dir.join("kraby/meshes")).unwrap();
    for file in [
        "hexapod.urdf",
        "meshes/foot.stl",
        "meshes/joint.stl",
        "meshes/box.stl",
    ] {
        std::fs::copy(kraby.join(file), dir.join("kraby").join(file)).unwrap();
    }
    write(
        &dir,
        "kraby.toml",
        &format!("robot = \"../kraby/hexapod.urdf\"\nduration = 0.1\nsettle = 0.1\n{FLAT}"),
    );
    write(
        &dir,
        "drop.toml",
        &format!("kind = \"ball\"\nduration = 0.2\n{FLAT}"),
    );
    let out = hexsim(&["batch", "scenarios", "-o", "r.jsonl", "-q"], &dir);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let first = records(&dir.join("r.jsonl"));
    // re-exported: the binary STL's header differs
    let foot = dir.join("kraby/meshes/foot.stl");
    let mut bytes = std::fs::read(&foot).unwrap();
    bytes[..8].copy_from_slice(b"Edited  ");
    std::fs::write(&foot, bytes).unwrap();
    let out = hexsim(
        &["batch", "scenarios", "-o", "r.jsonl", "--resume", "-q"],
        &dir,
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(
        text(&out).contains("1 results kept")
            && text(&out).contains("kraby: ")
            && text(&out).contains("foot.stl changed"),
        "{}",
        text(&out)
    );
    let after = records(&dir.join("r.jsonl"));
    let of = |list: &[Value], name: &str| list.iter().find(|r| r["name"] == name).unwrap().clone();
    assert_eq!(of(&first, "drop"), of(&after, "drop"));
    assert_ne!(of(&first, "kraby")["hash"], of(&after, "kraby")["hash"]);
}

/// A scenario's recording or trajectory (`--record-dir`) may not be a file the batch reads (another
/// scenario's height file) nor its results file, and the results may not go to a folder: each is
/// refused before anything runs, and nothing is overwritten or left behind.
#[test]
fn a_scenarios_output_may_not_overwrite_an_input_or_the_results() {
    let dir = scratch("clobber");
    let heights = format!("{}\n", vec!["0.0"; 41].join(",")).repeat(41);
    std::fs::write(dir.join("scenarios/ground.csv"), &heights).unwrap();
    write(
        &dir,
        "a.toml",
        &format!("name = \"ground\"\nduration = 0.05\n{FLAT}[record]\ntrajectory = true\n"),
    );
    write(
        &dir,
        "b.toml",
        "name = \"b\"\nduration = 0.05\n[terrain.source]\nkind = \"csv\"\npath = \"ground.csv\"\n\
         x_range = [-2.0, 2.0]\ny_range = [-2.0, 2.0]\n",
    );
    let (a, b) = ("scenarios/a.toml", "scenarios/b.toml");
    let out = hexsim(&["batch", a, b, "-q", "--record-dir", "scenarios"], &dir);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        text(&out).contains(
            "scenario's trajectory scenarios/ground.csv: it is the terrain's height file"
        ),
        "{}",
        text(&out)
    );
    let out = hexsim(
        &[
            "batch",
            a,
            "-q",
            "-o",
            "rec/ground.csv",
            "--record-dir",
            "rec",
        ],
        &dir,
    );
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        text(&out).contains("it is the same file as the results file -o rec/ground.csv"),
        "{}",
        text(&out)
    );
    std::fs::create_dir(dir.join("out")).unwrap();
    let out = hexsim(&["batch", a, "-q", "-o", "out"], &dir);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(
        text(&out).contains("cannot write out: it is a folder"),
        "{}",
        text(&out)
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("scenarios/ground.csv")).unwrap(),
        heights
    );
    assert!(!dir.join("out.partial").exists() && !dir.join("results.jsonl").exists());
}
