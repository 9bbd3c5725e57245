//! Restitution tables ε(v) from CSV, e.g. the output of `pdamp cor`
//! (`velocity_m_s,restitution,contact_time_s,max_force_n`), for the `gonthier-table` contact law
//! (D Tab. 8.1 "velocity dependent, see Chap. 4"). In a scenario,
//! `normal = { law = "gonthier-table", restitution_table_csv = "cor.csv" }` reads the file
//! (relative to the scenario) into `impact_velocities_m_s` and `restitutions`
//! (`pdamp_scenario::restitution::inline_tables`); this module is the file format.

/// Key of a contact `normal` table that names a restitution CSV.
pub const TABLE_KEY: &str = "restitution_table_csv";

/// A restitution table that cannot be used ([`parse_restitution_table`]); names the line.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// The CSV itself does not parse.
    #[error(transparent)]
    Csv(#[from] crate::csv::CsvError),
    /// A required column is missing.
    #[error(
        "no column '{column}' (columns: {columns}); the table needs velocity_m_s and restitution"
    )]
    NoColumn {
        /// The missing column.
        column: String,
        /// The columns the file has, comma separated.
        columns: String,
    },
    /// Only a header.
    #[error("the table has no rows")]
    NoRows,
    /// A value out of range.
    #[error("row {line}: {column} {message}")]
    Row {
        /// 1-based line in the file (the header is line 1).
        line: usize,
        /// The column.
        column: &'static str,
        /// What is wrong, e.g. `must be > 0, got -1`.
        message: String,
    },
}

impl TableError {
    fn row(line: usize, column: &'static str, message: String) -> Self {
        Self::Row {
            line,
            column,
            message,
        }
    }
}

/// Parses a restitution table: columns `velocity_m_s` and `restitution` (others are ignored),
/// velocities > 0 and strictly increasing, restitutions in (0, 1]. Never panics; errors name
/// the line.
pub fn parse_restitution_table(text: &str) -> Result<(Vec<f64>, Vec<f64>), TableError> {
    let (header, rows) = crate::csv::parse_csv_f64(text)?;
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| TableError::NoColumn {
                column: name.to_string(),
                columns: header.join(", "),
            })
    };
    let (iv, ie) = (col("velocity_m_s")?, col("restitution")?);
    if rows.is_empty() {
        return Err(TableError::NoRows);
    }
    let (mut v, mut e) = (
        Vec::with_capacity(rows.len()),
        Vec::with_capacity(rows.len()),
    );
    for (k, r) in rows.iter().enumerate() {
        let line = k + 2;
        let (vel, eps) = (r[iv], r[ie]);
        if !(vel.is_finite() && vel > 0.0) {
            return Err(TableError::row(
                line,
                "velocity_m_s",
                format!("must be > 0, got {vel}"),
            ));
        }
        if let Some(&prev) = v.last()
            && vel <= prev
        {
            let why = format!("must increase strictly ({vel} after {prev})");
            return Err(TableError::row(line, "velocity_m_s", why));
        }
        if !(eps > 0.0 && eps <= 1.0) {
            let why = format!("must lie in (0, 1], got {eps}");
            return Err(TableError::row(line, "restitution", why));
        }
        v.push(vel);
        e.push(eps);
    }
    Ok((v, e))
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
        let err = parse_restitution_table("velocity_m_s,restitution\n1.0,0.7\n0.5,0.8\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("row 3") && err.contains("increase"), "{err}");
        let err = parse_restitution_table("velocity_m_s,restitution\n1.0,1.7\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("(0, 1]"), "{err}");
        let err = parse_restitution_table("speed,restitution\n1.0,0.7\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("no column 'velocity_m_s'"), "{err}");
        let err = parse_restitution_table("velocity_m_s,restitution\n1.0,NaN\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("restitution"), "{err}");
    }
}
