//! Design studies on the structural level: the brute-force layer optimisation of D Sect. 5.2.1
//! ("Optimization", L2375–L2408; same procedure for the manipulator, L2430) and of
//! D Sect. 7.2.3 (vertical, one layer of 16 per step). For a given layered container the
//! particle number of every layer is varied in fixed increments; each design is simulated in
//! free vibration with the analytical damper formulas (approach 3) and the design with the
//! smallest container stroke at the evaluation time wins.
//!
//! Study file (`pdamp structure optimize-layers STUDY.toml --out DIR`):
//!
//! ```toml
//! scenario = "couple_ch5_free_formulas.toml"   # structure + [analysis] kind = "free"
//! [study]
//! model = "rolling"              # rolling (D Eq. 5.1–5.14) | vertical (D Eq. 7.1–7.19)
//! point = "damper"
//! layers = 3
//! container_length_m = 0.12
//! max_particles_per_layer = 48
//! particle_mass_kg = 4.1364e-3
//! step = 4
//! evaluate_at_s = 4.0
//! ```
//!
//! Layers of one container are interchangeable for the formulas (energies and masses add), so
//! only sorted particle numbers n₁ ≤ n₂ ≤ … are simulated.

use crate::StructureError;
use crate::effective::EffectiveDamper;
use crate::formulas::{LayeredDamper, RollingDamper, VerticalDamper, clearance_m};
use crate::free::{self, CoupledDamper, FreeVibrationSpec, TimeHistory};
use crate::modal::ModalStructure;
use crate::scenario::CoupleScenario;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Damper formula family of a layer study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum LayerModel {
    /// Horizontal rolling/scattered layers [D Eq. 5.1–5.14].
    #[default]
    Rolling,
    /// Vertical bed [D Eq. 7.1–7.19] (all particles in one container: use `layers = 1`).
    Vertical,
}

/// `[study]` of a layer optimisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerStudySpec {
    /// Formula family.
    #[serde(default)]
    pub model: LayerModel,
    /// Structure point of the damper.
    pub point: String,
    /// Number of layers.
    pub layers: usize,
    /// Inner container length L along the excitation (D Eq. 5.1/7.4), m.
    pub container_length_m: f64,
    /// Particles that fill one layer, n_p^max.
    pub max_particles_per_layer: usize,
    /// Mass of one particle, kg.
    pub particle_mass_kg: f64,
    /// Increment of the particle number per layer.
    pub step: usize,
    /// Time at which the stroke is evaluated, s (D: 4 s for the beam, 5 s for the manipulator,
    /// 0.8 s vertical).
    pub evaluate_at_s: f64,
    /// Smallest particle number per layer (default 0: an empty layer).
    #[serde(default)]
    pub min_particles_per_layer: usize,
}

/// A study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerStudyFile {
    /// Coupling scenario with the structure and a free analysis (its dampers are ignored).
    pub scenario: PathBuf,
    /// The study.
    pub study: LayerStudySpec,
}

/// One evaluated design.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LayerDesign {
    /// Particles per layer (ascending).
    pub particles: Vec<usize>,
    /// Bed mass, kg.
    pub bed_mass_kg: f64,
    /// Container stroke at the evaluation time (largest |x| over the last period), m.
    pub stroke_m: f64,
}

/// Damper model of a design.
pub fn layer_damper(spec: &LayerStudySpec, particles: &[usize]) -> LayeredDamper {
    let layers: Vec<Box<dyn EffectiveDamper>> = particles
        .iter()
        .filter(|&&n| n > 0)
        .map(|&n| {
            let h = clearance_m(
                spec.container_length_m,
                n as f64,
                spec.max_particles_per_layer as f64,
            );
            let m = n as f64 * spec.particle_mass_kg;
            match spec.model {
                LayerModel::Rolling => Box::new(RollingDamper {
                    bed_mass_kg: m,
                    clearance_m: h,
                    smoothing_log_width: None,
                }) as Box<dyn EffectiveDamper>,
                LayerModel::Vertical => Box::new(VerticalDamper {
                    bed_mass_kg: m,
                    clearance_m: h,
                }),
            }
        })
        .collect();
    LayeredDamper { layers }
}

/// Largest |x| over the last period (1/f of mode `mode`) before `t_s`.
pub fn stroke_at(hist: &TimeHistory, t_s: f64, period_s: f64) -> f64 {
    hist.time_s
        .iter()
        .zip(&hist.displacement_m)
        .filter(|(t, _)| **t <= t_s && **t >= t_s - period_s)
        .map(|(_, x)| x.abs())
        .fold(0.0, f64::max)
}

/// Most designs (particle-number combinations) of one study.
pub const MAX_DESIGNS: f64 = 1e6;

impl LayerStudySpec {
    /// Number of sorted combinations (multisets of `layers` values out of the particle
    /// numbers), as f64 so that it cannot overflow.
    pub fn design_count(&self) -> f64 {
        let step = self.step.max(1);
        let values = if self.max_particles_per_layer >= self.min_particles_per_layer {
            ((self.max_particles_per_layer - self.min_particles_per_layer) / step + 1) as f64
        } else {
            0.0
        };
        // C(values + layers − 1, layers)
        let mut c = 1.0;
        for i in 0..self.layers.min(1000) {
            c *= (values + i as f64) / (i as f64 + 1.0);
        }
        c
    }

    /// Checks the study keys (`study.*`): counts ≥ 1 and bounded, finite physical numbers,
    /// at most [`MAX_DESIGNS`] combinations.
    ///
    /// # Errors
    /// A message naming the key and the fix.
    pub fn validate(&self) -> Result<(), StructureError> {
        if self.layers == 0 || self.layers > 100 {
            return Err(StructureError::rule(
                "study.layers",
                format!("must be in [1, 100], got {}", self.layers),
            ));
        }
        if self.max_particles_per_layer == 0 || self.max_particles_per_layer > 1_000_000_000 {
            return Err(StructureError::rule(
                "study.max_particles_per_layer",
                format!("must be in [1, 1e9], got {}", self.max_particles_per_layer),
            ));
        }
        if self.min_particles_per_layer > self.max_particles_per_layer {
            return Err(StructureError::rule(
                "study.min_particles_per_layer",
                format!(
                    "= {} exceeds max_particles_per_layer = {}",
                    self.min_particles_per_layer, self.max_particles_per_layer
                ),
            ));
        }
        if self.step == 0 {
            return Err(StructureError::rule("study.step", "must be ≥ 1, got 0"));
        }
        for (key, v, hi) in [
            ("particle_mass_kg", self.particle_mass_kg, 1e6),
            ("container_length_m", self.container_length_m, 1e3),
            ("evaluate_at_s", self.evaluate_at_s, 1e6),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= hi) {
                return Err(StructureError::rule(
                    format!("study.{key}"),
                    format!("must be a finite number in (0, {hi:e}], got {v}"),
                ));
            }
        }
        let n = self.design_count();
        if n > MAX_DESIGNS {
            return Err(StructureError::invalid(
                "study.step",
                format!(
                    "{n:.3e} designs (layers {}, particle numbers {}..={} in steps of {}), more \
                     than the {MAX_DESIGNS:e} accepted; use a larger step or fewer layers",
                    self.layers,
                    self.min_particles_per_layer,
                    self.max_particles_per_layer,
                    self.step
                ),
            ));
        }
        Ok(())
    }
}

/// All sorted particle-number combinations of the study.
pub fn combinations(spec: &LayerStudySpec) -> Vec<Vec<usize>> {
    let step = spec.step.max(1);
    let values: Vec<usize> = (spec.min_particles_per_layer..=spec.max_particles_per_layer)
        .step_by(step)
        .collect();
    let mut out = Vec::new();
    let mut cur = Vec::new();
    fn rec(
        values: &[usize],
        start: usize,
        left: usize,
        cur: &mut Vec<usize>,
        out: &mut Vec<Vec<usize>>,
    ) {
        if left == 0 {
            out.push(cur.clone());
            return;
        }
        for i in start..values.len() {
            cur.push(values[i]);
            rec(values, i, left - 1, cur, out);
            cur.pop();
        }
    }
    rec(&values, 0, spec.layers.max(1), &mut cur, &mut out);
    out
}

/// Runs the brute-force study on a structure and free-vibration settings.
///
/// # Errors
/// Invalid settings or unknown points.
pub fn run_layer_study(
    structure: &ModalStructure,
    free_spec: &FreeVibrationSpec,
    spec: &LayerStudySpec,
) -> Result<Vec<LayerDesign>, StructureError> {
    spec.validate()?;
    if !(spec.evaluate_at_s > 0.0 && spec.evaluate_at_s <= free_spec.duration_s) {
        return Err(StructureError::invalid(
            "study",
            "evaluate_at_s must lie in (0, analysis.duration_s]",
        ));
    }
    let mut fs = free_spec.clone();
    fs.duration_s = spec.evaluate_at_s;
    let k = fs.mode.min(structure.modes.len() - 1);
    let period = 1.0 / structure.modes[k].frequency_hz;
    let mut out = Vec::new();
    for particles in combinations(spec) {
        let model = layer_damper(spec, &particles);
        let bed = model.bed_mass_kg();
        let dampers = if bed > 0.0 {
            vec![CoupledDamper {
                point: spec.point.clone(),
                model: Box::new(model),
            }]
        } else {
            Vec::new()
        };
        let hist = free::run_free_vibration(structure, &dampers, &fs)?;
        // the period of the loaded structure is a little longer: one bare period + 10 %
        let stroke = stroke_at(&hist, spec.evaluate_at_s, 1.1 * period);
        out.push(LayerDesign {
            particles,
            bed_mass_kg: bed,
            stroke_m: stroke,
        });
    }
    out.sort_by(|a, b| a.stroke_m.total_cmp(&b.stroke_m));
    Ok(out)
}

/// Loads a study file, runs it and writes `DIR/study.csv` (all designs, best first) and
/// `DIR/summary.json`.
///
/// # Errors
/// Input, solver and I/O errors.
pub fn run_layer_study_file(path: &Path, out: &Path) -> Result<serde_json::Value, StructureError> {
    let text = std::fs::read_to_string(path).map_err(|e| StructureError::read(path, e))?;
    let file: LayerStudyFile = toml::from_str(&text).map_err(|e| StructureError::toml(path, e))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let scn_path = if file.scenario.is_absolute() {
        file.scenario.clone()
    } else {
        base.join(&file.scenario)
    };
    let (scn, structure_spec) = CoupleScenario::load(&scn_path)?;
    file.study
        .validate()
        .map_err(|m| crate::scenario::locate_error(path, m))?;
    let structure = structure_spec
        .build(scn_path.parent().unwrap_or(Path::new(".")))
        .map_err(|m| crate::scenario::locate_error(&scn.structure_source(&scn_path), m))?
        .modal;
    let fs = scn.analysis.free_vibration_spec().ok_or_else(|| {
        StructureError::inconsistent("the study's scenario needs [analysis] kind = \"free\"")
    })?;
    let started = std::time::Instant::now();
    let designs = run_layer_study(&structure, &fs, &file.study)?;
    std::fs::create_dir_all(out)?;
    let mut header: Vec<String> = (1..=file.study.layers)
        .map(|i| format!("particles_layer_{i}"))
        .collect();
    header.push("bed_mass_kg".into());
    header.push("stroke_m".into());
    let h: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    let rows: Vec<Vec<f64>> = designs
        .iter()
        .map(|d| {
            let mut r: Vec<f64> = d.particles.iter().map(|&n| n as f64).collect();
            r.push(d.bed_mass_kg);
            r.push(d.stroke_m);
            r
        })
        .collect();
    pdamp_io::csv::write_csv_atomic(out.join("study.csv"), &h, &rows)?;
    let empty = designs.iter().find(|d| d.bed_mass_kg == 0.0).cloned();
    let summary = serde_json::json!({
        "study": file.study,
        "designs": designs.len(),
        "best": designs.first(),
        "top_10": designs.iter().take(10).collect::<Vec<_>>(),
        "no_particles": empty,
        "structure_frequency_hz": structure.modes.first().map(|m| m.frequency_hz),
        "wall_time_s": started.elapsed().as_secs_f64(),
    });
    pdamp_io::atomic::write_atomic(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    Ok(summary)
}
