//! The design-study file of `pdamp design STUDY.toml --out DIR`: the structure (through a
//! coupling scenario), the objective, the design space of the damper, the materials, the
//! constraints and the search settings. Every key carries its unit; [`DesignStudy::load`]
//! checks them all and names the key of the first problem.
//!
//! ```toml
//! scenario = "couple_ch5_free_formulas.toml"  # structure + [analysis] kind = "free"
//!                                              # (its dampers are ignored)
//! [objective]
//! kind = "min_stroke"          # or "max_damping" (modes, amplitude range)
//! evaluate_at_s = 4.0
//!
//! [damper]
//! direction = "horizontal"     # rolling/bouncing layers (D Eq. 5.1–5.14, 6.12) | "vertical" (D Eq. 7.1–7.19)
//! points = ["damper"]          # candidate structure points
//! container_lengths_m = [0.12] # inner length along the excitation
//! container_width_m = 0.04     # inner width across it
//! layers = 3                   # separate layers (horizontal)
//! particle_radii_m = [0.005]
//!
//! [[materials]]
//! name = "steel"
//! density_kg_m3 = 7900.0
//!
//! [constraints]
//! max_bed_mass_kg = 0.6
//! ```

use crate::DesignError;
pub use crate::spec::*;
use pdamp_structure::free::FreeVibrationSpec;
use pdamp_structure::modal::ModalStructure;
use pdamp_structure::scenario::{CoupleScenario, PointSpec, StructureSpec};
use std::path::{Path, PathBuf};

/// A candidate damper location: a named point of the structure, or a position along a beam
/// (with its own structure: the point added, the container mass moved).
#[derive(Debug, Clone)]
pub struct Location {
    /// How reports name it (`'damper'`, `x = 1.760 m`).
    pub label: String,
    /// The structure point the damper sits at (the first container's).
    pub point: String,
    /// Every container's point (one entry unless `damper.containers` asks for several).
    pub points: Vec<String>,
    /// The reduced structure with the damper there.
    pub structure: ModalStructure,
    /// The structure spec when it differs from the scenario's (positions along a beam): the
    /// scenario files of a design carry it inline.
    pub spec: Option<StructureSpec>,
    /// The damper's orientation there (`damper.direction` or `damper.point_directions`).
    pub direction: Direction,
}

/// Name of the damper point placed at `damper.positions_m`.
pub const POSITION_POINT: &str = "design_damper";

/// A loaded and checked study: the file, the reduced structure and the free-vibration settings.
#[derive(Debug, Clone)]
pub struct DesignStudy {
    /// The study file as read.
    pub file: DesignStudyFile,
    /// Where it was read from.
    pub path: PathBuf,
    /// The scenario's path (resolved).
    pub scenario_path: PathBuf,
    /// The structure, modally reduced.
    pub structure: ModalStructure,
    /// The scenario's free analysis (for a `steady_state` scenario: its output point, a
    /// placeholder for the rest).
    pub free: FreeVibrationSpec,
    /// The harmonic load of a `steady_state` scenario.
    pub load: Option<HarmonicLoad>,
    /// The scenario's structure source for the scenario files written for verified designs:
    /// the structure file (absolute) or `None` when the structure is inline in the scenario.
    pub structure_file: Option<PathBuf>,
    /// The candidate locations: `damper.points`, then `damper.positions_m`.
    pub locations: Vec<Location>,
}

/// Largest particle count of one layer or bed (guards the enumeration against absurd inputs).
pub const MAX_PARTICLES: usize = 10_000_000;

impl DesignStudy {
    /// Reads the study file, its scenario and its structure, and checks every key.
    ///
    /// # Errors
    /// [`DesignError::Load`] for unreadable or malformed files, [`DesignError::Input`] naming the
    /// key for out-of-range values.
    pub fn load(path: &Path) -> Result<Self, DesignError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| DesignError::Load(format!("{}: {e}", path.display())))?;
        let file: DesignStudyFile = toml::from_str(&text)
            .map_err(|e| DesignError::Load(format!("{}: {e}", path.display())))?;
        let base = path.parent().unwrap_or(Path::new("."));
        let scenario_path = if file.scenario.is_absolute() {
            file.scenario.clone()
        } else {
            base.join(&file.scenario)
        };
        let (scn, spec) = CoupleScenario::load(&scenario_path).map_err(DesignError::from)?;
        let structure = spec
            .build(scenario_path.parent().unwrap_or(Path::new(".")))
            .map_err(|m| {
                DesignError::from(pdamp_structure::scenario::locate_error(
                    &scn.structure_source(&scenario_path),
                    m,
                ))
            })?
            .modal;
        let load = match &scn.analysis {
            pdamp_structure::scenario::AnalysisSpec::SteadyState {
                force_amplitude_n,
                base_amplitude_m,
                excitation_point,
                ..
            } => Some(HarmonicLoad {
                force_n: pdamp_structure::scenario::ForceSpec {
                    force_amplitude_n: *force_amplitude_n,
                    base_amplitude_m: *base_amplitude_m,
                }
                .force_n(&spec)
                .map_err(|error| DesignError::StructureFile {
                    path: scenario_path.clone(),
                    error: Box::new(error),
                })?,
                excitation_point: excitation_point.clone(),
            }),
            _ => None,
        };
        let free = match (&scn.analysis, scn.analysis.free_vibration_spec()) {
            (_, Some(f)) => f,
            (pdamp_structure::scenario::AnalysisSpec::SteadyState { output_point, .. }, None) => {
                FreeVibrationSpec {
                    duration_s: 1.0,
                    time_step_s: 1e-3,
                    mode: 0,
                    initial_point: output_point.clone(),
                    initial_displacement_m: 0.0,
                    initial_velocity_m_s: 0.0,
                    scale_initial_by_bed_mass: false,
                    output_point: output_point.clone(),
                    update: pdamp_structure::free::UpdateRule::ZeroCrossing,
                    sample_every: 1,
                }
            }
            _ => {
                return Err(DesignError::Load(format!(
                    "{}: the design study's scenario needs [analysis] kind = \"free\" (initial \
                     condition, time step and output point of a decay) or kind = \
                     \"steady_state\" (force, excitation and output point; objective \
                     min_frf_peak)",
                    scenario_path.display()
                )));
            }
        };
        let structure_file = scn
            .structure_file
            .as_ref()
            .map(|_| scn.structure_source(&scenario_path))
            .map(|p| std::fs::canonicalize(&p).unwrap_or(p));
        let mut study = DesignStudy {
            file,
            path: path.to_path_buf(),
            scenario_path,
            structure,
            free,
            load,
            structure_file,
            locations: Vec::new(),
        };
        study.validate()?;
        study.locations = study.locations(&spec)?;
        Ok(study)
    }

    /// The damper's orientation at a named point (`damper.point_directions`, else
    /// `damper.direction`).
    pub fn direction_at(&self, point: &str) -> Direction {
        let d = &self.file.damper;
        d.point_directions
            .get(point)
            .copied()
            .unwrap_or(d.direction)
    }

    /// Whether some candidate location has orientation `dir`.
    pub fn offers(&self, dir: Direction) -> bool {
        let d = &self.file.damper;
        (d.direction == dir
            && (!d.positions_m.is_empty() || d.points.len() > d.point_directions.len()))
            || d.point_directions.values().any(|&x| x == dir)
    }

    /// The candidate locations: the named points on the scenario's structure, and for every
    /// position along the beam the structure rebuilt with the damper point there (and the
    /// container mass moved, `damper.move_mass_at_m`).
    fn locations(&self, spec: &StructureSpec) -> Result<Vec<Location>, DesignError> {
        let d = &self.file.damper;
        let named = |set: &[usize], direction: Direction| Location {
            label: set
                .iter()
                .map(|&i| format!("'{}'", d.points[i]))
                .collect::<Vec<_>>()
                .join(" + "),
            point: d.points[set[0]].clone(),
            points: set.iter().map(|&i| d.points[i].clone()).collect(),
            structure: self.structure.clone(),
            spec: None,
            direction,
        };
        let mut out: Vec<Location> = Vec::new();
        let mut counts = d.containers.clone();
        counts.sort_unstable();
        for &n in &counts {
            for set in combinations(d.points.len(), n) {
                let first = self.direction_at(&d.points[set[0]]);
                // the containers of a set share their orientation
                if set
                    .iter()
                    .all(|&i| self.direction_at(&d.points[i]) == first)
                {
                    out.push(named(&set, first));
                }
            }
        }
        if d.positions_m.is_empty() {
            return Ok(out);
        }
        let Some(beam) = &spec.beam else {
            return Err(self.input(
                "damper.positions_m",
                "positions along a beam need a [structure.beam] structure; name points instead",
            ));
        };
        let dof = match &d.position_dof {
            Some(dof) => dof.clone(),
            None => spec
                .points
                .iter()
                .find(|p| p.name == self.free.output_point)
                .map_or_else(|| "uy".to_string(), |p| p.dof.clone()),
        };
        let moved = match d.move_mass_at_m {
            Some(x) => Some(
                beam.masses
                    .iter()
                    .position(|m| (m.position_m - x).abs() < 1e-9)
                    .ok_or_else(|| {
                        self.input(
                            "damper.move_mass_at_m",
                            format!("no [structure.beam] mass at {x} m"),
                        )
                    })?,
            ),
            None => None,
        };
        let base = self.scenario_path.parent().unwrap_or(Path::new("."));
        for (i, &x) in d.positions_m.iter().enumerate() {
            let key = format!("damper.positions_m[{i}]");
            pdamp_structure::scenario::on_beam(&key, x, beam.length_m)
                .map_err(|m| self.input(&key, m.to_string()))?;
            let mut st = spec.clone();
            st.points.retain(|p| p.name != POSITION_POINT);
            st.points.push(PointSpec {
                name: POSITION_POINT.into(),
                position_m: Some(x),
                node: None,
                dof: dof.clone(),
            });
            if let (Some(m), Some(b)) = (moved, st.beam.as_mut()) {
                b.masses[m].position_m = x;
            }
            let structure = st
                .build(base)
                .map_err(|m| {
                    self.input(
                        &key,
                        format!("building the beam with the damper at {x} m: {m}"),
                    )
                })?
                .modal;
            out.push(Location {
                label: format!("x = {x:.3} m"),
                point: POSITION_POINT.into(),
                points: vec![POSITION_POINT.into()],
                structure,
                spec: Some(st),
                direction: d.direction,
            });
        }
        Ok(out)
    }

    fn input(&self, key: impl Into<String>, message: impl Into<String>) -> DesignError {
        DesignError::Input {
            path: self.path.clone(),
            key: key.into(),
            message: message.into(),
        }
    }

    fn positive(&self, key: &str, v: f64, hi: f64) -> Result<(), DesignError> {
        if v.is_finite() && v > 0.0 && v <= hi {
            Ok(())
        } else {
            Err(self.input(
                key,
                format!("must be a finite number in (0, {hi:e}], got {v}"),
            ))
        }
    }

    fn check_modes(&self, modes: &[usize]) -> Result<(), DesignError> {
        if modes.is_empty() {
            return Err(self.input("objective.modes", "give at least one mode (1-based)"));
        }
        for (i, &m) in modes.iter().enumerate() {
            if m == 0 || m > self.structure.modes.len() {
                return Err(self.input(
                    format!("objective.modes[{i}]"),
                    format!(
                        "mode {m} does not exist: the structure has modes 1 … {}",
                        self.structure.modes.len()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Checks every key against the structure and the scenario.
    ///
    /// # Errors
    /// [`DesignError::Input`] naming the first bad key.
    pub fn validate(&self) -> Result<(), DesignError> {
        self.validate_objective()?;
        self.validate_damper()?;
        self.validate_settings()?;
        self.validate_coatings_and_fields()
    }

    /// The coating of `[damper] coatings[index]` from `[[coatings]]` (`None` for the bare
    /// wall, `"none"`).
    pub fn coating(&self, index: usize) -> Option<&crate::spec::CoatingSpec> {
        let name = &self.file.damper.coatings[index];
        self.file.coatings.iter().find(|c| &c.name == name)
    }

    /// The coating table, `[damper] coatings` and the effective-field settings.
    fn validate_coatings_and_fields(&self) -> Result<(), DesignError> {
        let f = &self.file;
        for (i, c) in f.coatings.iter().enumerate() {
            let key = |k: &str| format!("coatings[{i}].{k}");
            if c.name.trim().is_empty() || c.name == crate::spec::NO_COATING {
                return Err(self.input(
                    key("name"),
                    format!(
                        "must be a non-empty name other than '{}' (the bare wall)",
                        crate::spec::NO_COATING
                    ),
                ));
            }
            if f.coatings[..i].iter().any(|o| o.name == c.name) {
                return Err(self.input(key("name"), format!("'{}' is listed twice", c.name)));
            }
            self.positive(&key("youngs_modulus_pa"), c.youngs_modulus_pa, 1e13)?;
            self.positive(&key("density_kg_m3"), c.density_kg_m3, 1e5)?;
            if !(c.poisson_ratio > 0.0 && c.poisson_ratio < 0.5) {
                return Err(self.input(
                    key("poisson_ratio"),
                    format!(
                        "must lie in (0, 0.5) (the contact law needs ν < 0.5; rubber: 0.49), \
                         got {}",
                        c.poisson_ratio
                    ),
                ));
            }
            if !(c.restitution > 0.0 && c.restitution <= 1.0) {
                return Err(self.input(
                    key("restitution"),
                    format!("must lie in (0, 1], got {}", c.restitution),
                ));
            }
        }
        let d = &f.damper;
        if d.coatings.is_empty() {
            return Err(self.input(
                "damper.coatings",
                format!("give at least one, e.g. [\"{}\"]", crate::spec::NO_COATING),
            ));
        }
        for (i, name) in d.coatings.iter().enumerate() {
            let key = format!("damper.coatings[{i}]");
            if name != crate::spec::NO_COATING && !f.coatings.iter().any(|c| &c.name == name) {
                let known: Vec<&str> = f.coatings.iter().map(|c| c.name.as_str()).collect();
                return Err(self.input(
                    key,
                    format!(
                        "'{name}' is neither '{}' nor a [[coatings]] name ({})",
                        crate::spec::NO_COATING,
                        if known.is_empty() {
                            "the table is empty".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                ));
            }
            if d.coatings[..i].contains(name) {
                return Err(self.input(key, format!("'{name}' is listed twice")));
            }
        }
        let v = &f.verification;
        if d.coatings.len() > 1 && v.field_designs == 0 {
            return Err(self.input(
                "verification.field_designs",
                format!(
                    "{} coatings are candidates, but the formulas do not see a coating: only \
                     the effective fields tell them apart; set field_designs ≥ 1",
                    d.coatings.len()
                ),
            ));
        }
        if v.field_designs > 20 {
            return Err(self.input(
                "verification.field_designs",
                format!("must be in [0, 20], got {}", v.field_designs),
            ));
        }
        if !(2..=50).contains(&v.field_amplitudes) {
            return Err(self.input(
                "verification.field_amplitudes",
                format!("must be in [2, 50], got {}", v.field_amplitudes),
            ));
        }
        if v.field_cycles == 0 || v.field_cycles > 10_000 {
            return Err(self.input(
                "verification.field_cycles",
                format!("must be in [1, 10000], got {}", v.field_cycles),
            ));
        }
        if v.field_transient_cycles >= v.field_cycles {
            return Err(self.input(
                "verification.field_transient_cycles",
                format!(
                    "must be below field_cycles = {} (at least one cycle is evaluated), got {}",
                    v.field_cycles, v.field_transient_cycles
                ),
            ));
        }
        Ok(())
    }

    /// The objective against the scenario (free or steady state) and the structure's modes.
    fn validate_objective(&self) -> Result<(), DesignError> {
        let f = &self.file;
        let forced = f.objective.is_forced();
        if forced != self.load.is_some() {
            return Err(self.input(
                "objective.kind",
                if forced {
                    "min_frf_peak and max_resonance_damping need a scenario with [analysis] kind = \
                     \"steady_state\" (the force)"
                } else {
                    "min_stroke and max_damping need a scenario with [analysis] kind = \"free\"; \
                     a steady_state scenario goes with kind = \"min_frf_peak\" or \
                     \"max_resonance_damping\""
                },
            ));
        }
        match &f.objective {
            ObjectiveSpec::MinFrfPeak {
                modes,
                frequencies,
                band,
            }
            | ObjectiveSpec::MaxResonanceDamping {
                modes,
                frequencies,
                band,
            } => {
                self.check_modes(modes)?;
                if !(11..=100_000).contains(frequencies) {
                    return Err(self.input(
                        "objective.frequencies",
                        format!("must be in [11, 100000], got {frequencies}"),
                    ));
                }
                if !(band.is_finite() && *band > 0.0 && *band < 0.9) {
                    return Err(self.input(
                        "objective.band",
                        format!("must lie in (0, 0.9), got {band}"),
                    ));
                }
                if let Some(l) = &self.load {
                    if let Err(m) = self.structure.point(&l.excitation_point) {
                        return Err(self.input("scenario analysis.excitation_point", m.to_string()));
                    }
                    self.positive("scenario analysis force", l.force_n.abs(), 1e12)?;
                }
            }
            ObjectiveSpec::MinStroke { evaluate_at_s } => {
                self.positive("objective.evaluate_at_s", *evaluate_at_s, 1e6)?;
                if *evaluate_at_s > self.free.duration_s {
                    return Err(self.input(
                        "objective.evaluate_at_s",
                        format!(
                            "{evaluate_at_s} s lies beyond the scenario's analysis.duration_s = {} s",
                            self.free.duration_s
                        ),
                    ));
                }
            }
            ObjectiveSpec::MaxDamping {
                modes,
                amplitude_min_m,
                amplitude_max_m,
                amplitudes,
            } => {
                self.check_modes(modes)?;
                self.positive("objective.amplitude_min_m", *amplitude_min_m, 10.0)?;
                self.positive("objective.amplitude_max_m", *amplitude_max_m, 10.0)?;
                if amplitude_min_m >= amplitude_max_m {
                    return Err(self.input(
                        "objective.amplitude_max_m",
                        format!("must exceed amplitude_min_m = {amplitude_min_m} m"),
                    ));
                }
                if !(2..=1000).contains(amplitudes) {
                    return Err(self.input(
                        "objective.amplitudes",
                        format!("must be in [2, 1000], got {amplitudes}"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The damper space: locations, containers, dimensions, radii.
    fn validate_damper(&self) -> Result<(), DesignError> {
        let f = &self.file;
        let d = &f.damper;
        if d.points.is_empty() && d.positions_m.is_empty() {
            return Err(self.input(
                "damper.points",
                "give at least one structure point (or positions_m along a beam)",
            ));
        }
        if d.points.len() + d.positions_m.len() > 10_000 {
            return Err(self.input("damper.positions_m", "at most 10 000 candidate locations"));
        }
        if d.containers.is_empty() {
            return Err(self.input("damper.containers", "give at least one number, e.g. [1]"));
        }
        for (i, &n) in d.containers.iter().enumerate() {
            let key = format!("damper.containers[{i}]");
            if !(1..=4).contains(&n) {
                return Err(self.input(key, format!("must be in 1..=4, got {n}")));
            }
            if d.containers[..i].contains(&n) {
                return Err(self.input(key, format!("{n} is listed twice")));
            }
            if n >= 2 && n > d.points.len() {
                return Err(self.input(
                    key,
                    format!(
                        "{n} containers need at least {n} different damper.points (one each), \
                         got {}",
                        d.points.len()
                    ),
                ));
            }
            if n >= 2 && f.objective.is_forced() {
                return Err(self.input(
                    key,
                    "several containers: free-decay objectives only (min_stroke, max_damping); \
                     the steady-state schemes of D Fig. 3.7 / Eq. 3.44 take one damper point",
                ));
            }
        }
        if !d.positions_m.is_empty() && !d.containers.contains(&1) {
            return Err(self.input(
                "damper.containers",
                "positions_m carry one container each: include 1",
            ));
        }
        for (i, p) in d.points.iter().enumerate() {
            if let Err(m) = self.structure.point(p) {
                return Err(self.input(format!("damper.points[{i}]"), m.to_string()));
            }
        }
        let output = self.structure.point(&self.free.output_point);
        if let Err(m) = output {
            return Err(self.input("scenario analysis.output_point", m.to_string()));
        }
        if d.container_lengths_m.is_empty() {
            return Err(self.input("damper.container_lengths_m", "give at least one length"));
        }
        for (i, &l) in d.container_lengths_m.iter().enumerate() {
            self.positive(&format!("damper.container_lengths_m[{i}]"), l, 100.0)?;
        }
        self.positive("damper.container_width_m", d.container_width_m, 100.0)?;
        if let Some(w) = d.container_depth_m {
            self.positive("damper.container_depth_m", w, 100.0)?;
        }
        if d.layers == 0 || d.layers > 12 {
            return Err(self.input(
                "damper.layers",
                format!("must be in [1, 12], got {}", d.layers),
            ));
        }
        for (name, _) in d.point_directions.iter() {
            if !d.points.contains(name) {
                return Err(self.input(
                    format!("damper.point_directions.{name}"),
                    format!("'{name}' is not one of damper.points {:?}", d.points),
                ));
            }
        }
        if self.offers(Direction::Vertical) && d.layers != 1 {
            return Err(self.input(
                "damper.layers",
                "a vertical bed is one block (D Sect. 7.1.1): use layers = 1",
            ));
        }
        if d.particle_radii_m.is_empty() {
            return Err(self.input("damper.particle_radii_m", "give at least one radius"));
        }
        let min_len = d
            .container_lengths_m
            .iter()
            .cloned()
            .fold(f64::MAX, f64::min);
        for (i, &r) in d.particle_radii_m.iter().enumerate() {
            self.positive(&format!("damper.particle_radii_m[{i}]"), r, 1.0)?;
            if 2.0 * r > d.container_width_m.min(min_len) {
                return Err(self.input(
                    format!("damper.particle_radii_m[{i}]"),
                    format!(
                        "a sphere of {r} m radius does not fit the container (width {} m, \
                         shortest length {min_len} m)",
                        d.container_width_m
                    ),
                ));
            }
        }
        if let Some(h) = d.container_height_m {
            self.positive("damper.container_height_m", h, 100.0)?;
            if !self.offers(Direction::Horizontal) {
                return Err(self.input(
                    "damper.container_height_m",
                    "a vertical container's height is its length along the excitation: use \
                     container_lengths_m (and container_depth_m for the second horizontal side)",
                ));
            }
            let rmax = d.particle_radii_m.iter().cloned().fold(0.0, f64::max);
            if h < 2.0 * rmax * d.layers as f64 {
                return Err(self.input(
                    "damper.container_height_m",
                    format!(
                        "{h} m holds no row of the largest spheres (r = {rmax} m) in each of the \
                         {} layer(s)",
                        d.layers
                    ),
                ));
            }
            if f.verification.layer_height_m.is_some() {
                return Err(self.input(
                    "verification.layer_height_m",
                    "the layers share damper.container_height_m: give one of the two",
                ));
            }
        }
        if d.particle_count_step == Some(0) {
            return Err(self.input("damper.particle_count_step", "must be ≥ 1"));
        }
        Ok(())
    }

    /// Materials, constraints, verification and search settings.
    fn validate_settings(&self) -> Result<(), DesignError> {
        let f = &self.file;
        let d = &f.damper;
        if f.materials.is_empty() {
            return Err(self.input("materials", "give at least one [[materials]] entry"));
        }
        for (i, m) in f.materials.iter().enumerate() {
            self.positive(
                &format!("materials[{i}].density_kg_m3"),
                m.density_kg_m3,
                1e5,
            )?;
            if m.name.trim().is_empty() {
                return Err(self.input(format!("materials[{i}].name"), "must not be empty"));
            }
        }
        if let Some(m) = f.constraints.max_bed_mass_kg {
            self.positive("constraints.max_bed_mass_kg", m, 1e6)?;
        }
        if let Some(h) = f.constraints.min_clearance_m
            && !(h.is_finite() && h >= 0.0)
        {
            return Err(self.input(
                "constraints.min_clearance_m",
                format!("must be a finite number ≥ 0, got {h}"),
            ));
        }
        let v = &f.verification;
        if v.dem_designs > 20 {
            return Err(self.input(
                "verification.dem_designs",
                format!("must be in [0, 20], got {}", v.dem_designs),
            ));
        }
        if v.dem_designs > f.search.top {
            return Err(self.input(
                "verification.dem_designs",
                format!("must not exceed search.top = {}", f.search.top),
            ));
        }
        if !(1..=100).contains(&v.packings) {
            return Err(self.input(
                "verification.packings",
                format!("must be in [1, 100], got {}", v.packings),
            ));
        }
        self.positive(
            "verification.youngs_modulus_scale",
            v.youngs_modulus_scale,
            1.0,
        )?;
        if let Some(h) = v.layer_height_m {
            self.positive("verification.layer_height_m", h, 10.0)?;
            let rmax = d.particle_radii_m.iter().cloned().fold(0.0, f64::max);
            if h < 2.0 * rmax {
                return Err(self.input(
                    "verification.layer_height_m",
                    format!(
                        "{h} m is below the largest particle diameter {} m",
                        2.0 * rmax
                    ),
                ));
            }
        }
        if let Some(dt) = v.time_step_s {
            self.positive("verification.time_step_s", dt, 1e-2)?;
        }
        self.positive(
            "verification.container.density_kg_m3",
            v.container.density_kg_m3,
            1e5,
        )?;
        self.positive(
            "verification.container.youngs_modulus_pa",
            v.container.youngs_modulus_pa,
            1e13,
        )?;
        if !(v.container.poisson_ratio > 0.0 && v.container.poisson_ratio <= 0.5) {
            return Err(self.input(
                "verification.container.poisson_ratio",
                format!("must lie in (0, 0.5], got {}", v.container.poisson_ratio),
            ));
        }
        let s = &f.search;
        if s.verifications == Some(0) {
            return Err(self.input("search.verifications", "must be ≥ 1"));
        }
        if s.top == 0 || s.top > 100 {
            return Err(self.input("search.top", format!("must be in [1, 100], got {}", s.top)));
        }
        if !(s.detuning.is_finite() && (0.0..0.5).contains(&s.detuning)) {
            return Err(self.input(
                "search.detuning",
                format!("must be in [0, 0.5), got {}", s.detuning),
            ));
        }
        if s.swarm_particles < 2 || s.swarm_particles > 10_000 {
            return Err(self.input(
                "search.swarm_particles",
                format!("must be in [2, 10000], got {}", s.swarm_particles),
            ));
        }
        if s.swarm_iterations == 0 || s.swarm_iterations > 100_000 {
            return Err(self.input(
                "search.swarm_iterations",
                format!("must be in [1, 100000], got {}", s.swarm_iterations),
            ));
        }
        Ok(())
    }
}

/// Every n-subset of 0..len, ascending, in lexicographic order.
fn combinations(len: usize, n: usize) -> Vec<Vec<usize>> {
    fn rec(start: usize, len: usize, n: usize, cur: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
        if cur.len() == n {
            out.push(cur.clone());
            return;
        }
        for i in start..len {
            cur.push(i);
            rec(i + 1, len, n, cur, out);
            cur.pop();
        }
    }
    let mut out = Vec::new();
    if n > 0 && n <= len {
        rec(0, len, n, &mut Vec::new(), &mut out);
    }
    out
}
