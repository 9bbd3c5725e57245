//! Validation of a scenario: every key checked, the message starting with its path.

use super::{
    AmplitudeAxis, DamperSpec, MAX_DAMPER_CYCLES, MAX_FIELD_CELLS, MAX_PACKINGS,
    MAX_PHASES_PER_CYCLE, MAX_TRAJECTORIES, MAX_VTK_FRAMES_PER_CYCLE, MotionSpec, PlacementMethod,
    PlacementSpec, Scenario,
};
use pdamp_dem::{Integrator, ParameterError, Vec3};

impl Scenario {
    /// Checks `damper.motion_output`: sizes that fit a cycle and the bed.
    fn validate_motion_output(&self, d: &DamperSpec) -> Result<(), ParameterError> {
        let m = &d.motion_output;
        if m.phases_per_cycle > MAX_PHASES_PER_CYCLE {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.phases_per_cycle must lie in 0..={MAX_PHASES_PER_CYCLE} (0 = no velocity fields), got {}; 4 gives the phases 0, 90, 180 and 270°",
                m.phases_per_cycle
            )));
        }
        if !(1..=MAX_FIELD_CELLS).contains(&m.field_cells) {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.field_cells must lie in 1..={MAX_FIELD_CELLS}, got {}; e.g. 12",
                m.field_cells
            )));
        }
        if m.vtk_frames_per_cycle > MAX_VTK_FRAMES_PER_CYCLE {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.vtk_frames_per_cycle must be at most {MAX_VTK_FRAMES_PER_CYCLE}, got {}; e.g. 8",
                m.vtk_frames_per_cycle
            )));
        }
        if let Some(f) = d.frequency_hz {
            let steps_per_cycle = 1.0 / (f * self.simulation.time_step_s);
            for (k, n) in [
                ("phases_per_cycle", m.phases_per_cycle),
                ("vtk_frames_per_cycle", m.vtk_frames_per_cycle),
            ] {
                if f64::from(n) > steps_per_cycle {
                    return Err(ParameterError::from_message(format!(
                        "damper.motion_output.{k} ({n}) exceeds the {steps_per_cycle:.0} time steps of a cycle at {f} Hz; use at most {}",
                        steps_per_cycle.floor().max(1.0)
                    )));
                }
            }
        }
        let n: Option<usize> = self
            .particles
            .iter()
            .map(|g| g.resolved_count().ok())
            .try_fold(0usize, |a, c| c.map(|c| a.saturating_add(c)))
            .filter(|_| {
                self.particles
                    .iter()
                    .all(|g| g.placement.method != PlacementMethod::File)
            });
        if let Some(n) = n
            && let Some(&i) = m.trajectory_particles.iter().find(|&&i| i >= n)
        {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.trajectory_particles: particle {i} does not exist (the bed has {n} particles, indices 0..={})",
                n.saturating_sub(1)
            )));
        }
        if m.trajectory_particles.len() > MAX_TRAJECTORIES {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.trajectory_particles lists {} particles, at most {MAX_TRAJECTORIES}",
                m.trajectory_particles.len()
            )));
        }
        Ok(())
    }

    /// Checks the placement of group `g` (keys as `particles[g].placement.…`).
    fn validate_placement(&self, g: usize, pl: &PlacementSpec) -> Result<(), ParameterError> {
        let key = format!("particles[{g}].placement");
        let is_file = pl.method == PlacementMethod::File;
        match (&pl.region, is_file) {
            (Some(r), false) => r
                .validate()
                .map_err(|e| e.under(&format!("{key}.region.")))?,
            (None, false) => {
                return Err(ParameterError::from_message(format!(
                    "{key}.region: missing; give the volume to fill, e.g. region = {{ type = \"box\", min_m = [..], max_m = [..] }}"
                )));
            }
            (Some(_), true) => {
                return Err(ParameterError::from_message(format!(
                    "{key}.region: a bed from a file has its own positions; remove region"
                )));
            }
            (None, true) => {}
        }
        if is_file && pl.path.is_none() {
            return Err(ParameterError::from_message(format!(
                "{key}.path: missing; method = \"file\" needs the bed file (from `pdamp settle`, LAMMPS write_data or CSV)"
            )));
        }
        if !is_file && (pl.path.is_some() || pl.format.is_some() || !pl.type_materials.is_empty()) {
            return Err(ParameterError::from_message(format!(
                "{key}.path: path, format and type_materials belong to method = \"file\""
            )));
        }
        if is_file && self.particles.len() > 1 {
            return Err(ParameterError::from_message(format!(
                "{key}.method: a bed file holds the whole bed; it must be the only [[particles]] group"
            )));
        }
        for m in &pl.type_materials {
            self.material_index(m, &format!("{key}.type_materials"))?;
        }
        let is_drop = pl.method == PlacementMethod::DropDown;
        if !is_drop
            && (pl.max_rounds.is_some()
                || pl.max_round_duration_s.is_some()
                || pl.round_kinetic_energy_per_particle_j.is_some()
                || pl.open_lid.is_some()
                || pl.inlet.is_some())
        {
            return Err(ParameterError::from_message(format!(
                "{key}.max_rounds: max_rounds, max_round_duration_s, round_kinetic_energy_per_particle_j, open_lid and inlet belong to method = \"drop_down\""
            )));
        }
        if let Some(i) = &pl.inlet {
            i.region
                .validate()
                .map_err(|e| e.under(&format!("{key}.inlet.region.")))?;
            if !(i.rate_per_s.is_finite() && i.rate_per_s > 0.0 && i.rate_per_s <= 1e9) {
                return Err(ParameterError::from_message(format!(
                    "{key}.inlet.rate_per_s must be in (0, 1e9] particles per second, got {}",
                    i.rate_per_s
                )));
            }
            if !i
                .velocity_m_s
                .iter()
                .all(|v| v.is_finite() && v.abs() <= 1e3)
            {
                return Err(ParameterError::from_message(format!(
                    "{key}.inlet.velocity_m_s must be finite and at most 1000 m/s, got {:?}",
                    i.velocity_m_s
                )));
            }
        }
        if let Some(l) = &pl.open_lid {
            l.validate(&key)?;
        }
        if pl.max_rounds == Some(0) {
            return Err(ParameterError::from_message(format!(
                "{key}.max_rounds must be >= 1"
            )));
        }
        if let Some(t) = pl.max_round_duration_s
            && !(t.is_finite() && t > 0.0 && t <= 1e3)
        {
            return Err(ParameterError::from_message(format!(
                "{key}.max_round_duration_s must be in (0, 1000] s, got {t}"
            )));
        }
        if let Some(e) = pl.round_kinetic_energy_per_particle_j
            && !(e.is_finite() && e >= 0.0)
        {
            return Err(ParameterError::from_message(format!(
                "{key}.round_kinetic_energy_per_particle_j must be finite and >= 0 (J), got {e}"
            )));
        }
        if is_drop && self.fill_gravity().norm() == 0.0 {
            return Err(ParameterError::from_message(format!(
                "{key}.method: drop_down lets the particles fall, but gravity is zero; set simulation.gravity_m_s2 or settle.gravity_m_s2, or use method = \"random\""
            )));
        }
        Ok(())
    }

    pub(super) fn material_index(&self, name: &str, key: &str) -> Result<u16, ParameterError> {
        self.materials
            .iter()
            .position(|m| m.name == name)
            .map(|i| i as u16)
            .ok_or_else(|| {
                let known: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
                ParameterError::invalid(
                    key,
                    format!(
                        "{key}: unknown material '{name}' (defined: {})",
                        known.join(", ")
                    ),
                )
            })
    }

    /// Checks ranges and references. Every message starts with the path of the offending key
    /// (`particles[0].size.radius_m …`, its `key()`, located in the file by
    /// [`ScenarioError::at_key`](super::ScenarioError::at_key)) and says how to fix it.
    pub fn validate(&self) -> Result<(), ParameterError> {
        self.validate_simulation_and_output()?;
        self.validate_materials_and_contact()?;
        self.validate_bodies()?;
        self.validate_damper()?;
        self.validate_fields()?;
        self.validate_settle_and_particles()
    }

    /// `[simulation]` and `[output]`.
    fn validate_simulation_and_output(&self) -> Result<(), ParameterError> {
        let s = &self.simulation;
        if !(s.duration_s.is_finite() && s.duration_s >= 0.0) {
            return Err(ParameterError::from_message(format!(
                "simulation.duration_s must be a finite time >= 0 in seconds, got {}",
                s.duration_s
            )));
        }
        if !finite_pos(s.time_step_s) {
            return Err(ParameterError::from_message(format!(
                "simulation.time_step_s must be > 0 (seconds), got {}; a safe value is about 1/20 \
                 of the contact time (`pdamp check` prints it)",
                s.time_step_s
            )));
        }
        if s.duration_s > 0.0 && s.time_step_s > s.duration_s {
            return Err(ParameterError::from_message(format!(
                "simulation.time_step_s ({}) exceeds simulation.duration_s ({}); check the units \
                 (both in seconds)",
                s.time_step_s, s.duration_s
            )));
        }
        if let Integrator::Gear(g) = &s.integrator {
            g.validate(s.time_step_s)
                .map_err(|e| e.under("simulation.integrator."))?;
        }
        if s.gravity_m_s2.iter().any(|g| !g.is_finite()) {
            return Err(ParameterError::from_message(format!(
                "simulation.gravity_m_s2 must be finite, got {:?}; e.g. [0.0, 0.0, -9.81]",
                s.gravity_m_s2
            )));
        }
        if let Some(skin) = s.skin_m
            && !finite_pos(skin)
        {
            return Err(ParameterError::from_message(format!(
                "simulation.skin_m must be > 0 (metres), got {skin}; leave it out for the default \
                 0.2 × smallest radius"
            )));
        }
        if !(s.max_time_step_ratio > 0.0 && s.max_time_step_ratio <= 1.0) {
            return Err(ParameterError::from_message(format!(
                "simulation.max_time_step_ratio must lie in (0, 1], got {}; 0.1 is the default",
                s.max_time_step_ratio
            )));
        }
        if !finite_pos(s.check_impact_velocity_m_s) {
            return Err(ParameterError::from_message(format!(
                "simulation.check_impact_velocity_m_s must be > 0 (m/s), got {}",
                s.check_impact_velocity_m_s
            )));
        }
        if !finite_pos(self.output.energy_interval_s) {
            return Err(ParameterError::from_message(format!(
                "output.energy_interval_s must be > 0 (seconds), got {}",
                self.output.energy_interval_s
            )));
        }
        if !(self.output.vtk_interval_s.is_finite() && self.output.vtk_interval_s >= 0.0) {
            return Err(ParameterError::from_message(format!(
                "output.vtk_interval_s must be >= 0 (seconds; 0 switches VTK off), got {}",
                self.output.vtk_interval_s
            )));
        }
        Ok(())
    }

    /// `[[materials]]` (unique names) and `[contact]` with its pairs.
    fn validate_materials_and_contact(&self) -> Result<(), ParameterError> {
        if self.materials.is_empty() {
            return Err(ParameterError::from_message(
                "materials: at least one material is needed; add a [[materials]] table with name, \
                 density_kg_m3, youngs_modulus_pa and poisson_ratio",
            ));
        }
        for (k, m) in self.materials.iter().enumerate() {
            m.validate()
                .map_err(|e| e.under(&format!("materials[{k}].")))?;
            if self.materials[..k].iter().any(|o| o.name == m.name) {
                return Err(ParameterError::from_message(format!(
                    "materials[{k}].name: duplicate material name '{}'; give every material its \
                     own name",
                    m.name
                )));
            }
        }
        self.contact
            .default
            .validate()
            .map_err(|e| e.under("contact."))?;
        for (k, p) in self.contact.pairs.iter().enumerate() {
            let key = format!("contact.pairs[{k}].materials");
            let a = self.material_index(&p.materials[0], &key)?;
            let b = self.material_index(&p.materials[1], &key)?;
            if self.contact.pairs[..k].iter().any(|o| {
                let (c, d) = (
                    self.material_index(&o.materials[0], "").unwrap_or(u16::MAX),
                    self.material_index(&o.materials[1], "").unwrap_or(u16::MAX),
                );
                (a, b) == (c, d) || (a, b) == (d, c)
            }) {
                return Err(ParameterError::from_message(format!(
                    "{key}: the pair {:?} has a contact model already; keep one [[contact.pairs]] \
                     entry per material pair",
                    p.materials
                )));
            }
            p.model
                .validate()
                .map_err(|e| e.under(&format!("contact.pairs[{k}].")))?;
        }
        Ok(())
    }

    /// `[[bodies]]`: unique names, motions, walls.
    fn validate_bodies(&self) -> Result<(), ParameterError> {
        for (b, body) in self.bodies.iter().enumerate() {
            if self.bodies[..b].iter().any(|o| o.name == body.name) {
                return Err(ParameterError::from_message(format!(
                    "bodies[{b}].name: duplicate body name '{}'; give every body its own name",
                    body.name
                )));
            }
            if body.position_m.iter().any(|x| !x.is_finite()) {
                return Err(ParameterError::from_message(format!(
                    "bodies[{b}].position_m must be finite"
                )));
            }
            if body.walls.is_empty() {
                return Err(ParameterError::from_message(format!(
                    "bodies[{b}].walls: body '{}' has no walls; add a [[bodies.walls]] table",
                    body.name
                )));
            }
            for (w, wall) in body.walls.iter().enumerate() {
                self.material_index(&wall.material, &format!("bodies[{b}].walls[{w}].material"))?;
            }
            if let MotionSpec::Harmonic(h) = &body.motion {
                if !Vec3::from(h.direction).norm().is_finite()
                    || Vec3::from(h.direction).norm() == 0.0
                {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.direction must be a finite non-zero vector, got {:?}; \
                         e.g. [1.0, 0.0, 0.0] for horizontal shaking",
                        h.direction
                    )));
                }
                if !finite_pos(h.frequency_hz) {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.frequency_hz must be > 0 (Hz), got {}",
                        h.frequency_hz
                    )));
                }
                if !(h.amplitude_m.is_finite() && h.amplitude_m >= 0.0 && h.amplitude_m <= 1.0) {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.amplitude_m must lie in [0, 1] m, got {}; check the unit",
                        h.amplitude_m
                    )));
                }
                if h.frequency_hz > 1e5 {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.frequency_hz must be at most 1e5 Hz, got {}",
                        h.frequency_hz
                    )));
                }
                if !h.phase_rad.is_finite() {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.phase_rad must be finite (radians), got {}",
                        h.phase_rad
                    )));
                }
            }
        }
        Ok(())
    }

    /// `[damper]`: the container body, the excitation and the cycles.
    fn validate_damper(&self) -> Result<(), ParameterError> {
        if let Some(d) = &self.damper {
            if !self.bodies.iter().any(|b| b.name == d.container_body) {
                let known: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
                return Err(ParameterError::from_message(format!(
                    "damper.container_body: no body named '{}'; use one of: {}",
                    d.container_body,
                    known.join(", ")
                )));
            }
            if !(1..=MAX_PACKINGS).contains(&d.packings) {
                return Err(ParameterError::from_message(format!(
                    "damper.packings must be in 1..={MAX_PACKINGS} (independently prepared beds), got {}",
                    d.packings
                )));
            }
            if !(d.container_mass_kg.is_finite()
                && d.container_mass_kg >= 0.0
                && d.container_mass_kg <= 1e6)
            {
                return Err(ParameterError::from_message(format!(
                    "damper.container_mass_kg must lie in [0, 1e6] kg, got {}; check the unit",
                    d.container_mass_kg
                )));
            }
            if Vec3::from(d.direction).norm() == 0.0 || !Vec3::from(d.direction).norm().is_finite()
            {
                return Err(ParameterError::from_message(format!(
                    "damper.direction must be a finite non-zero vector, got {:?}; e.g. [1.0, 0.0, 0.0]",
                    d.direction
                )));
            }
            let given = [
                d.amplitude_m.is_some(),
                d.acceleration_m_s2.is_some(),
                d.intensity.is_some(),
            ]
            .iter()
            .filter(|x| **x)
            .count();
            if given > 1 {
                return Err(ParameterError::from_message(
                    "damper: give only one of amplitude_m, acceleration_m_s2, intensity (they \
                     describe the same amplitude); delete the others",
                ));
            }
            if self.fields.is_none() && given == 0 {
                return Err(ParameterError::from_message(
                    "damper: give one of amplitude_m, acceleration_m_s2 or intensity (or a [fields] grid)",
                ));
            }
            for (k, v) in [
                ("amplitude_m", d.amplitude_m),
                ("acceleration_m_s2", d.acceleration_m_s2),
                ("intensity", d.intensity),
                ("frequency_hz", d.frequency_hz),
            ] {
                if let Some(v) = v
                    && !finite_pos(v)
                {
                    return Err(ParameterError::from_message(format!(
                        "damper.{k} must be > 0, got {v}"
                    )));
                }
            }
            if self.fields.is_none() && d.frequency_hz.is_none() {
                return Err(ParameterError::from_message(
                    "damper.frequency_hz is needed (or a [fields] grid)",
                ));
            }
            // Physical ranges (a finite but absurd number gives finite nonsense downstream).
            for (k, v, max, unit) in [
                ("amplitude_m", d.amplitude_m, 1.0, "m"),
                ("acceleration_m_s2", d.acceleration_m_s2, 1e6, "m/s²"),
                ("intensity", d.intensity, 1e5, "(A/g)"),
                ("frequency_hz", d.frequency_hz, 1e5, "Hz"),
            ] {
                if let Some(v) = v
                    && !(finite_pos(v) && v <= max)
                {
                    return Err(ParameterError::from_message(format!(
                        "damper.{k} must lie in (0, {max:e}] {unit}, got {v}; check the unit"
                    )));
                }
            }
            if d.cycles > MAX_DAMPER_CYCLES {
                return Err(ParameterError::from_message(format!(
                    "damper.cycles must be at most {MAX_DAMPER_CYCLES}, got {}; use [damper.convergence] to stop when the result has settled",
                    d.cycles
                )));
            }
            self.validate_motion_output(d)?;
            if d.cycles <= d.transient_cycles {
                return Err(ParameterError::from_message(format!(
                    "damper.cycles ({}) must exceed damper.transient_cycles ({}); e.g. cycles = {}",
                    d.cycles,
                    d.transient_cycles,
                    d.transient_cycles + 15
                )));
            }
            if let Some(c) = &d.convergence {
                if !(c.relative_tolerance.is_finite()
                    && c.relative_tolerance > 0.0
                    && c.relative_tolerance < 1.0)
                {
                    return Err(ParameterError::from_message(format!(
                        "damper.convergence.relative_tolerance must be in (0, 1), got {}; e.g. 0.02",
                        c.relative_tolerance
                    )));
                }
                if c.window_cycles == 0 {
                    return Err(ParameterError::from_message(
                        "damper.convergence.window_cycles must be >= 1, got 0; e.g. 2",
                    ));
                }
                if c.min_evaluated_cycles <= c.window_cycles {
                    return Err(ParameterError::from_message(format!(
                        "damper.convergence.min_evaluated_cycles ({}) must exceed \
                         damper.convergence.window_cycles ({}): the first estimate compared needs \
                         window_cycles earlier ones; e.g. min_evaluated_cycles = {}",
                        c.min_evaluated_cycles,
                        c.window_cycles,
                        c.window_cycles + 2
                    )));
                }
                if d.transient_cycles + c.min_evaluated_cycles > d.cycles {
                    return Err(ParameterError::from_message(format!(
                        "damper.convergence.min_evaluated_cycles ({}) plus damper.transient_cycles \
                         ({}) exceeds damper.cycles ({}), the maximum; raise cycles to at least {}",
                        c.min_evaluated_cycles,
                        d.transient_cycles,
                        d.cycles,
                        d.transient_cycles + c.min_evaluated_cycles
                    )));
                }
                if !(c.absolute_floor.is_finite() && c.absolute_floor >= 0.0) {
                    return Err(ParameterError::from_message(format!(
                        "damper.convergence.absolute_floor must be >= 0 (in units of the bed mass), \
                         got {}; e.g. 0.1",
                        c.absolute_floor
                    )));
                }
            }
        }
        Ok(())
    }

    /// `[fields]`: a damper and exactly one amplitude axis.
    fn validate_fields(&self) -> Result<(), ParameterError> {
        if let Some(f) = &self.fields {
            if self.damper.is_none() {
                return Err(ParameterError::from_message(
                    "fields: a [damper] section is needed; add one with container_body, \
                     container_mass_kg and direction",
                ));
            }
            f.frequencies_hz.validate("fields.frequencies_hz")?;
            match f.amplitude_axis() {
                Some((AmplitudeAxis::Displacement, a)) => a.validate("fields.amplitudes_m")?,
                Some((AmplitudeAxis::Acceleration, a)) => {
                    a.validate("fields.accelerations_m_s2")?
                }
                Some((AmplitudeAxis::Intensity, a)) => a.validate("fields.intensities")?,
                None => {
                    return Err(ParameterError::from_message(
                        "fields: give exactly one of amplitudes_m, accelerations_m_s2, intensities",
                    ));
                }
            }
        }
        Ok(())
    }

    /// `[settle]` and every `[[particles]]` group.
    fn validate_settle_and_particles(&self) -> Result<(), ParameterError> {
        if let Some(st) = &self.settle {
            if !(st.max_duration_s.is_finite() && st.max_duration_s >= 0.0) {
                return Err(ParameterError::from_message(format!(
                    "settle.max_duration_s must be >= 0 (seconds), got {}",
                    st.max_duration_s
                )));
            }
            if !(st.kinetic_energy_per_particle_j.is_finite()
                && st.kinetic_energy_per_particle_j >= 0.0)
            {
                return Err(ParameterError::from_message(format!(
                    "settle.kinetic_energy_per_particle_j must be >= 0 (J), got {}",
                    st.kinetic_energy_per_particle_j
                )));
            }
            if let Some(t) = st.turn_max_duration_s
                && !(t.is_finite() && t >= 0.0)
            {
                return Err(ParameterError::from_message(format!(
                    "settle.turn_max_duration_s must be >= 0 (seconds), got {t}"
                )));
            }
            if let Some(g) = st.gravity_m_s2
                && g.iter().any(|x| !x.is_finite())
            {
                return Err(ParameterError::from_message(format!(
                    "settle.gravity_m_s2 must be finite, got {g:?}"
                )));
            }
        }
        if self.particles.is_empty() && (self.damper.is_some() || self.settle.is_some()) {
            return Err(ParameterError::from_message(
                "particles: no [[particles]] group; a damper or settling needs particles",
            ));
        }
        for (g, grp) in self.particles.iter().enumerate() {
            self.material_index(&grp.material, &format!("particles[{g}].material"))?;
            let n = grp
                .resolved_count()
                .map_err(|e| e.under(&format!("particles[{g}].")))?;
            if n == 0 {
                return Err(ParameterError::from_message(format!(
                    "particles[{g}].count: the group has no particles; give count >= 1 or remove it"
                )));
            }
            grp.size
                .validate()
                .map_err(|e| e.under(&format!("particles[{g}].size.")))?;
            self.validate_placement(g, &grp.placement)?;
            if !(grp.placement.gap_m.is_finite() && grp.placement.gap_m >= 0.0) {
                return Err(ParameterError::from_message(format!(
                    "particles[{g}].placement.gap_m must be >= 0 (metres), got {}",
                    grp.placement.gap_m
                )));
            }
            if grp.initial_velocity_m_s.iter().any(|v| !v.is_finite()) {
                return Err(ParameterError::from_message(format!(
                    "particles[{g}].initial_velocity_m_s must be finite"
                )));
            }
        }
        Ok(())
    }
}

/// Refuses an array of the file that is longer than the one it was read into (a vector
/// `[x, y, z, w]` read as `[x, y, z]`): walks the tables of both, `key` is the path so far.
pub(super) fn check_array_lengths(
    original: &toml::Table,
    canonical: &toml::Table,
    key: &str,
) -> Result<(), ParameterError> {
    for (k, v) in original {
        let Some(c) = canonical.get(k) else { continue };
        let path = if key.is_empty() {
            k.clone()
        } else {
            format!("{key}.{k}")
        };
        check_value_lengths(v, c, &path)?;
    }
    Ok(())
}

fn check_value_lengths(v: &toml::Value, c: &toml::Value, path: &str) -> Result<(), ParameterError> {
    match (v, c) {
        (toml::Value::Table(a), toml::Value::Table(b)) => check_array_lengths(a, b, path),
        (toml::Value::Array(a), toml::Value::Array(b)) => {
            if a.len() != b.len() && a.iter().all(|x| x.is_float() || x.is_integer()) {
                return Err(ParameterError::from_message(format!(
                    "{path} has {} components, {} expected (e.g. [x, y, z])",
                    a.len(),
                    b.len()
                )));
            }
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                check_value_lengths(x, y, &format!("{path}[{k}]"))?;
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// Finite and positive.
fn finite_pos(v: f64) -> bool {
    v.is_finite() && v > 0.0
}
