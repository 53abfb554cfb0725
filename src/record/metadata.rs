//! Where a metrics file came from: the block a run's metrics JSON ends with, so that a result
//! read elsewhere names its inputs, their fingerprint, the version and the settings it ran with.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A run's provenance (docs/outputs.md lists each key).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metadata {
    pub hexsim_version: String,
    /// The scenario's name, and its file (null: made on the command line).
    pub scenario: String,
    pub scenario_file: Option<String>,
    /// The robot's URDF (walks; null for a ball).
    pub robot: Option<String>,
    pub terrain: String,
    /// The gait's file, "built in" or "inline" (walks; null for a ball).
    pub gait: Option<String>,
    /// The scenario's fingerprint: its fields, hexsim's version and the content of every file
    /// it read (what `batch --resume` compares).
    pub fingerprint: String,
    /// Every file it read → the first 16 hex digits of its content's SHA-256.
    pub inputs: BTreeMap<String, String>,
    /// The terrain generator's seed (null: it has none).
    pub seed: Option<u32>,
    /// The time step (s).
    pub dt: f64,
    /// "multibody" or "impulse" (walks; null for a ball).
    pub articulation: Option<String>,
    /// Each trajectory joint column's name (`lf_coxa`, …) → the URDF joint it is (walks; null
    /// for a ball).
    #[serde(default)]
    pub joints: Option<BTreeMap<String, String>>,
    /// The legs in the order of every per-foot array and column (`lf lm lr rf rm rr`; walks,
    /// null for a ball): a file read alone says whose each entry is.
    #[serde(default)]
    pub legs: Option<Vec<String>>,
}

/// Where a run's metrics are written, and the metadata they end with.
#[derive(Debug, Clone)]
pub struct MetricsFile {
    pub path: PathBuf,
    pub metadata: Option<Box<Metadata>>,
}

/// The metrics, then their metadata, as one JSON object.
#[derive(Serialize)]
struct Described<'a, T> {
    #[serde(flatten)]
    metrics: &'a T,
    #[serde(skip_serializing_if = "Option::is_none")]
    metadata: Option<&'a Metadata>,
}

/// Writes `metrics` to `file`, if there is one, ending with its metadata; returns its path.
pub fn write(
    file: Option<&MetricsFile>,
    metrics: &impl Serialize,
) -> anyhow::Result<Option<PathBuf>> {
    let Some(file) = file else { return Ok(None) };
    let described = Described {
        metrics,
        metadata: file.metadata.as_deref(),
    };
    super::output::write_json(Some(Path::new(&file.path)), &described)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_metadata_ends_the_metrics_object() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        let metadata = Metadata {
            hexsim_version: "0".into(),
            scenario: "s".into(),
            scenario_file: None,
            robot: None,
            terrain: "t".into(),
            gait: None,
            fingerprint: "f".into(),
            inputs: BTreeMap::new(),
            seed: Some(3),
            dt: 1e-3,
            articulation: None,
            joints: None,
            legs: None,
        };
        let file = MetricsFile {
            path: path.clone(),
            metadata: Some(Box::new(metadata)),
        };
        write(Some(&file), &serde_json::json!({"steps": 4})).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.starts_with("{\n  \"steps\": 4,\n  \"metadata\": {"),
            "{text}"
        );
        let read: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(read["metadata"]["seed"], 3);
    }
}
