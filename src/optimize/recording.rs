//! The recording of a gait search (`hexsim optimize`): over the evaluations (the `evaluation`
//! timeline), every candidate's objective and the best so far, and where each parameter was
//! sampled within its bounds — CMA-ES narrowing onto the best reads as the points converging —
//! and how many candidates failed, beside a table of the start against the best.

use super::{Domain, Optimization};
use crate::record::blueprint::{Layout, View};
use crate::record::rerun::Recording;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// The timeline: evaluations in the order the search asked for them (0: the start).
pub const TIMELINE: &str = "evaluation";

/// One evaluation, as the search told it.
pub struct Evaluated {
    pub x: Vec<f64>,
    /// None when it failed.
    pub objective: Option<f64>,
}

/// A colour per parameter.
const COLORS: [[u8; 3]; 8] = crate::compare::recording::COLORS;

fn layout() -> Layout {
    Layout::horizontal(
        vec![
            Layout::vertical(
                vec![
                    View::time_series("objective (maximised)", "plots/objective").into(),
                    View::time_series(
                        "parameters: 0 = lower bound, 1 = upper bound",
                        "plots/parameters",
                    )
                    .into(),
                    View::time_series("failed candidates so far", "plots/failures").into(),
                ],
                vec![0.42, 0.42, 0.16],
            ),
            View::text_document("start and best", "summary").into(),
        ],
        vec![0.68, 0.32],
    )
}

/// An entity name for a dotted parameter name.
fn entity(name: &str) -> String {
    name.replace('.', "_")
}

/// Writes the search's recording to `path`; `summary` is a Markdown table of the result.
pub fn write(
    path: &Path,
    opt: &Optimization,
    history: &[Evaluated],
    summary: &str,
) -> Result<PathBuf> {
    let recording = Recording::create_sequence(path, opt.name(), TIMELINE, &layout())?;
    let rec = recording.stream();
    rec.log_static("summary", &rerun::TextDocument::from_markdown(summary))?;
    rec.log_static(
        "plots/objective/evaluations",
        &rerun::SeriesPoints::new()
            .with_names(["candidate"])
            .with_colors([[60, 130, 230]])
            .with_marker_sizes([2.5]),
    )?;
    rec.log_static(
        "plots/objective/best",
        &rerun::SeriesLines::new()
            .with_names(["best so far"])
            .with_colors([[230, 80, 60]])
            .with_widths([2.0]),
    )?;
    for (k, p) in opt.parameters.iter().enumerate() {
        rec.log_static(
            format!("plots/parameters/{}", entity(&p.name)),
            &rerun::SeriesPoints::new()
                .with_names([p.name.as_str()])
                .with_colors([COLORS[k % COLORS.len()]])
                .with_marker_sizes([2.0]),
        )?;
    }
    rec.log_static(
        "plots/failures/failed",
        &rerun::SeriesLines::new()
            .with_names(["failed"])
            .with_colors([[150, 150, 150]]),
    )?;
    let mut best = f64::NEG_INFINITY;
    let mut failed = 0;
    for (n, e) in history.iter().enumerate() {
        recording.set_sequence(TIMELINE, n as i64);
        failed += usize::from(e.objective.is_none());
        recording.scalars("plots/failures/failed", &[failed as f64])?;
        if let Some(o) = e.objective {
            recording.scalars("plots/objective/evaluations", &[o])?;
            best = best.max(o);
        }
        if best.is_finite() {
            recording.scalars("plots/objective/best", &[best])?;
        }
        for (p, &x) in opt.parameters.iter().zip(&e.x) {
            let (low, high) = p.bounds();
            let share = match p.domain {
                // a choice: the centre of its cell
                Domain::Choice(ref names) => {
                    ((x.floor().clamp(0.0, names.len() as f64 - 1.0)) + 0.5) / names.len() as f64
                }
                Domain::Range { .. } => (x - low) / (high - low),
            };
            recording.scalars(format!("plots/parameters/{}", entity(&p.name)), &[share])?;
        }
    }
    recording.finish()
}
