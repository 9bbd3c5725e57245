//! Damper-position study (D Sect. 8.2.3, "Influence of Particle Damper Position", Fig. 8.27):
//! one equivalent damper (approach 2 or 3) is moved along a beam, and for every position and
//! mode the resonance equilibrium of D Fig. 3.7 (Eq. 3.48–3.50 with the damper model, 3.33,
//! 3.39, 3.49) gives the damping ratio, the damper amplitude and the frequency reduction.
//! The added damping scales with φ_pd² (D Eq. 3.51/3.52), so it vanishes at a node of a mode
//! and peaks near its antinodes; the mode-shape slope at the position is reported too (D: the
//! container rotation at positions with non-zero slope degrades the damper, which approaches 2
//! and 3 do not model).
//!
//! Study file (`pdamp structure damper-positions STUDY.toml --out DIR`):
//!
//! ```toml
//! scenario = "couple_ch8_fields_steady.toml"  # beam structure, one equivalent damper,
//!                                             # [analysis] kind = "steady_state" (force, excitation point)
//! [study]
//! positions_m = [0.0, 0.1, 0.2]               # or start_m, end_m, count
//! move_mass_at_m = 1.76                        # a structure point mass (container) moved along
//! ```
//!
//! Outputs: `positions.csv` (`position_m,mode,undamped_frequency_hz,frequency_hz,phi_damper_per_sqrt_kg,
//! slope_rad_per_m_sqrt_kg,structural_damping_ratio,damping_ratio,added_damping_ratio,
//! damper_amplitude_m,effective_loss_factor,converged`), `positions.png/svg` (ζ over the
//! position, one line per mode), `summary.json` (best position per mode).

use crate::StructureError;
use crate::forced::{ModeCoupling, resonance_equilibrium};
use crate::scenario::{AnalysisSpec, CoupleScenario, DamperSpec, PointSpec, StructureSpec};
use pdamp_io::csv::write_csv_atomic;
use pdamp_plot::{Axis, LinePlot, Marker, Series, line_plot};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::{Path, PathBuf};

/// `[study]` of a damper-position study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PositionStudySpec {
    /// Positions along the beam, m (snap to the nearest node).
    #[serde(default)]
    pub positions_m: Option<Vec<f64>>,
    /// First position of an even grid, m.
    #[serde(default)]
    pub start_m: Option<f64>,
    /// Last position of an even grid, m.
    #[serde(default)]
    pub end_m: Option<f64>,
    /// Number of grid positions.
    #[serde(default)]
    pub count: Option<usize>,
    /// Position of a structure point mass (the container) that moves with the damper, m.
    #[serde(default)]
    pub move_mass_at_m: Option<f64>,
}

/// A study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PositionStudyFile {
    /// Coupling scenario: beam structure, exactly one equivalent damper, steady_state analysis.
    pub scenario: PathBuf,
    /// The study.
    pub study: PositionStudySpec,
}

/// One (position, mode) result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PositionResult {
    /// Damper position (snapped to the node), m.
    pub position_m: f64,
    /// Mode (1-based).
    pub mode: usize,
    /// Eigenfrequency of the structure with the container at this position, Hz.
    pub undamped_frequency_hz: f64,
    /// Effective eigenfrequency ω̄/2π at the equilibrium [D Eq. 3.33], Hz.
    pub frequency_hz: f64,
    /// φ_pd, 1/√kg.
    pub phi_damper_per_sqrt_kg: f64,
    /// Mode-shape slope (rz) at the position, rad/(m·√kg)·m = 1/(m√kg).
    pub slope_rad_per_m_sqrt_kg: f64,
    /// Structural damping ratio ζ_k.
    pub structural_damping_ratio: f64,
    /// ζ at the equilibrium [D Eq. 3.49].
    pub damping_ratio: f64,
    /// ζ − ζ_k.
    pub added_damping_ratio: f64,
    /// Damper amplitude X [D Eq. 3.50], m.
    pub damper_amplitude_m: f64,
    /// η̄ at the equilibrium.
    pub effective_loss_factor: f64,
    /// Fig. 3.7 iteration converged.
    pub converged: bool,
}

/// Most positions of one study.
pub const MAX_POSITIONS: usize = 100_000;

impl PositionStudySpec {
    /// The positions, validated.
    ///
    /// # Errors
    /// Neither or both of `positions_m` and `start_m`/`end_m`/`count`, empty or non-finite.
    pub fn positions(&self) -> Result<Vec<f64>, StructureError> {
        let v = match (&self.positions_m, self.start_m, self.end_m, self.count) {
            (Some(p), None, None, None) => p.clone(),
            (None, Some(a), Some(b), Some(n)) if (2..=MAX_POSITIONS).contains(&n) => (0..n)
                .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
                .collect(),
            _ => {
                return Err(StructureError::invalid(
                    "study",
                    format!("give positions_m, or start_m + end_m + count (2 to {MAX_POSITIONS})"),
                ));
            }
        };
        if v.is_empty() || v.len() > MAX_POSITIONS {
            return Err(StructureError::invalid(
                "study.positions_m",
                format!("give 1 to {MAX_POSITIONS} positions, got {}", v.len()),
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(StructureError::rule(
                format!("study.positions_m[{i}]"),
                format!("must be a finite number, got {}", v[i]),
            ));
        }
        Ok(v)
    }
}

/// Runs the study for a loaded scenario (`base` resolves its paths).
///
/// # Errors
/// Not a beam, not exactly one equivalent damper, not a steady-state analysis, build errors.
pub fn position_study(
    scn: &CoupleScenario,
    structure: &StructureSpec,
    base: &Path,
    spec: &PositionStudySpec,
) -> Result<Vec<PositionResult>, StructureError> {
    let positions = spec.positions()?;
    let beam = structure.beam.as_ref().ok_or_else(|| {
        StructureError::invalid(
            "damper-position study",
            "the scenario's structure must be a [structure.beam]",
        )
    })?;
    let key = |i: usize| match (&spec.positions_m, i) {
        (Some(_), _) => format!("study.positions_m[{i}]"),
        (None, 0) => "study.start_m".to_string(),
        (None, _) => "study.end_m".to_string(),
    };
    for (i, &x) in positions.iter().enumerate() {
        crate::scenario::on_beam(&key(i), x, beam.length_m)?;
    }
    if let Some(x) = spec.move_mass_at_m {
        crate::scenario::on_beam("study.move_mass_at_m", x, beam.length_m)?;
    }
    let damper = match scn.dampers.as_slice() {
        [d] if !matches!(d, DamperSpec::Dem { .. }) => d,
        _ => {
            return Err(StructureError::invalid(
                "damper-position study",
                "the scenario needs exactly one equivalent damper (approach 2 or 3)",
            ));
        }
    };
    let AnalysisSpec::SteadyState {
        force_amplitude_n,
        base_amplitude_m,
        excitation_point,
        ..
    } = &scn.analysis
    else {
        return Err(StructureError::invalid(
            "damper-position study",
            "[analysis] must be kind = \"steady_state\" (force and excitation point)",
        ));
    };
    let force = crate::scenario::ForceSpec {
        force_amplitude_n: *force_amplitude_n,
        base_amplitude_m: *base_amplitude_m,
    }
    .force_n(structure)?;
    let point = damper.point().to_string();
    if !structure.points.iter().any(|p| p.name == point) {
        return Err(StructureError::invalid(
            "damper-position study",
            format!("damper point '{point}' is not a [[structure.points]] entry"),
        ));
    }
    let moved_mass = match spec.move_mass_at_m {
        Some(x) => Some(
            beam.masses
                .iter()
                .position(|m| (m.position_m - x).abs() < 1e-9)
                .ok_or_else(|| {
                    StructureError::invalid(
                        "study.move_mass_at_m",
                        format!("no structure mass at {x} m"),
                    )
                })?,
        ),
        None => None,
    };
    const SLOPE: &str = "__damper_slope_rz";
    let mut out = Vec::new();
    for &x in &positions {
        if !(0.0..=beam.length_m).contains(&x) {
            return Err(StructureError::invalid(
                "study.positions_m",
                format!("{x} m is outside the beam (0 … {} m)", beam.length_m),
            ));
        }
        let mut st = structure.clone();
        for p in st.points.iter_mut().filter(|p| p.name == point) {
            p.position_m = Some(x);
        }
        st.points.push(PointSpec {
            name: SLOPE.into(),
            position_m: Some(x),
            node: None,
            dof: "rz".into(),
        });
        if let (Some(i), Some(b)) = (moved_mass, st.beam.as_mut()) {
            b.masses[i].position_m = x;
        }
        let modal = st.build(base)?.modal;
        let snapped = nearest_node(beam, x);
        for (j, m) in modal.modes.iter().enumerate() {
            let model = damper.effective_model(base, &modal, j).or_else(|e| {
                // a node of mode j cannot carry a mode-dependent kinematic ratio: no damping
                if matches!(e, StructureError::NodeOfMode { .. }) {
                    Ok(None)
                } else {
                    Err(e)
                }
            })?;
            let phi_pd = modal.point(&point)?[j];
            let c = ModeCoupling {
                omega_rad_s: m.omega_rad_s(),
                damping_ratio: m.damping_ratio,
                phi_pd,
                phi_ex: modal.point(excitation_point)?[j],
                force_amplitude_n: force,
            };
            let (z, xa, f, eta, conv) = match &model {
                Some(model) if phi_pd != 0.0 => {
                    let e = resonance_equilibrium(&c, model.as_ref(), 400);
                    (
                        e.damping_ratio,
                        e.amplitude_m,
                        e.frequency_hz,
                        e.effective_loss_factor,
                        e.converged,
                    )
                }
                _ => (m.damping_ratio, 0.0, m.frequency_hz, 0.0, true),
            };
            out.push(PositionResult {
                position_m: snapped,
                mode: j + 1,
                undamped_frequency_hz: m.frequency_hz,
                frequency_hz: f,
                phi_damper_per_sqrt_kg: phi_pd,
                slope_rad_per_m_sqrt_kg: modal.point(SLOPE)?[j],
                structural_damping_ratio: m.damping_ratio,
                damping_ratio: z,
                added_damping_ratio: z - m.damping_ratio,
                damper_amplitude_m: xa,
                effective_loss_factor: eta,
                converged: conv,
            });
        }
    }
    Ok(out)
}

fn nearest_node(beam: &crate::scenario::BeamSpec, x: f64) -> f64 {
    let h = beam.length_m / beam.elements.max(1) as f64;
    (x / h).round() * h
}

/// `pdamp structure damper-positions`: runs the study file and writes `positions.csv`,
/// `positions.png/svg` and `summary.json` to `out`.
///
/// # Errors
/// Input, build and I/O errors.
pub fn run_position_study_file(
    path: &Path,
    out: &Path,
) -> Result<serde_json::Value, StructureError> {
    let text = std::fs::read_to_string(path).map_err(|e| StructureError::read(path, e))?;
    let f: PositionStudyFile = toml::from_str(&text).map_err(|e| StructureError::toml(path, e))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let scn_path = base.join(&f.scenario);
    let (scn, structure) = CoupleScenario::load(&scn_path)?;
    let started = std::time::Instant::now();
    let res = position_study(
        &scn,
        &structure,
        scn_path.parent().unwrap_or(Path::new(".")),
        &f.study,
    )
    .map_err(|m| {
        if m.to_string().starts_with("study") {
            crate::scenario::locate_error(path, m)
        } else {
            m
        }
    })?;
    std::fs::create_dir_all(out)?;
    let rows: Vec<Vec<f64>> = res
        .iter()
        .map(|r| {
            vec![
                r.position_m,
                r.mode as f64,
                r.undamped_frequency_hz,
                r.frequency_hz,
                r.phi_damper_per_sqrt_kg,
                r.slope_rad_per_m_sqrt_kg,
                r.structural_damping_ratio,
                r.damping_ratio,
                r.added_damping_ratio,
                r.damper_amplitude_m,
                r.effective_loss_factor,
                r.converged as u8 as f64,
            ]
        })
        .collect();
    write_csv_atomic(
        out.join("positions.csv"),
        &[
            "position_m",
            "mode",
            "undamped_frequency_hz",
            "frequency_hz",
            "phi_damper_per_sqrt_kg",
            "slope_rad_per_m_sqrt_kg",
            "structural_damping_ratio",
            "damping_ratio",
            "added_damping_ratio",
            "damper_amplitude_m",
            "effective_loss_factor",
            "converged",
        ],
        &rows,
    )?;
    let n_modes = res.iter().map(|r| r.mode).max().unwrap_or(0);
    let mut plot = LinePlot::new(
        Axis::linear("damper position (m)"),
        Axis::linear("damping ratio ζ (-)"),
    );
    let mut best = Vec::new();
    for k in 1..=n_modes {
        let rk: Vec<&PositionResult> = res.iter().filter(|r| r.mode == k).collect();
        plot.series.push(
            Series::new(
                format!("mode {k}"),
                rk.iter().map(|r| r.position_m).collect(),
                rk.iter().map(|r| r.damping_ratio).collect(),
            )
            .with_marker(Marker::Circle),
        );
        if let Some(b) = rk
            .iter()
            .max_by(|a, b| a.damping_ratio.total_cmp(&b.damping_ratio))
        {
            best.push(
                json!({"mode": k, "position_m": b.position_m, "damping_ratio": b.damping_ratio,
                "slope_rad_per_m_sqrt_kg": b.slope_rad_per_m_sqrt_kg}),
            );
        }
    }
    line_plot(out.join("positions"), &plot)?;
    let summary = json!({
        "study": f.study,
        "scenario": f.scenario,
        "positions": res.len() / n_modes.max(1),
        "best_position_per_mode": best,
        "wall_time_s": started.elapsed().as_secs_f64(),
    });
    pdamp_io::atomic::write_atomic(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    Ok(summary)
}
