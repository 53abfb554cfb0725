//! After a search: the start and the best on every terrain and seed, searched and not, in both
//! articulations — what the search found, and how much of it the exact (multibody) joints keep.
//! The multibody runs are a comparison of two settings (start, best), recorded superposed.

use super::{Case, Optimization};
use crate::compare::{self, Comparison};
use crate::sim::Articulation;
use anyhow::Result;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// A check run: its objective (None: failed) and each constraint's measured value.
pub struct Checked {
    pub objective: Option<f64>,
    pub constraints: serde_json::Map<String, serde_json::Value>,
}

/// The start and the best on one terrain and seed.
pub struct CaseCheck<'a> {
    pub case: &'a Case,
    pub start_impulse: Option<f64>,
    pub best_impulse: Option<f64>,
    pub start_multibody: Checked,
    pub best_multibody: Checked,
}

impl CaseCheck<'_> {
    /// The summary's entry for it.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "terrain": self.case.terrain_name,
            "seed": self.case.seeded.then_some(self.case.seed),
            "searched": self.case.searched,
            "start_impulse": self.start_impulse,
            "best_impulse": self.best_impulse,
            "start_multibody": self.start_multibody.objective,
            "best_multibody": self.best_multibody.objective,
            "start_multibody_constraints": self.start_multibody.constraints,
            "best_multibody_constraints": self.best_multibody.constraints,
        })
    }
}

/// Checks the best `x` against the start on every case (on the calling rayon pool, `jobs`
/// threads for the multibody pairs). With a folder, each multibody pair is recorded to
/// FOLDER/TERRAIN-seed-S.rrd, their trajectories kept in FOLDER/trajectories/; the files written
/// are added to `written`. None when Ctrl-C cut the checks short: their runs are not results.
pub fn run<'a>(
    opt: &'a Optimization,
    x: &[f64],
    record: Option<&Path>,
    jobs: usize,
    written: &mut Vec<PathBuf>,
) -> Result<Option<Vec<CaseCheck<'a>>>> {
    let cases: Vec<&Case> = opt.cases.iter().collect();
    let (start_impulse, best_impulse) = rayon::join(
        || per_case(opt, &opt.start, &cases, Articulation::Impulse),
        || per_case(opt, x, &cases, Articulation::Impulse),
    );
    let mut multibody = Vec::new();
    for case in &cases {
        let (pair, path) = multibody_pair(opt, x, case, record, jobs)?;
        multibody.push(pair);
        written.extend(path);
    }
    if crate::runner::interrupted() {
        return Ok(None);
    }
    Ok(Some(
        cases
            .into_iter()
            .zip(start_impulse.into_iter().zip(best_impulse))
            .zip(multibody)
            .map(
                |((case, (start_impulse, best_impulse)), (start_multibody, best_multibody))| {
                    CaseCheck {
                        case,
                        start_impulse,
                        best_impulse,
                        start_multibody,
                        best_multibody,
                    }
                },
            )
            .collect(),
    ))
}

/// The objective of candidate `x` on each of `cases` in `articulation` (None where it failed).
fn per_case(
    opt: &Optimization,
    x: &[f64],
    cases: &[&Case],
    articulation: Articulation,
) -> Vec<Option<f64>> {
    cases
        .par_iter()
        .map(|&c| opt.evaluate_on(x, &[c], Some(articulation)).objective)
        .collect()
}

/// The start and the best walking `case` in the multibody; with a folder, recorded superposed.
fn multibody_pair(
    opt: &Optimization,
    x: &[f64],
    case: &Case,
    record: Option<&Path>,
    jobs: usize,
) -> Result<((Checked, Checked), Option<PathBuf>)> {
    let settings = [("start", &opt.start[..]), ("best", x)]
        .into_iter()
        .map(|(name, x)| opt.scenario(x, case, Some(Articulation::Multibody), name))
        .collect::<Result<Vec<_>, _>>()?;
    let comparison = Comparison {
        file: PathBuf::from(format!("{} {}", opt.name(), case.label())),
        description: opt.description.clone(),
        settings,
    };
    let trajectories = record.map(|dir| dir.join("trajectories").join(case.file_stem()));
    let outcomes = compare::run(&comparison, trajectories.as_deref(), jobs)?;
    let checked = |k: usize| Checked {
        objective: super::judge(case, &outcomes[k].report)
            .ok()
            .map(|m| opt.score(&m)),
        constraints: outcomes[k]
            .report
            .as_ref()
            .map(|r| {
                r.checks
                    .iter()
                    .map(|c| (c.expectation.clone(), serde_json::json!(c.value)))
                    .collect()
            })
            .unwrap_or_default(),
    };
    let pair = (checked(0), checked(1));
    let Some(dir) = record else {
        return Ok((pair, None));
    };
    let path = compare::recording::write_titled(
        &dir.join(format!("{}.rrd", case.file_stem())),
        &format!("start and best on {}", case.label()),
        &comparison,
        &outcomes,
    )?;
    Ok((pair, Some(path)))
}
