//! Particle beds as a plain CSV table (see the [module documentation](super)).

use std::collections::HashMap;

use pdamp_dem::{Bed, Vec3};

use super::{BedFormatError, MAX_TYPES, file_err, line_err, shown};

/// The CSV columns, in the order [`write_bed_csv`] writes them.
pub const BED_CSV_COLUMNS: [&str; 11] = [
    "x_m", "y_m", "z_m", "radius_m", "vx_m_s", "vy_m_s", "vz_m_s", "wx_rad_s", "wy_rad_s",
    "wz_rad_s", "material",
];

const MATERIAL_COLUMN: usize = 10;

/// Reads a bed from CSV (see the [module documentation](super)): required columns
/// `x_m,y_m,z_m,radius_m`, optional `vx_m_s,vy_m_s,vz_m_s` and `wx_rad_s,wy_rad_s,wz_rad_s` (all
/// three or none; absent: zero) and `material` (absent: every particle is `default_material`).
/// The materials table lists the names in order of first appearance. Errors name the line and
/// the column. Never panics.
pub fn read_bed_csv(text: &str, default_material: &str) -> Result<Bed, BedFormatError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .filter(|(_, l)| {
            let t = l.trim_start();
            !t.trim_end().is_empty() && !t.starts_with('#')
        });
    let Some((header_line, header)) = lines.next() else {
        return Err(file_err(format!(
            "no header row (expected columns such as {})",
            BED_CSV_COLUMNS.join(",")
        )));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut col: [Option<usize>; 11] = [None; 11];
    for (j, name) in names.iter().enumerate() {
        match BED_CSV_COLUMNS.iter().position(|c| c == name) {
            Some(k) if col[k].is_some() => {
                return Err(line_err(
                    header_line,
                    format!("column {name} appears twice in the header"),
                ));
            }
            Some(k) => col[k] = Some(j),
            None => {
                return Err(line_err(
                    header_line,
                    format!(
                        "unknown column '{}' (field {}); known columns: {}",
                        shown(name),
                        j + 1,
                        BED_CSV_COLUMNS.join(",")
                    ),
                ));
            }
        }
    }
    let missing: Vec<&str> = (0..4)
        .filter(|&k| col[k].is_none())
        .map(|k| BED_CSV_COLUMNS[k])
        .collect();
    if !missing.is_empty() {
        return Err(line_err(
            header_line,
            format!("missing required column(s) {}", missing.join(",")),
        ));
    }
    for (first, what) in [(4, "velocity"), (7, "angular velocity")] {
        let have: Vec<&str> = (first..first + 3)
            .filter(|&k| col[k].is_some())
            .map(|k| BED_CSV_COLUMNS[k])
            .collect();
        if !have.is_empty() && have.len() < 3 {
            let lacking: Vec<&str> = (first..first + 3)
                .filter(|&k| col[k].is_none())
                .map(|k| BED_CSV_COLUMNS[k])
                .collect();
            return Err(line_err(
                header_line,
                format!(
                    "{what} columns come all three or none: the header has {} but not {}",
                    have.join(","),
                    lacking.join(",")
                ),
            ));
        }
    }

    let mut bed = Bed::default();
    let mut index: HashMap<String, u16> = HashMap::new();
    for (line, row) in lines {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(line_err(
                line,
                format!(
                    "expected {} fields (as in the header), found {}",
                    names.len(),
                    fields.len()
                ),
            ));
        }
        let value = |k: usize| -> Result<f64, BedFormatError> {
            let Some(j) = col[k] else { return Ok(0.0) };
            let text = fields[j];
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    line_err(
                        line,
                        format!(
                            "column {}: '{}' is not a finite number",
                            BED_CSV_COLUMNS[k],
                            shown(text)
                        ),
                    )
                })
        };
        let v3 = |k: usize| -> Result<Vec3, BedFormatError> {
            Ok(Vec3::new(value(k)?, value(k + 1)?, value(k + 2)?))
        };
        let position_m = v3(0)?;
        let radius_m = value(3)?;
        if radius_m <= 0.0 {
            return Err(line_err(
                line,
                format!("column radius_m: radius {radius_m} must be > 0"),
            ));
        }
        let velocity_m_s = v3(4)?;
        let angular_velocity_rad_s = v3(7)?;
        let name = match col[MATERIAL_COLUMN] {
            Some(j) if fields[j].is_empty() => {
                return Err(line_err(line, "column material: empty material name"));
            }
            Some(j) => fields[j],
            None => default_material,
        };
        let m = match index.get(name) {
            Some(&m) => m,
            None => {
                let m = u16::try_from(bed.materials.len()).map_err(|_| {
                    line_err(
                        line,
                        format!("column material: more than {MAX_TYPES} distinct materials"),
                    )
                })?;
                index.insert(name.to_string(), m);
                bed.materials.push(name.to_string());
                m
            }
        };
        bed.position_m.push(position_m);
        bed.radius_m.push(radius_m);
        bed.material.push(m);
        bed.velocity_m_s.push(velocity_m_s);
        bed.angular_velocity_rad_s.push(angular_velocity_rad_s);
    }
    bed.validate()?;
    Ok(bed)
}

/// Writes `bed` as CSV with all columns ([`BED_CSV_COLUMNS`]: positions, radius, velocities,
/// spins, material name), one row per particle in bed order, every f64 in shortest round-trip
/// form ([`crate::csv::format_f64`]). [`read_bed_csv`] reads it back to the identical bed when
/// the bed's materials table lists exactly the used names in order of first appearance (as in
/// any bed read from CSV) and the names are non-empty, without commas or line breaks, and
/// without surrounding whitespace (names are written unquoted).
///
/// # Panics
///
/// If the bed's columns are inconsistent (a bed that passes [`Bed::validate`] never makes it
/// panic).
pub fn write_bed_csv(bed: &Bed) -> String {
    let mut s = BED_CSV_COLUMNS.join(",");
    s.push('\n');
    for i in 0..bed.len() {
        let p = &bed.position_m[i];
        let v = &bed.velocity_m_s[i];
        let w = &bed.angular_velocity_rad_s[i];
        for x in [p.x, p.y, p.z, bed.radius_m[i], v.x, v.y, v.z, w.x, w.y, w.z] {
            crate::csv::format_f64(x, &mut s);
            s.push(',');
        }
        s.push_str(&bed.materials[bed.material[i] as usize]);
        s.push('\n');
    }
    s
}
