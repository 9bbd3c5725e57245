//! The design space: categorical choices (point, container length, material, particle radius)
//! and the particle numbers of the layers, with the container geometry that turns them into
//! clearances [D Eq. 5.1, 7.4: $h = L(1 - n_p/n_p^{max})$] and bed masses.
//!
//! Layers of one horizontal container are interchangeable for the formulas (energies and
//! effective masses add), so a design's particle numbers are kept sorted ascending and every
//! multiset is one design.

use crate::error::DesignError;
use crate::study::{DesignStudy, Direction, ObjectiveSpec};
use pdamp_dem::math::STANDARD_GRAVITY_M_S2;
use pdamp_structure::effective::EffectiveDamper;
use pdamp_structure::free::CoupledDamper;
use pdamp_structure::scenario::{DamperSpec, RollingLayerSpec};
use serde::Serialize;
use std::f64::consts::PI;

/// The categorical part of a design: indices into the study's candidate lists.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct Choice {
    /// Index into `damper.points`.
    pub point: usize,
    /// Index into `damper.container_lengths_m`.
    pub length: usize,
    /// Index into `materials`.
    pub material: usize,
    /// Index into `damper.particle_radii_m`.
    pub radius: usize,
    /// Index into `damper.coatings`. The formulas do not see it: the search (levels 0 and 1)
    /// keeps 0, and the effective fields (level 2) expand a design over every coating.
    pub coating: usize,
}

/// One damper design: a categorical choice and the particle number of every layer (ascending).
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct Design {
    /// Point, length, material, radius.
    pub choice: Choice,
    /// Particles per layer, ascending (one entry for a vertical bed).
    pub particles: Vec<usize>,
}

/// Container geometry of a categorical choice.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// Inner length L along the excitation, m.
    pub length_m: f64,
    /// Particle radius, m.
    pub radius_m: f64,
    /// Mass of one particle, kg.
    pub particle_mass_kg: f64,
    /// Particles that fill one layer (horizontal) or the bed (vertical), n_p^max.
    pub capacity: usize,
    /// Increment of the particle number.
    pub step: usize,
}

impl Geometry {
    /// Clearance of a layer/bed with `n` particles [D Eq. 5.1, 7.4], m.
    pub fn clearance_m(&self, n: usize) -> f64 {
        pdamp_structure::formulas::clearance_m(self.length_m, n as f64, self.capacity as f64)
    }
}

/// The design space of a study.
#[derive(Debug, Clone)]
pub struct Space<'a> {
    /// The study.
    pub study: &'a DesignStudy,
}

impl<'a> Space<'a> {
    /// The space of a loaded study.
    pub fn new(study: &'a DesignStudy) -> Self {
        Space { study }
    }

    /// The location of a choice.
    pub fn location(&self, c: Choice) -> &crate::study::Location {
        &self.study.locations[c.point]
    }

    /// The structure with the damper at the choice's location.
    pub fn structure(&self, c: Choice) -> &pdamp_structure::modal::ModalStructure {
        &self.study.locations[c.point].structure
    }

    /// Every categorical choice the formulas tell apart (coating 0), in a fixed order.
    pub fn choices(&self) -> Vec<Choice> {
        let d = &self.study.file.damper;
        let mut out = Vec::new();
        for point in 0..self.study.locations.len() {
            for length in 0..d.container_lengths_m.len() {
                for material in 0..self.study.file.materials.len() {
                    for radius in 0..d.particle_radii_m.len() {
                        out.push(Choice {
                            point,
                            length,
                            material,
                            radius,
                            coating: 0,
                        });
                    }
                }
            }
        }
        out
    }

    /// Geometry of a choice: capacity ⌊L/2r⌋·⌊W/2r⌋ per horizontal layer (× ⌊H/(layers·2r)⌋ with
    /// a container height H), ⌊L/2r⌋·⌊W/2r⌋·⌊D/2r⌋ for a vertical bed; default step one row
    /// (one cross-section) across (horizontal) or one level (vertical).
    pub fn geometry(&self, c: Choice) -> Geometry {
        let d = &self.study.file.damper;
        let l = d.container_lengths_m[c.length];
        let r = d.particle_radii_m[c.radius];
        let dia = 2.0 * r;
        let fit = |x: f64| ((x / dia) * (1.0 + 1e-12)).floor().max(0.0) as usize;
        let across = match self.location(c).direction {
            Direction::Horizontal => {
                fit(d.container_width_m)
                    * d.container_height_m
                        .map_or(1, |h| fit(h / d.layers as f64).max(1))
            }
            Direction::Vertical => {
                fit(d.container_width_m) * fit(d.container_depth_m.unwrap_or(d.container_width_m))
            }
        };
        let capacity = (fit(l) * across).min(crate::study::MAX_PARTICLES);
        let rho = self.study.file.materials[c.material].density_kg_m3;
        Geometry {
            length_m: l,
            radius_m: r,
            particle_mass_kg: 4.0 / 3.0 * PI * r.powi(3) * rho,
            capacity,
            step: d.particle_count_step.unwrap_or(across).max(1),
        }
    }

    /// Particle numbers a layer may take: 0, step, 2·step, … ≤ capacity.
    pub fn counts(&self, c: Choice) -> Vec<usize> {
        let g = self.geometry(c);
        (0..=g.capacity).step_by(g.step).collect()
    }

    /// Bed mass of a design (all its containers), kg.
    pub fn bed_mass_kg(&self, d: &Design) -> f64 {
        let g = self.geometry(d.choice);
        let containers = self.location(d.choice).points.len();
        (containers * d.particles.iter().sum::<usize>()) as f64 * g.particle_mass_kg
    }

    /// Whether a design satisfies the constraints (and carries particles).
    pub fn feasible(&self, d: &Design) -> bool {
        let g = self.geometry(d.choice);
        if d.particles.iter().all(|&n| n == 0) || d.particles.iter().any(|&n| n > g.capacity) {
            return false;
        }
        let c = &self.study.file.constraints;
        if c.max_bed_mass_kg
            .is_some_and(|m| self.bed_mass_kg(d) > m * (1.0 + 1e-12))
        {
            return false;
        }
        if let Some(h) = c.min_clearance_m
            && d.particles.iter().any(|&n| n > 0 && g.clearance_m(n) < h)
        {
            return false;
        }
        true
    }

    /// Number of sorted particle-number multisets of one choice (before constraints).
    pub fn multiset_count(&self, c: Choice) -> f64 {
        let values = self.counts(c).len() as f64;
        let k = self.study.file.damper.layers;
        (0..k).fold(1.0, |acc, i| acc * (values + i as f64) / (i as f64 + 1.0))
    }

    /// Size of the whole space before constraints.
    pub fn size(&self) -> f64 {
        self.choices().iter().map(|&c| self.multiset_count(c)).sum()
    }

    /// Every feasible design of a choice (sorted multisets of the layer counts).
    pub fn enumerate(&self, c: Choice) -> Vec<Design> {
        let values = self.counts(c);
        let k = self.study.file.damper.layers;
        let mut out = Vec::new();
        let mut cur = Vec::with_capacity(k);
        fn rec(
            space: &Space,
            c: Choice,
            values: &[usize],
            start: usize,
            left: usize,
            cur: &mut Vec<usize>,
            out: &mut Vec<Design>,
        ) {
            if left == 0 {
                let d = Design {
                    choice: c,
                    particles: cur.clone(),
                };
                if space.feasible(&d) {
                    out.push(d);
                }
                return;
            }
            for i in start..values.len() {
                cur.push(values[i]);
                rec(space, c, values, i, left - 1, cur, out);
                cur.pop();
            }
        }
        rec(self, c, &values, 0, k, &mut cur, &mut out);
        out
    }

    /// The design nearest to fill fractions `fill` ∈ [0, 1] of every layer (the swarm's
    /// continuous relaxation), rounded to the count grid and sorted.
    pub fn from_fill(&self, c: Choice, fill: &[f64]) -> Design {
        let g = self.geometry(c);
        let top = g.capacity / g.step;
        let mut particles: Vec<usize> = fill
            .iter()
            .map(|f| ((f.clamp(0.0, 1.0) * top as f64).round() as usize).min(top) * g.step)
            .collect();
        particles.sort_unstable();
        Design {
            choice: c,
            particles,
        }
    }

    /// Neighbours of a design: one layer one step up or down, or one categorical index moved by
    /// one (particle numbers carried over as fill fractions); feasible ones only.
    pub fn neighbours(&self, d: &Design) -> Vec<Design> {
        let g = self.geometry(d.choice);
        let mut out = Vec::new();
        for i in 0..d.particles.len() {
            for up in [true, false] {
                let mut p = d.particles.clone();
                if up && p[i] + g.step <= g.capacity {
                    p[i] += g.step;
                } else if !up && p[i] >= g.step {
                    p[i] -= g.step;
                } else {
                    continue;
                }
                p.sort_unstable();
                out.push(Design {
                    choice: d.choice,
                    particles: p,
                });
            }
        }
        let f = &self.study.file;
        let lens = [
            self.study.locations.len(),
            f.damper.container_lengths_m.len(),
            f.materials.len(),
            f.damper.particle_radii_m.len(),
        ];
        for (axis, &len) in lens.iter().enumerate() {
            for delta in [-1i64, 1] {
                let mut c = d.choice;
                let slot = match axis {
                    0 => &mut c.point,
                    1 => &mut c.length,
                    2 => &mut c.material,
                    _ => &mut c.radius,
                };
                let v = *slot as i64 + delta;
                if v < 0 || v >= len as i64 {
                    continue;
                }
                *slot = v as usize;
                let fill: Vec<f64> = d
                    .particles
                    .iter()
                    .map(|&n| n as f64 / g.capacity.max(1) as f64)
                    .collect();
                out.push(self.from_fill(c, &fill));
            }
        }
        out.sort();
        out.dedup();
        out.retain(|n| n != d && self.feasible(n));
        out
    }

    /// Largest acceleration amplitude the design's damper points see in the study, m/s²
    /// (the largest over its containers, [`Self::peak_acceleration_at_m_s2`]).
    pub fn peak_acceleration_m_s2(&self, d: &Design) -> f64 {
        self.location(d.choice)
            .points
            .iter()
            .map(|p| self.peak_acceleration_at_m_s2(d, p))
            .fold(0.0, f64::max)
    }

    /// Largest acceleration amplitude the structure point `point` sees in the study, m/s²: the
    /// initial amplitude (min_stroke) or the top of the amplitude range (max_damping) times ω_k².
    pub fn peak_acceleration_at_m_s2(&self, d: &Design, point: &str) -> f64 {
        let c = d.choice;
        let st = self.structure(c);
        let phi = st.point(point).expect("validated point");
        let out = st
            .point(&self.study.free.output_point)
            .expect("validated point");
        match &self.study.file.objective {
            ObjectiveSpec::MinStroke { .. } => {
                let k = self.study.free.mode;
                let init = st
                    .point(&self.study.free.initial_point)
                    .map(|s| s[k])
                    .unwrap_or(1.0);
                let w = st.modes[k].omega_rad_s();
                let scale = if self.study.free.scale_initial_by_bed_mass {
                    pdamp_structure::free::bed_mass_scale(init, self.bed_mass_kg(d))
                } else {
                    1.0
                };
                let q0 = scale
                    * (self.study.free.initial_displacement_m.powi(2)
                        + (self.study.free.initial_velocity_m_s / w).powi(2))
                    .sqrt()
                    / init.abs().max(1e-300);
                q0 * phi[k].abs() * w * w
            }
            ObjectiveSpec::MaxDamping {
                modes,
                amplitude_max_m,
                ..
            } => modes
                .iter()
                .map(|&m| {
                    let k = m - 1;
                    let w = st.modes[k].omega_rad_s();
                    amplitude_max_m / out[k].abs().max(1e-300) * phi[k].abs() * w * w
                })
                .fold(0.0, f64::max),
            // the bare structure's resonance: an upper bound, $|\varphi_{pd}\varphi_{ex}|F/(2\zeta_k)$
            ObjectiveSpec::MinFrfPeak { modes, .. }
            | ObjectiveSpec::MaxResonanceDamping { modes, .. } => {
                let Some(load) = &self.study.load else {
                    return 0.0;
                };
                let ex = st.point(&load.excitation_point).expect("validated point");
                modes
                    .iter()
                    .map(|&m| {
                        let k = m - 1;
                        (phi[k] * ex[k] * load.force_n).abs()
                            / (2.0 * st.modes[k].damping_ratio.max(1e-12))
                    })
                    .fold(0.0, f64::max)
            }
        }
    }

    /// The scenario `[[dampers]]` entries of a design: a horizontal container whose damper
    /// point never reaches g in the study is the rolling model with its layers (D Eq. 5.1–5.14),
    /// otherwise one combined rolling/bouncing damper per layer (D Eq. 6.12, $h_{bou} =
    /// h_{rol}$, m̄ = m_bed when bouncing); a vertical bed is the vertical model
    /// (D Eq. 7.1–7.19). These specs are exactly what the scenario files of the verified
    /// designs contain, and what the time simulation runs.
    pub fn damper_specs(&self, d: &Design) -> Vec<DamperSpec> {
        self.location(d.choice)
            .points
            .iter()
            .flat_map(|p| self.container_specs(d, p))
            .collect()
    }

    /// [`Self::damper_specs`] of the design's container at `point`.
    fn container_specs(&self, d: &Design, point: &str) -> Vec<DamperSpec> {
        let g = self.geometry(d.choice);
        let point = point.to_string();
        let filled: Vec<usize> = d.particles.iter().copied().filter(|&n| n > 0).collect();
        match self.location(d.choice).direction {
            Direction::Vertical => filled
                .iter()
                .map(|&n| DamperSpec::Vertical {
                    point: point.clone(),
                    bed_mass_kg: n as f64 * g.particle_mass_kg,
                    clearance_m: None,
                    container_length_m: Some(g.length_m),
                    particles: Some(n as f64),
                    max_particles: Some(g.capacity as f64),
                })
                .collect(),
            Direction::Horizontal
                if self.peak_acceleration_at_m_s2(d, &point) < STANDARD_GRAVITY_M_S2 =>
            {
                vec![DamperSpec::Rolling {
                    point,
                    layers: filled
                        .iter()
                        .map(|&n| RollingLayerSpec {
                            bed_mass_kg: n as f64 * g.particle_mass_kg,
                            clearance_m: None,
                            container_length_m: Some(g.length_m),
                            particles: Some(n as f64),
                            particles_per_layer: Some(g.capacity as f64),
                        })
                        .collect(),
                    smoothing_log_width: None,
                }]
            }
            Direction::Horizontal => filled
                .iter()
                .map(|&n| DamperSpec::Horizontal {
                    point: point.clone(),
                    bed_mass_kg: n as f64 * g.particle_mass_kg,
                    rolling_clearance_m: g.clearance_m(n),
                    bouncing_clearance_m: g.clearance_m(n),
                    bouncing_mass_ratio: 1.0,
                })
                .collect(),
        }
    }

    /// The equivalent dampers of a design for the structural solvers (approach 3).
    ///
    /// # Errors
    /// A damper spec the structure refuses.
    pub fn coupled_dampers(&self, d: &Design) -> Result<Vec<CoupledDamper>, DesignError> {
        let base = self
            .study
            .scenario_path
            .parent()
            .unwrap_or(std::path::Path::new("."));
        let mut out = Vec::new();
        for spec in self.damper_specs(d) {
            let model: Box<dyn EffectiveDamper> = spec
                .effective_model(base, self.structure(d.choice), self.study.free.mode)?
                .ok_or_else(|| {
                    DesignError::Solver("design: a damper without an equivalent model".into())
                })?;
            out.push(CoupledDamper {
                point: spec.point().to_string(),
                model,
            });
        }
        Ok(out)
    }
}
