//! Range checks of every number of a structure spec and a couple scenario (finite, physical
//! range, the key named), the limits they use, and the location of a message in its file.

use super::{
    AnalysisSpec, BeamSpec, CoupleScenario, DamperSpec, RollingLayerSpec, StructureSpec,
    SupportKind,
};
use crate::StructureError;
use crate::fe::Dof;
use std::path::Path;

/// Most elements of a built-in beam.
pub const MAX_ELEMENTS: usize = 1_000_000;
/// Most modes kept.
pub const MAX_MODES: usize = 1000;
/// Longest beam, m.
pub const MAX_LENGTH_M: f64 = 1e4;
/// Largest Young's modulus, Pa (diamond: 1.2e12).
pub const MAX_MODULUS_PA: f64 = 1e13;
/// Largest density, kg/m³ (osmium: 22 590).
pub const MAX_DENSITY_KG_M3: f64 = 1e5;
/// Largest mass of a structure or damper entry, kg.
pub const MAX_MASS_KG: f64 = 1e9;
/// Largest frequency, Hz.
pub const MAX_FREQUENCY_HZ: f64 = 1e7;
/// Longest simulated time, s.
pub const MAX_DURATION_S: f64 = 1e6;
/// Largest force amplitude, N.
pub const MAX_FORCE_N: f64 = 1e12;
/// Largest displacement (amplitude, clearance, section size), m.
pub const MAX_DISPLACEMENT_M: f64 = 1e3;
/// Most frequencies of a steady-state FRF, windows cycles and similar counts.
pub const MAX_POINTS: usize = 1_000_000;
/// Most segments of a segmented sweep.
pub const MAX_SEGMENTS: usize = 1000;

/// One number of the input: finite and `ok`, else a message starting with the key path (for
/// its line and column), the value and the wanted range.
fn check_num(key: &str, v: f64, ok: bool, want: &str) -> Result<(), StructureError> {
    if !v.is_finite() {
        return Err(StructureError::NotFinite {
            key: key.to_string(),
            expected: want.to_string(),
            value: v,
        });
    }
    if !ok {
        return Err(StructureError::OutOfRange {
            key: key.to_string(),
            expected: want.to_string(),
            value: v,
        });
    }
    Ok(())
}

/// `v` in (0, hi].
fn positive(key: &str, v: f64, hi: f64, unit: &str) -> Result<(), StructureError> {
    check_num(
        key,
        v,
        v > 0.0 && v <= hi,
        &format!("in (0, {hi:e}] {unit}"),
    )
}

/// `v` in [0, hi].
fn non_negative(key: &str, v: f64, hi: f64, unit: &str) -> Result<(), StructureError> {
    check_num(
        key,
        v,
        (0.0..=hi).contains(&v),
        &format!("in [0, {hi:e}] {unit}"),
    )
}

/// A count in [lo, hi].
fn count(key: &str, v: usize, lo: usize, hi: usize) -> Result<(), StructureError> {
    if v < lo || v > hi {
        return Err(StructureError::Count {
            key: key.to_string(),
            value: v,
            lo,
            hi,
        });
    }
    Ok(())
}

/// A position along a beam of length `length_m`: finite and in [0, L] (1e-9·L tolerance).
///
/// # Errors
/// A message naming `key`, the value and the beam length.
pub fn on_beam(key: &str, x: f64, length_m: f64) -> Result<(), StructureError> {
    check_num(key, x, true, "")?;
    let tol = 1e-9 * length_m;
    if x < -tol || x > length_m + tol {
        return Err(StructureError::OffBeam {
            key: key.to_string(),
            value: x,
            length_m,
        });
    }
    Ok(())
}

/// The key, value and text of a validation message turned into a located error about `path`
/// (`scenario 'FILE', line L, column C: message`): the key path the message starts with is
/// looked up in the file.
pub fn locate(path: &Path, message: impl Into<String>) -> String {
    let text = std::fs::read_to_string(path).ok();
    pdamp_scenario::schema::ScenarioError::invalid(path, text.as_deref(), message).to_string()
}

/// [`locate`] as a typed error: `error` located in the file `path` (read again for the key's
/// line and column), a [`StructureError::Scenario`].
pub fn locate_error(path: &Path, error: StructureError) -> StructureError {
    let text = std::fs::read_to_string(path).ok();
    error.located(path, text.as_deref())
}

impl StructureSpec {
    /// Checks every number of the structure for finiteness and a physical range, the point
    /// names, and that supports, masses and points lie on the beam; messages start with the
    /// key (`structure.beam.supports[0].position_m …`) and say what to give.
    ///
    /// # Errors
    /// The first invalid value.
    pub fn validate(&self) -> Result<(), StructureError> {
        self.validate_modes()?;
        self.validate_model_and_damping()?;
        self.validate_points()
    }

    /// Mode count, frequency floor, a single mode or given modal data.
    fn validate_modes(&self) -> Result<(), StructureError> {
        count("structure.n_modes", self.n_modes, 1, MAX_MODES)?;
        non_negative(
            "structure.min_frequency_hz",
            self.min_frequency_hz,
            MAX_FREQUENCY_HZ,
            "Hz",
        )?;
        if let Some(s) = &self.single_mode {
            positive(
                "structure.single_mode.mass_kg",
                s.mass_kg,
                MAX_MASS_KG,
                "kg",
            )?;
            positive(
                "structure.single_mode.stiffness_n_m",
                s.stiffness_n_m,
                1e16,
                "N/m",
            )?;
            non_negative(
                "structure.single_mode.damping_n_s_m",
                s.damping_n_s_m,
                1e14,
                "N·s/m",
            )?;
        }
        if let Some(m) = &self.modal {
            if m.frequencies_hz.is_empty() {
                return Err(StructureError::invalid(
                    "structure.modal.frequencies_hz",
                    "give at least one mode",
                ));
            }
            count(
                "structure.modal.frequencies_hz",
                m.frequencies_hz.len(),
                1,
                MAX_MODES,
            )?;
            for (k, f) in m.frequencies_hz.iter().enumerate() {
                positive(
                    &format!("structure.modal.frequencies_hz[{k}]"),
                    *f,
                    MAX_FREQUENCY_HZ,
                    "Hz",
                )?;
            }
            if m.damping_ratios.len() != m.frequencies_hz.len() {
                return Err(StructureError::rule(
                    "structure.modal.damping_ratios",
                    format!(
                        "needs one value per frequency ({}), got {}",
                        m.frequencies_hz.len(),
                        m.damping_ratios.len()
                    ),
                ));
            }
            for (k, z) in m.damping_ratios.iter().enumerate() {
                non_negative(&format!("structure.modal.damping_ratios[{k}]"), *z, 1.0, "")?;
            }
            let mut names = std::collections::HashSet::new();
            for (i, p) in m.points.iter().enumerate() {
                let key = format!("structure.modal.points[{i}]");
                if p.name.trim().is_empty() || !names.insert(p.name.as_str()) {
                    return Err(StructureError::rule(
                        format!("{key}.name"),
                        format!(
                            "'{}' is empty or used twice; give every point its own name",
                            p.name
                        ),
                    ));
                }
                if p.shape.len() != m.frequencies_hz.len() {
                    return Err(StructureError::rule(
                        format!("{key}.shape"),
                        format!(
                            "needs one value per mode ({}), got {}",
                            m.frequencies_hz.len(),
                            p.shape.len()
                        ),
                    ));
                }
                for (k, v) in p.shape.iter().enumerate() {
                    check_num(&format!("{key}.shape[{k}]"), *v, v.abs() <= 1e12, "(1/√kg)")?;
                }
            }
        }
        Ok(())
    }

    /// The beam or Matrix Market model and the damping.
    fn validate_model_and_damping(&self) -> Result<(), StructureError> {
        if let Some(b) = &self.beam {
            b.validate()?;
        }
        if let Some(mm) = &self.matrix_market {
            for (k, p) in [
                ("stiffness", &mm.stiffness),
                ("mass", &mm.mass),
                ("dof_map", &mm.dof_map),
            ] {
                if p.as_os_str().is_empty() {
                    return Err(StructureError::invalid(
                        format!("structure.matrix_market.{k}"),
                        "give a file name",
                    ));
                }
            }
        }
        if let Some(d) = &self.damping {
            if let Some(z) = d.ratio {
                non_negative("structure.damping.ratio", z, 1.0, "")?;
            }
            for (k, z) in d.ratios.iter().flatten().enumerate() {
                non_negative(&format!("structure.damping.ratios[{k}]"), *z, 1.0, "")?;
            }
            if let Some(a) = d.rayleigh_alpha_1_s {
                non_negative("structure.damping.rayleigh_alpha_1_s", a, 1e6, "1/s")?;
            }
            if let Some(b) = d.rayleigh_beta_s {
                non_negative("structure.damping.rayleigh_beta_s", b, 1.0, "s")?;
            }
        }
        Ok(())
    }

    /// The named points: unique names, dofs, on the beam or at a node.
    fn validate_points(&self) -> Result<(), StructureError> {
        let mut names = std::collections::HashSet::new();
        for (i, p) in self.points.iter().enumerate() {
            let key = format!("structure.points[{i}]");
            if p.name.trim().is_empty() || !names.insert(p.name.as_str()) {
                return Err(StructureError::rule(
                    format!("{key}.name"),
                    format!(
                        "'{}' is empty or used twice; give every point its own name",
                        p.name
                    ),
                ));
            }
            if Dof::parse(&p.dof).is_none() {
                return Err(StructureError::rule(
                    format!("{key}.dof"),
                    format!(
                        "'{}' is not a dof; give one of ux uy uz rotx roty rotz",
                        p.dof
                    ),
                ));
            }
            if let Some(b) = &self.beam {
                let x = p.position_m.ok_or_else(|| {
                    StructureError::rule(
                        format!("{key}.position_m"),
                        "is missing: a point on a beam needs its position",
                    )
                })?;
                on_beam(&format!("{key}.position_m"), x, b.length_m)?;
            }
            if self.matrix_market.is_some() && p.node.is_none() {
                return Err(StructureError::rule(
                    format!("{key}.node"),
                    "is missing: a point of a Matrix Market model needs its node id",
                ));
            }
        }
        Ok(())
    }
}

impl BeamSpec {
    /// Checks the beam's numbers (`structure.beam.*`): length, element count (≤
    /// [`MAX_ELEMENTS`]), material, section, supports and masses on the beam.
    ///
    /// # Errors
    /// The first invalid value, naming its key.
    pub fn validate(&self) -> Result<(), StructureError> {
        let k = |s: &str| format!("structure.beam.{s}");
        positive(&k("length_m"), self.length_m, MAX_LENGTH_M, "m")?;
        count(&k("elements"), self.elements, 1, MAX_ELEMENTS)?;
        positive(
            &k("youngs_modulus_pa"),
            self.youngs_modulus_pa,
            MAX_MODULUS_PA,
            "Pa",
        )?;
        check_num(
            &k("poisson_ratio"),
            self.poisson_ratio,
            self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5,
            "in (-1, 0.5)",
        )?;
        positive(
            &k("density_kg_m3"),
            self.density_kg_m3,
            MAX_DENSITY_KG_M3,
            "kg/m³",
        )?;
        for (key, v, hi, unit) in [
            ("area_m2", self.area_m2, 1e4, "m²"),
            ("second_moment_m4", self.second_moment_m4, 1e6, "m⁴"),
            ("second_moment_z_m4", self.second_moment_z_m4, 1e6, "m⁴"),
            ("torsion_constant_m4", self.torsion_constant_m4, 1e6, "m⁴"),
            ("width_m", self.width_m, MAX_DISPLACEMENT_M, "m"),
            ("height_m", self.height_m, MAX_DISPLACEMENT_M, "m"),
        ] {
            if let Some(v) = v {
                positive(&k(key), v, hi, unit)?;
            }
        }
        for (i, s) in self.supports.iter().enumerate() {
            on_beam(
                &k(&format!("supports[{i}].position_m")),
                s.position_m,
                self.length_m,
            )?;
            let key = k(&format!("supports[{i}].stiffness_n_m"));
            match s.kind {
                SupportKind::Spring => positive(&key, s.stiffness_n_m, 1e16, "N/m")?,
                _ => non_negative(&key, s.stiffness_n_m, 1e16, "N/m")?,
            }
        }
        for (i, m) in self.masses.iter().enumerate() {
            let key = |s: &str| k(&format!("masses[{i}].{s}"));
            on_beam(&key("position_m"), m.position_m, self.length_m)?;
            non_negative(&key("mass_kg"), m.mass_kg, MAX_MASS_KG, "kg")?;
            non_negative(
                &key("rotary_inertia_kg_m2"),
                m.rotary_inertia_kg_m2,
                MAX_MASS_KG,
                "kg·m²",
            )?;
            check_num(
                &key("offset_y_m"),
                m.offset_y_m,
                m.offset_y_m.abs() <= MAX_DISPLACEMENT_M,
                &format!("in [-{MAX_DISPLACEMENT_M:e}, {MAX_DISPLACEMENT_M:e}] m"),
            )?;
        }
        Ok(())
    }
}

/// Number of modes a structure spec yields at most (for the `mode` keys).
fn mode_count(structure: &StructureSpec) -> usize {
    if structure.single_mode.is_some() {
        1
    } else if let Some(m) = &structure.modal {
        m.frequencies_hz.len()
    } else {
        structure.n_modes
    }
}

/// Time step, duration and sampling of a time-domain analysis (`analysis.*`).
fn check_time(
    duration_s: f64,
    time_step_s: f64,
    sample_every: usize,
) -> Result<(), StructureError> {
    positive("analysis.duration_s", duration_s, MAX_DURATION_S, "s")?;
    positive(
        "analysis.time_step_s",
        time_step_s,
        duration_s,
        "s (the duration)",
    )?;
    let steps = duration_s / time_step_s;
    if steps > crate::integrate::MAX_STEPS {
        return Err(StructureError::rule(
            "analysis.time_step_s",
            format!(
                "= {time_step_s:e} s gives {steps:.3e} steps over {duration_s:e} s, more than the \
                 {:e} accepted; use a longer time step or a shorter duration",
                crate::integrate::MAX_STEPS
            ),
        ));
    }
    count("analysis.sample_every", sample_every, 1, usize::MAX)?;
    if steps / sample_every as f64 > crate::integrate::MAX_SAMPLES {
        return Err(StructureError::rule(
            "analysis.sample_every",
            format!(
                "= {sample_every} stores {:.3e} samples, more than the {:e} accepted; use \
                 sample_every ≥ {}",
                steps / sample_every as f64,
                crate::integrate::MAX_SAMPLES,
                (steps / crate::integrate::MAX_SAMPLES).ceil()
            ),
        ));
    }
    Ok(())
}

/// Force or base amplitude of a forced analysis: exactly one, finite, bounded.
fn check_force(force: Option<f64>, base: Option<f64>) -> Result<(), StructureError> {
    match (force, base) {
        (Some(f), None) => check_num(
            "analysis.force_amplitude_n",
            f,
            f.abs() <= MAX_FORCE_N && f != 0.0,
            &format!("non-zero with |F| ≤ {MAX_FORCE_N:e} N"),
        ),
        (None, Some(u)) => check_num(
            "analysis.base_amplitude_m",
            u,
            u.abs() <= MAX_DISPLACEMENT_M && u != 0.0,
            &format!("non-zero with |U| ≤ {MAX_DISPLACEMENT_M:e} m"),
        ),
        _ => Err(StructureError::invalid(
            "analysis.force_amplitude_n",
            "give exactly one of force_amplitude_n and base_amplitude_m",
        )),
    }
}

/// Frequency range of a forced analysis.
fn check_range(start_hz: f64, end_hz: f64) -> Result<(), StructureError> {
    positive("analysis.start_hz", start_hz, MAX_FREQUENCY_HZ, "Hz")?;
    positive("analysis.end_hz", end_hz, MAX_FREQUENCY_HZ, "Hz")
}

impl CoupleScenario {
    /// Checks the analysis and the dampers of the scenario (`structure` is its resolved
    /// structure, for the mode count): every number finite and in range, the key named.
    ///
    /// # Errors
    /// The first invalid value.
    pub fn validate(&self, structure: &StructureSpec) -> Result<(), StructureError> {
        let modes = mode_count(structure);
        let mode_ok = |m: usize| count("analysis.mode", m, 1, modes.max(1));
        let dem = self
            .dampers
            .iter()
            .any(|d| matches!(d, DamperSpec::Dem { .. }));
        match &self.analysis {
            AnalysisSpec::Free {
                duration_s,
                time_step_s,
                mode,
                initial_point,
                initial_displacement_m,
                initial_velocity_m_s,
                output_point,
                sample_every,
                ..
            } => {
                if dem {
                    positive("analysis.duration_s", *duration_s, MAX_DURATION_S, "s")?;
                } else {
                    check_time(*duration_s, *time_step_s, *sample_every)?;
                }
                mode_ok(*mode)?;
                for (k, p) in [
                    ("initial_point", initial_point),
                    ("output_point", output_point),
                ] {
                    if p.trim().is_empty() {
                        return Err(StructureError::invalid(
                            format!("analysis.{k}"),
                            "give a structure point name",
                        ));
                    }
                }
                check_num(
                    "analysis.initial_displacement_m",
                    *initial_displacement_m,
                    initial_displacement_m.abs() <= MAX_DISPLACEMENT_M,
                    &format!("in [-{MAX_DISPLACEMENT_M:e}, {MAX_DISPLACEMENT_M:e}] m"),
                )?;
                check_num(
                    "analysis.initial_velocity_m_s",
                    *initial_velocity_m_s,
                    initial_velocity_m_s.abs() <= 1e6,
                    "in [-1e6, 1e6] m/s",
                )?;
                if *initial_displacement_m == 0.0 && *initial_velocity_m_s == 0.0 {
                    return Err(StructureError::invalid(
                        "analysis.initial_displacement_m",
                        "the structure starts at rest; give a non-zero initial_displacement_m or \
                         initial_velocity_m_s",
                    ));
                }
            }
            AnalysisSpec::Sweep {
                start_hz,
                end_hz,
                duration_s,
                force_amplitude_n,
                base_amplitude_m,
                time_step_s,
                sample_every,
                window_cycles,
                mode,
                segments,
                segment_overlap,
                excitation_point,
                output_point,
                ..
            } => {
                check_range(*start_hz, *end_hz)?;
                if dem {
                    positive("analysis.duration_s", *duration_s, MAX_DURATION_S, "s")?;
                } else {
                    check_time(*duration_s, *time_step_s, *sample_every)?;
                    let f_max = start_hz.max(*end_hz);
                    if time_step_s * f_max > 0.125 {
                        return Err(StructureError::rule(
                            "analysis.time_step_s",
                            format!(
                                "= {time_step_s:e} s gives {:.2} steps per period of the highest \
                                 excitation frequency {f_max} Hz; use at most {:e} s (8 steps \
                                 per period, better 20)",
                                1.0 / (time_step_s * f_max),
                                0.125 / f_max
                            ),
                        ));
                    }
                }
                check_force(*force_amplitude_n, *base_amplitude_m)?;
                count("analysis.window_cycles", *window_cycles, 1, MAX_POINTS)?;
                mode_ok(*mode)?;
                count("analysis.segments", *segments, 1, MAX_SEGMENTS)?;
                check_num(
                    "analysis.segment_overlap",
                    *segment_overlap,
                    (0.0..1.0).contains(segment_overlap),
                    "in [0, 1)",
                )?;
                for (k, p) in [
                    ("excitation_point", excitation_point),
                    ("output_point", output_point),
                ] {
                    if p.trim().is_empty() {
                        return Err(StructureError::invalid(
                            format!("analysis.{k}"),
                            "give a structure point name",
                        ));
                    }
                }
            }
            AnalysisSpec::SteadyState {
                start_hz,
                end_hz,
                points,
                force_amplitude_n,
                base_amplitude_m,
                mode,
                ..
            } => {
                check_range(*start_hz, *end_hz)?;
                count("analysis.points", *points, 1, MAX_POINTS)?;
                check_force(*force_amplitude_n, *base_amplitude_m)?;
                mode_ok(*mode)?;
            }
        }
        for (i, d) in self.dampers.iter().enumerate() {
            d.validate(i)?;
        }
        Ok(())
    }
}

impl DamperSpec {
    /// Checks the numbers of damper `dampers[index]` (finite, physical range), naming the key.
    ///
    /// # Errors
    /// The first invalid value.
    pub fn validate(&self, index: usize) -> Result<(), StructureError> {
        let k = |s: &str| format!("dampers[{index}].{s}");
        if self.point().trim().is_empty() {
            return Err(StructureError::invalid(
                k("point"),
                "give a structure point name",
            ));
        }
        let bed = |v: f64| positive(&k("bed_mass_kg"), v, MAX_MASS_KG, "kg");
        let clearance = |key: &str, v: f64| non_negative(&k(key), v, MAX_DISPLACEMENT_M, "m");
        match self {
            DamperSpec::Viscous {
                damping_n_s_m,
                mass_kg,
                ..
            } => {
                non_negative(&k("damping_n_s_m"), *damping_n_s_m, 1e14, "N·s/m")?;
                non_negative(&k("mass_kg"), *mass_kg, MAX_MASS_KG, "kg")?;
            }
            DamperSpec::Fields {
                path, bed_mass_kg, ..
            } => {
                if path.as_os_str().is_empty() {
                    return Err(StructureError::invalid(
                        k("path"),
                        "give the fields.csv file",
                    ));
                }
                bed(*bed_mass_kg)?;
            }
            DamperSpec::Rolling {
                layers,
                smoothing_log_width,
                ..
            } => validate_rolling(index, layers, *smoothing_log_width)?,
            DamperSpec::Horizontal {
                bed_mass_kg,
                rolling_clearance_m,
                bouncing_clearance_m,
                bouncing_mass_ratio,
                ..
            } => {
                bed(*bed_mass_kg)?;
                clearance("rolling_clearance_m", *rolling_clearance_m)?;
                clearance("bouncing_clearance_m", *bouncing_clearance_m)?;
                non_negative(&k("bouncing_mass_ratio"), *bouncing_mass_ratio, 10.0, "")?;
            }
            DamperSpec::Vertical {
                bed_mass_kg,
                clearance_m,
                container_length_m,
                particles,
                max_particles,
                ..
            } => {
                bed(*bed_mass_kg)?;
                if let Some(h) = clearance_m {
                    clearance("clearance_m", *h)?;
                }
                if let Some(v) = container_length_m {
                    positive(&k("container_length_m"), *v, MAX_DISPLACEMENT_M, "m")?;
                }
                if let Some(v) = particles {
                    positive(&k("particles"), *v, 1e9, "")?;
                }
                if let Some(v) = max_particles {
                    positive(&k("max_particles"), *v, 1e9, "")?;
                }
            }
            DamperSpec::Constant {
                bed_mass_kg,
                effective_loss_factor,
                effective_mass_ratio,
                ..
            } => {
                bed(*bed_mass_kg)?;
                non_negative(
                    &k("effective_loss_factor"),
                    *effective_loss_factor,
                    100.0,
                    "",
                )?;
                non_negative(&k("effective_mass_ratio"), *effective_mass_ratio, 100.0, "")?;
            }
            DamperSpec::PowderFriction {
                cavity_length_m,
                cavity_width_m,
                friction,
                wall_normal_force_n,
                angle_per_displacement_rad_m,
                bed_mass_kg,
                effective_mass_kg,
                ..
            } => {
                positive(
                    &k("cavity_length_m"),
                    *cavity_length_m,
                    MAX_DISPLACEMENT_M,
                    "m",
                )?;
                if let Some(w) = cavity_width_m {
                    positive(&k("cavity_width_m"), *w, MAX_DISPLACEMENT_M, "m")?;
                }
                non_negative(&k("friction"), *friction, 10.0, "")?;
                non_negative(
                    &k("wall_normal_force_n"),
                    *wall_normal_force_n,
                    MAX_FORCE_N,
                    "N",
                )?;
                if let Some(a) = angle_per_displacement_rad_m {
                    check_num(
                        &k("angle_per_displacement_rad_m"),
                        *a,
                        a.abs() <= 1e12,
                        "in [-1e12, 1e12] rad/m",
                    )?;
                }
                bed(*bed_mass_kg)?;
                non_negative(
                    &k("effective_mass_kg"),
                    *effective_mass_kg,
                    MAX_MASS_KG,
                    "kg",
                )?;
            }
            DamperSpec::Dem {
                scenario,
                attachment_point_m,
                ..
            } => validate_dem(index, scenario, attachment_point_m.as_ref())?,
        }
        Ok(())
    }
}

/// The layers and smoothing of rolling damper `dampers[index]`.
fn validate_rolling(
    index: usize,
    layers: &[RollingLayerSpec],
    smoothing_log_width: Option<f64>,
) -> Result<(), StructureError> {
    let k = |s: &str| format!("dampers[{index}].{s}");
    let clearance = |key: &str, v: f64| non_negative(&k(key), v, MAX_DISPLACEMENT_M, "m");
    if layers.is_empty() {
        return Err(StructureError::invalid(
            k("layers"),
            "give at least one layer",
        ));
    }
    for (j, l) in layers.iter().enumerate() {
        let lk = |s: &str| format!("layers[{j}].{s}");
        positive(&k(&lk("bed_mass_kg")), l.bed_mass_kg, MAX_MASS_KG, "kg")?;
        if let Some(h) = l.clearance_m {
            clearance(&lk("clearance_m"), h)?;
        }
        if let Some(v) = l.container_length_m {
            positive(&k(&lk("container_length_m")), v, MAX_DISPLACEMENT_M, "m")?;
        }
        if let Some(v) = l.particles {
            positive(&k(&lk("particles")), v, 1e9, "")?;
        }
        if let Some(v) = l.particles_per_layer {
            positive(&k(&lk("particles_per_layer")), v, 1e9, "")?;
        }
    }
    if let Some(w) = smoothing_log_width {
        positive(&k("smoothing_log_width"), w, 100.0, "")?;
    }
    Ok(())
}

/// The damper scenario file and attachment point of DEM damper `dampers[index]`.
fn validate_dem(
    index: usize,
    scenario: &Path,
    attachment_point_m: Option<&[f64; 3]>,
) -> Result<(), StructureError> {
    let k = |s: &str| format!("dampers[{index}].{s}");
    if scenario.as_os_str().is_empty() {
        return Err(StructureError::invalid(
            k("scenario"),
            "give the damper scenario file",
        ));
    }
    for (j, x) in attachment_point_m.into_iter().flatten().enumerate() {
        check_num(
            &k(&format!("attachment_point_m[{j}]")),
            *x,
            x.abs() <= MAX_DISPLACEMENT_M,
            &format!("in [-{MAX_DISPLACEMENT_M:e}, {MAX_DISPLACEMENT_M:e}] m"),
        )?;
    }
    Ok(())
}
