//! Scenario files: a TOML description of a DEM run (materials, contact laws, walls on rigid
//! bodies, particle groups, time stepping, output). See `docs/scenario.md` for the schema.
//!
//! Loading validates everything up front; every error names the key that is wrong.

use pdamp_dem::contact::ContactModel;
use pdamp_dem::generate::{
    Layering, Region, SizeDistribution, grid_packing, random_insertion, tight_packing,
};
use pdamp_dem::walls::{BoxInside, CylinderInside, CylinderOutside, Geometry, Plane};
use pdamp_dem::{
    BodyState, HarmonicTranslation, Integrator, Material, Motion, RigidBody, Vec3, World,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Errors while reading or checking a scenario.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read scenario '{path}': {source}")]
    Read {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (serde names key, line and column).
    #[error("scenario '{path}': {message}")]
    Parse {
        /// File.
        path: PathBuf,
        /// Message from the TOML parser.
        message: String,
    },
    /// A value is out of range or inconsistent.
    #[error("scenario '{path}': {message}")]
    Invalid {
        /// File.
        path: PathBuf,
        /// What is wrong and which key.
        message: String,
    },
}

/// A complete scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Free text shown in outputs.
    #[serde(default)]
    pub title: String,
    /// Time stepping and global settings.
    pub simulation: SimulationSpec,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
    /// Materials, referred to by name.
    pub materials: Vec<Material>,
    /// Contact models.
    pub contact: ContactSpec,
    /// Rigid bodies with their walls.
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
    /// Particle groups.
    #[serde(default)]
    pub particles: Vec<ParticleGroupSpec>,
    /// Optional settling (drop-down) phase before the main run.
    #[serde(default)]
    pub settle: Option<SettleSpec>,
}

/// Global settings of the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Simulated duration of the main run (after settling), s.
    pub duration_s: f64,
    /// Time step, s (initial step for Gear).
    pub time_step_s: f64,
    /// Integrator: `{ scheme = "velocity-verlet" }` (default) or `{ scheme = "gear", ... }`.
    #[serde(default = "default_integrator")]
    pub integrator: Integrator,
    /// Gravitational acceleration vector, m/s².
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 3],
    /// Seed of all random choices.
    #[serde(default)]
    pub seed: u64,
    /// Verlet skin, m (default 0.2 × smallest radius).
    #[serde(default)]
    pub skin_m: Option<f64>,
    /// Largest allowed ratio time step / shortest contact time (default 0.1).
    #[serde(default = "default_dt_ratio")]
    pub max_time_step_ratio: f64,
    /// Impact velocity used to estimate the shortest contact time, m/s (default 1).
    #[serde(default = "default_check_velocity")]
    pub check_impact_velocity_m_s: f64,
}

fn default_integrator() -> Integrator {
    Integrator::VelocityVerlet
}
fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}
fn default_dt_ratio() -> f64 {
    0.1
}
fn default_check_velocity() -> f64 {
    1.0
}

/// Output settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Interval of rows in `energy.csv`, s.
    #[serde(default = "default_energy_interval")]
    pub energy_interval_s: f64,
    /// Interval of VTK snapshots, s; 0 disables VTK.
    #[serde(default = "default_vtk_interval")]
    pub vtk_interval_s: f64,
}

fn default_energy_interval() -> f64 {
    1e-3
}
fn default_vtk_interval() -> f64 {
    0.05
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            energy_interval_s: default_energy_interval(),
            vtk_interval_s: default_vtk_interval(),
        }
    }
}

/// Contact models: a default for all pairs and overrides per material pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Model used for every pair without an override.
    #[serde(flatten)]
    pub default: ContactModel,
    /// Overrides for given material pairs.
    #[serde(default)]
    pub pairs: Vec<PairOverride>,
}

/// A contact model for one pair of materials.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairOverride {
    /// The two material names.
    pub materials: [String; 2],
    /// The model.
    #[serde(flatten)]
    pub model: ContactModel,
}

/// A rigid body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name.
    pub name: String,
    /// Reference position, m.
    #[serde(default)]
    pub position_m: [f64; 3],
    /// Motion: `{ type = "fixed" }` (default), `{ type = "harmonic", ... }`, `{ type = "driven" }`.
    #[serde(default)]
    pub motion: MotionSpec,
    /// Walls.
    pub walls: Vec<WallSpec>,
}

/// Motion of a body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum MotionSpec {
    /// Does not move.
    #[default]
    Fixed,
    /// $x(t) = X \sin(2\pi f t + \varphi)$ along `direction`.
    Harmonic(HarmonicTranslation),
    /// Set from outside (structural coupling).
    Driven,
}

/// One wall of a body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// Name.
    pub name: String,
    /// Material name.
    pub material: String,
    /// Geometry in the body frame.
    pub geometry: GeometrySpec,
}

/// Geometry of a wall in the scenario file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum GeometrySpec {
    /// Infinite plane.
    Plane(Plane),
    /// Closed cuboid container.
    BoxInside(BoxInside),
    /// Closed cylindrical container.
    CylinderInside(CylinderInside),
    /// Solid rod.
    CylinderOutside(CylinderOutside),
    /// Triangle mesh from an STL file.
    Stl(StlSpec),
}

/// A triangle mesh read from STL.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StlSpec {
    /// Path, relative to the scenario file.
    pub path: PathBuf,
    /// Factor applied to the coordinates (e.g. 0.001 for millimetres).
    #[serde(default = "one")]
    pub scale: f64,
    /// Translation applied after scaling, m.
    #[serde(default)]
    pub translation_m: [f64; 3],
    /// Flip triangle normals (STL normals point out of the solid; a container's cavity needs
    /// them pointing into the particle region).
    #[serde(default)]
    pub flip_normals: bool,
}

fn one() -> f64 {
    1.0
}

/// A group of particles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleGroupSpec {
    /// Material name.
    pub material: String,
    /// Number of particles.
    pub count: usize,
    /// Size distribution.
    pub size: SizeDistribution,
    /// Where the particles start.
    pub placement: PlacementSpec,
    /// Initial velocity, m/s.
    #[serde(default)]
    pub initial_velocity_m_s: [f64; 3],
}

/// Initial placement of a particle group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlacementSpec {
    /// `grid` (simple cubic), `tight` (hexagonal close packing) or `random`.
    pub method: PlacementMethod,
    /// Region to fill.
    pub region: Region,
    /// Gap between neighbouring spheres (lattices), m.
    #[serde(default)]
    pub gap_m: f64,
    /// For `random`: height of insertion layers (layer by layer), m.
    #[serde(default)]
    pub layer_height_m: Option<f64>,
}

/// Placement method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlacementMethod {
    /// Simple cubic lattice.
    Grid,
    /// Hexagonal close packing.
    Tight,
    /// Random without overlap.
    Random,
}

/// Settling (drop-down) before the main run: the bodies stay at their reference pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettleSpec {
    /// Longest settling time, s.
    pub max_duration_s: f64,
    /// Settling ends early when the kinetic energy per particle falls below this, J.
    #[serde(default)]
    pub kinetic_energy_per_particle_j: f64,
}

impl Scenario {
    /// Reads and validates a scenario file.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let s = Self::from_toml(&text).map_err(|message| ScenarioError::Parse {
            path: path.to_path_buf(),
            message,
        })?;
        s.validate().map_err(|message| ScenarioError::Invalid {
            path: path.to_path_buf(),
            message,
        })?;
        Ok(s)
    }

    /// Parses TOML text (no validation).
    pub fn from_toml(text: &str) -> Result<Self, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }

    /// Serialises to TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }

    fn material_index(&self, name: &str, key: &str) -> Result<u16, String> {
        self.materials
            .iter()
            .position(|m| m.name == name)
            .map(|i| i as u16)
            .ok_or_else(|| {
                let known: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
                format!(
                    "{key}: unknown material '{name}' (defined: {})",
                    known.join(", ")
                )
            })
    }

    /// Checks ranges and references; the message names the key.
    pub fn validate(&self) -> Result<(), String> {
        let s = &self.simulation;
        if !(s.duration_s.is_finite() && s.duration_s >= 0.0) {
            return Err(format!(
                "simulation.duration_s must be >= 0, got {}",
                s.duration_s
            ));
        }
        if !(s.time_step_s.is_finite() && s.time_step_s > 0.0) {
            return Err(format!(
                "simulation.time_step_s must be > 0, got {}",
                s.time_step_s
            ));
        }
        if self.materials.is_empty() {
            return Err("materials: at least one [[materials]] entry is needed".into());
        }
        for (k, m) in self.materials.iter().enumerate() {
            m.validate().map_err(|e| format!("materials[{k}]: {e}"))?;
            if self.materials[..k].iter().any(|o| o.name == m.name) {
                return Err(format!(
                    "materials[{k}].name: duplicate material name '{}'",
                    m.name
                ));
            }
        }
        self.contact
            .default
            .validate()
            .map_err(|e| format!("contact.{e}"))?;
        for (k, p) in self.contact.pairs.iter().enumerate() {
            self.material_index(&p.materials[0], &format!("contact.pairs[{k}].materials"))?;
            self.material_index(&p.materials[1], &format!("contact.pairs[{k}].materials"))?;
            p.model
                .validate()
                .map_err(|e| format!("contact.pairs[{k}].{e}"))?;
        }
        for (b, body) in self.bodies.iter().enumerate() {
            for (w, wall) in body.walls.iter().enumerate() {
                self.material_index(&wall.material, &format!("bodies[{b}].walls[{w}].material"))?;
            }
            if let MotionSpec::Harmonic(h) = &body.motion {
                if Vec3::from(h.direction).norm() == 0.0 {
                    return Err(format!("bodies[{b}].motion.direction must not be zero"));
                }
                if !(h.frequency_hz > 0.0 && h.amplitude_m >= 0.0) {
                    return Err(format!(
                        "bodies[{b}].motion: frequency_hz must be > 0 and amplitude_m >= 0"
                    ));
                }
            }
        }
        for (g, grp) in self.particles.iter().enumerate() {
            self.material_index(&grp.material, &format!("particles[{g}].material"))?;
            grp.size
                .validate()
                .map_err(|e| format!("particles[{g}].size: {e}"))?;
            grp.placement
                .region
                .validate()
                .map_err(|e| format!("particles[{g}].placement.region: {e}"))?;
        }
        Ok(())
    }

    /// Builds the world: bodies, walls (STL paths relative to `base_dir`), particles placed
    /// and checked for overlaps, and the time step checked against the contact time.
    pub fn build_world(&self, base_dir: &Path) -> Result<World, String> {
        let mut model = self.contact.default.clone();
        model.prepare();
        let mut world = World::new(self.materials.clone(), model, self.simulation.time_step_s);
        for p in &self.contact.pairs {
            let a = self.material_index(&p.materials[0], "contact.pairs")?;
            let b = self.material_index(&p.materials[1], "contact.pairs")?;
            world.set_contact_model(a, b, p.model.clone());
        }
        world.gravity_m_s2 = Vec3::from(self.simulation.gravity_m_s2);
        world.integrator = self.simulation.integrator.clone();
        for (bi, b) in self.bodies.iter().enumerate() {
            let motion = match &b.motion {
                MotionSpec::Fixed => Motion::Fixed,
                MotionSpec::Harmonic(h) => Motion::Prescribed(Arc::new(h.clone())),
                MotionSpec::Driven => Motion::Driven,
            };
            let mut body = RigidBody::new(
                &b.name,
                BodyState::at_rest(Vec3::from(b.position_m)),
                motion,
            );
            for (wi, w) in b.walls.iter().enumerate() {
                let mat = self.material_index(&w.material, "walls")?;
                let geometry = match &w.geometry {
                    GeometrySpec::Plane(g) => Geometry::Plane(g.clone()),
                    GeometrySpec::BoxInside(g) => Geometry::BoxInside(g.clone()),
                    GeometrySpec::CylinderInside(g) => Geometry::CylinderInside(g.clone()),
                    GeometrySpec::CylinderOutside(g) => Geometry::CylinderOutside(g.clone()),
                    GeometrySpec::Stl(s) => {
                        let path = base_dir.join(&s.path);
                        let mut mesh = crate::stl::read_stl(&path)
                            .map_err(|e| format!("bodies[{bi}].walls[{wi}].geometry.path: {e}"))?;
                        mesh = mesh
                            .transformed(s.scale, Vec3::from(s.translation_m))
                            .map_err(|e| format!("bodies[{bi}].walls[{wi}].geometry.scale: {e}"))?;
                        if s.flip_normals {
                            mesh.flip_normals();
                        }
                        Geometry::Mesh(mesh)
                    }
                };
                body.walls.push(pdamp_dem::Wall {
                    geometry,
                    material: mat,
                    name: w.name.clone(),
                });
            }
            world.add_body(body);
        }
        let up = -world.gravity_m_s2;
        let up = if up.norm() > 0.0 {
            up.normalize()
        } else {
            Vec3::z()
        };
        let mut placed: Vec<(Vec3, f64)> = Vec::new();
        for (g, grp) in self.particles.iter().enumerate() {
            let mat = self.material_index(&grp.material, "particles")?;
            let radii = grp
                .size
                .sample_n(grp.count, self.simulation.seed.wrapping_add(g as u64));
            let pl = &grp.placement;
            let pos = match pl.method {
                PlacementMethod::Grid => grid_packing(&pl.region, &radii, pl.gap_m, &up),
                PlacementMethod::Tight => tight_packing(&pl.region, &radii, pl.gap_m, &up),
                PlacementMethod::Random => {
                    let layering = pl.layer_height_m.map(|h| Layering {
                        up,
                        layer_height_m: h,
                    });
                    random_insertion(
                        &pl.region,
                        &radii,
                        self.simulation.seed.wrapping_add(1000 + g as u64),
                        1000,
                        layering.as_ref(),
                    )
                }
            }
            .map_err(|e| format!("particles[{g}].placement: {e}"))?;
            for (x, r) in pos.iter().zip(&radii) {
                let id = world.add_particle(*x, *r, mat);
                world.particles.velocity[id] = Vec3::from(grp.initial_velocity_m_s);
                placed.push((*x, *r));
            }
        }
        check_initial_overlaps(&world)?;
        if let Some(skin) = self.simulation.skin_m {
            world.set_skin(skin);
        }
        if !world.particles.is_empty() {
            let tc = world.min_contact_time_s(self.simulation.check_impact_velocity_m_s);
            let ratio = self.simulation.time_step_s / tc;
            if matches!(world.integrator, Integrator::VelocityVerlet)
                && ratio > self.simulation.max_time_step_ratio
            {
                return Err(format!(
                    "simulation.time_step_s = {:.3e} s is {:.2} of the shortest contact time {:.3e} s (impact at {} m/s); \
                     use at most {:.3e} s (max_time_step_ratio = {})",
                    self.simulation.time_step_s,
                    ratio,
                    tc,
                    self.simulation.check_impact_velocity_m_s,
                    self.simulation.max_time_step_ratio * tc,
                    self.simulation.max_time_step_ratio
                ));
            }
        }
        Ok(world)
    }
}

/// Fails if two particles overlap by more than 1e-9 of the smaller radius at the start.
fn check_initial_overlaps(world: &World) -> Result<(), String> {
    let p = &world.particles;
    let n = p.len();
    if n < 2 {
        return Ok(());
    }
    // Sort by x and sweep (O(n log n) for reasonable packings).
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| p.position[a].x.total_cmp(&p.position[b].x));
    let r_max = p.max_radius();
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if p.position[j].x - p.position[i].x > 2.0 * r_max {
                break;
            }
            let d = (p.position[i] - p.position[j]).norm();
            let ov = p.radius[i] + p.radius[j] - d;
            if ov > 1e-9 * p.radius[i].min(p.radius[j]) {
                return Err(format!(
                    "particles: initial overlap of {:.3e} m between particle {} at {:?} and particle {} at {:?}",
                    ov,
                    i,
                    p.position[i].as_slice(),
                    j,
                    p.position[j].as_slice()
                ));
            }
        }
    }
    Ok(())
}
