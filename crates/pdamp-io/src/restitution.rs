//! Restitution tables ε(v) from CSV, e.g. the output of `pdamp cor`
//! (`velocity_m_s,restitution,contact_time_s,max_force_n`), for the `gonthier-table` contact law
//! (D Tab. 8.1 "velocity dependent, see Chap. 4"). In a scenario,
//! `normal = { law = "gonthier-table", restitution_table_csv = "cor.csv" }` reads the file
//! (relative to the scenario) into `impact_velocities_m_s` and `restitutions`.

/// Key of a contact `normal` table that names a restitution CSV.
pub const TABLE_KEY: &str = "restitution_table_csv";

/// Parses a restitution table: columns `velocity_m_s` and `restitution` (others are ignored),
/// velocities > 0 and strictly increasing, restitutions in (0, 1]. Never panics; errors name
/// the line.
pub fn parse_restitution_table(text: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (header, rows) = crate::csv::parse_csv_f64(text).map_err(|e| e.to_string())?;
    let col = |name: &str| {
        header.iter().position(|h| h == name).ok_or_else(|| {
            format!(
                "no column '{name}' (columns: {}); the table needs velocity_m_s and restitution",
                header.join(", ")
            )
        })
    };
    let (iv, ie) = (col("velocity_m_s")?, col("restitution")?);
    if rows.is_empty() {
        return Err("the table has no rows".into());
    }
    let (mut v, mut e) = (
        Vec::with_capacity(rows.len()),
        Vec::with_capacity(rows.len()),
    );
    for (k, r) in rows.iter().enumerate() {
        let line = k + 2;
        let (vel, eps) = (r[iv], r[ie]);
        if !(vel.is_finite() && vel > 0.0) {
            return Err(format!("row {line}: velocity_m_s must be > 0, got {vel}"));
        }
        if let Some(&prev) = v.last()
            && vel <= prev
        {
            return Err(format!(
                "row {line}: velocity_m_s must increase strictly ({vel} after {prev})"
            ));
        }
        if !(eps > 0.0 && eps <= 1.0) {
            return Err(format!(
                "row {line}: restitution must lie in (0, 1], got {eps}"
            ));
        }
        v.push(vel);
        e.push(eps);
    }
    Ok((v, e))
}

/// Replaces every `restitution_table_csv = "FILE"` in the contact normal tables of a parsed
/// scenario (`contact.normal`, `contact.pairs[k].normal`) by the arrays read from FILE
/// (relative to `base_dir`). Returns whether anything was replaced; errors name the key.
pub fn inline_tables(doc: &mut toml::Table, base_dir: &std::path::Path) -> Result<bool, String> {
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
            .ok_or_else(|| format!("{key} must be a file name (string)"))?;
        let path = base_dir.join(file);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("{key}: cannot read {}: {e}", path.display()))?;
        let (vel, eps) = parse_restitution_table(&text)
            .map_err(|e| format!("{key}: {}: {e}", path.display()))?;
        if t.contains_key("impact_velocities_m_s") || t.contains_key("restitutions") {
            return Err(format!(
                "{key}: give either the file or impact_velocities_m_s/restitutions, not both"
            ));
        }
        let arr = |x: Vec<f64>| toml::Value::Array(x.into_iter().map(toml::Value::Float).collect());
        t.insert("impact_velocities_m_s".into(), arr(vel));
        t.insert("restitutions".into(), arr(eps));
        any = true;
    }
    Ok(any)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_cor_output_and_rejects_bad_rows() {
        let (v, e) = parse_restitution_table(
            "velocity_m_s,restitution,contact_time_s,max_force_n\n0.1,0.95,1e-4,10\n1.0,0.7,9e-5,200\n",
        )
        .unwrap();
        assert_eq!(v, vec![0.1, 1.0]);
        assert_eq!(e, vec![0.95, 0.7]);
        let err =
            parse_restitution_table("velocity_m_s,restitution\n1.0,0.7\n0.5,0.8\n").unwrap_err();
        assert!(err.contains("row 3") && err.contains("increase"), "{err}");
        let err = parse_restitution_table("velocity_m_s,restitution\n1.0,1.7\n").unwrap_err();
        assert!(err.contains("(0, 1]"), "{err}");
        let err = parse_restitution_table("speed,restitution\n1.0,0.7\n").unwrap_err();
        assert!(err.contains("no column 'velocity_m_s'"), "{err}");
        let err = parse_restitution_table("velocity_m_s,restitution\n1.0,NaN\n").unwrap_err();
        assert!(err.contains("restitution"), "{err}");
    }
}
