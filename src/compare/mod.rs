//! Contact models side by side (`hexsim compare FILE`): one scenario — a ball or a walk — run
//! under several contact settings (normal and friction laws, the paper's variant, stiffness,
//! damping, rolling resistance…), each a set of `[contact]` fields laid over the scenario's, the
//! runs in parallel, their metrics in one table and their motion in one recording
//! (`compare::recording`).
//!
//! ```toml
//! description = "the ball on the bell: hexsim's contact, the paper's, with rolling resistance"
//! scenario = "../scenarios/ball_bell.toml"
//! duration = 20.0                 # optional: overrides the scenario's
//! [[setting]]
//! name = "hexsim"                 # no fields: the scenario's own contact
//! [[setting]]
//! name = "paper"
//! contact = { variant = "paper" }
//! ```

pub mod recording;

use crate::record::table::{SharedTable, Table};
use crate::runner::{Output, Outputs};
use crate::scenario::{self, Report, Scenario, ScenarioError};
use rayon::prelude::*;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// At most this many settings, each drawn in its own colour.
pub const MAX_SETTINGS: usize = 8;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CompareSpec {
    #[serde(default)]
    description: Option<String>,
    scenario: PathBuf,
    #[serde(default)]
    duration: Option<f64>,
    #[serde(rename = "setting", default)]
    settings: Vec<SettingSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SettingSpec {
    name: String,
    #[serde(default)]
    contact: toml::Table,
}

/// A comparison ready to run: the scenario once per setting, each named by its setting.
pub struct Comparison {
    pub file: PathBuf,
    pub description: Option<String>,
    pub settings: Vec<Scenario>,
}

/// Reads a comparison file and resolves the scenario under each setting; errors name the file,
/// the setting and the field.
pub fn load(path: &Path) -> Result<Comparison, ScenarioError> {
    let fail = |message: String| ScenarioError {
        file: path.to_path_buf(),
        message,
    };
    let text = crate::limits::read_to_string(path, crate::limits::TEXT_FILE_BYTES)
        .map_err(|e| fail(format!("cannot read the comparison file: {e}")))?;
    let spec: CompareSpec =
        toml::from_str(&text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
    if spec.settings.is_empty() {
        return Err(fail(
            "expected at least one [[setting]] (a name and the [contact] fields it changes)".into(),
        ));
    }
    if spec.settings.len() > MAX_SETTINGS {
        return Err(fail(format!(
            "{} settings: expected at most {MAX_SETTINGS}",
            spec.settings.len()
        )));
    }
    for (k, s) in spec.settings.iter().enumerate() {
        let clean = !s.name.is_empty()
            && s.name
                .chars()
                .all(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | '.' | ' '));
        if !clean {
            return Err(fail(format!(
                "setting {}: name {:?}: expected letters, digits, spaces, '-', '_' or '.'",
                k + 1,
                s.name
            )));
        }
        if spec.settings[..k].iter().any(|o| o.name == s.name) {
            return Err(fail(format!(
                "setting {:?} is named twice: expected distinct names",
                s.name
            )));
        }
    }
    if let Some(d) = spec.duration {
        crate::limits::check_number(d, crate::limits::Range::Positive, "s")
            .map_err(|e| fail(format!("duration: {e}")))?;
    }
    let (scenario_path, table) = scenario::read_table(path, &spec.scenario).map_err(fail)?;
    if table.contains_key("sweep") {
        return Err(fail(format!(
            "scenario {}: has a [sweep]; expected one scenario (the settings are the comparison)",
            scenario_path.display()
        )));
    }
    let mut settings = Vec::with_capacity(spec.settings.len());
    for setting in &spec.settings {
        let mut table = table.clone();
        if let Some(d) = spec.duration {
            table.insert("duration".into(), toml::Value::Float(d));
        }
        scenario::overlay::set_all(&mut table, "contact", setting.contact.clone())
            .map_err(|e| fail(format!("scenario {}: {e}", scenario_path.display())))?;
        let resolved = scenario::from_table(table, setting.name.clone(), &scenario_path)
            .map_err(|e| fail(format!("setting {:?}: {e}", setting.name)))?;
        settings.push(resolved);
    }
    Ok(Comparison {
        file: path.to_path_buf(),
        description: spec.description,
        settings,
    })
}

/// One setting's run: its report (or why it could not run) and its trajectory, kept in memory
/// (empty when it could not run).
pub struct Outcome {
    pub name: String,
    pub report: anyhow::Result<Report>,
    pub trajectory: Table,
}

/// Runs every setting, in parallel on `jobs` threads (each run alone is deterministic), keeping
/// each trajectory in memory and, given a folder, also writing it there as NAME.csv.
pub fn run(
    comparison: &Comparison,
    trajectories: Option<&Path>,
    jobs: usize,
) -> anyhow::Result<Vec<Outcome>> {
    if let Some(dir) = trajectories {
        crate::record::output::create_folder(dir, "--trajectories")?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()?;
    Ok(pool.install(|| {
        comparison
            .settings
            .par_iter()
            .map(|s| {
                let table = SharedTable::new();
                let file = trajectories.map(|dir| {
                    Output::Trajectory(dir.join(format!("{}.csv", s.name.replace(' ', "_"))))
                });
                let report = s.run(
                    Outputs::new()
                        .with(Output::Table(table.clone()))
                        .with_some(file),
                );
                Outcome {
                    name: s.name.clone(),
                    report,
                    trajectory: table.take(),
                }
            })
            .collect()
    }))
}
