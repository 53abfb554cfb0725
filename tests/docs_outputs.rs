//! docs/outputs.md against real outputs: every trajectory column and metrics key a run writes is
//! documented there, and everything documented there is written (or, for a batch record, a key
//! the format has).

mod common;
use common::Scratch;
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

/// The first cell's backticked names of each table row under the section whose title starts
/// with `section`.
fn documented(section: &str) -> Vec<String> {
    let page =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/outputs.md"))
            .unwrap();
    let start = page
        .find(&format!("## {section}"))
        .unwrap_or_else(|| panic!("docs/outputs.md has no section `{section}`"));
    let body = &page[start + 3..];
    let body = &body[..body.find("\n## ").unwrap_or(body.len())];
    let mut names = Vec::new();
    for row in body.lines().filter(|l| l.starts_with("| `")) {
        let cell = row.trim_start_matches('|').split(" | ").next().unwrap();
        names.extend(cell.split('`').skip(1).step_by(2).map(str::to_string));
    }
    assert!(!names.is_empty(), "no rows under `{section}`");
    names
}

/// Whether a column matches a documented pattern: `{leg}` a leg's name, `{joint}` any name.
fn matches(pattern: &str, column: &str) -> bool {
    if let Some(rest) = pattern.strip_prefix("{leg}_") {
        ["lf", "lm", "lr", "rf", "rm", "rr"]
            .iter()
            .any(|leg| column == format!("{leg}_{rest}"))
    } else if let Some(rest) = pattern.strip_prefix("{joint}_") {
        column.len() > rest.len() + 1 && column.ends_with(&format!("_{rest}"))
    } else {
        pattern == column
    }
}

/// Each column matches exactly one documented pattern, and each pattern some column.
fn check_columns(section: &str, header: &str) {
    let patterns = documented(section);
    let columns: Vec<&str> = header.trim().split(',').collect();
    for column in &columns {
        let found: Vec<&String> = patterns.iter().filter(|p| matches(p, column)).collect();
        assert_eq!(
            found.len(),
            1,
            "{section}: column `{column}` matches {found:?}"
        );
    }
    for pattern in &patterns {
        assert!(
            columns.iter().any(|c| matches(pattern, c)),
            "{section}: `{pattern}` is documented but not written"
        );
    }
}

/// The keys of a metrics object, with those of its `stance`, `ground` and `metadata` objects as
/// `stance.KEY`.
fn keys(metrics: &Value) -> BTreeSet<String> {
    let mut keys = BTreeSet::new();
    for (key, value) in metrics.as_object().unwrap() {
        keys.insert(key.clone());
        if matches!(key.as_str(), "stance" | "ground" | "metadata") {
            for inner in value.as_object().unwrap().keys() {
                keys.insert(format!("{key}.{inner}"));
            }
        }
    }
    keys
}

fn run(dir: &Path, args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_hexsim"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_outputs_page_lists_every_column_and_key_a_run_writes() {
    let dir = Scratch::new("hexsim-docs-outputs-");
    run(
        &dir,
        &[
            "run",
            "--duration",
            "0.5",
            "--no-record",
            "--trajectory",
            "walk.csv",
            "--metrics",
            "walk.json",
        ],
    );
    run(
        &dir,
        &[
            "ball",
            "--duration",
            "0.5",
            "--no-record",
            "--trajectory",
            "ball.csv",
            "--metrics",
            "ball.json",
        ],
    );
    let header = |f: &str| {
        let text = std::fs::read_to_string(dir.join(f)).unwrap();
        text.lines().next().unwrap().to_string()
    };
    check_columns("Trajectory CSV of a walk", &header("walk.csv"));
    check_columns("Trajectory CSV of a ball", &header("ball.csv"));
    for (section, file) in [
        ("Metrics JSON of a walk", "walk.json"),
        ("Metrics JSON of a ball", "ball.json"),
    ] {
        let metrics: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(file)).unwrap()).unwrap();
        let written = keys(&metrics);
        let listed: BTreeSet<String> = documented(section).into_iter().collect();
        let missing: Vec<_> = written.difference(&listed).collect();
        let stale: Vec<_> = listed.difference(&written).collect();
        assert!(missing.is_empty(), "{section}: not documented: {missing:?}");
        assert!(
            stale.is_empty(),
            "{section}: documented, not written: {stale:?}"
        );
    }
}

#[test]
fn the_outputs_page_lists_every_key_of_a_batch_record() {
    let dir = Scratch::new("hexsim-docs-batch-");
    std::fs::write(
        dir.join("drop.toml"),
        "kind = \"ball\"\nduration = 0.3\n[terrain.source]\nkind = \"flat\"\nsize = [4.0, 4.0]\n",
    )
    .unwrap();
    run(&dir, &["batch", "drop.toml", "-q", "-o", "r.jsonl"]);
    let text = std::fs::read_to_string(dir.join("r.jsonl")).unwrap();
    let record: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    let listed: BTreeSet<String> = documented("Batch results").into_iter().collect();
    for key in record.as_object().unwrap().keys() {
        assert!(
            listed.contains(key),
            "batch record key `{key}` not documented"
        );
    }
    // the keys written only sometimes are the documented ones the record lacks
    let absent: BTreeSet<&str> = listed
        .iter()
        .map(String::as_str)
        .filter(|k| record.get(*k).is_none())
        .collect();
    assert_eq!(absent, BTreeSet::from(["message", "regressions"]));
    // the record's metadata is a metrics file's, and agrees with the keys --resume reads
    let metadata = &record["metadata"];
    assert_eq!(metadata["fingerprint"], record["hash"]);
    assert_eq!(metadata["inputs"], record["inputs"]);
    assert!(
        metadata["dt"].as_f64().is_some_and(|dt| dt > 0.0),
        "{metadata}"
    );
}

/// The benchmark's JSON: its top-level keys are the section's rows, and every key of a figure
/// is named in the `figures[]` row.
#[test]
fn the_outputs_page_lists_every_key_of_the_benchmark() {
    let dir = Scratch::new("hexsim-docs-bench-");
    run(
        &dir,
        &[
            "bench",
            "--articulation",
            "multibody",
            "--duration",
            "0.2",
            "--repeats",
            "1",
            "--jobs",
            "1",
            "--json",
            "bench.json",
        ],
    );
    let bench: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("bench.json")).unwrap()).unwrap();
    let listed: BTreeSet<String> = documented("Benchmark")
        .into_iter()
        .map(|k| k.trim_end_matches("[]").to_string())
        .collect();
    let written: BTreeSet<String> = bench.as_object().unwrap().keys().cloned().collect();
    // `mujoco` only with --mujoco
    let mut expected = written.clone();
    expected.insert("mujoco".into());
    assert_eq!(listed, expected);
    let page =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/outputs.md"))
            .unwrap();
    let row = page
        .lines()
        .find(|l| l.starts_with("| `figures[]`"))
        .expect("a row for the figures");
    for key in bench["figures"][0].as_object().unwrap().keys() {
        assert!(
            row.contains(&format!("`{key}`")),
            "figure key `{key}` not documented"
        );
    }
}
