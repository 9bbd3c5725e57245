//! Equivalent damper models for coupling approaches 2 and 3 [D Sect. 3.3, Eq. 3.29–3.39]: a
//! particle damper replaced by its effective particle mass $\bar m_{bed}(\Omega, X)$
//! [D Eq. 3.38] and the effective viscous damping $\bar d = \tilde E_{diss}/(\pi\Omega X^2)$
//! [D Eq. 3.39], from a viscous reference, an effective field (`fields.csv`) or analytical
//! formulas ([`crate::formulas`]).

use crate::StructureError;
use std::path::Path;

/// Effective properties of a damper at one excitation state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectiveState {
    /// Effective particle mass m̄_bed, kg [D Eq. 3.17].
    pub effective_mass_kg: f64,
    /// Dissipated energy per cycle Ẽ_diss, J [D Eq. 3.13].
    pub dissipated_energy_per_cycle_j: f64,
}

impl EffectiveState {
    /// Effective viscous damping $\bar d = \tilde E/(\pi\Omega X^2)$ [D Eq. 3.39], N·s/m.
    pub fn viscous_damping_n_s_m(&self, amplitude_m: f64, omega_rad_s: f64) -> f64 {
        let x = amplitude_m.max(1e-12);
        self.dissipated_energy_per_cycle_j / (std::f64::consts::PI * omega_rad_s * x * x)
    }
}

/// A damper model of approach 2 or 3: effective mass and dissipated energy per cycle as
/// functions of displacement amplitude X (m) and angular frequency Ω (rad/s).
pub trait EffectiveDamper: Send + Sync + std::fmt::Debug {
    /// Effective state at (X, Ω).
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState;
    /// Mass of the particle bed m_bed, kg.
    fn bed_mass_kg(&self) -> f64;
}

/// A purely viscous "damper" (reference for verification): $\tilde E = \pi c\,\Omega X^2$,
/// constant effective mass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViscousDamper {
    /// Viscous coefficient c, N·s/m.
    pub damping_n_s_m: f64,
    /// Effective (rigidly coupled) mass, kg.
    pub mass_kg: f64,
}

impl EffectiveDamper for ViscousDamper {
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState {
        EffectiveState {
            effective_mass_kg: self.mass_kg,
            dissipated_energy_per_cycle_j: std::f64::consts::PI
                * self.damping_n_s_m
                * omega_rad_s
                * amplitude_m
                * amplitude_m,
        }
    }
    fn bed_mass_kg(&self) -> f64 {
        self.mass_kg
    }
}

/// An effective field read from `fields.csv` (the single-damper level's output or
/// measurements in the same format) with bilinear interpolation [D Sect. 3.3, approach 2].
///
/// Rows are grouped by frequency; within each frequency the amplitude values may differ
/// (grids over acceleration or Γ give frequency-dependent X). For a query (f, X) the two
/// bracketing frequencies are found, at each of them the two bracketing amplitudes, and the
/// effective loss factor η̄ and mass ratio m̄_bed/m_bed are interpolated. Axes are
/// interpolated in log space when they are logarithmically spaced (ratio of neighbours
/// constant), and values as power laws where both neighbours are positive, linearly otherwise;
/// a viscous damper (η̄ ∝ 1/Ω) and a constant η̄ are thereby reproduced exactly between grid
/// points. Outside the grid the values at the edge are kept (η̄ and m̄/m_bed constant, so
/// Ẽ ∝ X²Ω² there). Then $\tilde E = \pi\bar\eta\, m_{bed}\Omega^2X^2$ [D Eq. 3.15].
#[derive(Debug, Clone, PartialEq)]
pub struct FieldTable {
    /// Frequencies, Hz (ascending).
    pub frequencies_hz: Vec<f64>,
    /// Per frequency: amplitudes X (ascending), η̄, m̄/m_bed.
    pub columns: Vec<FieldColumn>,
    /// Mass of the particle bed, kg.
    pub bed_mass_kg: f64,
    /// Frequency axis logarithmic.
    pub frequency_log: bool,
}

/// The points of one frequency of a [`FieldTable`].
#[derive(Debug, Clone, PartialEq)]
pub struct FieldColumn {
    /// Amplitudes X, m (ascending).
    pub amplitudes_m: Vec<f64>,
    /// Effective loss factors η̄.
    pub effective_loss_factor: Vec<f64>,
    /// Effective mass ratios m̄_bed/m_bed.
    pub effective_mass_ratio: Vec<f64>,
    /// Amplitude axis logarithmic.
    pub log: bool,
}

fn is_log_spaced(v: &[f64]) -> bool {
    if v.len() < 3 || v.iter().any(|x| *x <= 0.0) {
        return false;
    }
    let r0 = v[1] / v[0];
    let lin = v[1] - v[0];
    let ratio_const = v
        .windows(2)
        .all(|w| ((w[1] / w[0]) / r0 - 1.0).abs() < 1e-3);
    let diff_const = v
        .windows(2)
        .all(|w| ((w[1] - w[0]) / lin - 1.0).abs() < 1e-3);
    ratio_const && !diff_const
}

/// Interpolation weight of `x` between `a` and `b` (clamped to [0, 1]).
fn weight(x: f64, a: f64, b: f64, log: bool) -> f64 {
    if b == a {
        return 0.0;
    }
    let t = if log && a > 0.0 && b > 0.0 && x > 0.0 {
        (x / a).ln() / (b / a).ln()
    } else {
        (x - a) / (b - a)
    };
    t.clamp(0.0, 1.0)
}

/// Power-law interpolation where both values are positive, linear otherwise.
fn blend(va: f64, vb: f64, t: f64) -> f64 {
    if va > 0.0 && vb > 0.0 {
        va * (vb / va).powf(t)
    } else {
        va + (vb - va) * t
    }
}

/// Index `i` with `v[i] ≤ x ≤ v[i+1]` (clamped to the ends).
fn bracket(v: &[f64], x: f64) -> (usize, usize) {
    if v.len() == 1 || x <= v[0] {
        return (0, 0);
    }
    if x >= v[v.len() - 1] {
        return (v.len() - 1, v.len() - 1);
    }
    let i = v.partition_point(|&y| y <= x).saturating_sub(1);
    (i, (i + 1).min(v.len() - 1))
}

impl FieldColumn {
    fn at(&self, x: f64) -> (f64, f64) {
        let (i, j) = bracket(&self.amplitudes_m, x);
        let t = weight(x, self.amplitudes_m[i], self.amplitudes_m[j], self.log);
        (
            blend(
                self.effective_loss_factor[i],
                self.effective_loss_factor[j],
                t,
            ),
            blend(
                self.effective_mass_ratio[i],
                self.effective_mass_ratio[j],
                t,
            ),
        )
    }
}

impl FieldTable {
    /// Builds the table from `fields.csv` rows. Needs the columns `frequency_hz` and
    /// `amplitude_m`, `effective_mass_ratio`, and `effective_loss_factor` or
    /// `dissipated_energy_per_cycle_j` (then η̄ = Ẽ/(π m_bed Ω² X²)). Rows whose η̄ or mass
    /// ratio is NaN (failed points of `pdamp fields`) are skipped; see [`Self::from_rows_at`]
    /// for what is refused (errors name the row as `row k`).
    ///
    /// # Errors
    /// See [`Self::from_rows_at`].
    pub fn from_rows(
        header: &[String],
        rows: &[Vec<f64>],
        bed_mass_kg: f64,
    ) -> Result<Self, StructureError> {
        Self::from_rows_at(header, rows, None, bed_mass_kg)
    }

    /// Parses `fields.csv` text ([`pdamp_io::csv::parse_csv_f64`]) into a table; errors name
    /// the line of the file.
    ///
    /// # Errors
    /// CSV errors and everything [`Self::from_rows_at`] refuses.
    pub fn parse(text: &str, bed_mass_kg: f64) -> Result<Self, StructureError> {
        let (header, rows) = pdamp_io::csv::parse_csv_f64(text)?;
        // the lines parse_csv_f64 reads: not blank, not a '#' comment; the first is the header
        let lines: Vec<usize> = text
            .lines()
            .enumerate()
            .filter(|(_, l)| {
                let l = l.trim();
                !l.is_empty() && !l.starts_with('#')
            })
            .map(|(i, _)| i + 1)
            .skip(1)
            .collect();
        Self::from_rows_at(&header, &rows, Some(&lines), bed_mass_kg)
    }

    /// [`Self::from_rows`] with the file line of every row (`lines[k]` of `rows[k]`) for the
    /// messages. Refused: a frequency or amplitude that is not a finite number > 0, an η̄ or
    /// mass ratio that is ±∞ or negative (η̄ down to −1e-6 is taken as round-off and read as
    /// 0), a table without usable points, a bed mass that is not finite and > 0.
    ///
    /// # Errors
    /// A message naming the line (or row), the column, the value and the fix.
    pub fn from_rows_at(
        header: &[String],
        rows: &[Vec<f64>],
        lines: Option<&[usize]>,
        bed_mass_kg: f64,
    ) -> Result<Self, StructureError> {
        if !(bed_mass_kg > 0.0 && bed_mass_kg.is_finite()) {
            return Err(StructureError::rule(
                "bed_mass_kg",
                format!("must be > 0, got {bed_mass_kg}"),
            ));
        }
        let no_column =
            |name: &str| StructureError::invalid("fields.csv", format!("no column {name}"));
        let col = |name: &str| header.iter().position(|h| h.trim() == name);
        let fi = col("frequency_hz").ok_or_else(|| no_column("frequency_hz"))?;
        let xi = col("amplitude_m").ok_or_else(|| no_column("amplitude_m"))?;
        let mi = col("effective_mass_ratio").ok_or_else(|| no_column("effective_mass_ratio"))?;
        let ei = col("effective_loss_factor");
        let di = col("dissipated_energy_per_cycle_j");
        if ei.is_none() && di.is_none() {
            return Err(StructureError::invalid(
                "fields.csv",
                "needs effective_loss_factor or dissipated_energy_per_cycle_j",
            ));
        }
        let mut pts: Vec<(f64, f64, f64, f64)> = Vec::new();
        let eta_col = if ei.is_some() {
            "effective_loss_factor"
        } else {
            "dissipated_energy_per_cycle_j"
        };
        for (k, r) in rows.iter().enumerate() {
            let at = match lines.and_then(|l| l.get(k)) {
                Some(l) => format!("fields.csv line {l}"),
                None => format!("fields.csv row {}", k + 1),
            };
            let get = |i: usize| r.get(i).copied().unwrap_or(f64::NAN);
            let (f, x, m) = (get(fi), get(xi), get(mi));
            for (col, v) in [("frequency_hz", f), ("amplitude_m", x)] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(StructureError::invalid(
                        at,
                        format!(
                            "column {col} = {v} must be a finite number > 0 (a grid point of \
                             the effective field)"
                        ),
                    ));
                }
            }
            let mut eta = match ei {
                Some(i) => get(i),
                None => {
                    let w = std::f64::consts::TAU * f;
                    get(di.unwrap_or(0)) / (std::f64::consts::PI * bed_mass_kg * w * w * x * x)
                }
            };
            if eta.is_nan() || m.is_nan() {
                continue; // a failed point of `pdamp fields`
            }
            if !eta.is_finite() || eta < -1e-6 {
                return Err(StructureError::invalid(
                    at,
                    format!(
                        "column {eta_col} gives η̄ = {eta:e}; the effective loss factor must be \
                         a finite number ≥ 0 (energy is dissipated, not created): recompute the \
                         point or remove the row"
                    ),
                ));
            }
            eta = eta.max(0.0);
            if !(m.is_finite() && m >= 0.0) {
                return Err(StructureError::invalid(
                    at,
                    format!(
                        "column effective_mass_ratio = {m:e} must be a finite number ≥ 0 \
                         (m̄_bed/m_bed): recompute the point or remove the row"
                    ),
                ));
            }
            pts.push((f, x, eta, m));
        }
        if pts.is_empty() {
            return Err(StructureError::invalid(
                "fields.csv",
                "no usable (finite) points",
            ));
        }
        pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut frequencies_hz: Vec<f64> = Vec::new();
        let mut columns: Vec<FieldColumn> = Vec::new();
        for (f, x, eta, m) in pts {
            let same = frequencies_hz
                .last()
                .is_some_and(|&g| (g - f).abs() <= 1e-9 * f.abs());
            if !same {
                frequencies_hz.push(f);
                columns.push(FieldColumn {
                    amplitudes_m: Vec::new(),
                    effective_loss_factor: Vec::new(),
                    effective_mass_ratio: Vec::new(),
                    log: false,
                });
            }
            let c = columns.last_mut().expect("pushed");
            if c.amplitudes_m.last().is_some_and(|&y| y == x) {
                continue;
            }
            c.amplitudes_m.push(x);
            c.effective_loss_factor.push(eta);
            c.effective_mass_ratio.push(m);
        }
        for c in &mut columns {
            c.log = is_log_spaced(&c.amplitudes_m);
        }
        Ok(Self {
            frequency_log: is_log_spaced(&frequencies_hz),
            frequencies_hz,
            columns,
            bed_mass_kg,
        })
    }

    /// Reads `fields.csv`.
    ///
    /// # Errors
    /// I/O and format errors, see [`Self::from_rows`].
    pub fn read(path: &Path, bed_mass_kg: f64) -> Result<Self, StructureError> {
        let text = std::fs::read_to_string(path).map_err(|e| StructureError::read(path, e))?;
        Self::parse(&text, bed_mass_kg).map_err(|e| e.context(path.display().to_string()))
    }

    /// Interpolated (η̄, m̄/m_bed) at (f, X).
    pub fn interpolate(&self, frequency_hz: f64, amplitude_m: f64) -> (f64, f64) {
        let (i, j) = bracket(&self.frequencies_hz, frequency_hz);
        let t = weight(
            frequency_hz,
            self.frequencies_hz[i],
            self.frequencies_hz[j],
            self.frequency_log,
        );
        let (ea, ma) = self.columns[i].at(amplitude_m);
        let (eb, mb) = self.columns[j].at(amplitude_m);
        (blend(ea, eb, t), ma + (mb - ma) * t)
    }
}

impl EffectiveDamper for FieldTable {
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState {
        let f = omega_rad_s / std::f64::consts::TAU;
        let (eta, ratio) = self.interpolate(f, amplitude_m);
        let v = amplitude_m * omega_rad_s;
        EffectiveState {
            effective_mass_kg: ratio * self.bed_mass_kg,
            dissipated_energy_per_cycle_j: std::f64::consts::PI * eta * self.bed_mass_kg * v * v,
        }
    }
    fn bed_mass_kg(&self) -> f64 {
        self.bed_mass_kg
    }
}

/// Rows of a `fields.csv` (columns `frequency_hz, amplitude_m, acceleration_m_s2, intensity,
/// dissipated_energy_per_cycle_j, loss_factor, effective_loss_factor, effective_mass_ratio`)
/// for any model on a grid: used to tabulate a viscous reference or a formula.
pub fn tabulate(
    model: &dyn EffectiveDamper,
    container_mass_kg: f64,
    frequencies_hz: &[f64],
    amplitudes_m: &[f64],
) -> (Vec<&'static str>, Vec<Vec<f64>>) {
    // The leading columns of the single-damper `fields.csv`, so the table reads back in.
    let header = pdamp_design::fields::FIELD_COLUMNS[..8].to_vec();
    let mut rows = Vec::new();
    let mb = model.bed_mass_kg();
    for &f in frequencies_hz {
        for &x in amplitudes_m {
            let w = std::f64::consts::TAU * f;
            let s = model.evaluate(x, w);
            let v = x * w;
            let e_kin_total = 0.5 * (mb + container_mass_kg) * v * v;
            let a = x * w * w;
            rows.push(vec![
                f,
                x,
                a,
                a / pdamp_scenario::schema::STANDARD_GRAVITY_M_S2,
                s.dissipated_energy_per_cycle_j,
                s.dissipated_energy_per_cycle_j / (std::f64::consts::TAU * e_kin_total),
                s.dissipated_energy_per_cycle_j / (std::f64::consts::PI * mb * v * v),
                s.effective_mass_kg / mb,
            ]);
        }
    }
    (header, rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_of_viscous_damper_is_exact_between_grid_points() {
        let visc = ViscousDamper {
            damping_n_s_m: 3.0,
            mass_kg: 0.2,
        };
        let fs: Vec<f64> = (0..6).map(|i| 10.0 * 2f64.powi(i)).collect();
        let xs: Vec<f64> = (0..5).map(|i| 1e-4 * 3f64.powi(i)).collect();
        let (h, rows) = tabulate(&visc, 0.1, &fs, &xs);
        let header: Vec<String> = h.iter().map(|s| s.to_string()).collect();
        let t = FieldTable::from_rows(&header, &rows, 0.2).unwrap();
        assert!(t.frequency_log && t.columns[0].log);
        for (f, x) in [(13.7, 2.2e-4), (250.0, 5e-3), (10.0, 1e-4), (55.5, 7.7e-4)] {
            let w = std::f64::consts::TAU * f;
            let a = t.evaluate(x, w);
            let b = visc.evaluate(x, w);
            assert!(
                (a.dissipated_energy_per_cycle_j / b.dissipated_energy_per_cycle_j - 1.0).abs()
                    < 1e-12
            );
            assert!((a.effective_mass_kg - 0.2).abs() < 1e-12);
            assert!((a.viscous_damping_n_s_m(x, w) - 3.0).abs() < 1e-10);
        }
    }

    #[test]
    fn bracket_edges() {
        let v = [1.0, 2.0, 4.0];
        assert_eq!(bracket(&v, 0.5), (0, 0));
        assert_eq!(bracket(&v, 1.5), (0, 1));
        assert_eq!(bracket(&v, 2.0), (1, 2));
        assert_eq!(bracket(&v, 9.0), (2, 2));
        assert_eq!(bracket(&[3.0], 9.0), (0, 0));
    }
}
