//! The table printed at the end of a batch.

use super::results::{Record, Status};
use super::status_word;
use crate::metrics::{self, HexapodMetrics, Metric, Side, walk};
use crate::scenario::Kind;
use std::fmt::Write;

/// A walk's metric from a result (none for a ball, or a result without metrics).
fn walk_metric(r: &Record, metric: &Metric<HexapodMetrics>) -> Option<f64> {
    let m: HexapodMetrics = metrics::from_json(&r.metrics)?;
    (metric.value)(&m).bounded(Side::Max)
}

fn cell(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or("-".into(), |v| format!("{:.*}", digits, v * scale))
}

/// One row per result (only the ones that did not pass, when `all` is false), then the counts —
/// with the regressions against the baseline when one was given (`baseline`) — and the slowest
/// scenarios.
pub fn table(records: &[Record], baseline: bool, all: bool) -> String {
    let mut out = String::new();
    let shown: Vec<&Record> = records
        .iter()
        .filter(|r| all || r.status != Status::Passed)
        .collect();
    if !shown.is_empty() {
        let width = shown
            .iter()
            .map(|r| r.name.chars().count())
            .max()
            .unwrap_or(8)
            .max(8);
        let _ = writeln!(
            out,
            "{:<9} {:<width$} {:>7} {:>8} {:>8} {:>6} {:>7}  notes",
            "status", "scenario", "wall s", "steps/s", "dist m", "tilt°", "pen mm"
        );
        for r in shown {
            let walk = |metric| {
                (r.kind == Kind::Walk)
                    .then(|| walk_metric(r, metric))
                    .flatten()
            };
            // a ball's penetration too
            let penetration = match r.kind {
                Kind::Walk => walk(&walk::MAX_PENETRATION),
                Kind::Ball => metrics::from_json::<metrics::BallMetrics>(&r.metrics)
                    .map(|m| m.max_penetration),
            };
            let mut notes = r.message.clone().unwrap_or_default();
            let status = status_word(r.status);
            if !r.regressions.is_empty() {
                let moved: Vec<String> = r.regressions.iter().map(|m| m.to_string()).collect();
                if !notes.is_empty() {
                    notes.push_str("; ");
                }
                notes.push_str(&format!("moved: {}", moved.join(", ")));
            }
            let _ = writeln!(
                out,
                "{status:<9} {:<width$} {:>7.1} {:>8.0} {:>8} {:>6} {:>7}  {notes}",
                r.name,
                r.wall_time_s,
                r.steps_per_second,
                cell(walk(&walk::DISTANCE), 1.0, 3),
                cell(walk(&walk::TILT), 1.0, 1),
                cell(penetration, 1e3, 2),
            );
        }
        out.push('\n');
    }
    let count = |s: Status| records.iter().filter(|r| r.status == s).count();
    let _ = write!(
        out,
        "{} scenarios: {} passed, {} failed, {} diverged, {} errors",
        records.len(),
        count(Status::Passed) + count(Status::Regressed),
        count(Status::Failed),
        count(Status::Diverged),
        count(Status::Error),
    );
    if baseline {
        let moved = records.iter().filter(|r| !r.regressions.is_empty()).count();
        let _ = write!(out, "; {moved} regressed against the baseline");
    }
    out.push('\n');
    let mut slowest: Vec<&Record> = records.iter().collect();
    slowest.sort_by(|a, b| b.wall_time_s.total_cmp(&a.wall_time_s));
    let slowest: Vec<String> = slowest
        .iter()
        .take(3)
        .map(|r| format!("{} ({:.1} s)", r.name, r.wall_time_s))
        .collect();
    if !slowest.is_empty() {
        let _ = writeln!(out, "slowest: {}", slowest.join(", "));
    }
    out
}
