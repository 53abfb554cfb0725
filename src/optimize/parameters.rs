//! What a search changes: the scenario fields that can be searched, what each accepts, a
//! parameter's domain (a range, a phase, a choice) and where its value goes in the scenario.

use crate::scenario::Scenario;
use serde::Deserialize;

/// What a searchable field accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Accepts {
    /// A number > 0.
    Positive,
    /// A number strictly between 0 and 1.
    Fraction,
    /// A cycle fraction: bounds within [0, 1], the value taken modulo 1 (a phase of 1 is 0).
    Phase,
    /// Any finite number.
    Finite,
    /// One of these names, searched as a choice.
    OneOf(&'static [&'static str]),
}

/// The fields that can be searched, and what each accepts.
const SEARCHABLE: &[(&str, Accepts)] = &[
    ("gait.period", Accepts::Positive),
    ("gait.duty_factor", Accepts::Fraction),
    ("gait.stride_length", Accepts::Positive),
    ("gait.step_height", Accepts::Positive),
    ("gait.stance_height", Accepts::Positive),
    ("gait.reach", Accepts::Positive),
    ("gait.swing", Accepts::OneOf(SWINGS)),
    ("gait.phase_offsets.lf", Accepts::Phase),
    ("gait.phase_offsets.lm", Accepts::Phase),
    ("gait.phase_offsets.lr", Accepts::Phase),
    ("gait.phase_offsets.rf", Accepts::Phase),
    ("gait.phase_offsets.rm", Accepts::Phase),
    ("gait.phase_offsets.rr", Accepts::Phase),
    ("servo.stiffness", Accepts::Positive),
    ("servo.damping", Accepts::Positive),
    ("command.forward", Accepts::Finite),
];

/// The gait file's swing shapes (`gait::SwingShape`).
const SWINGS: &[&str] = &["sine", "cycloid", "rectangle"];

/// The names of the fields that can be searched.
pub fn searchable() -> impl Iterator<Item = &'static str> {
    SEARCHABLE.iter().map(|(name, _)| *name)
}

/// A searched parameter: a number within bounds, or a choice among names. CMA-ES searches
/// numbers; a choice of k names is the coordinate range [0, k], each name a unit cell of it.
#[derive(Clone, Debug, PartialEq)]
pub enum Domain {
    Range { low: f64, high: f64, phase: bool },
    Choice(Vec<String>),
}

/// One searched field (a dotted path into the scenario) and its domain.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub domain: Domain,
}

impl Parameter {
    /// The coordinate range CMA-ES searches.
    pub fn bounds(&self) -> (f64, f64) {
        match &self.domain {
            Domain::Range { low, high, .. } => (*low, *high),
            Domain::Choice(names) => (0.0, names.len() as f64),
        }
    }

    /// The field's value at coordinate `x`.
    pub fn value(&self, x: f64) -> toml::Value {
        match &self.domain {
            Domain::Range { phase: true, .. } => toml::Value::Float(x.rem_euclid(1.0)),
            Domain::Range { .. } => toml::Value::Float(x),
            Domain::Choice(names) => {
                let k = (x.floor().max(0.0) as usize).min(names.len() - 1);
                toml::Value::String(names[k].clone())
            }
        }
    }

    /// The coordinate of a value the scenario has (a choice's cell centre), inside the bounds;
    /// None when the value is not one of the choices.
    fn coordinate(&self, value: &toml::Value) -> Option<f64> {
        let (low, high) = self.bounds();
        match (&self.domain, value) {
            (Domain::Choice(names), toml::Value::String(s)) => {
                names.iter().position(|n| n == s).map(|k| k as f64 + 0.5)
            }
            (Domain::Range { .. }, v) => v
                .as_float()
                .or_else(|| v.as_integer().map(|i| i as f64))
                .map(|v| v.clamp(low, high)),
            _ => None,
        }
    }
}

/// The parameter `name` with the range or choices a file gave, checked against what the field
/// accepts.
pub(super) fn parameter(name: &str, range: &Range) -> Result<Parameter, String> {
    let Some(&(_, accepts)) = SEARCHABLE.iter().find(|(p, _)| *p == name) else {
        return Err(format!(
            "parameters.{name}: unknown parameter; expected one of {}",
            searchable().collect::<Vec<_>>().join(", ")
        ));
    };
    let domain = match (accepts, range) {
        (Accepts::OneOf(known), Range::Choice(names)) => {
            if names.len() < 2 {
                return Err(format!(
                    "parameters.{name}: expected at least two choices among {}",
                    known.join(", ")
                ));
            }
            for (k, n) in names.iter().enumerate() {
                if !known.contains(&n.as_str()) {
                    return Err(format!(
                        "parameters.{name}: unknown choice {n:?}; expected some of {}",
                        known.join(", ")
                    ));
                }
                if names[..k].contains(n) {
                    return Err(format!("parameters.{name}: {n:?} is listed twice"));
                }
            }
            Domain::Choice(names.clone())
        }
        (Accepts::OneOf(known), Range::Bounds(_)) => {
            return Err(format!(
                "parameters.{name}: a choice; expected a list of names among {}, e.g. {:?}",
                known.join(", "),
                known
            ));
        }
        (_, Range::Choice(_)) => {
            return Err(format!(
                "parameters.{name}: a number; expected bounds [low, high]"
            ));
        }
        (accepts, &Range::Bounds([low, high])) => {
            if !(low.is_finite() && high.is_finite() && low < high) {
                return Err(format!(
                    "parameters.{name}: expected [low, high] with low < high, got [{low}, {high}]"
                ));
            }
            let (inside, expected) = match accepts {
                Accepts::Positive => (low > 0.0, "values > 0"),
                Accepts::Fraction => (low > 0.0 && high < 1.0, "values in (0, 1)"),
                Accepts::Phase => (low >= 0.0 && high <= 1.0, "a cycle fraction in [0, 1]"),
                _ => (true, ""),
            };
            if !inside {
                return Err(format!(
                    "parameters.{name}: [{low}, {high}] leaves what the field accepts: expected {expected}"
                ));
            }
            Domain::Range {
                low,
                high,
                phase: accepts == Accepts::Phase,
            }
        }
    };
    Ok(Parameter {
        name: name.to_string(),
        domain,
    })
}

/// A parameter's range in a file: `[low, high]`, or a list of choices.
#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum Range {
    Bounds([f64; 2]),
    Choice(Vec<String>),
}

/// The starting point: each parameter's value in the resolved scenario (the gait as fitted, the
/// servo gains as fitted, the commanded speed), clamped into its bounds; a choice the scenario's
/// value is not among starts at the first choice.
pub(super) fn start_point(
    parameters: &[Parameter],
    base: &toml::Table,
    reference: &Scenario,
) -> Vec<f64> {
    let mut values = toml::Table::new();
    if let Some(gait) = reference.gait() {
        if let Ok(v) = toml::Value::try_from(gait.to_spec()) {
            values.insert("gait".into(), v);
        }
        let forward = base
            .get("command")
            .and_then(|c| c.get(0))
            .and_then(|c| c.get("forward"))
            .and_then(toml::Value::as_float)
            .unwrap_or_else(|| gait.nominal_speed());
        values.insert(
            "command".into(),
            toml::Value::Table(toml::Table::from_iter([(
                "forward".to_string(),
                toml::Value::Float(forward),
            )])),
        );
    }
    if let Some((gains, _)) = reference.drive() {
        values.insert(
            "servo".into(),
            toml::Value::Table(toml::Table::from_iter([
                ("stiffness".to_string(), toml::Value::Float(gains.stiffness)),
                ("damping".to_string(), toml::Value::Float(gains.damping)),
            ])),
        );
    }
    parameters
        .iter()
        .map(|p| {
            let (low, high) = p.bounds();
            // a searchable parameter is a dotted path (see `searchable`)
            p.name
                .rsplit_once('.')
                .and_then(|(tables, field)| {
                    tables
                        .split('.')
                        .try_fold(&values, |t, part| t.get(part)?.as_table())?
                        .get(field)
                })
                .and_then(|v| p.coordinate(v))
                .unwrap_or(match p.domain {
                    Domain::Choice(_) => 0.5,
                    Domain::Range { .. } => 0.5 * (low + high),
                })
        })
        .collect()
}
