//! `--set path.to.key=value` overrides applied to the parsed TOML table.

/// Sets `path.to.key` in `table` to the TOML value after `=`. A value that is
/// not valid TOML (a bare word such as `coulomb`) is taken as a string.
pub fn apply_override(table: &mut toml::Table, item: &str) -> Result<(), String> {
    let (path, raw) = item
        .split_once('=')
        .ok_or_else(|| format!("--set `{item}`: expected path.to.key=value"))?;
    let path = path.trim();
    let raw = raw.trim();
    if path.is_empty() || path.split('.').any(str::is_empty) {
        return Err(format!("--set `{item}`: empty key in path `{path}`"));
    }
    let value = parse_value(raw);
    let mut keys: Vec<&str> = path.split('.').collect();
    let last = keys.pop().expect("non-empty path");
    let mut node = table;
    for (depth, key) in keys.iter().enumerate() {
        let entry = node
            .entry(key.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        node = entry.as_table_mut().ok_or_else(|| {
            format!(
                "--set `{item}`: `{}` is a value, not a table",
                keys[..=depth].join(".")
            )
        })?;
    }
    node.insert(last.to_string(), value);
    Ok(())
}

fn parse_value(raw: &str) -> toml::Value {
    let doc = format!("v = {raw}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").expect("key v present"),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_nested_values_with_types() {
        let mut t: toml::Table = "[a]\nb = 1.0\n".parse().unwrap();
        apply_override(&mut t, "a.b=2.5").unwrap();
        apply_override(&mut t, "a.c=coulomb").unwrap();
        apply_override(&mut t, "x.y.z=3").unwrap();
        assert_eq!(t["a"]["b"].as_float(), Some(2.5));
        assert_eq!(t["a"]["c"].as_str(), Some("coulomb"));
        assert_eq!(t["x"]["y"]["z"].as_integer(), Some(3));
    }

    #[test]
    fn refuses_malformed_items() {
        let mut t = toml::Table::new();
        assert!(apply_override(&mut t, "novalue").is_err());
        assert!(apply_override(&mut t, "a..b=1").is_err());
        apply_override(&mut t, "a=1").unwrap();
        assert!(apply_override(&mut t, "a.b=1")
            .unwrap_err()
            .contains("not a table"));
    }
}
