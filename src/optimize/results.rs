//! A search's results in its output folder: the best gait as a gait file (`best_gait.toml`),
//! the summary (`summary.json`: evaluations, start and best, later each terrain's check) and a
//! table of the start against the best, which the search's recording and the command show.

use super::check::CaseCheck;
use super::search::Searched;
use super::{Optimization, log};
use anyhow::Result;
use std::path::{Path, PathBuf};

/// The results written so far.
pub struct Results {
    pub gait: PathBuf,
    pub summary_path: PathBuf,
    pub summary: serde_json::Value,
    /// The start against the best, parameter by parameter, and their objectives (Markdown).
    pub table: String,
}

/// `opt`'s results for the best `x` (objective `objective`) that `searched` found, the search
/// given as `file`, written to `output`; `wall_time` in seconds.
pub fn write(
    opt: &Optimization,
    file: &Path,
    output: &Path,
    searched: &Searched,
    (objective, x): (f64, &[f64]),
    wall_time: f64,
) -> Result<Results> {
    let start_objective = searched.start.as_ref().and_then(|s| s.objective);
    let shown = |o: Option<f64>| o.map_or("failed".to_string(), |o| format!("{o:.4}"));
    let gait = output.join("best_gait.toml");
    crate::record::output::write_atomically(
        &gait,
        format!(
            "# found by `hexsim optimize {}`: objective {objective:.4} (start {})\n{}",
            file.display(),
            shown(start_objective),
            opt.gait_file(x)
        )
        .as_bytes(),
    )?;
    let summary = serde_json::json!({
        "optimization": file.display().to_string(),
        "evaluations": searched.history.len(),
        "failed": searched.history.iter().filter(|e| e.objective.is_none()).count(),
        "wall_time_s": wall_time,
        "start": { "parameters": opt.values(&opt.start), "objective": start_objective },
        "best": { "parameters": opt.values(x), "objective": objective },
    });
    let mut table = String::from("| parameter | start | best |\n|---|---|---|\n");
    let values = (opt.values(&opt.start), opt.values(x));
    for p in &opt.parameters {
        let cell = |v: &serde_json::Value| match v {
            serde_json::Value::Number(n) => format!("{:.4}", n.as_f64().unwrap_or(f64::NAN)),
            other => other.as_str().unwrap_or("").to_string(),
        };
        table += &format!(
            "| {} | {} | {} |\n",
            p.name,
            cell(&values.0[&p.name]),
            cell(&values.1[&p.name])
        );
    }
    table += &format!(
        "| **objective** | {} | {objective:.4} |\n",
        shown(start_objective)
    );
    let results = Results {
        gait,
        summary_path: output.join("summary.json"),
        summary,
        table,
    };
    // written now, so the summary survives checks that Ctrl-C cuts short
    results.write_summary()?;
    Ok(results)
}

impl Results {
    fn write_summary(&self) -> Result<()> {
        crate::record::output::write_atomically(
            &self.summary_path,
            (serde_json::to_string_pretty(&self.summary)? + "\n").as_bytes(),
        )?;
        Ok(())
    }

    /// The files so far: the best gait, the log, the summary.
    pub fn files(&self, output: &Path) -> Vec<PathBuf> {
        vec![
            self.gait.clone(),
            log::main_file(output),
            self.summary_path.clone(),
        ]
    }

    /// Writes the search's recording (`search.rrd` in `output`), its text the table and what was
    /// searched.
    pub fn record(
        &self,
        opt: &Optimization,
        file: &Path,
        output: &Path,
        searched: &Searched,
    ) -> Result<PathBuf> {
        let failed = self.summary["failed"].as_u64().unwrap_or(0);
        let text = format!(
            "# {}\n\n{}\n\n{}\n\n{} evaluations ({failed} failed) on {}.\n",
            file.display(),
            opt.description.as_deref().unwrap_or(""),
            self.table,
            searched.history.len(),
            opt.searched()
                .iter()
                .map(|c| c.label())
                .collect::<Vec<_>>()
                .join(", "),
        );
        super::recording::write(&output.join("search.rrd"), opt, &searched.history, &text)
    }

    /// Adds each terrain's check to the summary and writes it again.
    pub fn add_checks(&mut self, checks: &[CaseCheck]) -> Result<()> {
        self.summary["per_terrain"] =
            serde_json::Value::Array(checks.iter().map(CaseCheck::to_json).collect());
        self.write_summary()
    }
}
