//! Restitution tables in a scenario: `normal = { law = "gonthier-table", restitution_table_csv =
//! "cor.csv" }` is replaced by the table's arrays before the scenario is parsed (the file format
//! is [`pdamp_io::restitution`]).

use crate::InputError;
use pdamp_io::restitution::{TABLE_KEY, parse_restitution_table};

/// Replaces every `restitution_table_csv = "FILE"` in the contact normal tables of a parsed
/// scenario (`contact.normal`, `contact.pairs[k].normal`) by the arrays read from FILE
/// (relative to `base_dir`). Returns whether anything was replaced; errors name the key.
pub fn inline_tables(
    doc: &mut toml::Table,
    base_dir: &std::path::Path,
) -> Result<bool, InputError> {
    let Some(toml::Value::Table(contact)) = doc.get_mut("contact") else {
        return Ok(false);
    };
    let mut normals: Vec<(String, &mut toml::Table)> = Vec::new();
    let mut pairs_slot = None;
    for (k, v) in contact.iter_mut() {
        match (k.as_str(), v) {
            ("normal", toml::Value::Table(t)) => normals.push(("contact.normal".into(), t)),
            ("pairs", toml::Value::Array(a)) => pairs_slot = Some(a),
            _ => {}
        }
    }
    if let Some(pairs) = pairs_slot {
        for (i, p) in pairs.iter_mut().enumerate() {
            if let toml::Value::Table(p) = p
                && let Some(toml::Value::Table(t)) = p.get_mut("normal")
            {
                normals.push((format!("contact.pairs[{i}].normal"), t));
            }
        }
    }
    let mut any = false;
    for (key, t) in normals {
        let Some(v) = t.remove(TABLE_KEY) else {
            continue;
        };
        let key = format!("{key}.{TABLE_KEY}");
        let file = v
            .as_str()
            .ok_or_else(|| InputError::message(format!("{key} must be a file name (string)")))?;
        let path = base_dir.join(file);
        let text = std::fs::read_to_string(&path).map_err(|e| InputError::read(&key, &path, e))?;
        let (vel, eps) =
            parse_restitution_table(&text).map_err(|e| InputError::file(&key, &path, e))?;
        if t.contains_key("impact_velocities_m_s") || t.contains_key("restitutions") {
            return Err(InputError::message(format!(
                "{key}: give either the file or impact_velocities_m_s/restitutions, not both"
            )));
        }
        let arr = |x: Vec<f64>| toml::Value::Array(x.into_iter().map(toml::Value::Float).collect());
        t.insert("impact_velocities_m_s".into(), arr(vel));
        t.insert("restitutions".into(), arr(eps));
        any = true;
    }
    Ok(any)
}
