//! Particle beds ([`pdamp_dem::Bed`]) in two foreign formats: LAMMPS / LIGGGHTS data files
//! (the format of their `read_data` / `write_data` commands) and a plain CSV table.
//!
//! Both readers take arbitrary text and return a bed that passes [`Bed::validate`] or a
//! [`BedFormatError`]; they never panic, and they never allocate from a count announced in the
//! file without first bounding it by the size of the input. Both writers format every f64 so
//! that it parses back to the identical value: reading a written bed gives the identical bed.
//!
//! # LAMMPS / LIGGGHTS data files
//!
//! [`read_lammps_data`] reads `atom_style sphere` (LAMMPS) and `atom_style granular`
//! (LIGGGHTS) data files **in SI units** (`units si`: m, kg/m³, m/s, rad/s); nothing in the file
//! says which units it uses, so a file in other units is read as if it were SI. The rules:
//!
//! * The first line is a title and is always skipped. `#` starts a comment anywhere on a line;
//!   blank lines are skipped everywhere (the blank line after a section name is not required).
//! * Header (every line before the first section name): `N atoms` and `K atom types` are
//!   required; `xlo xhi`, `ylo yhi`, `zlo zhi` (finite, lo < hi) and `xy xz yz` (finite) are
//!   checked but not kept (a bed has no box). Any other header line whose first word is a number
//!   (`N bonds`, `N bond types`, `N extra bond per atom`, `N ellipsoids`, …) is accepted and
//!   ignored; a header line starting with anything else is an error.
//! * A section starts at a line (comment removed) that is one of the section names of LAMMPS and
//!   LIGGGHTS (`Atoms`, `Velocities`, `Masses`, `Ellipsoids`, `Lines`, `Triangles`, `Bodies`,
//!   `Bonds`, `Angles`, `Dihedrals`, `Impropers`, `Pair Coeffs`, `PairIJ Coeffs`,
//!   `Bond Coeffs`, …, `Atom Type Labels`, …) or any line of letter-initial words whose last
//!   word is `Coeffs` or `Labels`. Every other line up to the next section name belongs to the
//!   section. Lines of sections this reader does not use are skipped without being interpreted,
//!   so their number need not match any header count (rule chosen because it does not depend on
//!   knowing how many lines each foreign section has).
//! * `Atoms` (required when `N atoms` > 0): `atom-ID atom-type diameter density x y z`,
//!   optionally followed by three integer image flags `ix iy iz`, which are checked and ignored
//!   (positions are taken as written, i.e. wrapped into the box). A comment after the section
//!   name that names a style must name `sphere` or `granular`; any other (`Atoms # full`) is
//!   refused. IDs are positive integers, unique, in any order and not necessarily contiguous;
//!   the bed is ordered by ascending ID. Types are integers in `1..=K` (type labels are not
//!   supported). Diameter and density must be finite and > 0; the density is only checked (the
//!   scenario's material sets it). Radius = diameter / 2. Exactly `N atoms` entries.
//! * `Velocities` (optional): `atom-ID vx vy vz wx wy wz` (the same 7 columns for sphere and
//!   granular), matched to atoms by ID; if present, exactly one entry per atom. Without it,
//!   velocities and spins are zero.
//! * `Masses` (optional): `type mass`, checked (type in range, mass finite and > 0) and
//!   ignored, as LAMMPS does for per-atom-mass styles.
//! * Material names: `type_materials[t - 1]` names atom type `t` and must then have exactly `K`
//!   entries; the bed's materials table is `type_materials` itself. With an empty
//!   `type_materials` the names are `type1`, `type2`, …, `typeK`. At most 65 536 types (material
//!   indices are u16).
//!
//! [`write_lammps_data`] writes what the reader accepts (and what LAMMPS `read_data` reads with
//! `atom_style sphere`, `units si`).
//!
//! # CSV
//!
//! [`read_bed_csv`] / [`write_bed_csv`]: a header row naming the columns, then one row per
//! particle, comma-separated, fields trimmed, no quoting. Columns (SI units in the names):
//! `x_m,y_m,z_m,radius_m` (required), `vx_m_s,vy_m_s,vz_m_s` and `wx_rad_s,wy_rad_s,wz_rad_s`
//! (optional, each triple all or none; absent means zero), `material` (optional: a non-empty
//! name; absent means the default material). Columns may come in any order. Blank lines and
//! lines whose first non-blank character is `#` are skipped (also before the header).

use pdamp_dem::{Bed, Vec3};
use std::fmt::Write as _;

mod bed_csv;

pub use self::bed_csv::{BED_CSV_COLUMNS, read_bed_csv, write_bed_csv};

/// Errors of the bed readers. Line numbers are 1-based and count every line of the input.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BedFormatError {
    /// The bed read is inconsistent (names the particle and column).
    #[error(transparent)]
    Bed(#[from] pdamp_dem::bed::BedError),
    /// Something is wrong on one line of the input (a malformed, out-of-range or repeated
    /// entry, an unknown column, …).
    #[error("line {line}: {message}")]
    Line {
        /// Line number (1-based).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Something is wrong with the file as a whole (a missing section or header line, entry
    /// counts that do not match the header, …).
    #[error("{message}")]
    File {
        /// What is wrong.
        message: String,
    },
}

fn line_err(line: usize, message: impl Into<String>) -> BedFormatError {
    BedFormatError::Line {
        line,
        message: message.into(),
    }
}

fn file_err(message: impl Into<String>) -> BedFormatError {
    BedFormatError::File {
        message: message.into(),
    }
}

/// `word` for an error message: at most 64 characters.
fn shown(word: &str) -> String {
    let mut s: String = word.chars().take(64).collect();
    if s.len() < word.len() {
        s.push('…');
    }
    s
}

/// Most atom types / materials a bed can index (material indices are u16).
const MAX_TYPES: u64 = 1 << 16;

// ---------------------------------------------------------------------------------------------
// LAMMPS / LIGGGHTS data files
// ---------------------------------------------------------------------------------------------

/// Section names of LAMMPS and LIGGGHTS data files (besides any `… Coeffs` / `… Labels`).
const SECTION_NAMES: &[&str] = &[
    "Atoms",
    "Velocities",
    "Masses",
    "Ellipsoids",
    "Lines",
    "Triangles",
    "Bodies",
    "Bonds",
    "Angles",
    "Dihedrals",
    "Impropers",
    "Pair Coeffs",
    "PairIJ Coeffs",
    "Bond Coeffs",
    "Angle Coeffs",
    "Dihedral Coeffs",
    "Improper Coeffs",
    "BondBond Coeffs",
    "BondAngle Coeffs",
    "MiddleBondTorsion Coeffs",
    "EndBondTorsion Coeffs",
    "AngleTorsion Coeffs",
    "AngleAngleTorsion Coeffs",
    "BondBond13 Coeffs",
    "AngleAngle Coeffs",
    "Atom Type Labels",
    "Bond Type Labels",
    "Angle Type Labels",
    "Dihedral Type Labels",
    "Improper Type Labels",
];

/// The section name on a (comment-free, trimmed, non-empty) line, words joined by one space.
fn section_name(content: &str) -> Option<String> {
    if !content.starts_with(|c: char| c.is_ascii_alphabetic()) {
        return None;
    }
    let words: Vec<&str> = content.split_whitespace().collect();
    let name = words.join(" ");
    if SECTION_NAMES.contains(&name.as_str()) {
        return Some(name);
    }
    let last = *words.last()?;
    let wordlike = |w: &&str| {
        w.starts_with(|c: char| c.is_ascii_alphabetic())
            && w.chars().all(|c| c.is_ascii_alphanumeric())
    };
    ((last == "Coeffs" || last == "Labels") && words.iter().all(wordlike)).then_some(name)
}

/// `(content, comment)` of a line: the text before the first `#` and the text after it.
fn split_comment(raw: &str) -> (&str, Option<&str>) {
    match raw.find('#') {
        Some(i) => (&raw[..i], Some(&raw[i + 1..])),
        None => (raw, None),
    }
}

fn parse_finite(word: &str, line: usize, what: &str) -> Result<f64, BedFormatError> {
    word.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            line_err(
                line,
                format!("{what} '{}' is not a finite number", shown(word)),
            )
        })
}

fn parse_positive(word: &str, line: usize, what: &str) -> Result<f64, BedFormatError> {
    let v = parse_finite(word, line, what)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(line_err(line, format!("{what} {v} must be > 0")))
    }
}

fn parse_count(word: &str, line: usize, what: &str) -> Result<u64, BedFormatError> {
    word.parse::<u64>().map_err(|_| {
        line_err(
            line,
            format!("{what} '{}' is not a non-negative integer", shown(word)),
        )
    })
}

fn parse_id(word: &str, line: usize) -> Result<u64, BedFormatError> {
    match word.parse::<u64>() {
        Ok(id) if id >= 1 => Ok(id),
        _ => Err(line_err(
            line,
            format!("atom ID '{}' is not a positive integer", shown(word)),
        )),
    }
}

/// Atom type `word` (1-based) as a 0-based material index, checked against `1..=n_types`.
fn parse_type(word: &str, line: usize, n_types: u64) -> Result<u16, BedFormatError> {
    let t = word.parse::<u64>().map_err(|_| {
        line_err(
            line,
            format!(
                "atom type '{}' is not an integer (type labels are not supported)",
                shown(word)
            ),
        )
    })?;
    if t == 0 || t > n_types {
        return Err(line_err(
            line,
            format!("atom type {t} is out of range 1..={n_types}"),
        ));
    }
    u16::try_from(t - 1).map_err(|_| line_err(line, format!("atom type {t} is too large")))
}

/// Header counts and the lines they were read from.
#[derive(Default)]
struct Header {
    atoms: Option<(u64, usize)>,
    types: Option<(u64, usize)>,
    boxes: [bool; 4],
}

impl Header {
    fn parse_line(&mut self, words: &[&str], line: usize) -> Result<(), BedFormatError> {
        let repeated = |what: &str| line_err(line, format!("repeated '{what}' header line"));
        match words {
            [n, "atoms"] => {
                if self.atoms.is_some() {
                    return Err(repeated("atoms"));
                }
                self.atoms = Some((parse_count(n, line, "atom count")?, line));
            }
            [n, "atom", "types"] => {
                if self.types.is_some() {
                    return Err(repeated("atom types"));
                }
                self.types = Some((parse_count(n, line, "atom type count")?, line));
            }
            [
                lo,
                hi,
                a @ ("xlo" | "ylo" | "zlo"),
                b @ ("xhi" | "yhi" | "zhi"),
            ] if a[..1] == b[..1] => {
                let k = match &a[..1] {
                    "x" => 0,
                    "y" => 1,
                    _ => 2,
                };
                if self.boxes[k] {
                    return Err(repeated(&format!("{a} {b}")));
                }
                self.boxes[k] = true;
                let lo_v = parse_finite(lo, line, a)?;
                let hi_v = parse_finite(hi, line, b)?;
                if lo_v >= hi_v {
                    return Err(line_err(
                        line,
                        format!("box bounds must satisfy {a} < {b}, got {lo_v} {hi_v}"),
                    ));
                }
            }
            [xy, xz, yz, "xy", "xz", "yz"] => {
                if self.boxes[3] {
                    return Err(repeated("xy xz yz"));
                }
                self.boxes[3] = true;
                parse_finite(xy, line, "xy")?;
                parse_finite(xz, line, "xz")?;
                parse_finite(yz, line, "yz")?;
            }
            [first, ..] if first.parse::<f64>().is_ok() => {} // other header lines: ignored
            _ => {
                return Err(line_err(
                    line,
                    format!(
                        "'{}' is neither a header line nor a known section name",
                        shown(&words.join(" "))
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Checks the header once it is complete; returns `(atoms, atom types)`.
    fn finish(&self, n_lines: usize, n_names: usize) -> Result<(u64, u64), BedFormatError> {
        let (atoms, atoms_line) = self
            .atoms
            .ok_or_else(|| file_err("the header has no 'N atoms' line"))?;
        let (types, types_line) = self
            .types
            .ok_or_else(|| file_err("the header has no 'N atom types' line"))?;
        if atoms > n_lines as u64 {
            return Err(line_err(
                atoms_line,
                format!(
                    "the header announces {atoms} atoms, but the file has only {n_lines} lines"
                ),
            ));
        }
        if types > MAX_TYPES {
            return Err(line_err(
                types_line,
                format!("{types} atom types; at most {MAX_TYPES} are supported"),
            ));
        }
        if n_names != 0 && n_names as u64 != types {
            return Err(line_err(
                types_line,
                format!("the file has {types} atom types, but {n_names} material names were given"),
            ));
        }
        Ok((atoms, types))
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Section {
    Header,
    Atoms,
    Velocities,
    Masses,
    Skip,
}

struct AtomRow {
    id: u64,
    line: usize,
    material: u16,
    radius_m: f64,
    position_m: Vec3,
}

struct VelocityRow {
    id: u64,
    line: usize,
    velocity_m_s: Vec3,
    angular_velocity_rad_s: Vec3,
}

fn parse_vec3(words: &[&str], line: usize, names: [&str; 3]) -> Result<Vec3, BedFormatError> {
    Ok(Vec3::new(
        parse_finite(words[0], line, names[0])?,
        parse_finite(words[1], line, names[1])?,
        parse_finite(words[2], line, names[2])?,
    ))
}

fn parse_atom(words: &[&str], line: usize, n_types: u64) -> Result<AtomRow, BedFormatError> {
    if words.len() != 7 && words.len() != 10 {
        return Err(line_err(
            line,
            format!(
                "Atoms entry has {} columns; atom_style sphere/granular has 7 \
                 (atom-ID atom-type diameter density x y z) or 10 with image flags ix iy iz",
                words.len()
            ),
        ));
    }
    let id = parse_id(words[0], line)?;
    let material = parse_type(words[1], line, n_types)?;
    let diameter = parse_positive(words[2], line, "diameter")?;
    let radius_m = diameter / 2.0;
    if radius_m <= 0.0 {
        return Err(line_err(
            line,
            format!("diameter {diameter} is too small (its half is 0)"),
        ));
    }
    parse_positive(words[3], line, "density")?;
    let position_m = parse_vec3(&words[4..7], line, ["x", "y", "z"])?;
    for w in words.iter().skip(7) {
        if w.parse::<i64>().is_err() {
            return Err(line_err(
                line,
                format!("image flag '{}' is not an integer", shown(w)),
            ));
        }
    }
    Ok(AtomRow {
        id,
        line,
        material,
        radius_m,
        position_m,
    })
}

fn parse_velocity(words: &[&str], line: usize) -> Result<VelocityRow, BedFormatError> {
    if words.len() != 7 {
        return Err(line_err(
            line,
            format!(
                "Velocities entry has {} columns; atom_style sphere/granular has 7 \
                 (atom-ID vx vy vz wx wy wz)",
                words.len()
            ),
        ));
    }
    Ok(VelocityRow {
        id: parse_id(words[0], line)?,
        line,
        velocity_m_s: parse_vec3(&words[1..4], line, ["vx", "vy", "vz"])?,
        angular_velocity_rad_s: parse_vec3(&words[4..7], line, ["wx", "wy", "wz"])?,
    })
}

fn parse_mass(words: &[&str], line: usize, n_types: u64) -> Result<(), BedFormatError> {
    if words.len() != 2 {
        return Err(line_err(
            line,
            format!(
                "Masses entry has {} columns; expected 2 (type mass)",
                words.len()
            ),
        ));
    }
    parse_type(words[0], line, n_types)?;
    parse_positive(words[1], line, "mass")?;
    Ok(())
}

/// Reads a LAMMPS (`atom_style sphere`) or LIGGGHTS (`atom_style granular`) data file in SI
/// units into a bed ordered by ascending atom ID; `type_materials[t - 1]` names atom type `t`
/// (empty: `type1`, `type2`, …). See the [module documentation](self) for the accepted
/// format. Never panics.
pub fn read_lammps_data(text: &str, type_materials: &[String]) -> Result<Bed, BedFormatError> {
    let n_lines = text.lines().count();
    let mut header = Header::default();
    let mut counts: Option<(u64, u64)> = None;
    let mut section = Section::Header;
    let mut seen: Vec<&'static str> = Vec::new();
    let mut atoms: Vec<AtomRow> = Vec::new();
    let mut velocities: Option<Vec<VelocityRow>> = None;

    for (i, raw) in text.lines().enumerate().skip(1) {
        let line = i + 1;
        let (content, comment) = split_comment(raw);
        let content = content.trim();
        if content.is_empty() {
            continue;
        }
        if let Some(name) = section_name(content) {
            if counts.is_none() {
                counts = Some(header.finish(n_lines, type_materials.len())?);
            }
            let next = open_section(&name, comment, line, &mut seen)?;
            if next == Section::Velocities {
                velocities = Some(Vec::new());
            }
            section = next;
            continue;
        }
        let words: Vec<&str> = content.split_whitespace().collect();
        let n_types = counts.map_or(0, |c| c.1);
        match section {
            Section::Header => header.parse_line(&words, line)?,
            Section::Skip => {}
            Section::Atoms | Section::Velocities | Section::Masses
                if content.starts_with(|c: char| c.is_ascii_alphabetic()) =>
            {
                return Err(line_err(
                    line,
                    format!(
                        "'{}' is neither an entry of the section nor a known section name",
                        shown(content)
                    ),
                ));
            }
            Section::Atoms => atoms.push(parse_atom(&words, line, n_types)?),
            Section::Velocities => {
                let row = parse_velocity(&words, line)?;
                if let Some(v) = velocities.as_mut() {
                    v.push(row);
                }
            }
            Section::Masses => parse_mass(&words, line, n_types)?,
        }
    }
    let (n_atoms, n_types) = match counts {
        Some(c) => c,
        None => header.finish(n_lines, type_materials.len())?,
    };
    if n_atoms > 0 && !seen.contains(&"Atoms") {
        return Err(file_err(format!(
            "the header announces {n_atoms} atoms, but the file has no Atoms section"
        )));
    }

    sort_atoms(&mut atoms)?;
    if atoms.len() as u64 != n_atoms {
        return Err(file_err(format!(
            "the header says {n_atoms} atoms, the Atoms section has {}",
            atoms.len()
        )));
    }

    let n = atoms.len();
    let (velocity_m_s, angular_velocity_rad_s) = match velocities {
        Some(vels) => atom_velocities(vels, &atoms)?,
        None => (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]),
    };

    let materials = if type_materials.is_empty() {
        (1..=n_types).map(|t| format!("type{t}")).collect()
    } else {
        type_materials.to_vec()
    };
    let bed = Bed {
        materials,
        position_m: atoms.iter().map(|a| a.position_m).collect(),
        radius_m: atoms.iter().map(|a| a.radius_m).collect(),
        material: atoms.iter().map(|a| a.material).collect(),
        velocity_m_s,
        angular_velocity_rad_s,
    };
    bed.validate()?;
    Ok(bed)
}

/// Checks a new section's name line: Atoms, Velocities and Masses at most once each, the
/// Atoms section of atom_style sphere or granular (its `# style` comment); returns the
/// section (unknown sections are skipped).
fn open_section(
    name: &str,
    comment: Option<&str>,
    line: usize,
    seen: &mut Vec<&'static str>,
) -> Result<Section, BedFormatError> {
    let (next, key) = match name {
        "Atoms" => (Section::Atoms, "Atoms"),
        "Velocities" => (Section::Velocities, "Velocities"),
        "Masses" => (Section::Masses, "Masses"),
        _ => (Section::Skip, ""),
    };
    if !key.is_empty() {
        if seen.contains(&key) {
            return Err(line_err(line, format!("second {key} section")));
        }
        seen.push(key);
    }
    if next == Section::Atoms {
        let style = comment.and_then(|c| c.split_whitespace().next());
        if let Some(style) = style.filter(|s| !matches!(*s, "sphere" | "granular")) {
            return Err(line_err(
                line,
                format!(
                    "the Atoms section is for atom_style '{}'; only atom_style sphere \
                     (LAMMPS) or granular (LIGGGHTS) is read",
                    shown(style)
                ),
            ));
        }
    }
    Ok(next)
}

/// Sorts the atoms by ID and refuses a duplicate ID (naming both lines).
fn sort_atoms(atoms: &mut [AtomRow]) -> Result<(), BedFormatError> {
    atoms.sort_unstable_by_key(|a| a.id);
    for w in atoms.windows(2) {
        if w[0].id == w[1].id {
            return Err(line_err(
                w[0].line.max(w[1].line),
                format!(
                    "duplicate atom ID {} (also on line {})",
                    w[0].id,
                    w[0].line.min(w[1].line)
                ),
            ));
        }
    }
    Ok(())
}

/// Velocities and angular velocities of the Velocities section in atom order; refuses a
/// second entry for an atom, an entry for an unknown atom ID and an entry count other than
/// the atoms'.
fn atom_velocities(
    mut vels: Vec<VelocityRow>,
    atoms: &[AtomRow],
) -> Result<(Vec<Vec3>, Vec<Vec3>), BedFormatError> {
    let n = atoms.len();
    let mut velocity_m_s = vec![Vec3::zeros(); n];
    let mut angular_velocity_rad_s = vec![Vec3::zeros(); n];
    vels.sort_unstable_by_key(|v| v.id);
    for w in vels.windows(2) {
        if w[0].id == w[1].id {
            return Err(line_err(
                w[0].line.max(w[1].line),
                format!(
                    "second velocity for atom ID {} (also on line {})",
                    w[0].id,
                    w[0].line.min(w[1].line)
                ),
            ));
        }
    }
    for v in &vels {
        let Ok(k) = atoms.binary_search_by_key(&v.id, |a| a.id) else {
            return Err(line_err(
                v.line,
                format!(
                    "velocity for atom ID {}, which is not in the Atoms section",
                    v.id
                ),
            ));
        };
        velocity_m_s[k] = v.velocity_m_s;
        angular_velocity_rad_s[k] = v.angular_velocity_rad_s;
    }
    if vels.len() != n {
        return Err(file_err(format!(
            "the Velocities section has {} entries for {n} atoms",
            vels.len()
        )));
    }
    Ok((velocity_m_s, angular_velocity_rad_s))
}

/// Writes `bed` as a LAMMPS data file for `atom_style sphere` in SI units (`units si`), which
/// [`read_lammps_data`] reads back to the identical bed when given `bed.materials` as
/// `type_materials`.
///
/// Written: a title line; `N atoms`, `K atom types` (K = `bed.materials.len()`); the box
/// `box_m = (lo, hi)` as `xlo xhi`, `ylo yhi`, `zlo zhi` (m; not checked here: LAMMPS and the
/// reader need lo < hi, and LAMMPS drops atoms outside the box); when the bed is not empty, an
/// `Atoms # sphere` section (IDs 1..=N in bed order, type = material index + 1, diameter
/// = 2 × radius, density = `densities_kg_m3[material]`, which must be finite and > 0 for the
/// reader, x y z) and a `Velocities` section (`ID vx vy vz wx wy wz`). Every f64 is written with
/// `{}` (shortest round-trip decimal, no exponent).
///
/// # Panics
///
/// If `densities_kg_m3` has fewer entries than `bed.materials`, or the bed's columns are
/// inconsistent (a bed that passes [`Bed::validate`] never makes it panic).
pub fn write_lammps_data(
    bed: &Bed,
    densities_kg_m3: &[f64],
    box_m: ([f64; 3], [f64; 3]),
) -> String {
    assert!(
        densities_kg_m3.len() >= bed.materials.len(),
        "write_lammps_data: {} densities for {} materials",
        densities_kg_m3.len(),
        bed.materials.len()
    );
    let n = bed.len();
    let mut s = String::new();
    s.push_str("LAMMPS data file written by pdamp (atom_style sphere, units si)\n\n");
    let _ = writeln!(s, "{n} atoms");
    let _ = writeln!(s, "{} atom types", bed.materials.len());
    s.push('\n');
    let (lo, hi) = box_m;
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let _ = writeln!(s, "{} {} {axis}lo {axis}hi", lo[k], hi[k]);
    }
    if n == 0 {
        return s;
    }
    s.push_str("\nAtoms # sphere\n\n");
    for i in 0..n {
        let m = bed.material[i] as usize;
        let p = &bed.position_m[i];
        let _ = writeln!(
            s,
            "{} {} {} {} {} {} {}",
            i + 1,
            m + 1,
            2.0 * bed.radius_m[i],
            densities_kg_m3[m],
            p.x,
            p.y,
            p.z
        );
    }
    s.push_str("\nVelocities\n\n");
    for i in 0..n {
        let v = &bed.velocity_m_s[i];
        let w = &bed.angular_velocity_rad_s[i];
        let _ = writeln!(
            s,
            "{} {} {} {} {} {} {}",
            i + 1,
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| s.to_string()).collect()
    }

    /// A bed with awkward values: many digits, extremes, negative zero, three materials.
    fn sample_bed() -> Bed {
        Bed {
            materials: names(&["steel", "glass", "pmma"]),
            position_m: vec![
                Vec3::new(0.1, -0.2, 0.30000000000000004),
                Vec3::new(1e-300, -1e300, -0.0),
                Vec3::new(std::f64::consts::PI, 5e-324, 123_456_789.123_456_79),
                Vec3::new(-7.25e-3, 2.0 / 3.0, 1e22),
            ],
            radius_m: vec![0.001, 1.0 / 3.0 * 1e-3, 2.5e-4, 1e-310],
            material: vec![0, 1, 0, 2],
            velocity_m_s: vec![
                Vec3::new(0.0, 0.0, -1.5),
                Vec3::new(1e-17, -3.3, 0.7),
                Vec3::zeros(),
                Vec3::new(f64::MAX, f64::MIN_POSITIVE, -1.0 / 7.0),
            ],
            angular_velocity_rad_s: vec![
                Vec3::new(10.0, -20.0, 30.5),
                Vec3::zeros(),
                Vec3::new(1.0 / 3.0, 2.0 / 3.0, 1e-5),
                Vec3::new(-0.0, 4e10, 1.1),
            ],
        }
    }

    fn err_text(r: Result<Bed, BedFormatError>) -> String {
        match r {
            Ok(b) => panic!("expected an error, got a bed of {} particles", b.len()),
            Err(e) => e.to_string(),
        }
    }

    fn assert_err(r: Result<Bed, BedFormatError>, parts: &[&str]) {
        let msg = err_text(r);
        for p in parts {
            assert!(msg.contains(p), "error {msg:?} does not contain {p:?}");
        }
    }

    const LIGGGHTS: &str = "\
LIGGGHTS data file via write_data, version Version LIGGGHTS-PUBLIC 3.8.0, timestep = 200000

3 atoms
1 atom types

-0.05 0.05 xlo xhi
-0.05 0.05 ylo yhi
0 0.1 zlo zhi

Atoms # granular

7 1 0.004 2500 0.01 0.02 0.003 0 0 0
2 1 0.002 2500 -0.01 0.015 0.002 0 -1 0
5 1 0.003 2500 0 0 0.0015 1 0 0

Velocities

5 0.5 0 0 0 0 3
7 0 0 -1 10 20 30
2 0 0.25 0 0 -5 0
";

    #[test]
    fn lammps_liggghts_write_data_file_parses() {
        let bed = read_lammps_data(LIGGGHTS, &names(&["glass"])).unwrap();
        assert_eq!(bed.materials, names(&["glass"]));
        assert_eq!(bed.len(), 3);
        // ordered by ID: 2, 5, 7
        assert_eq!(bed.position_m[0], Vec3::new(-0.01, 0.015, 0.002));
        assert_eq!(bed.position_m[1], Vec3::new(0.0, 0.0, 0.0015));
        assert_eq!(bed.position_m[2], Vec3::new(0.01, 0.02, 0.003));
        assert_eq!(bed.radius_m, vec![0.001, 0.0015, 0.002]);
        assert_eq!(bed.material, vec![0, 0, 0]);
        assert_eq!(bed.velocity_m_s[0], Vec3::new(0.0, 0.25, 0.0));
        assert_eq!(bed.velocity_m_s[1], Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(bed.velocity_m_s[2], Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(bed.angular_velocity_rad_s[0], Vec3::new(0.0, -5.0, 0.0));
        assert_eq!(bed.angular_velocity_rad_s[1], Vec3::new(0.0, 0.0, 3.0));
        assert_eq!(bed.angular_velocity_rad_s[2], Vec3::new(10.0, 20.0, 30.0));
        // default type names
        let bed = read_lammps_data(LIGGGHTS, &[]).unwrap();
        assert_eq!(bed.materials, names(&["type1"]));
    }

    #[test]
    fn lammps_optional_parts_parse() {
        let text = "# title line with a hash\n\
            \n\
            4 atoms   # four spheres\n\
            2 atom types\n\
            0 bonds\n\
            0 bond types\n\
            2 extra bond per atom\n\
            0 ellipsoids\n\
            -1 1 xlo xhi\n\
            -1.0e0 1 ylo yhi\n\
            0 2 zlo zhi # tall\n\
            0 0 0 xy xz yz\n\
            \n\
            Masses\n\
            \n\
            1 0.5\n\
            2 1.5 # heavy\n\
            \n\
            Pair Coeffs # granular\n\
            \n\
            1 1e7 0.3\n\
            C 2e7 0.3\n\
            \n\
            Atoms # sphere\n\
            \n\
            # a comment line inside the section\n\
            10 2 0.2 7800 0.5 0.5 1   \n\
            3 1 0.1 2500 -0.5 -0.5 0.25\n\
            \t4 1 1.0e-1 2.5e3 0 0 0.5\n\
            1000 2 0.2 7800 0 0.5 1.5 0 0 0\n\
            Bonds\n\
            \n\
            1 1 3 4\n\
            Some Fix Coeffs\n\
            1 2 3\n";
        let bed = read_lammps_data(text, &names(&["glass", "steel"])).unwrap();
        assert_eq!(bed.len(), 4);
        assert_eq!(bed.material, vec![0, 0, 1, 1]); // IDs 3, 4, 10, 1000
        assert_eq!(bed.radius_m, vec![0.05, 0.05, 0.1, 0.1]);
        assert_eq!(bed.position_m[3], Vec3::new(0.0, 0.5, 1.5));
        assert!(bed.velocity_m_s.iter().all(|v| *v == Vec3::zeros()));
        assert!(
            bed.angular_velocity_rad_s
                .iter()
                .all(|v| *v == Vec3::zeros())
        );
        // CRLF line ends
        let crlf = text.replace('\n', "\r\n");
        assert_eq!(
            read_lammps_data(&crlf, &names(&["glass", "steel"])).unwrap(),
            bed
        );
        // an empty bed without sections
        let empty = read_lammps_data("title\n0 atoms\n0 atom types\n", &[]).unwrap();
        assert_eq!(empty, Bed::default());
    }

    #[test]
    fn lammps_round_trip_is_exact() {
        let bed = sample_bed();
        bed.validate().unwrap();
        let densities = [7800.0, 2500.0, 1190.0];
        let bx = ([-1.0, -2.0, -3.0], [1.0, 2.0, 1e30]);
        let text = write_lammps_data(&bed, &densities, bx);
        let back = read_lammps_data(&text, &bed.materials).unwrap();
        assert_eq!(back, bed);
        for (a, b) in back.position_m.iter().zip(&bed.position_m) {
            for k in 0..3 {
                assert_eq!(a[k].to_bits(), b[k].to_bits());
            }
        }
        // import → export → import
        let again = write_lammps_data(&back, &densities, bx);
        assert_eq!(again, text);
        assert_eq!(read_lammps_data(&again, &bed.materials).unwrap(), bed);
        // the LIGGGHTS file too
        let first = read_lammps_data(LIGGGHTS, &[]).unwrap();
        let text = write_lammps_data(&first, &[2500.0], ([-0.05; 3], [0.1; 3]));
        assert_eq!(read_lammps_data(&text, &first.materials).unwrap(), first);
        // an empty bed
        let empty = Bed {
            materials: names(&["steel"]),
            ..Bed::default()
        };
        let text = write_lammps_data(&empty, &[7800.0], ([0.0; 3], [1.0; 3]));
        assert_eq!(read_lammps_data(&text, &empty.materials).unwrap(), empty);
    }

    fn one_atom(atom_line: &str) -> String {
        format!("t\n1 atoms\n1 atom types\nAtoms\n\n{atom_line}\n")
    }

    #[test]
    fn lammps_bad_files_are_errors() {
        let g = names(&["glass"]);
        // wrong count
        let short = LIGGGHTS.replace("5 1 0.003 2500 0 0 0.0015 1 0 0\n", "");
        assert_err(
            read_lammps_data(&short, &g),
            &["header says 3 atoms", "has 2"],
        );
        // duplicate ID
        let dup = LIGGGHTS.replace("5 1 0.003", "7 1 0.003");
        assert_err(
            read_lammps_data(&dup, &g),
            &["line 14", "duplicate atom ID 7", "line 12"],
        );
        // type out of range
        let ty = LIGGGHTS.replace("2 1 0.002", "2 2 0.002");
        assert_err(
            read_lammps_data(&ty, &g),
            &["line 13", "out of range 1..=1"],
        );
        let ty0 = LIGGGHTS.replace("2 1 0.002", "2 0 0.002");
        assert_err(read_lammps_data(&ty0, &g), &["line 13", "out of range"]);
        // non-finite coordinate
        for bad in ["nan", "inf", "-inf", "1e999", "abc"] {
            let f = one_atom(&format!("1 1 0.1 1000 0 {bad} 0"));
            assert_err(
                read_lammps_data(&f, &[]),
                &["line 6", "y '", "not a finite number"],
            );
        }
        // negative or zero diameter, bad density
        assert_err(
            read_lammps_data(&one_atom("1 1 -0.1 1000 0 0 0"), &[]),
            &["line 6", "diameter -0.1 must be > 0"],
        );
        assert_err(
            read_lammps_data(&one_atom("1 1 0 1000 0 0 0"), &[]),
            &["line 6", "diameter"],
        );
        assert_err(
            read_lammps_data(&one_atom("1 1 5e-324 1000 0 0 0"), &[]),
            &["line 6", "too small"],
        );
        assert_err(
            read_lammps_data(&one_atom("1 1 0.1 0 0 0 0"), &[]),
            &["line 6", "density 0 must be > 0"],
        );
        // other atom styles
        let full = LIGGGHTS.replace("Atoms # granular", "Atoms # full");
        assert_err(
            read_lammps_data(&full, &g),
            &["line 10", "'full'", "sphere"],
        );
        let atomic = LIGGGHTS.replace("Atoms # granular", "Atoms  #atomic");
        assert_err(read_lammps_data(&atomic, &g), &["line 10", "'atomic'"]);
        // huge announced count in a tiny file
        let huge = "t\n1000000000000 atoms\n1 atom types\nAtoms\n\n1 1 1 1 0 0 0\n";
        assert_err(
            read_lammps_data(huge, &[]),
            &["line 2", "1000000000000 atoms", "only 6 lines"],
        );
        let huge_types = "t\n1 atoms\n99999999999 atom types\nAtoms\n\n1 1 1 1 0 0 0\n";
        assert_err(read_lammps_data(huge_types, &[]), &["line 3", "atom types"]);
        // missing section / header lines
        let no_atoms = "t\n3 atoms\n1 atom types\n\nVelocities\n\n1 0 0 0 0 0 0\n";
        assert_err(read_lammps_data(no_atoms, &[]), &["no Atoms section"]);
        assert_err(read_lammps_data("", &[]), &["no 'N atoms' line"]);
        assert_err(
            read_lammps_data("t\n1 atoms\nAtoms\n\n1 1 1 1 0 0 0\n", &[]),
            &["no 'N atom types' line"],
        );
        // truncated line
        assert_err(
            read_lammps_data(&one_atom("1 1 0.1 1000 0 0"), &[]),
            &["line 6", "has 6 columns"],
        );
        let cut = LIGGGHTS.replace("7 0 0 -1 10 20 30", "7 0 0 -1 10 20");
        assert_err(
            read_lammps_data(&cut, &g),
            &["line 19", "Velocities entry has 6"],
        );
        // image flags must be integers
        assert_err(
            read_lammps_data(&one_atom("1 1 0.1 1000 0 0 0 0 0.5 0"), &[]),
            &["line 6", "image flag '0.5'"],
        );
        // velocities: unknown ID, duplicate, missing
        let unknown = LIGGGHTS.replace("5 0.5 0 0", "6 0.5 0 0");
        assert_err(
            read_lammps_data(&unknown, &g),
            &["line 18", "atom ID 6", "not in the Atoms section"],
        );
        let twice = LIGGGHTS.replace("5 0.5 0 0", "7 0.5 0 0");
        assert_err(
            read_lammps_data(&twice, &g),
            &["second velocity for atom ID 7"],
        );
        let fewer = LIGGGHTS.replace("5 0.5 0 0 0 0 3\n", "");
        assert_err(
            read_lammps_data(&fewer, &g),
            &["Velocities section has 2 entries"],
        );
        // names table of the wrong length
        assert_err(
            read_lammps_data(LIGGGHTS, &names(&["a", "b"])),
            &["line 4", "1 atom types", "2 material names"],
        );
        // an unknown section name among the entries, an unknown header line, repeated sections
        let unknown_section = LIGGGHTS.replace("Velocities\n", "Velocitys\n");
        assert_err(
            read_lammps_data(&unknown_section, &g),
            &["line 16", "'Velocitys'", "known section name"],
        );
        let bad_header = LIGGGHTS.replace("1 atom types", "1 atom types\nfoo bar");
        assert_err(read_lammps_data(&bad_header, &g), &["line 5", "'foo bar'"]);
        let again = format!("{LIGGGHTS}\nAtoms\n\n");
        assert_err(
            read_lammps_data(&again, &g),
            &["line 22", "second Atoms section"],
        );
        let bad_box = LIGGGHTS.replace("0 0.1 zlo zhi", "0.1 0 zlo zhi");
        assert_err(read_lammps_data(&bad_box, &g), &["line 8", "zlo < zhi"]);
    }

    #[test]
    fn lammps_reader_survives_every_truncation() {
        let text = write_lammps_data(&sample_bed(), &[1.0, 2.0, 3.0], ([-1.0; 3], [1.0; 3]));
        for end in (0..text.len()).filter(|&e| text.is_char_boundary(e)) {
            let _ = read_lammps_data(&text[..end], &[]);
        }
        for end in (0..LIGGGHTS.len()).filter(|&e| LIGGGHTS.is_char_boundary(e)) {
            let _ = read_lammps_data(&LIGGGHTS[..end], &[]);
        }
    }

    #[test]
    fn csv_round_trip_is_exact() {
        let bed = sample_bed();
        let text = write_bed_csv(&bed);
        assert!(text.starts_with(
            "x_m,y_m,z_m,radius_m,vx_m_s,vy_m_s,vz_m_s,wx_rad_s,wy_rad_s,wz_rad_s,material\n"
        ));
        let back = read_bed_csv(&text, "unused").unwrap();
        assert_eq!(back, bed);
        assert_eq!(write_bed_csv(&back), text);
        let empty = read_bed_csv(&write_bed_csv(&Bed::default()), "x").unwrap();
        assert_eq!(empty, Bed::default());
    }

    #[test]
    fn csv_column_order_is_free_and_optional_columns_default() {
        let text = "# bed exported by hand\n\
            \n\
            material, radius_m ,z_m,y_m,x_m,wz_rad_s,wy_rad_s,wx_rad_s\n\
            glass,0.001,3,2,1,0.3,0.2,0.1\n\
            # comment between rows\n\
            steel,0.002,6,5,4,0,0,0\r\n\
            glass , 0.001 , 9 , 8 , 7 , 0 , 0 , 0\n";
        let bed = read_bed_csv(text, "unused").unwrap();
        assert_eq!(bed.materials, names(&["glass", "steel"]));
        assert_eq!(bed.material, vec![0, 1, 0]);
        assert_eq!(bed.position_m[0], Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(bed.position_m[2], Vec3::new(7.0, 8.0, 9.0));
        assert_eq!(bed.radius_m, vec![0.001, 0.002, 0.001]);
        assert_eq!(bed.angular_velocity_rad_s[0], Vec3::new(0.1, 0.2, 0.3));
        assert!(bed.velocity_m_s.iter().all(|v| *v == Vec3::zeros()));
        let minimal = read_bed_csv("radius_m,x_m,y_m,z_m\n0.5,1,2,3\n", "sand").unwrap();
        assert_eq!(minimal.materials, names(&["sand"]));
        assert_eq!(minimal.material, vec![0]);
        assert_eq!(minimal.position_m[0], Vec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn csv_bad_files_are_errors() {
        assert_err(read_bed_csv("", "m"), &["no header row"]);
        assert_err(
            read_bed_csv("x_m,y_m,radius_m\n1,2,3\n", "m"),
            &["line 1", "missing required column(s) z_m"],
        );
        assert_err(
            read_bed_csv("x_m,y_m,z_m,radius_m,vx_m_s,vz_m_s\n1,2,3,4,5,6\n", "m"),
            &["line 1", "velocity columns", "vx_m_s,vz_m_s", "not vy_m_s"],
        );
        assert_err(
            read_bed_csv("x_m,y_m,z_m,radius_m,wx_rad_s\n1,2,3,4,5\n", "m"),
            &["angular velocity columns"],
        );
        assert_err(
            read_bed_csv("#c\nx_m,y_m,z_m,radius_m,colour\n1,2,3,4,red\n", "m"),
            &[
                "line 2",
                "unknown column 'colour'",
                "known columns: x_m,y_m",
            ],
        );
        assert_err(
            read_bed_csv("x_m,y_m,z_m,radius_m,x_m\n", "m"),
            &["column x_m appears twice"],
        );
        let bad = "x_m,y_m,z_m,radius_m\n1,2,3,0.5\n\n4,5e,6,0.5\n";
        assert_err(
            read_bed_csv(bad, "m"),
            &["line 4", "column y_m", "'5e'", "not a finite number"],
        );
        assert_err(
            read_bed_csv("x_m,y_m,z_m,radius_m\n1,2,NaN,0.5\n", "m"),
            &["line 2", "column z_m"],
        );
        assert_err(
            read_bed_csv("x_m,y_m,z_m,radius_m\n1,2,3,-0.5\n", "m"),
            &["line 2", "column radius_m", "must be > 0"],
        );
        assert_err(
            read_bed_csv("x_m,y_m,z_m,radius_m\n1,2,3\n", "m"),
            &["line 2", "expected 4 fields", "found 3"],
        );
        assert_err(
            read_bed_csv("x_m,y_m,z_m,radius_m,material\n1,2,3,1, \n", "m"),
            &["line 2", "empty material name"],
        );
    }
}
