//! The ladder as a picture a person reads at a glance (`ladder.svg`): per family a row blind
//! and a row perceptive, a cell per level coloured by how the run ended, with the distance it
//! got past its start in metres, and a mark where a foot or link sank past [`DEEP`]. Plain SVG,
//! for a browser or a page of docs; the numbers behind it are in `ladder.json`.

use super::{LadderResult, Outcome};
use std::fmt::Write;

/// A foot or link sunk deeper than this (m) is marked: the ground's spring let it in further
/// than a landing should.
pub const DEEP: f64 = 5e-3;

const CELL_W: f64 = 58.0;
const CELL_H: f64 = 24.0;
const LABEL_W: f64 = 190.0;
const MARGIN: f64 = 12.0;

fn colour(outcome: Outcome) -> (&'static str, &'static str) {
    match outcome {
        Outcome::Crossed => ("#66bb6a", "#000"),
        Outcome::Scrambled => ("#c5e1a5", "#000"),
        Outcome::Stalled => ("#ffca28", "#000"),
        Outcome::SlidBack => ("#ab47bc", "#fff"),
        Outcome::Fell => ("#e53935", "#fff"),
        Outcome::Diverged => ("#212121", "#fff"),
        Outcome::Error => ("#9e9e9e", "#000"),
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The chart of `result` as an SVG document.
pub fn svg(result: &LadderResult) -> String {
    let most_levels = result
        .families
        .iter()
        .map(|f| f.levels.len())
        .max()
        .unwrap_or(0);
    let width = 2.0 * MARGIN + LABEL_W + most_levels as f64 * CELL_W;
    let block = 3.0 * CELL_H + 10.0;
    let legend_y = MARGIN + 30.0 + result.families.len() as f64 * block;
    let height = legend_y + 2.5 * CELL_H;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" \
         font-family=\"sans-serif\" font-size=\"11\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n\
         <text x=\"{MARGIN}\" y=\"{}\" font-size=\"14\" font-weight=\"bold\">Terrain ladder: {}</text>",
        MARGIN + 12.0,
        escape(&result.robot)
    );
    for (f, family) in result.families.iter().enumerate() {
        let top = MARGIN + 30.0 + f as f64 * block;
        let _ = writeln!(
            out,
            "<text x=\"{MARGIN}\" y=\"{}\" font-weight=\"bold\">{}</text>\
             <text x=\"{MARGIN}\" y=\"{}\" fill=\"#555\">{}</text>",
            top + 16.0,
            escape(&family.family),
            top + 30.0,
            escape(
                family
                    .parameter
                    .rsplit('.')
                    .next()
                    .unwrap_or(&family.parameter)
            ),
        );
        for (k, level) in family.levels.iter().enumerate() {
            let x = MARGIN + LABEL_W + k as f64 * CELL_W;
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"#555\">{level}</text>",
                x + CELL_W / 2.0,
                top + 16.0
            );
        }
        for (row, perceptive) in [false, true].into_iter().enumerate() {
            let y = top + (row + 1) as f64 * CELL_H;
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
                MARGIN + LABEL_W - 6.0,
                y + 16.0,
                if perceptive { "perceptive" } else { "blind" }
            );
            let runs = result
                .runs
                .iter()
                .filter(|r| r.family == family.family && r.perceptive == perceptive);
            for run in runs {
                let Some(k) = family.levels.iter().position(|&l| l == run.level) else {
                    continue;
                };
                let x = MARGIN + LABEL_W + k as f64 * CELL_W;
                let (fill, ink) = colour(run.outcome);
                let deep = run
                    .max_penetration
                    .into_iter()
                    .chain(run.max_link_penetration)
                    .any(|d| d > DEEP);
                let label = run
                    .forward
                    .map_or_else(|| run.outcome.word().into(), |d| format!("{d:.2}"));
                let _ = writeln!(
                    out,
                    "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{fill}\" \
                     stroke=\"#fff\"><title>{} at {} ({}): {}</title></rect>\
                     <text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"{ink}\">{label}{}</text>",
                    x + 1.0,
                    y + 1.0,
                    CELL_W - 2.0,
                    CELL_H - 2.0,
                    escape(&family.family),
                    run.level,
                    if perceptive { "perceptive" } else { "blind" },
                    run.outcome.word(),
                    x + CELL_W / 2.0,
                    y + 16.0,
                    if deep { " ▾" } else { "" }
                );
            }
        }
    }
    let mut x = MARGIN;
    for outcome in [
        Outcome::Crossed,
        Outcome::Scrambled,
        Outcome::Stalled,
        Outcome::SlidBack,
        Outcome::Fell,
        Outcome::Diverged,
    ] {
        let (fill, _) = colour(outcome);
        let _ = writeln!(
            out,
            "<rect x=\"{x}\" y=\"{legend_y}\" width=\"14\" height=\"14\" fill=\"{fill}\"/>\
             <text x=\"{}\" y=\"{}\">{}</text>",
            x + 18.0,
            legend_y + 11.0,
            outcome.word()
        );
        x += 90.0;
    }
    let _ = writeln!(
        out,
        "<text x=\"{MARGIN}\" y=\"{}\" fill=\"#555\">in each cell the metres walked past the \
         start; ▾ a foot or link sank past {} mm</text>\n</svg>",
        legend_y + 11.0 + CELL_H,
        DEEP * 1e3
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ladder::{FamilySummary, RungResult};

    #[test]
    fn every_run_is_a_cell_coloured_by_its_outcome() {
        let run = |level: f64, perceptive: bool, outcome: Outcome, deep: f64| RungResult {
            family: "stairs <up>".into(),
            level,
            perceptive,
            outcome,
            forward: Some(level * 10.0),
            max_tilt_deg: Some(1.0),
            max_penetration: Some(deep),
            max_link_penetration: None,
            walk_flags: Vec::new(),
            message: None,
        };
        let result = LadderResult {
            robot: "hex18".into(),
            families: vec![FamilySummary {
                family: "stairs <up>".into(),
                parameter: "terrain.source.step_height".into(),
                levels: vec![0.02, 0.04],
                blind: Some(0.02),
                perceptive: Some(0.04),
                blind_stopped_by: Some((0.04, Outcome::Stalled)),
                perceptive_stopped_by: None,
                blind_as_commanded: Some(0.02),
                perceptive_as_commanded: Some(0.02),
                blind_as_commanded_stopped_by: Some((0.04, Outcome::Stalled)),
                perceptive_as_commanded_stopped_by: Some((0.04, Outcome::Scrambled)),
            }],
            runs: vec![
                run(0.02, false, Outcome::Crossed, 1e-3),
                run(0.04, false, Outcome::Stalled, 1e-3),
                run(0.02, true, Outcome::Crossed, 1e-3),
                run(0.04, true, Outcome::Scrambled, 6e-3),
            ],
            caveats: Vec::new(),
        };
        let svg = svg(&result);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<title>").count(), 4);
        assert_eq!(svg.matches(colour(Outcome::Crossed).0).count(), 2 + 1);
        assert_eq!(svg.matches(colour(Outcome::Scrambled).0).count(), 1 + 1);
        assert_eq!(svg.matches(colour(Outcome::Fell).0).count(), 1);
        assert!(svg.contains("0.40 ▾"), "{svg}");
        assert!(svg.contains("stairs &lt;up&gt;") && !svg.contains("stairs <up>"));
        assert!(svg.contains(">step_height<"));
    }
}
