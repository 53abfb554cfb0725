//! Fields laid over a scenario's table by dotted path (`gait.period`, `contact.stiffness`), the
//! one way sweeps, comparisons and searches change a scenario: missing tables are made on the
//! way, `command.FIELD` is the first `[[command]]`'s and `command.N.FIELD` the one at place N
//! (from 0), and the result is then read as a [`super::ScenarioSpec`], whose schema refuses a
//! field it does not have, naming it.

use toml::{Table, Value};

/// Sets the field at dotted `path` of a scenario's `table`. Refused: an empty part, and a part on
/// the way that is not a table (a file's name where a table was meant: `terrain = "t.toml"`
/// under `terrain.source.peak_to_peak`).
pub fn set(table: &mut Table, path: &str, value: Value) -> Result<(), String> {
    let parts: Vec<&str> = path.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err("not a dotted key".into());
    }
    if let ["command", field] = parts[..] {
        // the first command, made when the scenario has none (at 0 s, no ramp: the default's)
        let list = table
            .entry("command")
            .or_insert_with(|| Value::Array(Vec::new()));
        let Value::Array(list) = list else {
            return Err(format!("`command` is a {}, not a list", list.type_str()));
        };
        if list.is_empty() {
            list.push(Value::Table(Table::from_iter([(
                "ramp".to_string(),
                Value::Float(0.0),
            )])));
        }
        let Value::Table(command) = &mut list[0] else {
            return Err(format!(
                "the first `command` is a {}, not a table",
                list[0].type_str()
            ));
        };
        command.insert(field.to_string(), value);
        return Ok(());
    }
    if let ["command", index, field] = parts[..] {
        // a later command's field, by its place in the list (0 the first)
        let count = table
            .get("command")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        let Some(Value::Table(command)) = index
            .parse::<usize>()
            .ok()
            .and_then(|i| table.get_mut("command")?.as_array_mut()?.get_mut(i))
        else {
            return Err(format!(
                "`command.{index}`: expected the place (from 0) of one of the scenario's \
                 {count} [[command]] tables"
            ));
        };
        command.insert(field.to_string(), value);
        return Ok(());
    }
    if parts[0] == "command" {
        return Err(
            "expected `command.FIELD` (the first [[command]]'s) or `command.N.FIELD`".into(),
        );
    }
    let mut at = table;
    for (i, part) in parts[..parts.len() - 1].iter().enumerate() {
        let entry = at
            .entry(part.to_string())
            .or_insert_with(|| Value::Table(Table::new()));
        at = match entry {
            Value::Table(t) => t,
            other => {
                return Err(format!(
                    "`{}` is a {}, not a table (write it as an inline table to change its fields)",
                    parts[..=i].join("."),
                    other.type_str()
                ));
            }
        };
    }
    at.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

/// Lays `fields` over the table `section` of a scenario's `table` (made if it has none).
pub fn set_all(
    table: &mut Table,
    section: &str,
    fields: impl IntoIterator<Item = (String, Value)>,
) -> Result<(), String> {
    for (field, value) in fields {
        set(table, &format!("{section}.{field}"), value)
            .map_err(|e| format!("{section}.{field}: {e}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> Table {
        text.parse().unwrap()
    }

    #[test]
    fn a_field_is_set_and_missing_tables_made() {
        let mut t = table("[contact]\nstiffness = 1.0\n");
        set(&mut t, "contact.damping", Value::Float(2.0)).unwrap();
        set(&mut t, "gait.phase_offsets.rf", Value::Float(0.5)).unwrap();
        assert_eq!(t["contact"]["stiffness"].as_float(), Some(1.0));
        assert_eq!(t["contact"]["damping"].as_float(), Some(2.0));
        assert_eq!(t["gait"]["phase_offsets"]["rf"].as_float(), Some(0.5));
    }

    #[test]
    fn a_command_field_is_the_first_commands() {
        let mut t = Table::new();
        set(&mut t, "command.forward", Value::Float(0.1)).unwrap();
        assert_eq!(t["command"][0]["forward"].as_float(), Some(0.1));
        assert_eq!(t["command"][0]["ramp"].as_float(), Some(0.0));
        let mut t = table("[[command]]\nat = 0.0\nforward = 0.2\n[[command]]\nat = 2.0\n");
        set(&mut t, "command.forward", Value::Float(0.1)).unwrap();
        assert_eq!(t["command"][0]["forward"].as_float(), Some(0.1));
        assert!(t["command"][1].get("forward").is_none());
        // a later one by its place
        set(&mut t, "command.1.forward", Value::Float(0.3)).unwrap();
        assert_eq!(t["command"][1]["forward"].as_float(), Some(0.3));
        assert_eq!(t["command"][0]["forward"].as_float(), Some(0.1));
        for (path, expected) in [
            (
                "command.2.forward",
                "of one of the scenario's 2 [[command]] tables",
            ),
            ("command.x.forward", "`command.x`: expected the place"),
            ("command.1.a.b", "expected `command.FIELD`"),
        ] {
            let e = set(&mut t, path, Value::Float(0.3)).unwrap_err();
            assert!(e.contains(expected), "{path}: {e}");
        }
    }

    #[test]
    fn a_path_through_a_value_or_with_an_empty_part_is_refused() {
        let mut t = table("terrain = \"t.toml\"\n");
        let e = set(&mut t, "terrain.source.peak_to_peak", Value::Float(0.1)).unwrap_err();
        assert!(e.contains("`terrain` is a string"), "{e}");
        assert_eq!(
            set(&mut t, "gait..period", Value::Float(1.0)),
            Err("not a dotted key".into())
        );
        let e = set_all(&mut t, "terrain", [("x".to_string(), Value::Float(1.0))]).unwrap_err();
        assert!(e.starts_with("terrain.x: `terrain` is a string"), "{e}");
    }
}
