//! Validation of a cantilever scenario: every key in its physical range, the run within the
//! size limits ([`super::MAX_PARTICLES`], [`super::MAX_STEPS`], …) before anything is allocated.

use super::cost::BYTES_PER_ELEMENT;
use super::{
    BeamSpec, CantileverError, CantileverScenario, MAX_ELEMENTS, MAX_LENGTH_M, MAX_PARTICLES,
    MAX_SAMPLES, MAX_STEPS, MAX_VTK_FRAMES,
};
use crate::error::ParameterError;

impl BeamSpec {
    pub(super) fn validate(&self) -> Result<(), ParameterError> {
        let len = |v: f64, k: &str| {
            if v > 0.0 && v <= MAX_LENGTH_M {
                Ok(())
            } else {
                Err(ParameterError::out_of_range(
                    format!("beam.{k}"),
                    v,
                    format!("must be a finite length in (0, {MAX_LENGTH_M}] m"),
                ))
            }
        };
        len(self.length_m, "length_m")?;
        len(self.width_m, "width_m")?;
        len(self.wall_thickness_m, "wall_thickness_m")?;
        len(self.cavity_length_m, "cavity_length_m")?;
        len(self.wall_element_m, "wall_element_m")?;
        len(self.core_element_m, "core_element_m")?;
        len(self.length_element_m, "length_element_m")?;
        let m = &self.material;
        if !(m.youngs_modulus_pa > 0.0 && m.youngs_modulus_pa <= 1e13) {
            return Err(ParameterError::out_of_range(
                "beam.material.youngs_modulus_pa",
                m.youngs_modulus_pa,
                "must be a finite modulus in (0, 1e13] Pa (Table A.3: 175e9)",
            ));
        }
        if !(m.density_kg_m3 > 0.0 && m.density_kg_m3 <= 1e5) {
            return Err(ParameterError::out_of_range(
                "beam.material.density_kg_m3",
                m.density_kg_m3,
                "must be in (0, 1e5] kg/m³ (Table A.3: 8000)",
            ));
        }
        if !(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
            return Err(ParameterError::out_of_range(
                "beam.material.poisson_ratio",
                m.poisson_ratio,
                "must be in (-1, 0.5)",
            ));
        }
        if 2.0 * self.wall_thickness_m >= self.width_m {
            return Err(ParameterError::invalid(
                "beam.wall_thickness_m",
                "must be less than half of width_m",
            ));
        }
        if !(self.cavity_offset_m > 0.0
            && self.cavity_offset_m + self.cavity_length_m < self.length_m)
        {
            return Err(ParameterError::out_of_range(
                "beam.cavity_offset_m",
                self.cavity_offset_m,
                "cavity must lie strictly inside the beam (0 < offset, offset + cavity_length_m < length_m)",
            ));
        }
        if !(0.0..=1.0).contains(&self.rho_inf) {
            return Err(ParameterError::out_of_range(
                "beam.rho_inf",
                self.rho_inf,
                "must be in [0, 1]",
            ));
        }
        for (k, v) in [
            ("mass_coeff_per_s", self.rayleigh.mass_coeff_per_s),
            ("stiffness_coeff_s", self.rayleigh.stiffness_coeff_s),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(ParameterError::out_of_range(
                    format!("beam.rayleigh.{k}"),
                    v,
                    "must be finite and ≥ 0",
                ));
            }
        }
        let (elements, nodes) = self.mesh_size();
        if elements > MAX_ELEMENTS as f64 {
            return Err(ParameterError::invalid(
                "beam.wall_element_m / core_element_m / length_element_m",
                format!(
                    "the mesh would have ≈ {elements:.3e} elements and {nodes:.3e} nodes (≈ {:.1} GB for the element data and matrices, before the factorization's fill-in), more than {MAX_ELEMENTS}; use larger element sizes",
                    elements * BYTES_PER_ELEMENT / 1e9
                ),
            ));
        }
        Ok(())
    }
}

impl CantileverScenario {
    /// `[load]` and `[run]` (time step, gravity, output, coupling).
    pub(super) fn validate_load_and_run(&self) -> Result<(), CantileverError> {
        let (l, r) = (&self.load, &self.run);
        let e = self.beam.material.youngs_modulus_pa;
        if !(l.pressure_pa.is_finite() && l.pressure_pa.abs() <= 1e-3 * e) {
            return Err(ParameterError::out_of_range(
                "load.pressure_pa",
                l.pressure_pa,
                format!(
                    "must be finite with |q| ≤ 1e-3 of beam.material.youngs_modulus_pa ({:.3e} Pa; larger loads bend the beam beyond the elastic range)",
                    1e-3 * e
                ),
            )
            .into());
        }
        if !(l.rise_s > 0.0 && l.rise_s <= 1e3) {
            return Err(ParameterError::out_of_range(
                "load.rise_s",
                l.rise_s,
                "must be in (0, 1000] s",
            )
            .into());
        }
        if !(l.hold_s >= 0.0 && l.hold_s <= 1e3) {
            return Err(ParameterError::out_of_range(
                "load.hold_s",
                l.hold_s,
                "must be in [0, 1000] s",
            )
            .into());
        }
        if !(r.duration_s > 0.0 && r.duration_s <= 1e3) {
            return Err(ParameterError::out_of_range(
                "run.duration_s",
                r.duration_s,
                "must be in (0, 1000] s",
            )
            .into());
        }
        if !(r.time_step_s > 0.0 && r.time_step_s < r.duration_s) {
            return Err(ParameterError::out_of_range(
                "run.time_step_s",
                r.time_step_s,
                "must be positive and below duration_s",
            )
            .into());
        }
        let g = r.gravity_m_s2;
        if !(g.iter().all(|x| x.is_finite()) && g.iter().map(|x| x * x).sum::<f64>() <= 1e6) {
            return Err(ParameterError::invalid(
                "run.gravity_m_s2",
                format!("must be finite with |g| ≤ 1000 m/s², got {g:?}"),
            )
            .into());
        }
        if !(r.output_interval_s >= 0.0 && r.output_interval_s <= r.duration_s) {
            return Err(ParameterError::out_of_range(
                "run.output_interval_s",
                r.output_interval_s,
                "must be in [0, duration_s] (0 = every step)",
            )
            .into());
        }
        if !(r.vtk_interval_s >= 0.0 && r.vtk_interval_s.is_finite()) {
            return Err(ParameterError::out_of_range(
                "run.vtk_interval_s",
                r.vtk_interval_s,
                "must be finite and >= 0 (seconds between ParaView frames, 0 = none)",
            )
            .into());
        }
        let c = &r.coupling;
        if !(c.tolerance > 0.0 && c.tolerance.is_finite()) {
            return Err(ParameterError::out_of_range(
                "run.coupling.tolerance",
                c.tolerance,
                "must be finite and positive (eq. 16: 1e-3 m/s)",
            )
            .into());
        }
        if !(1..=10_000).contains(&c.max_iterations) {
            return Err(ParameterError::invalid(
                "run.coupling.max_iterations",
                format!("must be in [1, 10000], got {}", c.max_iterations),
            )
            .into());
        }
        if let Some(t) = c.structure_tolerance
            && !(1e-14..=1e-4).contains(&t)
        {
            return Err(ParameterError::out_of_range(
                "run.coupling.structure_tolerance",
                t,
                "must be in [1e-14, 1e-4] (relative Newton residual of the structure step; default 1e-10)",
            )
            .into());
        }
        if !(c.initial_relaxation > 0.0 && c.initial_relaxation <= 2.0) {
            return Err(ParameterError::out_of_range(
                "run.coupling.initial_relaxation",
                c.initial_relaxation,
                "must be in (0, 2]",
            )
            .into());
        }
        Ok(())
    }

    /// `[powder]`: law, size distribution, density, preparation, fit in the cavity.
    pub(super) fn validate_powder(&self) -> Result<(), CantileverError> {
        if let Some(p) = &self.powder {
            p.law.validate("powder.law.")?;
            p.psd().validate("powder.")?;
            if !(p.density_kg_m3 > 0.0 && p.density_kg_m3 <= 1e5) {
                return Err(ParameterError::out_of_range(
                    "powder.density_kg_m3",
                    p.density_kg_m3,
                    "must be in (0, 1e5] kg/m³",
                )
                .into());
            }
            let f = p.d50_m / p.reference_d50_m;
            if !(p.reference_d50_m > 0.0 && (1e-3..=1e3).contains(&f)) {
                return Err(ParameterError::out_of_range(
                    "powder.reference_d50_m",
                    p.reference_d50_m,
                    "must be positive with d50_m / reference_d50_m in [1e-3, 1e3]",
                )
                .into());
            }
            let s = &p.prep;
            if !(s.packing_density > 0.0 && s.packing_density < 0.74) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.packing_density",
                    s.packing_density,
                    "must be in (0, 0.74)",
                )
                .into());
            }
            if !(s.settling_gravity_factor >= 1.0 && s.settling_gravity_factor <= 1e4) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.settling_gravity_factor",
                    s.settling_gravity_factor,
                    "must be in [1, 1e4]",
                )
                .into());
            }
            if !(s.plate_speed_m_s > 0.0 && s.plate_speed_m_s <= 100.0) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.plate_speed_m_s",
                    s.plate_speed_m_s,
                    "must be in (0, 100] m/s",
                )
                .into());
            }
            if !(s.relax_time_s >= 0.0 && s.relax_time_s <= 1e3) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.relax_time_s",
                    s.relax_time_s,
                    "must be in [0, 1000] s",
                )
                .into());
            }
            // the preparation's friction and surface energy, checked like the law's
            s.law_of_preparation(&p.law).validate("powder.prep.")?;
            if !(s.max_settling_time_s > 0.0 && s.max_settling_time_s <= 1e3) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.max_settling_time_s",
                    s.max_settling_time_s,
                    "must be in (0, 1000] s",
                )
                .into());
            }
            let gap = self.beam.width_m - 2.0 * self.beam.wall_thickness_m;
            if p.psd().d_max_m * 1.02 > gap.min(self.beam.cavity_length_m) {
                return Err(ParameterError::invalid(
                    "powder.d50_m",
                    format!(
                        "the largest particles ({:.3e} m) do not fit the cavity ({gap:.3e} m across); use a smaller d50_m",
                        p.psd().d_max_m
                    ),
                )
                .into());
            }
        }
        Ok(())
    }

    /// Particles, steps, samples and frames within the limits, and the time step against the stiffest contact.
    pub(super) fn validate_cost(&self) -> Result<(), CantileverError> {
        let r = &self.run;
        let est = self.estimate();
        if est.particles > MAX_PARTICLES as f64 {
            return Err(CantileverError::TooLarge {
                keys: "powder.d50_m / powder.prep.packing_density",
                estimate: est,
                limit: format!(
                    "more than {MAX_PARTICLES} particles; use a larger d50_m (coarse-graining with reference_d50_m)"
                ),
            });
        }
        if est.steps > MAX_STEPS {
            return Err(CantileverError::TooLarge {
                keys: "run.duration_s / run.time_step_s",
                estimate: est,
                limit: format!(
                    "more than {MAX_STEPS:e} steps; shorten duration_s or lengthen time_step_s"
                ),
            });
        }
        if est.prep_steps > MAX_STEPS {
            return Err(CantileverError::TooLarge {
                keys: "powder.prep.max_settling_time_s / relax_time_s",
                estimate: est,
                limit: format!(
                    "more than {MAX_STEPS:e} preparation steps at run.time_step_s; shorten them"
                ),
            });
        }
        if let Some(p) = &self.powder {
            // the stiffest contact: two of the smallest particles, coarse-grained stiffness
            let law = p.scaled_law();
            let dmin = p.psd().d_min_m;
            let m = p.density_kg_m3 * std::f64::consts::PI / 6.0 * dmin.powi(3);
            let tc = std::f64::consts::PI * (0.5 * m / law.normal_stiffness_n_m).sqrt();
            let ratio = r.time_step_s / tc;
            if !(ratio <= crate::health::MAX_STEP_RATIO) {
                return Err(CantileverError::TimeStep {
                    time_step_s: r.time_step_s,
                    ratio,
                    contact_time_s: tc,
                    diameter_m: dmin,
                    stiffness_n_m: law.normal_stiffness_n_m,
                    max_ratio: crate::health::MAX_STEP_RATIO,
                });
            }
        }
        let every = (r.output_interval_s / r.time_step_s).round().max(1.0);
        if est.steps / every > MAX_SAMPLES {
            return Err(ParameterError::invalid(
                "run.output_interval_s",
                format!(
                    "{:.3e} samples of tip.csv, more than {MAX_SAMPLES:e}; use a larger output_interval_s",
                    est.steps / every
                ),
            )
            .into());
        }
        if r.vtk_interval_s > 0.0 && r.duration_s / r.vtk_interval_s > MAX_VTK_FRAMES {
            return Err(ParameterError::invalid(
                "run.vtk_interval_s",
                format!(
                    "{:.3e} ParaView frames over duration_s = {} s, more than {MAX_VTK_FRAMES}; use a larger interval (or 0 for none)",
                    r.duration_s / r.vtk_interval_s,
                    r.duration_s
                ),
            )
            .into());
        }
        Ok(())
    }
}
