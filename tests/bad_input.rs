//! The bad-input corpus (tests/data/bad/cases.toml): every broken robot, terrain, gait and scenario
//! gets a clear message naming the file and the place, the right exit code, and no panic.

use std::path::Path;
use std::process::Command;

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Case {
    file: String,
    read: String,
    #[serde(default = "two")]
    exit: i32,
    expect: Vec<String>,
}

fn two() -> i32 {
    2
}

#[derive(serde::Deserialize)]
struct Corpus {
    case: Vec<Case>,
}

#[test]
fn every_bad_file_gets_its_clear_message() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = root.join("tests/data/bad");
    let corpus: Corpus =
        toml::from_str(&std::fs::read_to_string(dir.join("cases.toml")).unwrap()).unwrap();
    let scratch = tempfile::Builder::new()
        .prefix("hexsim-bad-")
        .tempdir()
        .unwrap();
    let scratch = scratch.path();
    let results = scratch.join("results.jsonl");
    let mut failures = Vec::new();
    for case in &corpus.case {
        let file = dir.join(&case.file);
        let file = file.to_str().unwrap();
        let mut words = case.read.split_whitespace();
        let mut args: Vec<&str> = match words.next().unwrap() {
            "robot" => vec![
                "run",
                "--robot",
                file,
                "--duration",
                "0.001",
                "--settle",
                "0",
                "--no-record",
            ],
            "gait" => vec![
                "run",
                "--gait",
                file,
                "--duration",
                "0.001",
                "--settle",
                "0",
                "--no-record",
            ],
            "terrain" => vec!["terrain", "info", file],
            "scenario" => vec!["batch", file, "-q", "-o", results.to_str().unwrap()],
            other => panic!("{}: unknown reader {other}", case.file),
        };
        args.extend(words);
        let out = Command::new(env!("CARGO_BIN_EXE_hexsim"))
            .args(&args)
            .current_dir(scratch)
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        let mut problems = Vec::new();
        if out.status.code() != Some(case.exit) {
            problems.push(format!(
                "exit {:?}, expected {}",
                out.status.code(),
                case.exit
            ));
        }
        if text.contains("panicked") || text.contains("RUST_BACKTRACE") {
            problems.push("panicked".into());
        }
        for fragment in &case.expect {
            if !text.contains(fragment.as_str()) {
                problems.push(format!("no {fragment:?}"));
            }
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{} ({}): {}\n{text}",
                case.file,
                case.read,
                problems.join(", ")
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        corpus.case.len(),
        failures.join("\n")
    );
    assert!(
        corpus.case.len() >= 60,
        "the corpus shrank to {}",
        corpus.case.len()
    );
}
