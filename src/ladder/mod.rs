//! The terrain ladder: a robot walked over each terrain family at rising difficulty (riser
//! height, slope angle, bump height, gap width, …), blind and perceptive, and for each family the
//! highest level it crossed — the curriculum legged_gym trains on, as a measurement.
//!
//! A family is a sweep scenario file (`ladder/*.toml`, runnable as it is with `hexsim batch`): its
//! `[sweep]` lists the difficulty parameter's levels (one dotted key) and `follow_terrain =
//! [false, true]`; its `[expect]` says what crossing is — `forward_min`, the distance to get past
//! the start, and `max_body_tilt_deg = 45`, not falling (the body's tilt from upright); and
//! `stop_at_fall = true` ends a run at its fall, which decides the level (what a tumbling robot
//! does after is no part of it, as legged_gym ends an episode at a fall; set unless the family's
//! file sets it, and a run whose body tilted past 45° is a fall whatever its file bounds). Blind
//! runs walk the reactive gait (`reactive_gait = true` unless the family's file sets it; a plain
//! `hexsim batch` of the files walks them rigid). The ladder is a client of the batch engine: it expands
//! the families (for another robot, with that robot and a duration fitted to its speed), runs
//! them as one batch and reads each run's record into an [`Outcome`]. A stall, a slide back, a
//! fall or a divergence is a result, said as such; and a crossing that was not the walk
//! commanded (its feet skated, it drifted or turned: the metrics' `walk_flags`) is a scramble,
//! counted as crossed but told apart, with each family's highest level crossed as commanded
//! beside its highest crossed.

pub mod chart;

use crate::batch::results::{Record, Status};
use crate::scenario::builtin::{self, Builtin};
use crate::scenario::{self, Scenario, ScenarioError, sweep};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The fraction of its nominal speed a robot must keep on average to cross in the time it is
/// given: a ladder run for another robot lasts `forward_min / (SPEED_SHARE · v_nominal)`.
pub const SPEED_SHARE: f64 = 0.5;

/// Moving back more than this (m) against the command is sliding back, not a stall.
const SLID_BACK: f64 = 0.05;

/// A terrain family: its file, the difficulty parameter and its levels (easiest first).
#[derive(Debug, Clone, Serialize)]
pub struct Family {
    pub name: String,
    pub description: String,
    pub file: PathBuf,
    /// The dotted scenario key the levels set (e.g. `terrain.source.step_height`).
    pub parameter: String,
    pub levels: Vec<f64>,
    /// The distance past the start that crosses a level (m).
    pub distance: f64,
}

/// One run of the ladder: a family's level, blind or perceptive, and its scenario's name.
pub struct Rung {
    pub family: usize,
    pub level: usize,
    pub perceptive: bool,
    pub name: String,
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Got the distance past the start without falling, as the walk commanded.
    Crossed,
    /// Got the distance past the start without falling, but not as the walk commanded: its feet
    /// skated, or it drifted sideways or turned off its heading (the metrics' `walk_flags`,
    /// issue 40's bars) — across, but scrambling.
    Scrambled,
    /// Stopped short, neither falling nor sliding back.
    Stalled,
    /// Ended behind where it started.
    SlidBack,
    /// Tilted past 45° from upright.
    Fell,
    /// The simulation left physics (the message says why).
    Diverged,
    /// The scenario could not be run.
    Error,
}

impl Outcome {
    pub fn word(self) -> &'static str {
        match self {
            Outcome::Crossed => "crossed",
            Outcome::Scrambled => "scrambled",
            Outcome::Stalled => "stalled",
            Outcome::SlidBack => "slid back",
            Outcome::Fell => "fell",
            Outcome::Diverged => "diverged",
            Outcome::Error => "error",
        }
    }

    /// What a run's record says happened: crossing needs every expectation met and no fall (the
    /// body past 45° from upright, the metrics' `fell_at`, whatever a family's file bounds), and
    /// crossing as commanded no walk flag as well.
    pub fn of(record: &Record) -> Outcome {
        let metric = |name: &str| record.metrics.get(name).and_then(|v| v.as_f64());
        match record.status {
            Status::Error => return Outcome::Error,
            Status::Diverged => return Outcome::Diverged,
            _ if metric("fell_at").is_some() => return Outcome::Fell,
            Status::Passed | Status::Regressed if walk_flags(record).is_empty() => {
                return Outcome::Crossed;
            }
            Status::Passed | Status::Regressed => return Outcome::Scrambled,
            Status::Failed => {}
        }
        if metric("forward_distance").is_some_and(|d| d < -SLID_BACK) {
            Outcome::SlidBack
        } else {
            Outcome::Stalled
        }
    }

    /// Got across, as commanded or scrambling.
    pub fn crossed(self) -> bool {
        matches!(self, Outcome::Crossed | Outcome::Scrambled)
    }
}

/// A run's walk flags (`metrics::walk`: skated, went backwards, drifted, turned), as sentences.
fn walk_flags(record: &Record) -> Vec<String> {
    record
        .metrics
        .get("walk_flags")
        .and_then(|v| v.as_array())
        .map(|flags| {
            flags
                .iter()
                .filter_map(|f| f.as_str().map(str::to_string))
                .collect()
        })
        .unwrap_or_default()
}

/// A run's result as the ladder's JSON lists it.
#[derive(Debug, Clone, Serialize)]
pub struct RungResult {
    pub family: String,
    pub level: f64,
    pub perceptive: bool,
    pub outcome: Outcome,
    /// Forward distance past the start (m), when the run produced one.
    pub forward: Option<f64>,
    /// The body's largest tilt from upright (°): past 45° it fell.
    pub max_tilt_deg: Option<f64>,
    /// Deepest penetration of a foot and of any other link (m).
    pub max_penetration: Option<f64>,
    pub max_link_penetration: Option<f64>,
    /// How the walk was not the one commanded (a scramble's, or a failed run's), if it was not.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub walk_flags: Vec<String>,
    /// The divergence's or the error's message.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
}

/// A family's summary: the highest level crossed blind and perceptive, and what stopped it; and
/// the highest crossed as the walk commanded (no scramble on the way up), and what stopped that.
#[derive(Debug, Clone, Serialize)]
pub struct FamilySummary {
    pub family: String,
    pub parameter: String,
    pub levels: Vec<f64>,
    /// The highest level crossed with every level below it crossed too (None: not the first).
    pub blind: Option<f64>,
    pub perceptive: Option<f64>,
    /// The first level not crossed, and how it ended.
    pub blind_stopped_by: Option<(f64, Outcome)>,
    pub perceptive_stopped_by: Option<(f64, Outcome)>,
    /// The highest level crossed as commanded with every level below it so too.
    pub blind_as_commanded: Option<f64>,
    pub perceptive_as_commanded: Option<f64>,
    pub blind_as_commanded_stopped_by: Option<(f64, Outcome)>,
    pub perceptive_as_commanded_stopped_by: Option<(f64, Outcome)>,
}

/// The whole ladder's result (its JSON).
#[derive(Debug, Clone, Serialize)]
pub struct LadderResult {
    pub robot: String,
    pub families: Vec<FamilySummary>,
    pub runs: Vec<RungResult>,
    /// What the levels do not show, said under the table ([`caveats`]).
    pub caveats: Vec<String>,
}

/// The ladder's families, its runs, and their scenarios (name-sorted, as a batch runs them).
pub struct Ladder {
    pub families: Vec<Family>,
    pub rungs: Vec<Rung>,
    pub scenarios: Vec<Scenario>,
}

/// A ladder family's file: one on disk, or one of the binary's (`ladder/`'s, run from any
/// folder).
#[derive(Debug, Clone)]
pub enum Source {
    File(PathBuf),
    Builtin(Builtin),
}

impl Source {
    /// The families `inputs` name: files and folders of them as `hexsim batch` reads them; a
    /// bare name that is neither (`stairs_up`) the built-in family of that name; `ladder`, where
    /// there is no such folder, every built-in family.
    pub fn resolve(inputs: &[String]) -> anyhow::Result<Vec<Source>> {
        let mut sources = Vec::new();
        for input in inputs {
            let path = Path::new(input);
            if input == "ladder" && !path.exists() {
                sources.extend(builtin::LADDER.iter().map(|(_, b)| Source::Builtin(*b)));
            } else if let Some(b) = builtin::named(builtin::LADDER, path, path) {
                sources.push(Source::Builtin(b));
            } else {
                let files =
                    crate::batch::scenario_files(std::slice::from_ref(input)).map_err(|e| {
                        if path.components().count() == 1 && path.extension().is_none() {
                            anyhow::anyhow!(
                                "{e}, nor a built-in family ({})",
                                builtin::names(builtin::LADDER)
                            )
                        } else {
                            e
                        }
                    })?;
                sources.extend(files.into_iter().map(Source::File));
            }
        }
        Ok(sources)
    }

    /// Its path (a built-in family's as in the repository), and its table.
    fn read(&self) -> Result<(PathBuf, toml::Table), String> {
        match self {
            Source::File(file) => {
                scenario::read_table(file, Path::new(file.file_name().unwrap_or_default()))
            }
            Source::Builtin(b) => {
                let table = b.text.parse().map_err(|e: toml::de::Error| {
                    format!(
                        "scenario {} (built in): {}",
                        b.path,
                        e.to_string().trim_end()
                    )
                })?;
                Ok((PathBuf::from(b.path), table))
            }
        }
    }

    fn path(&self) -> PathBuf {
        match self {
            Source::File(file) => file.clone(),
            Source::Builtin(b) => PathBuf::from(b.path),
        }
    }
}

/// Reads the ladder's families from `sources` and expands them into runs, for `robot` if given
/// (the files' own robot otherwise).
pub fn load(sources: &[Source], robot: Option<&Path>) -> Result<Ladder, ScenarioError> {
    let mut families = Vec::new();
    let mut rungs = Vec::new();
    let mut scenarios = Vec::new();
    for source in sources {
        let fail = |message: String| ScenarioError {
            file: source.path(),
            message,
        };
        let (path, mut table) = source.read().map_err(fail)?;
        if let Some(robot) = robot {
            let absolute = std::path::absolute(robot)
                .map_err(|e| fail(format!("robot {}: {e}", robot.display())))?;
            table.insert(
                "robot".into(),
                toml::Value::String(absolute.to_string_lossy().into_owned()),
            );
        }
        let (parameter, levels) = difficulty(&table).map_err(fail)?;
        let distance = table
            .get("expect")
            .and_then(|e| e.get("forward_min"))
            .and_then(toml::Value::as_float)
            .ok_or_else(|| {
                fail("a ladder family's [expect] needs forward_min: the distance that crosses a level (m)".into())
            })?;
        let name = path
            .file_stem()
            .map_or("family".into(), |s| s.to_string_lossy().into_owned());
        let description = table
            .get("description")
            .and_then(toml::Value::as_str)
            .unwrap_or_default()
            .to_string();
        let family = families.len();
        let variants = sweep::expand(table).map_err(fail)?;
        for variant in variants {
            let value = |key: &str| {
                variant
                    .assignments
                    .iter()
                    .find(|(k, _)| k == key)
                    .map(|(_, v)| v.clone())
            };
            let level_value = value(&parameter).and_then(|v| as_number(&v)).unwrap_or(0.0);
            let level = levels
                .iter()
                .position(|l| *l == level_value)
                .unwrap_or_default();
            let perceptive = value("follow_terrain").and_then(|v| v.as_bool()) == Some(true);
            let run_name = variant.name(&name);
            let mut table = variant.table;
            if !perceptive && !table.contains_key("reactive_gait") {
                // blind, the feet find risers and drops only by touch: the rigid schedule stalls
                // hex18 at a 4 cm riser where the reactive gait climbs 10 cm. It is not the
                // default walk's gait: on the natural terrain it leaves hex18's distance as it
                // is, but moves some third-party robots' by up to 3.3 % and leaves worms'
                // targets out of reach (docs/rough-ground.md). Perceptive runs plan from the
                // terrain they know, and heights found by touch fight that plan (hex18,
                // perceptive and reactive, fell down 10 cm stairs it descends without).
                table.insert("reactive_gait".into(), toml::Value::Boolean(true));
            }
            if !table.contains_key("stop_at_fall") {
                // a fall decides the level: a family of its own stops there as ladder/'s do
                table.insert("stop_at_fall".into(), toml::Value::Boolean(true));
            }
            let mut scenario = scenario::from_table(table.clone(), run_name.clone(), &path)?;
            if robot.is_some() {
                // the time a robot of this speed needs at SPEED_SHARE of it, and its settling
                let speed = scenario.gait().map_or(0.0, |g| g.nominal_speed());
                if speed > 0.0 {
                    table.insert(
                        "duration".into(),
                        toml::Value::Float(distance / (SPEED_SHARE * speed)),
                    );
                    scenario = scenario::from_table(table, run_name, &path)?;
                }
            }
            rungs.push(Rung {
                family,
                level,
                perceptive,
                name: scenario.name.clone(),
            });
            scenarios.push(scenario);
        }
        families.push(Family {
            name,
            description,
            file: path,
            parameter,
            levels,
            distance,
        });
    }
    scenarios.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(Ladder {
        families,
        rungs,
        scenarios,
    })
}

/// The family's difficulty: the one `[sweep]` key other than `follow_terrain`, and its levels,
/// which must be numbers rising.
fn difficulty(table: &toml::Table) -> Result<(String, Vec<f64>), String> {
    let sweep = table
        .get("sweep")
        .and_then(toml::Value::as_table)
        .ok_or("a ladder family needs a [sweep] of its difficulty's levels")?;
    let keys: Vec<&String> = sweep.keys().filter(|k| *k != "follow_terrain").collect();
    let [key] = keys[..] else {
        return Err(format!(
            "a ladder family's [sweep] sweeps one difficulty (and follow_terrain), got {}",
            if keys.is_empty() {
                "none".to_string()
            } else {
                keys.iter()
                    .map(|k| k.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        ));
    };
    let levels: Vec<f64> = sweep[key]
        .as_array()
        .ok_or(format!(
            "sweep.{key}: a ladder's levels are a list of numbers"
        ))?
        .iter()
        .map(|v| as_number(v).ok_or(format!("sweep.{key}: expected numbers, got {v}")))
        .collect::<Result<_, _>>()?;
    // easiest first: a riser's height rises, a drop's falls
    let rising = levels.windows(2).all(|w| w[0] < w[1]);
    let falling = levels.windows(2).all(|w| w[0] > w[1]);
    if levels.is_empty() || !(rising || falling) {
        return Err(format!(
            "sweep.{key}: a ladder's levels must rise (or fall) steadily, easiest first, got {levels:?}"
        ));
    }
    Ok((key.clone(), levels))
}

/// A level's number: the value, or a range's high end (`[low, high]`, as discrete obstacles'
/// heights are drawn from).
fn as_number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Array(range) => range.last().and_then(as_number),
        _ => v.as_float().or_else(|| v.as_integer().map(|i| i as f64)),
    }
}

/// Reads the batch's records (one per rung, by scenario name) into the ladder's result.
pub fn summarise(
    robot: &str,
    families: &[Family],
    rungs: &[Rung],
    records: &[Record],
) -> LadderResult {
    let mut runs = Vec::new();
    let mut outcomes = Vec::new();
    for rung in rungs {
        let family = &families[rung.family];
        let record = records.iter().find(|r| r.name == rung.name);
        let outcome = record.map_or(Outcome::Error, Outcome::of);
        let metric = |name: &str| record.and_then(|r| r.metrics.get(name)?.as_f64());
        outcomes.push((rung.family, rung.level, rung.perceptive, outcome));
        runs.push(RungResult {
            family: family.name.clone(),
            level: family.levels[rung.level],
            perceptive: rung.perceptive,
            outcome,
            forward: metric("forward_distance"),
            max_tilt_deg: metric("max_body_tilt_deg"),
            max_penetration: metric("max_penetration"),
            max_link_penetration: metric("max_link_penetration"),
            walk_flags: record.map(walk_flags).unwrap_or_default(),
            message: record.and_then(|r| r.message.clone()),
        });
    }
    let families = families
        .iter()
        .enumerate()
        .map(|(f, family)| {
            // the highest level whose run and every easier one's `counts`
            let climb = |perceptive: bool, counts: fn(Outcome) -> bool| {
                let mut highest = None;
                for (level, value) in family.levels.iter().enumerate() {
                    let outcome = outcomes
                        .iter()
                        .find(|o| o.0 == f && o.1 == level && o.2 == perceptive)
                        .map(|o| o.3);
                    match outcome {
                        Some(o) if counts(o) => highest = Some(*value),
                        Some(other) => return (highest, Some((*value, other))),
                        None => {}
                    }
                }
                (highest, None)
            };
            let as_commanded = |o: Outcome| o == Outcome::Crossed;
            let (blind, blind_stopped_by) = climb(false, Outcome::crossed);
            let (perceptive, perceptive_stopped_by) = climb(true, Outcome::crossed);
            let (blind_as_commanded, blind_as_commanded_stopped_by) = climb(false, as_commanded);
            let (perceptive_as_commanded, perceptive_as_commanded_stopped_by) =
                climb(true, as_commanded);
            FamilySummary {
                family: family.name.clone(),
                parameter: family.parameter.clone(),
                levels: family.levels.clone(),
                blind,
                perceptive,
                blind_stopped_by,
                perceptive_stopped_by,
                blind_as_commanded,
                perceptive_as_commanded,
                blind_as_commanded_stopped_by,
                perceptive_as_commanded_stopped_by,
            }
        })
        .collect();
    LadderResult {
        robot: robot.to_string(),
        families,
        runs,
        caveats: Vec::new(),
    }
}

/// What a ladder's levels do not show about its robots: links that touch nothing
/// ([`crate::robot::RobotModel::links_without_contact`]) pass through the terrain, so the levels
/// are those of a robot touching with its other links alone, a body or shin on a riser unfelt.
pub fn caveats(scenarios: &[Scenario]) -> Vec<String> {
    let mut robots: Vec<&crate::robot::RobotModel> = Vec::new();
    for robot in scenarios.iter().filter_map(Scenario::robot) {
        if !robots
            .iter()
            .any(|r| (&r.name, &r.source) == (&robot.name, &robot.source))
        {
            robots.push(robot);
        }
    }
    robots
        .into_iter()
        .filter_map(|robot| {
            let untouching = robot.links_without_contact();
            let first = untouching.first()?;
            let more = match untouching.len() - 1 {
                0 => String::new(),
                n => format!(" and {n} more"),
            };
            Some(format!(
                "{} of {}'s {} links have no collision geometry hexsim could read ({first}{more}): \
                 they pass through the terrain, so these levels are of a robot that touches it \
                 with its other {} links only",
                untouching.len(),
                robot.name,
                robot.links.len(),
                robot.links.len() - untouching.len()
            ))
        })
        .collect()
}

impl LadderResult {
    /// The table a person reads: per family, the highest level crossed blind and perceptive, and
    /// what stopped the robot at the next; then, where it differs, the highest crossed as the
    /// walk commanded (Markdown, as docs/ holds it).
    pub fn table(&self, families: &[Family]) -> String {
        let mut out = format!(
            "| family ({}) | levels | blind | perceptive |\n|---|---|---|---|\n",
            self.robot
        );
        for (summary, family) in self.families.iter().zip(families) {
            let short = family
                .parameter
                .rsplit('.')
                .next()
                .unwrap_or(&family.parameter);
            let part = |highest: Option<f64>, stopped: Option<(f64, Outcome)>| {
                let reached = highest.map_or("none".to_string(), |v| format!("{v}"));
                match stopped {
                    Some((level, outcome)) => format!("{reached} ({} at {level})", outcome.word()),
                    None => format!("{reached} (all)"),
                }
            };
            let cell = |highest, stopped, clean, clean_stopped| {
                let crossed = part(highest, stopped);
                if clean == highest {
                    crossed
                } else {
                    format!("{crossed}; as commanded {}", part(clean, clean_stopped))
                }
            };
            out.push_str(&format!(
                "| {} | {short} {} | {} | {} |\n",
                family.name,
                summary
                    .levels
                    .iter()
                    .map(|l| format!("{l}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                cell(
                    summary.blind,
                    summary.blind_stopped_by,
                    summary.blind_as_commanded,
                    summary.blind_as_commanded_stopped_by
                ),
                cell(
                    summary.perceptive,
                    summary.perceptive_stopped_by,
                    summary.perceptive_as_commanded,
                    summary.perceptive_as_commanded_stopped_by
                ),
            ));
        }
        for caveat in &self.caveats {
            out.push_str(&format!("\nCaveat: {caveat}.\n"));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A batch record of `name` that ended `status` with `flags` in its metrics.
    fn record(name: &str, status: &str, forward: f64, flags: &[&str]) -> Record {
        serde_json::from_value(serde_json::json!({
            "name": name, "file": "f.toml", "hash": "0", "kind": "walk", "seed": null,
            "index": 0, "total": 1, "shard": [0, 1], "hexsim_version": "0", "status": status,
            "wall_time_s": 0.0, "steps": 1, "steps_per_second": 0.0, "expectations": [],
            "metrics": { "forward_distance": forward, "walk_flags": flags },
        }))
        .unwrap()
    }

    /// A crossing whose feet skated is a scramble: it counts towards the highest level crossed,
    /// not towards the highest crossed as commanded, and the table says both.
    #[test]
    fn a_scrambled_crossing_is_crossed_but_not_as_commanded() {
        let family = Family {
            name: "stairs".into(),
            description: String::new(),
            file: "stairs.toml".into(),
            parameter: "terrain.source.step_height".into(),
            levels: vec![0.02, 0.04, 0.06],
            distance: 1.5,
        };
        let rung = |level, perceptive, name: &str| Rung {
            family: 0,
            level,
            perceptive,
            name: name.into(),
        };
        let rungs = [
            rung(0, false, "b2"),
            rung(1, false, "b4"),
            rung(2, false, "b6"),
            rung(0, true, "p2"),
            rung(1, true, "p4"),
            rung(2, true, "p6"),
        ];
        let skated = ["skated: its worst foot slid 0.8 m in contact, 46 % of the 1.7 m"];
        let records = [
            record("b2", "passed", 2.8, &[]),
            record("b4", "passed", 2.6, &skated),
            record("b6", "failed", 0.5, &[]),
            record("p2", "passed", 2.9, &[]),
            record("p4", "passed", 2.9, &[]),
            record("p6", "passed", 2.9, &[]),
        ];
        let result = summarise("hex18", std::slice::from_ref(&family), &rungs, &records);
        let outcomes: Vec<Outcome> = result.runs.iter().map(|r| r.outcome).collect();
        assert_eq!(outcomes[1], Outcome::Scrambled);
        assert_eq!(result.runs[1].walk_flags, skated);
        assert!(result.runs[0].walk_flags.is_empty());
        let summary = &result.families[0];
        assert_eq!(summary.blind, Some(0.04));
        assert_eq!(summary.blind_stopped_by, Some((0.06, Outcome::Stalled)));
        assert_eq!(summary.blind_as_commanded, Some(0.02));
        assert_eq!(
            summary.blind_as_commanded_stopped_by,
            Some((0.04, Outcome::Scrambled))
        );
        assert_eq!(summary.perceptive, Some(0.06));
        assert_eq!(summary.perceptive_as_commanded, Some(0.06));
        let table = result.table(&[family]);
        assert!(
            table.contains(
                "| 0.04 (stalled at 0.06); as commanded 0.02 (scrambled at 0.04) | 0.06 (all) |"
            ),
            "{table}"
        );
    }

    /// A run whose body tilted past 45° from upright fell, even where its family's file bounds
    /// only roll and pitch (each under 45°) and the run passed them, or got its distance first.
    #[test]
    fn a_run_that_fell_is_a_fall_whatever_it_passed() {
        let mut fell = record("b2", "passed", 2.8, &[]);
        fell.metrics["fell_at"] = serde_json::json!(7.6);
        assert_eq!(Outcome::of(&fell), Outcome::Fell);
        fell.status = Status::Failed;
        assert_eq!(Outcome::of(&fell), Outcome::Fell);
        fell.status = Status::Diverged;
        assert_eq!(Outcome::of(&fell), Outcome::Diverged);
        assert_eq!(
            Outcome::of(&record("b2", "passed", 2.8, &[])),
            Outcome::Crossed
        );
    }

    #[test]
    fn a_family_sweeps_one_rising_difficulty() {
        let table: toml::Table = r#"
            [sweep]
            "terrain.source.step_height" = [0.02, 0.04]
            follow_terrain = [false, true]
        "#
        .parse()
        .unwrap();
        let (key, levels) = difficulty(&table).unwrap();
        assert_eq!(key, "terrain.source.step_height");
        assert_eq!(levels, [0.02, 0.04]);
        for (bad, expected) in [
            ("[sweep]\nfollow_terrain = [false]\n", "got none"),
            ("[sweep]\na = [1, 2]\nb = [1, 2]\n", "got a, b"),
            ("[sweep]\na = [2, 1, 3]\n", "must rise"),
            ("[sweep]\na = [\"x\"]\n", "expected numbers"),
            ("[sweep]\na = [[0, 2], [0, 1], [0, 3]]\n", "must rise"),
            ("duration = 1\n", "needs a [sweep]"),
        ] {
            let e = difficulty(&bad.parse().unwrap()).unwrap_err();
            assert!(e.contains(expected), "{bad}: {e}");
        }
    }
}
