//! hexsim's command line: one file per command (its clap arguments and its function), as cargo
//! keeps its `commands/`; what they share (warnings, the progress bar, the end of a run) here.

/// `println!` for the commands' reports on stdout, which a closed pipe does not stop: piped into
/// `head` (or a reader that quits), std's `println!` panics ("failed printing to stdout: Broken
/// pipe") and the run dies before it writes its files. A report line that cannot be written is
/// dropped; the work and the files it was asked for go on.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `print!` as [`out!`] is `println!`.
macro_rules! out_part {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($arg)*);
    }};
}

mod ball;
mod batch;
mod bench;
mod compare;
mod ladder;
mod merge;
mod optimize;
mod robot;
mod run;
mod terrain;

use anyhow::Result;
use clap::{Parser, Subcommand};
use hexsim::scenario::{Report, Scenario};
use std::io::IsTerminal;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "hexsim",
    version,
    about = "Hexapod walking-robot simulator on uneven ground, built on the Burkus & Odry ground contact model",
    long_about = "Hexapod walking-robot simulator on uneven ground, built on the Burkus & Odry ground contact \
                  model (spring-damper normal force, exchangeable friction laws, height-grid terrain).\n\n\
                  Without a subcommand, runs `hexsim run` with the options given (`hexsim --duration 2` is \
                  `hexsim run --duration 2`): by default hex18 walks a tripod gait on the paper's natural terrain \
                  for 20 s and the run is recorded to hexsim.rrd.",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// `hexsim run`'s options, for `hexsim` without a subcommand.
    #[command(flatten)]
    run: Box<run::RunArgs>,
}

#[derive(Subcommand)]
pub enum Command {
    /// Walk the hexapod on a terrain with a gait and record it (the main job). Exit 1 if it
    /// diverged or its walk is not the one commanded (skated, drifted, turned: --allow-flags).
    Run(Box<run::RunArgs>),
    /// Drop a ball on a terrain (the paper's experiment) and record it.
    Ball(Box<ball::BallArgs>),
    /// Run scenario files headless in parallel and check their expectations (exit 0: all met,
    /// 1: some failed, diverged or regressed, 2: input error, 130: interrupted).
    Batch(Box<batch::BatchArgs>),
    /// Measure simulated steps per second on the reference workloads (build with --release):
    /// the walk with the recording off and on, a batch on every core, and the ball.
    Bench(bench::BenchArgs),
    /// Run one scenario under several contact settings side by side: a table of their metrics
    /// and one recording with every setting superposed (exit 1: some diverged).
    Compare(compare::CompareArgs),
    /// Walk a robot over each terrain family at rising difficulty (stairs, slopes, rough ground,
    /// …), blind and perceptive, and report the highest level it crossed in each, and the
    /// highest it crossed as the walk commanded (a crossing whose feet skated is a scramble).
    Ladder(ladder::LadderArgs),
    /// Join the results of a batch's shards (`batch --shard I/N`) into one file.
    Merge(merge::MergeArgs),
    /// Search gait and servo parameters for the best walk on a set of terrains and seeds
    /// (CMA-ES), and write the best gait as a gait file.
    Optimize(optimize::OptimizeArgs),
    /// Show what hexsim makes of a robot: its legs, walking direction, masses, and the torque
    /// each servo holds standing in a gait's pose.
    Robot(robot::RobotArgs),
    /// Inspect or export terrains.
    #[command(subcommand)]
    Terrain(terrain::TerrainCommand),
}

impl Cli {
    /// Runs the command (without one, `hexsim run` on its defaults). Exit codes: 0 done, 1 the
    /// run failed (diverged, expectations not met, a walk not as commanded), 2 a usage or input
    /// error, 130 interrupted.
    pub fn execute(self) -> Result<ExitCode> {
        match self.command {
            None => run::run(*self.run),
            Some(Command::Run(args)) => run::run(*args),
            Some(Command::Ball(args)) => ball::ball(*args),
            Some(Command::Batch(args)) => batch::batch(*args),
            Some(Command::Compare(args)) => compare::compare(args),
            Some(Command::Optimize(args)) => optimize::optimize(args),
            Some(Command::Ladder(args)) => ladder::ladder(args),
            Some(Command::Merge(args)) => merge::merge(args).map(|()| ExitCode::SUCCESS),
            Some(Command::Bench(args)) => bench::bench(args).map(|()| ExitCode::SUCCESS),
            Some(Command::Robot(args)) => robot::robot_command(args).map(|()| ExitCode::SUCCESS),
            Some(Command::Terrain(command)) => {
                terrain::terrain_command(command).map(|()| ExitCode::SUCCESS)
            }
        }
    }
}

/// Prints the scenarios' notes (a step hexsim chose) and warnings (a missing visual mesh, a gait
/// with too few feet down), each once; with `strict` the warnings are errors, the notes not: a
/// note says what hexsim chose, nothing doubtful in the input.
pub(crate) fn warn_about<'a>(
    scenarios: impl IntoIterator<Item = &'a Scenario>,
    strict: bool,
) -> Result<()> {
    let scenarios: Vec<&Scenario> = scenarios.into_iter().collect();
    say_once(&scenarios, "note", |s| &s.notes);
    let level = if strict { "error" } else { "warning" };
    let warnings = say_once(&scenarios, level, |s| &s.warnings);
    if strict && warnings > 0 {
        anyhow::bail!(
            "{} warning{} treated as errors (--strict); nothing was run",
            warnings,
            if warnings == 1 { "" } else { "s" }
        );
    }
    Ok(())
}

/// Prints each of the scenarios' messages that `of` picks once, at `level`, with the scenarios
/// it concerns (all of them, or up to a few by name); returns how many there were.
fn say_once(scenarios: &[&Scenario], level: &str, of: impl Fn(&Scenario) -> &Vec<String>) -> usize {
    let mut said: std::collections::BTreeMap<&String, Vec<&str>> = Default::default();
    for s in scenarios {
        for m in of(s) {
            said.entry(m).or_default().push(s.name.as_str());
        }
    }
    for (message, names) in &said {
        let whose = if scenarios.len() == 1 {
            String::new()
        } else if names.len() == scenarios.len() {
            format!(" (all {} scenarios)", names.len())
        } else if names.len() <= 3 {
            format!(" ({})", names.join(", "))
        } else {
            format!(" ({}, {} and {} more)", names[0], names[1], names.len() - 2)
        };
        eprintln!("{level}: {message}{whose}");
    }
    said.len()
}

/// A progress bar on a terminal, nothing otherwise.
pub(crate) fn progress_bar(steps: u64, what: String) -> Option<indicatif::ProgressBar> {
    std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(steps);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} simulating [{bar:40}] {percent:>3}% ({eta} left) {msg}",
            )
            .expect("the template is valid")
            .progress_chars("=> "),
        );
        bar.set_message(what);
        bar
    })
}

/// A command-line run has no scenario file: relative paths resolve from the working folder, and
/// errors name the option's own file.
pub(crate) const COMMAND_LINE: &str = "";

/// Lists the files written. Exit code: 0 done, 1 diverged (the message says when, where and why),
/// 130 interrupted (Ctrl-C, SIGTERM); the files hold the run so far either way. (`hexsim run`
/// also exits 1 for a walk not as commanded, unless `--allow-flags`.)
pub(crate) fn conclude(report: &Report) -> ExitCode {
    for path in &report.written {
        out!("  wrote {}", path.display());
    }
    if let Some(rrd) = report
        .written
        .iter()
        .find(|p| p.extension().is_some_and(|e| e == "rrd"))
    {
        out!(
            "  view it: `rerun {}` (the viewer: `pip install rerun-sdk==0.36.3`), or run with --spawn",
            rrd.display()
        );
    }
    if let Some(failure) = &report.failure {
        eprintln!(
            "error: {:#}",
            hexsim::runner::failure_error(failure, &report.written)
        );
        ExitCode::from(1)
    } else if !report.metrics.complete() {
        eprintln!("interrupted: the files hold the run so far, marked incomplete");
        ExitCode::from(130)
    } else {
        ExitCode::SUCCESS
    }
}

#[cfg(test)]
mod documented_commands {
    use super::Cli;
    use clap::Parser;
    use std::path::Path;

    /// Every `hexsim …` command in a shell block of the README or a page of docs/, its comment
    /// cut and its continued lines joined: (document, line, the command).
    fn commands() -> Vec<(String, usize, String)> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut documents = vec![root.join("README.md")];
        for page in std::fs::read_dir(root.join("docs")).unwrap() {
            let page = page.unwrap().path();
            if page.extension().is_some_and(|e| e == "md") {
                documents.push(page);
            }
        }
        let mut found = Vec::new();
        for document in documents {
            let text = std::fs::read_to_string(&document).unwrap();
            let name = document.file_name().unwrap().to_string_lossy().into_owned();
            let mut in_shell = false;
            let mut pending: Option<(usize, String)> = None;
            for (i, line) in text.lines().enumerate() {
                if let Some(fence) = line.trim_start().strip_prefix("```") {
                    in_shell = !in_shell && matches!(fence, "sh" | "bash" | "console");
                    continue;
                }
                if !in_shell {
                    continue;
                }
                let line = line.trim().trim_start_matches("$ ");
                let line = match line.find(" # ") {
                    Some(at) => line[..at].trim_end(),
                    None => line,
                };
                let (start, mut command) = match pending.take() {
                    Some((start, before)) => (start, before + " " + line),
                    None if line.starts_with("hexsim ") || line == "hexsim" => {
                        (i + 1, line.to_string())
                    }
                    None => continue,
                };
                if let Some(continued) = command.strip_suffix('\\') {
                    command = continued.to_string();
                    pending = Some((start, command));
                } else {
                    found.push((name.clone(), start, command));
                }
            }
        }
        found
    }

    /// A job script's command with its shell variables (`$NAME`, `${NAME:-default}`) set to 1,
    /// which every option they stand for accepts (a shard 1/1, one thread, a path).
    fn with_variables_set(command: &str) -> String {
        let mut out = String::new();
        let mut chars = command.chars().peekable();
        while let Some(c) = chars.next() {
            if c != '$' {
                out.push(c);
                continue;
            }
            if chars.peek() == Some(&'{') {
                for c in chars.by_ref() {
                    if c == '}' {
                        break;
                    }
                }
            } else {
                while chars
                    .peek()
                    .is_some_and(|c| c.is_ascii_alphanumeric() || *c == '_')
                {
                    chars.next();
                }
            }
            out.push('1');
        }
        out
    }

    /// The commands the documentation shows parse as it shows them (an option renamed or
    /// removed fails here, naming the page and line).
    #[test]
    fn the_documented_commands_parse() {
        let commands = commands();
        // the README's usage block alone shows 21: fewer means the blocks were not found
        assert!(
            commands.len() >= 21,
            "only {} commands found",
            commands.len()
        );
        let mut failures = Vec::new();
        for (document, line, command) in &commands {
            let words = shlex::split(&with_variables_set(command))
                .unwrap_or_else(|| panic!("{document}:{line}: cannot split `{command}`"));
            if let Err(e) = Cli::try_parse_from(&words) {
                failures.push(format!("{document}:{line}: `{command}`: {}", e.kind()));
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }
}
