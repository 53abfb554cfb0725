//! Sweeps: a scenario file with a `[sweep]` table expands into one scenario per combination of
//! the listed values (a Cartesian product), each named by its parameters.
//!
//! ```toml
//! duration = 5.0                          # … the base scenario, as in any scenario file …
//! [sweep]
//! "contact.stiffness" = [1e4, 2e4, 4e4]   # a list of values
//! "contact.mu_static" = { from = 0.5, to = 0.9, count = 3 }   # evenly spaced, ends included
//! seed = { from = 1, to = 4 }             # integers from..=to (or give `step`)
//! ```
//! Keys are dotted paths into the scenario; a key whose tables do not exist yet creates them. The
//! expanded scenario is named `NAME[mu_static=0.5,stiffness=10000,seed=1]`, its keys in the
//! order of their dotted paths.

use toml::{Table, Value};

/// More scenarios than this from one file is a mistake, not a sweep.
pub const MAX_VARIANTS: usize = 100_000;

/// One expanded scenario: its parameter assignments and the scenario table.
pub struct Variant {
    pub assignments: Vec<(String, Value)>,
    pub table: Table,
}

impl Variant {
    /// `base[k=v,…]`, with each key shortened to its last segment where that is unambiguous.
    pub fn name(&self, base: &str) -> String {
        if self.assignments.is_empty() {
            return base.to_string();
        }
        let last = |k: &str| k.rsplit('.').next().unwrap_or(k).to_string();
        let parts: Vec<String> = self
            .assignments
            .iter()
            .map(|(k, v)| {
                let short = last(k);
                let unique = self
                    .assignments
                    .iter()
                    .filter(|(other, _)| last(other) == short)
                    .count()
                    == 1;
                let key = if unique { short } else { k.clone() };
                format!("{key}={}", display(v))
            })
            .collect();
        format!("{base}[{}]", parts.join(","))
    }
}

fn display(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Float(f) => format!("{f}"),
        other => other.to_string(),
    }
}

/// Splits off the `[sweep]` table and expands it; a file without one is a single variant.
pub fn expand(mut table: Table) -> Result<Vec<Variant>, String> {
    let Some(sweep) = table.remove("sweep") else {
        return Ok(vec![Variant {
            assignments: Vec::new(),
            table,
        }]);
    };
    let Value::Table(sweep) = sweep else {
        return Err("`sweep`: expected a table of \"dotted.key\" = [values]".into());
    };
    let mut axes = Vec::new();
    for (key, spec) in sweep {
        let values = values(&key, &spec)?;
        axes.push((key, values));
    }
    let total = axes
        .iter()
        .try_fold(1usize, |n, (_, v)| n.checked_mul(v.len()))
        .filter(|&n| n <= MAX_VARIANTS)
        .ok_or_else(|| {
            format!(
                "`sweep`: more than {MAX_VARIANTS} combinations; split the sweep into several files"
            )
        })?;
    let mut variants = Vec::with_capacity(total);
    for index in 0..total {
        // mixed-radix digits of `index`, the last axis varying fastest
        let mut rest = index;
        let mut assignments = vec![(String::new(), Value::Boolean(false)); axes.len()];
        for (slot, (key, values)) in assignments.iter_mut().zip(&axes).rev() {
            *slot = (key.clone(), values[rest % values.len()].clone());
            rest /= values.len();
        }
        let mut t = table.clone();
        for (key, value) in &assignments {
            super::overlay::set(&mut t, key, value.clone())
                .map_err(|e| format!("sweep.\"{key}\": {e}"))?;
        }
        variants.push(Variant {
            assignments,
            table: t,
        });
    }
    Ok(variants)
}

/// The values of one sweep axis: a list, or `{ from, to, count }` / `{ from, to, step }`.
fn values(key: &str, spec: &Value) -> Result<Vec<Value>, String> {
    let err = |what: &str| Err(format!("sweep.\"{key}\": {what}"));
    match spec {
        Value::Array(list) if list.is_empty() => err("the list of values is empty"),
        Value::Array(list) => Ok(list.clone()),
        Value::Table(range) => {
            if let Some(extra) = range
                .keys()
                .find(|k| !["from", "to", "count", "step"].contains(&k.as_str()))
            {
                return err(&format!(
                    "unknown field `{extra}`; a range has `from`, `to` and `count` or `step`"
                ));
            }
            let number = |k: &str| -> Result<Option<f64>, String> {
                match range.get(k) {
                    None => Ok(None),
                    Some(Value::Integer(i)) => Ok(Some(*i as f64)),
                    Some(Value::Float(f)) if f.is_finite() => Ok(Some(*f)),
                    Some(other) => Err(format!(
                        "sweep.\"{key}\".{k}: expected a finite number, got {other}"
                    )),
                }
            };
            let (Some(from), Some(to)) = (number("from")?, number("to")?) else {
                return err("a range needs `from` and `to`");
            };
            let integers = matches!(range.get("from"), Some(Value::Integer(_)))
                && matches!(range.get("to"), Some(Value::Integer(_)))
                && !matches!(range.get("step"), Some(Value::Float(_)))
                && range.get("count").is_none();
            match (number("count")?, number("step")?) {
                (Some(_), Some(_)) => err("give `count` or `step`, not both"),
                (Some(count), None) => {
                    if !(count >= 1.0 && count.fract() == 0.0 && count as usize <= MAX_VARIANTS) {
                        return err(&format!(
                            "`count`: expected a whole number from 1 to {MAX_VARIANTS}, got {count}"
                        ));
                    }
                    let n = count as usize;
                    Ok((0..n)
                        .map(|i| {
                            let s = if n == 1 {
                                0.0
                            } else {
                                i as f64 / (n - 1) as f64
                            };
                            Value::Float(round12(from + s * (to - from)))
                        })
                        .collect())
                }
                (None, step) => {
                    let step = step.unwrap_or(1.0);
                    if step.is_nan() || step <= 0.0 {
                        return err(&format!("`step`: expected a number > 0, got {step}"));
                    }
                    if to < from {
                        return err(&format!("`to` ({to}) is below `from` ({from})"));
                    }
                    let n = ((to - from) / step + 1e-9).floor() as usize + 1;
                    if n > MAX_VARIANTS {
                        return err(&format!("more than {MAX_VARIANTS} values"));
                    }
                    Ok((0..n)
                        .map(|i| {
                            let v = round12(from + i as f64 * step);
                            if integers {
                                Value::Integer(v as i64)
                            } else {
                                Value::Float(v)
                            }
                        })
                        .collect())
                }
            }
        }
        other => err(&format!(
            "expected a list of values or a range table, got a {}",
            other.type_str()
        )),
    }
}

/// Rounds to 12 significant digits, so that 0.1 + 2·0.1 is the 0.3 the user meant (and the
/// scenario's name says so).
fn round12(v: f64) -> f64 {
    format!("{v:.11e}").parse().unwrap_or(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> Table {
        text.parse().unwrap()
    }

    #[test]
    fn expands_the_cartesian_product_and_names_each_variant() {
        let v = expand(table(
            "duration = 1.0\n[sweep]\n\"contact.stiffness\" = [1e4, 2e4]\nseed = { from = 1, to = 3 }\n",
        ))
        .unwrap();
        assert_eq!(v.len(), 6);
        assert_eq!(v[0].name("s"), "s[stiffness=10000,seed=1]");
        assert_eq!(v[5].name("s"), "s[stiffness=20000,seed=3]");
        assert_eq!(v[5].table["contact"]["stiffness"].as_float(), Some(2e4));
        assert_eq!(v[5].table["seed"].as_integer(), Some(3));
        assert!(!v[0].table.contains_key("sweep"));
    }

    #[test]
    fn linspace_includes_both_ends() {
        let v = expand(table("[sweep]\nx = { from = 0.5, to = 0.9, count = 3 }\n")).unwrap();
        let xs: Vec<f64> = v.iter().map(|v| v.table["x"].as_float().unwrap()).collect();
        assert_eq!(xs.len(), 3);
        assert!((xs[1] - 0.7).abs() < 1e-12 && xs[2] == 0.9);
    }

    #[test]
    fn refuses_sweeping_into_a_file_name() {
        let e = expand(table(
            "terrain = \"t.toml\"\n[sweep]\n\"terrain.source.peak_to_peak\" = [0.1]\n",
        ))
        .err()
        .unwrap();
        assert!(e.contains("`terrain` is a string"), "{e}");
    }

    #[test]
    fn refuses_empty_and_malformed_axes() {
        for bad in [
            "[sweep]\nx = []\n",
            "[sweep]\nx = 3\n",
            "[sweep]\nx = { from = 1 }\n",
            "[sweep]\nx = { from = 3, to = 1 }\n",
            "[sweep]\nx = { from = 1, to = 2, count = 0 }\n",
        ] {
            assert!(expand(table(bad)).is_err(), "{bad}");
        }
    }
}
