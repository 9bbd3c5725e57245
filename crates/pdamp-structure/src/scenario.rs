//! TOML input of `pdamp structure modes` and `pdamp couple` (see docs/structure.md). SI units
//! in every key name; unknown keys are errors.

use crate::effective::{EffectiveDamper, FieldTable, ViscousDamper};
use crate::fe::{BeamSection, Dof, FeModel, GroundSpring, PointMass};
use crate::forced::SweepLaw;
use crate::formulas::{
    ConstantLossFactor, HorizontalDamper, LayeredDamper, RollingDamper, clearance_m,
};
use crate::free::UpdateRule;
use crate::matrix_market;
use crate::modal::{ModalPoint, ModalStructure, Mode, lowest_modes};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

/// A structure file: `[structure]` with one model section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureFile {
    /// The structure.
    pub structure: StructureSpec,
}

/// The structure model and its reduction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureSpec {
    /// Number of modes kept (FE and Matrix Market models).
    #[serde(default = "default_modes")]
    pub n_modes: usize,
    /// Modes below this frequency (rigid-body modes) are dropped, Hz.
    #[serde(default = "default_min_frequency")]
    pub min_frequency_hz: f64,
    /// Eigen solver of FE and Matrix Market models: `auto` (dense up to
    /// [`crate::sparse::AUTO_SPARSE_ABOVE_DOF`] active dof, sparse above), `dense` or `sparse`
    /// (shift-invert subspace iteration, [`crate::sparse`]).
    #[serde(default)]
    pub solver: EigenSolver,
    /// Single mode in damper coordinates [D Eq. 3.27/3.36].
    #[serde(default)]
    pub single_mode: Option<SingleModeSpec>,
    /// Direct modal input.
    #[serde(default)]
    pub modal: Option<ModalSpec>,
    /// Built-in straight beam.
    #[serde(default)]
    pub beam: Option<BeamSpec>,
    /// Imported matrices.
    #[serde(default)]
    pub matrix_market: Option<MatrixMarketSpec>,
    /// Structural damping (FE and Matrix Market models).
    #[serde(default)]
    pub damping: Option<DampingSpec>,
    /// Named points (FE and Matrix Market models).
    #[serde(default)]
    pub points: Vec<PointSpec>,
}

/// Eigen solver selection (`[structure] solver`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EigenSolver {
    /// Dense up to [`crate::sparse::AUTO_SPARSE_ABOVE_DOF`] dof, sparse above.
    #[default]
    Auto,
    /// Dense Cholesky + symmetric eigen solver ([`crate::modal::lowest_modes`]).
    Dense,
    /// Sparse shift-invert subspace iteration ([`crate::sparse::lowest_modes_sparse`]).
    Sparse,
}

/// Dense solver limit (memory n² and time n³).
pub const DENSE_MAX_DOF: usize = 4000;

fn default_modes() -> usize {
    4
}
fn default_min_frequency() -> f64 {
    1e-3
}

/// `[structure.single_mode]`: $M\ddot x + D\dot x + Kx = f$ at the damper [D Eq. 3.36].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SingleModeSpec {
    /// M, kg.
    pub mass_kg: f64,
    /// K, N/m.
    pub stiffness_n_m: f64,
    /// D, N·s/m.
    #[serde(default)]
    pub damping_n_s_m: f64,
}

/// `[structure.modal]`: eigenfrequencies, damping ratios and mass-normalised shape values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModalSpec {
    /// f_k, Hz.
    pub frequencies_hz: Vec<f64>,
    /// ζ_k (one per mode).
    pub damping_ratios: Vec<f64>,
    /// Points with their φ^(k) values (1/√kg).
    pub points: Vec<ModalPoint>,
}

/// Structural damping of FE/imported models.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DampingSpec {
    /// Same ζ for all modes.
    #[serde(default)]
    pub ratio: Option<f64>,
    /// ζ per mode.
    #[serde(default)]
    pub ratios: Option<Vec<f64>>,
    /// Rayleigh α (mass-proportional), 1/s.
    #[serde(default)]
    pub rayleigh_alpha_1_s: Option<f64>,
    /// Rayleigh β (stiffness-proportional), s.
    #[serde(default)]
    pub rayleigh_beta_s: Option<f64>,
}

/// `[structure.beam]`: a straight beam along x with planar (x–y) or 3D motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamSpec {
    /// Length, m.
    pub length_m: f64,
    /// Number of elements.
    pub elements: usize,
    /// E, Pa.
    pub youngs_modulus_pa: f64,
    /// ν.
    pub poisson_ratio: f64,
    /// ρ, kg/m³.
    pub density_kg_m3: f64,
    /// Cross-section area, m² (or give width_m/height_m).
    #[serde(default)]
    pub area_m2: Option<f64>,
    /// Second moment for bending in x–y (deflection along y), m⁴.
    #[serde(default)]
    pub second_moment_m4: Option<f64>,
    /// Second moment for bending in x–z, m⁴ (default: as second_moment_m4).
    #[serde(default)]
    pub second_moment_z_m4: Option<f64>,
    /// Torsion constant, m⁴ (default: sum of the second moments).
    #[serde(default)]
    pub torsion_constant_m4: Option<f64>,
    /// Rectangle width (z extent), m.
    #[serde(default)]
    pub width_m: Option<f64>,
    /// Rectangle height (y extent, bending direction), m.
    #[serde(default)]
    pub height_m: Option<f64>,
    /// Timoshenko elements (κ = 5/6).
    #[serde(default = "yes")]
    pub timoshenko: bool,
    /// Only in-plane (x–y) motion: uz, θx, θy fixed everywhere.
    #[serde(default = "yes")]
    pub planar: bool,
    /// Supports.
    #[serde(default)]
    pub supports: Vec<SupportSpec>,
    /// Lumped masses.
    #[serde(default)]
    pub masses: Vec<MassSpec>,
}

fn yes() -> bool {
    true
}

/// Support kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SupportKind {
    /// All six dof fixed.
    Clamped,
    /// Translations fixed.
    Pinned,
    /// Transverse spring (y) of `stiffness_n_m`.
    Spring,
}

/// A support at a position along the beam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportSpec {
    /// Position along the beam, m.
    pub position_m: f64,
    /// Kind.
    pub kind: SupportKind,
    /// Spring stiffness, N/m (kind = "spring").
    #[serde(default)]
    pub stiffness_n_m: f64,
}

/// A lumped mass on the beam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MassSpec {
    /// Position along the beam, m.
    pub position_m: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Rotary inertia about z, kg·m².
    #[serde(default)]
    pub rotary_inertia_kg_m2: f64,
    /// Offset of the mass centre from the beam axis along y, m (rigid attachment).
    #[serde(default)]
    pub offset_y_m: f64,
}

/// `[structure.matrix_market]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatrixMarketSpec {
    /// Stiffness matrix file.
    pub stiffness: PathBuf,
    /// Mass matrix file.
    pub mass: PathBuf,
    /// Dof map file (`row node dof`).
    pub dof_map: PathBuf,
}

/// A named point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointSpec {
    /// Name.
    pub name: String,
    /// Position along the beam, m (built-in beam).
    #[serde(default)]
    pub position_m: Option<f64>,
    /// Node id (Matrix Market model).
    #[serde(default)]
    pub node: Option<i64>,
    /// Direction dof: `uy` (default), `uz`, `ux`, …
    #[serde(default = "default_dof")]
    pub dof: String,
}

fn default_dof() -> String {
    "uy".into()
}

/// Result of building a structure.
#[derive(Debug, Clone)]
pub struct BuiltStructure {
    /// The reduced structure.
    pub modal: ModalStructure,
    /// Total mass of an FE model, kg.
    pub total_mass_kg: Option<f64>,
    /// Active dof of an FE/imported model.
    pub dof_count: Option<usize>,
    /// Eigen solver used ("dense", "sparse"; `None` for modal/single-mode input).
    pub solver: Option<&'static str>,
}

fn resolve(base: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.join(p)
    }
}

impl StructureSpec {
    /// Builds and reduces the structure (paths relative to `base_dir`).
    ///
    /// # Errors
    /// Not exactly one model section, invalid values, unknown points, solver errors.
    pub fn build(&self, base_dir: &Path) -> Result<BuiltStructure, String> {
        let count = [
            self.single_mode.is_some(),
            self.modal.is_some(),
            self.beam.is_some(),
            self.matrix_market.is_some(),
        ]
        .iter()
        .filter(|b| **b)
        .count();
        if count != 1 {
            return Err(
                "[structure]: give exactly one of single_mode, modal, beam, matrix_market".into(),
            );
        }
        if let Some(s) = &self.single_mode {
            if !(s.mass_kg > 0.0 && s.stiffness_n_m > 0.0 && s.damping_n_s_m >= 0.0) {
                return Err("single_mode: mass_kg, stiffness_n_m > 0, damping_n_s_m ≥ 0".into());
            }
            return Ok(BuiltStructure {
                modal: ModalStructure::single_mode(s.mass_kg, s.stiffness_n_m, s.damping_n_s_m),
                total_mass_kg: None,
                dof_count: None,
                solver: None,
            });
        }
        if let Some(m) = &self.modal {
            if m.damping_ratios.len() != m.frequencies_hz.len() {
                return Err("modal: damping_ratios needs one value per frequency".into());
            }
            let s = ModalStructure {
                modes: m
                    .frequencies_hz
                    .iter()
                    .zip(&m.damping_ratios)
                    .map(|(&f, &z)| Mode {
                        frequency_hz: f,
                        damping_ratio: z,
                    })
                    .collect(),
                points: m.points.clone(),
            };
            s.validate()?;
            return Ok(BuiltStructure {
                modal: s,
                total_mass_kg: None,
                dof_count: None,
                solver: None,
            });
        }
        let want_sparse = |n: usize| match self.solver {
            EigenSolver::Auto => n > crate::sparse::AUTO_SPARSE_ABOVE_DOF,
            EigenSolver::Dense => false,
            EigenSolver::Sparse => true,
        };
        let dense_limit = |n: usize| {
            if n > DENSE_MAX_DOF {
                Err(format!(
                    "{n} dof: the dense modal solver is limited to {DENSE_MAX_DOF} dof (use \
                     solver = \"sparse\" or \"auto\")"
                ))
            } else {
                Ok(())
            }
        };
        let (basis, n, rows, total, solver): (_, usize, Vec<Option<usize>>, Option<f64>, _) =
            if let Some(b) = &self.beam {
                let (fe, positions) = b.model()?;
                let total = fe.total_mass_kg();
                let mut wanted = Vec::new();
                for p in &self.points {
                    let x = p
                        .position_m
                        .ok_or_else(|| format!("point '{}': needs position_m", p.name))?;
                    let dof = Dof::parse(&p.dof)
                        .ok_or_else(|| format!("point '{}': unknown dof '{}'", p.name, p.dof))?;
                    wanted.push((nearest(&positions, x), dof));
                }
                let a = fe.assemble_sparse()?;
                let n = a.dofs.len();
                let rows: Vec<Option<usize>> = wanted.iter().map(|&(nd, d)| a.row(nd, d)).collect();
                if want_sparse(n) {
                    let basis = crate::sparse::lowest_modes_sparse(
                        &a.stiffness,
                        &a.mass,
                        self.n_modes,
                        self.min_frequency_hz,
                    )?;
                    (basis, n, rows, Some(total), "sparse")
                } else {
                    dense_limit(n)?;
                    let a = fe.assemble()?;
                    let basis =
                        lowest_modes(&a.stiffness, &a.mass, self.n_modes, self.min_frequency_hz)?;
                    (basis, n, rows, Some(total), "dense")
                }
            } else {
                let mm = self.matrix_market.as_ref().expect("counted");
                let k = matrix_market::read_matrix_market(&resolve(base_dir, &mm.stiffness))
                    .map_err(|e| e.to_string())?;
                let m = matrix_market::read_matrix_market(&resolve(base_dir, &mm.mass))
                    .map_err(|e| e.to_string())?;
                if k.nrows != m.nrows || k.nrows != k.ncols || m.nrows != m.ncols {
                    return Err(format!(
                        "K is {}×{}, M is {}×{}",
                        k.nrows, k.ncols, m.nrows, m.ncols
                    ));
                }
                let map = matrix_market::read_dof_map(&resolve(base_dir, &mm.dof_map), k.nrows)
                    .map_err(|e| e.to_string())?;
                let mut rows = Vec::new();
                for p in &self.points {
                    let node = p
                        .node
                        .ok_or_else(|| format!("point '{}': needs node", p.name))?;
                    let dof = Dof::parse(&p.dof)
                        .ok_or_else(|| format!("point '{}': unknown dof '{}'", p.name, p.dof))?;
                    rows.push(Some(map.row(node, dof).ok_or_else(|| {
                        format!("point '{}': node {node} {dof:?} not in the dof map", p.name)
                    })?));
                }
                let n = k.nrows;
                if want_sparse(n) {
                    let ks = crate::sparse::SparseSym::from_triplets(n, &k.entries, false)?;
                    let ms = crate::sparse::SparseSym::from_triplets(n, &m.entries, false)?;
                    let basis = crate::sparse::lowest_modes_sparse(
                        &ks,
                        &ms,
                        self.n_modes,
                        self.min_frequency_hz,
                    )?;
                    (basis, n, rows, None, "sparse")
                } else {
                    dense_limit(n)?;
                    let basis = lowest_modes(
                        &k.to_dense(),
                        &m.to_dense(),
                        self.n_modes,
                        self.min_frequency_hz,
                    )?;
                    (basis, n, rows, None, "dense")
                }
            };
        let mut modal = ModalStructure {
            modes: basis
                .omega_rad_s
                .iter()
                .map(|w| Mode {
                    frequency_hz: w / TAU,
                    damping_ratio: 0.0,
                })
                .collect(),
            points: self
                .points
                .iter()
                .zip(&rows)
                .map(|(p, r)| ModalPoint {
                    name: p.name.clone(),
                    shape: match r {
                        Some(r) => basis.shapes.row(*r).iter().copied().collect(),
                        None => vec![0.0; basis.omega_rad_s.len()], // fixed dof
                    },
                })
                .collect(),
        };
        if let Some(d) = &self.damping {
            if let Some(z) = d.ratio {
                modal.modes.iter_mut().for_each(|m| m.damping_ratio = z);
            }
            if let Some(zs) = &d.ratios {
                for (m, z) in modal.modes.iter_mut().zip(zs) {
                    m.damping_ratio = *z;
                }
            }
            if d.rayleigh_alpha_1_s.is_some() || d.rayleigh_beta_s.is_some() {
                modal.set_rayleigh(
                    d.rayleigh_alpha_1_s.unwrap_or(0.0),
                    d.rayleigh_beta_s.unwrap_or(0.0),
                );
            }
        }
        modal.validate()?;
        Ok(BuiltStructure {
            modal,
            total_mass_kg: total,
            dof_count: Some(n),
            solver: Some(solver),
        })
    }
}

fn nearest(positions: &[f64], x: f64) -> usize {
    positions
        .iter()
        .enumerate()
        .min_by(|a, b| (a.1 - x).abs().total_cmp(&(b.1 - x).abs()))
        .map(|(i, _)| i)
        .unwrap_or(0)
}

impl BeamSpec {
    /// The FE model and the axial position of every node.
    ///
    /// # Errors
    /// Missing section data.
    pub fn model(&self) -> Result<(FeModel, Vec<f64>), String> {
        let g = self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio));
        let section = match (self.width_m, self.height_m) {
            (Some(w), Some(h)) => BeamSection::rectangle(
                w,
                h,
                self.youngs_modulus_pa,
                self.poisson_ratio,
                self.density_kg_m3,
                self.timoshenko,
            ),
            _ => {
                let a = self
                    .area_m2
                    .ok_or("beam: give width_m and height_m, or area_m2 and second_moment_m4")?;
                let iz = self
                    .second_moment_m4
                    .ok_or("beam: second_moment_m4 missing")?;
                let iy = self.second_moment_z_m4.unwrap_or(iz);
                BeamSection {
                    youngs_modulus_pa: self.youngs_modulus_pa,
                    shear_modulus_pa: g,
                    density_kg_m3: self.density_kg_m3,
                    area_m2: a,
                    iy_m4: iy,
                    iz_m4: iz,
                    torsion_constant_m4: self.torsion_constant_m4.unwrap_or(iy + iz),
                    shear_coefficient: self.timoshenko.then_some(5.0 / 6.0),
                }
            }
        };
        section.validate()?;
        if self.elements == 0 || self.length_m <= 0.0 {
            return Err("beam: elements ≥ 1 and length_m > 0".into());
        }
        // Nodes at the element ends plus exact nodes at supports, masses and points are not
        // inserted: positions snap to the nearest node (use element counts that hit them).
        let mut fe = FeModel::straight_beam(
            [0.0; 3],
            [self.length_m, 0.0, 0.0],
            self.elements,
            section,
            [0.0, 1.0, 0.0],
        );
        let positions: Vec<f64> = fe.nodes.iter().map(|p| p[0]).collect();
        if self.planar {
            fe.fix_all_nodes(&[Dof::Uz, Dof::Rx, Dof::Ry]);
        }
        for s in &self.supports {
            let n = nearest(&positions, s.position_m);
            match s.kind {
                SupportKind::Clamped => fe.fix(n, &Dof::ALL),
                SupportKind::Pinned => fe.fix(n, &Dof::TRANSLATIONS),
                SupportKind::Spring => fe.springs.push(GroundSpring {
                    node: n,
                    dof: Dof::Uy,
                    stiffness: s.stiffness_n_m,
                }),
            }
        }
        for m in &self.masses {
            fe.point_masses.push(PointMass {
                node: nearest(&positions, m.position_m),
                mass_kg: m.mass_kg,
                inertia_kg_m2: [
                    m.rotary_inertia_kg_m2,
                    m.rotary_inertia_kg_m2,
                    m.rotary_inertia_kg_m2,
                ],
                offset_m: [0.0, m.offset_y_m, 0.0],
            });
        }
        Ok((fe, positions))
    }
}

/// Loads a structure file.
///
/// # Errors
/// I/O and TOML errors.
pub fn load_structure(path: &Path) -> Result<StructureFile, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// A `pdamp couple` scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoupleScenario {
    /// Structure file (relative to the scenario), or give `[structure]` inline.
    #[serde(default)]
    pub structure_file: Option<PathBuf>,
    /// Inline structure.
    #[serde(default)]
    pub structure: Option<StructureSpec>,
    /// Dampers.
    #[serde(default)]
    pub dampers: Vec<DamperSpec>,
    /// The analysis.
    pub analysis: AnalysisSpec,
}

/// A damper model at a structure point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
pub enum DamperSpec {
    /// Viscous reference: Ẽ = πcΩX², constant mass.
    Viscous {
        /// Structure point.
        point: String,
        /// c, N·s/m.
        damping_n_s_m: f64,
        /// Coupled mass, kg.
        #[serde(default)]
        mass_kg: f64,
    },
    /// Approach 2: effective field from fields.csv.
    Fields {
        /// Structure point.
        point: String,
        /// fields.csv (relative to the scenario).
        path: PathBuf,
        /// Bed mass m_bed, kg.
        bed_mass_kg: f64,
    },
    /// Approach 3: rolling/scattered layers (D Eq. 5.1–5.14).
    Rolling {
        /// Structure point.
        point: String,
        /// Layers.
        layers: Vec<RollingLayerSpec>,
        /// Smoothing of the X_opt jump (logistic width in ln X).
        #[serde(default)]
        smoothing_log_width: Option<f64>,
    },
    /// Approach 3: combined horizontal rolling/bouncing model (D Eq. 6.12).
    Horizontal {
        /// Structure point.
        point: String,
        /// Bed mass, kg.
        bed_mass_kg: f64,
        /// h_rol, m.
        rolling_clearance_m: f64,
        /// h_bou, m.
        bouncing_clearance_m: f64,
        /// m̄/m_bed for A ≥ g.
        #[serde(default = "one")]
        bouncing_mass_ratio: f64,
    },
    /// Approach 3: vertical single/double collect-and-collide bed (D Eq. 7.1–7.19).
    Vertical {
        /// Structure point.
        point: String,
        /// Bed mass, kg.
        bed_mass_kg: f64,
        /// Clearance h to the top wall, m (or give `container_length_m`, `particles`,
        /// `max_particles` for Eq. 7.4).
        #[serde(default)]
        clearance_m: Option<f64>,
        /// Inner container length L along the excitation, m (Eq. 7.4).
        #[serde(default)]
        container_length_m: Option<f64>,
        /// Particle number n_p (Eq. 7.4).
        #[serde(default)]
        particles: Option<f64>,
        /// n_p^max (Eq. 7.4).
        #[serde(default)]
        max_particles: Option<f64>,
    },
    /// Fixed η̄ and m̄/m_bed.
    Constant {
        /// Structure point.
        point: String,
        /// Bed mass, kg.
        bed_mass_kg: f64,
        /// η̄.
        effective_loss_factor: f64,
        /// m̄/m_bed.
        effective_mass_ratio: f64,
    },
    /// Approach 3: powder-filled cavity, sliding-friction work under pure shear or bending
    /// (paper Sect. 4, eq. 17–26; [`crate::formulas::PowderFrictionDamper`]).
    PowderFriction {
        /// Structure point (X is its amplitude).
        point: String,
        /// `shear` (eq. 20) or `bending` (eq. 26).
        mechanism: crate::formulas::FrictionMechanism,
        /// Cavity length l, m.
        cavity_length_m: f64,
        /// Cavity width b, m (bending).
        #[serde(default)]
        cavity_width_m: Option<f64>,
        /// Coefficient of friction μ.
        friction: f64,
        /// Wall normal force F_N,y (shear) / F_N,x (bending), N.
        wall_normal_force_n: f64,
        /// κ = φ/X, rad/m; or give `angle_points`.
        #[serde(default)]
        angle_per_displacement_rad_m: Option<f64>,
        /// Points giving φ from the analysed mode: bending `[θ_start, θ_end]`
        /// (φ = (θ_end − θ_start)/2), shear `[u_start, θ_start, u_end, θ_end]`
        /// (φ = (u_end − u_start)/l − (θ_start + θ_end)/2).
        #[serde(default)]
        angle_points: Option<Vec<String>>,
        /// Powder mass, kg.
        bed_mass_kg: f64,
        /// m̄ added at the point, kg (the powder mass itself belongs to the structure).
        #[serde(default)]
        effective_mass_kg: f64,
    },
    /// Approach 1: full DEM damper from a damper scenario (`[damper]` section).
    Dem {
        /// Structure point.
        point: String,
        /// Damper scenario (relative to this scenario).
        scenario: PathBuf,
        /// Subtract the static bed weight.
        #[serde(default = "yes")]
        compensate_static_weight: bool,
        /// Container dof that follow the structure: `"1d"` (along the damper's direction at
        /// `point`), `"translation"` or `"translation+rotation"` (rigid body, D Eq. 3.21–3.26).
        #[serde(default)]
        dofs: DemDofs,
        /// Rigid-body modes: structure points of u_x, u_y, u_z of the damper node in the
        /// DEM frame (`""` = that dof is not moved); `point` must be one of them.
        #[serde(default)]
        translation_points: Option<Vec<String>>,
        /// `"translation+rotation"`: points of θ_x, θ_y, θ_z (rad), `""` = not rotated.
        #[serde(default)]
        rotation_points: Option<Vec<String>>,
        /// Attachment point (rotation centre, torque reference) in the damper scenario's
        /// frame, m; default: the container's reference position.
        #[serde(default)]
        attachment_point_m: Option<[f64; 3]>,
    },
}

/// Container dof of a DEM damper (approach 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum DemDofs {
    /// Translation along the damper's direction only.
    #[default]
    #[serde(rename = "1d")]
    OneDimensional,
    /// Three translations.
    #[serde(rename = "translation")]
    Translation,
    /// Three translations and three small rotations.
    #[serde(rename = "translation+rotation")]
    TranslationRotation,
}

fn one() -> f64 {
    1.0
}

fn default_overlap() -> f64 {
    0.3
}

/// One layer of a rolling damper: give `clearance_m` or `container_length_m` with
/// `particles` and `particles_per_layer` (Eq. 5.1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RollingLayerSpec {
    /// Bed mass of the layer, kg.
    pub bed_mass_kg: f64,
    /// Clearance h_rol, m.
    #[serde(default)]
    pub clearance_m: Option<f64>,
    /// Container length L, m.
    #[serde(default)]
    pub container_length_m: Option<f64>,
    /// n_p.
    #[serde(default)]
    pub particles: Option<f64>,
    /// n_p^max.
    #[serde(default)]
    pub particles_per_layer: Option<f64>,
}

impl DamperSpec {
    /// Structure point of the damper.
    pub fn point(&self) -> &str {
        match self {
            DamperSpec::Viscous { point, .. }
            | DamperSpec::Fields { point, .. }
            | DamperSpec::Rolling { point, .. }
            | DamperSpec::Horizontal { point, .. }
            | DamperSpec::Vertical { point, .. }
            | DamperSpec::Constant { point, .. }
            | DamperSpec::PowderFriction { point, .. }
            | DamperSpec::Dem { point, .. } => point,
        }
    }

    /// Kinematics of a DEM damper (`dampers[index]`), validated: the point lists have three
    /// entries, `point` is one of the translation points, the keys fit `dofs`.
    ///
    /// # Errors
    /// Messages name the offending key; not a DEM damper.
    pub fn dem_kinematics(&self, index: usize) -> Result<crate::dem::DemKinematics, String> {
        use crate::dem::{DemKinematics, RigidKinematics};
        let DamperSpec::Dem {
            point,
            dofs,
            translation_points,
            rotation_points,
            attachment_point_m,
            ..
        } = self
        else {
            return Err(format!("dampers[{index}]: not a DEM damper"));
        };
        let key = |k: &str| format!("dampers[{index}].{k}");
        let three = |v: &Option<Vec<String>>, k: &str| -> Result<[Option<String>; 3], String> {
            let v = v
                .as_ref()
                .ok_or_else(|| format!("{}: required for dofs = {dofs:?}", key(k)))?;
            if v.len() != 3 {
                return Err(format!(
                    "{}: give three point names (x, y, z; \"\" = not moved), got {}",
                    key(k),
                    v.len()
                ));
            }
            let o = |s: &String| (!s.trim().is_empty()).then(|| s.trim().to_string());
            Ok([o(&v[0]), o(&v[1]), o(&v[2])])
        };
        match dofs {
            DemDofs::OneDimensional => {
                for (k, set) in [
                    ("translation_points", translation_points.is_some()),
                    ("rotation_points", rotation_points.is_some()),
                    ("attachment_point_m", attachment_point_m.is_some()),
                ] {
                    if set {
                        return Err(format!(
                            "{}: only with dofs = \"translation\" or \"translation+rotation\"",
                            key(k)
                        ));
                    }
                }
                Ok(DemKinematics::OneDimensional)
            }
            DemDofs::Translation | DemDofs::TranslationRotation => {
                let tr = three(translation_points, "translation_points")?;
                if !tr.iter().flatten().any(|p| p == point) {
                    return Err(format!(
                        "{}: '{point}' must be one of translation_points",
                        key("point")
                    ));
                }
                let rot = if *dofs == DemDofs::TranslationRotation {
                    Some(three(rotation_points, "rotation_points")?)
                } else if rotation_points.is_some() {
                    return Err(format!(
                        "{}: only with dofs = \"translation+rotation\"",
                        key("rotation_points")
                    ));
                } else {
                    None
                };
                if let Some(a) = attachment_point_m
                    && !a.iter().all(|x| x.is_finite())
                {
                    return Err(format!("{}: must be finite", key("attachment_point_m")));
                }
                Ok(DemKinematics::Rigid(RigidKinematics {
                    translation_points: tr,
                    rotation_points: rot,
                    attachment_point_m: attachment_point_m.map(pdamp_dem::Vec3::from),
                }))
            }
        }
    }

    /// The equivalent model of approaches 2/3 (`None` for DEM); `structure` and the analysed
    /// `mode` (0-based) resolve mode-dependent kinematics (`powder_friction` `angle_points`).
    ///
    /// # Errors
    /// Invalid layer data, unreadable fields.csv, invalid powder-friction keys.
    pub fn effective_model(
        &self,
        base_dir: &Path,
        structure: &crate::modal::ModalStructure,
        mode: usize,
    ) -> Result<Option<Box<dyn EffectiveDamper>>, String> {
        Ok(Some(match self {
            DamperSpec::Viscous {
                damping_n_s_m,
                mass_kg,
                ..
            } => Box::new(ViscousDamper {
                damping_n_s_m: *damping_n_s_m,
                mass_kg: *mass_kg,
            }),
            DamperSpec::Fields {
                path, bed_mass_kg, ..
            } => Box::new(FieldTable::read(&resolve(base_dir, path), *bed_mass_kg)?),
            DamperSpec::Rolling {
                layers,
                smoothing_log_width,
                ..
            } => {
                let mut v: Vec<Box<dyn EffectiveDamper>> = Vec::new();
                for l in layers {
                    let h = match (l.clearance_m, l.container_length_m, l.particles, l.particles_per_layer) {
                        (Some(h), _, _, _) => h,
                        (None, Some(len), Some(n), Some(nmax)) => clearance_m(len, n, nmax),
                        _ => return Err("rolling layer: give clearance_m or container_length_m + particles + particles_per_layer".into()),
                    };
                    v.push(Box::new(RollingDamper {
                        bed_mass_kg: l.bed_mass_kg,
                        clearance_m: h,
                        smoothing_log_width: *smoothing_log_width,
                    }));
                }
                if v.len() == 1 {
                    v.pop().expect("one")
                } else {
                    Box::new(LayeredDamper { layers: v })
                }
            }
            DamperSpec::Horizontal {
                bed_mass_kg,
                rolling_clearance_m,
                bouncing_clearance_m,
                bouncing_mass_ratio,
                ..
            } => Box::new(HorizontalDamper {
                rolling: RollingDamper {
                    bed_mass_kg: *bed_mass_kg,
                    clearance_m: *rolling_clearance_m,
                    smoothing_log_width: None,
                },
                bouncing_clearance_m: *bouncing_clearance_m,
                bouncing_mass_ratio: *bouncing_mass_ratio,
            }),
            DamperSpec::Vertical {
                bed_mass_kg,
                clearance_m: h,
                container_length_m,
                particles,
                max_particles,
                ..
            } => {
                let h = match (h, container_length_m, particles, max_particles) {
                    (Some(h), None, None, None) => *h,
                    (None, Some(l), Some(n), Some(nm)) => crate::formulas::clearance_m(*l, *n, *nm),
                    _ => {
                        return Err("vertical damper: give clearance_m, or container_length_m, \
                                    particles and max_particles (Eq. 7.4)"
                            .into());
                    }
                };
                if !(h >= 0.0 && *bed_mass_kg > 0.0) {
                    return Err("vertical damper: bed_mass_kg > 0 and clearance ≥ 0".into());
                }
                Box::new(crate::formulas::VerticalDamper {
                    bed_mass_kg: *bed_mass_kg,
                    clearance_m: h,
                })
            }
            DamperSpec::Constant {
                bed_mass_kg,
                effective_loss_factor,
                effective_mass_ratio,
                ..
            } => Box::new(ConstantLossFactor {
                bed_mass_kg: *bed_mass_kg,
                effective_loss_factor: *effective_loss_factor,
                effective_mass_ratio: *effective_mass_ratio,
            }),
            DamperSpec::PowderFriction {
                point,
                mechanism,
                cavity_length_m,
                cavity_width_m,
                friction,
                wall_normal_force_n,
                angle_per_displacement_rad_m,
                angle_points,
                bed_mass_kg,
                effective_mass_kg,
            } => {
                use crate::formulas::{FrictionMechanism, PowderFrictionDamper};
                let kappa = match (angle_per_displacement_rad_m, angle_points) {
                    (Some(k), None) => *k,
                    (None, Some(pts)) => {
                        let val = |p: &str| -> Result<f64, String> {
                            let v = structure
                                .point(p)
                                .map_err(|e| format!("powder_friction.angle_points: {e}"))?;
                            v.get(mode).copied().ok_or_else(|| {
                                format!("powder_friction: mode {} does not exist", mode + 1)
                            })
                        };
                        let x = val(point)?;
                        if x == 0.0 {
                            return Err(format!(
                                "powder_friction: point '{point}' is a node of mode {} (φ/X undefined)",
                                mode + 1
                            ));
                        }
                        match (mechanism, pts.len()) {
                            (FrictionMechanism::Bending, 2) => {
                                0.5 * (val(&pts[1])? - val(&pts[0])?) / x
                            }
                            (FrictionMechanism::Shear, 4) => {
                                ((val(&pts[2])? - val(&pts[0])?) / cavity_length_m
                                    - 0.5 * (val(&pts[1])? + val(&pts[3])?))
                                    / x
                            }
                            _ => {
                                return Err("powder_friction.angle_points: bending needs \
                                            [θ_start, θ_end], shear [u_start, θ_start, u_end, \
                                            θ_end]"
                                    .into());
                            }
                        }
                    }
                    _ => {
                        return Err("powder_friction: give exactly one of \
                                    angle_per_displacement_rad_m and angle_points"
                            .into());
                    }
                };
                let d = PowderFrictionDamper {
                    mechanism: *mechanism,
                    cavity_length_m: *cavity_length_m,
                    cavity_width_m: match (mechanism, cavity_width_m) {
                        (FrictionMechanism::Bending, None) => {
                            return Err("powder_friction: bending needs cavity_width_m".into());
                        }
                        (_, w) => w.unwrap_or(0.0),
                    },
                    friction: *friction,
                    wall_normal_force_n: *wall_normal_force_n,
                    angle_per_displacement_rad_m: kappa,
                    bed_mass_kg: *bed_mass_kg,
                    effective_mass_kg: *effective_mass_kg,
                };
                d.validate()?;
                Box::new(d)
            }
            DamperSpec::Dem { .. } => return Ok(None),
        }))
    }
}

/// Excitation force: a force amplitude, or a base amplitude U of a single-mode structure
/// (R' = UK, D Sect. 5.2.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    /// F, N.
    #[serde(default)]
    pub force_amplitude_n: Option<f64>,
    /// U, m (single_mode structures: F = U K).
    #[serde(default)]
    pub base_amplitude_m: Option<f64>,
}

/// The analysis of a `pdamp couple` scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum AnalysisSpec {
    /// Free vibration from an initial condition [D Sect. 3.3.1].
    Free {
        /// Simulated time, s.
        duration_s: f64,
        /// Time step, s (DEM dampers use their scenario's step).
        time_step_s: f64,
        /// Mode carrying the initial condition (1-based).
        #[serde(default = "one_usize")]
        mode: usize,
        /// Point of the initial condition.
        initial_point: String,
        /// Initial displacement, m.
        initial_displacement_m: f64,
        /// Initial velocity, m/s.
        #[serde(default)]
        initial_velocity_m_s: f64,
        /// Output point.
        output_point: String,
        /// Update rule for approaches 2/3.
        #[serde(default)]
        update: UpdateRule,
        /// Store every n-th step.
        #[serde(default = "one_usize")]
        sample_every: usize,
    },
    /// Sine sweep in the time domain [D Sect. 3.3.2].
    Sweep {
        /// Start frequency, Hz.
        start_hz: f64,
        /// End frequency, Hz.
        end_hz: f64,
        /// Duration, s.
        duration_s: f64,
        /// Linear or logarithmic.
        #[serde(default)]
        law: SweepLaw,
        /// Force amplitude F, N.
        #[serde(default)]
        force_amplitude_n: Option<f64>,
        /// Base amplitude U of a single-mode structure (F = U K), m.
        #[serde(default)]
        base_amplitude_m: Option<f64>,
        /// Excitation point.
        excitation_point: String,
        /// Output point.
        output_point: String,
        /// Time step, s.
        time_step_s: f64,
        /// Store every n-th step.
        #[serde(default = "one_usize")]
        sample_every: usize,
        /// Cycles per FRF window.
        #[serde(default = "four")]
        window_cycles: usize,
        /// Mode analysed by Eq. 3.47 (1-based).
        #[serde(default = "one_usize")]
        mode: usize,
        /// Split the sweep into this many overlapping segments, each started from rest, FRFs
        /// combined by peak hold (frequency-domain approach, D Sect. 3.3.2); 1 = one sweep.
        #[serde(default = "one_usize")]
        segments: usize,
        /// Overlap of neighbouring segments as a fraction of the segment width (half of it is
        /// the cut-off start-up transient).
        #[serde(default = "default_overlap")]
        segment_overlap: f64,
    },
    /// Steady-state FRF of approaches 2/3 by the iteration of D Fig. 3.7 / Eq. 3.44, one mode.
    SteadyState {
        /// Start frequency, Hz.
        start_hz: f64,
        /// End frequency, Hz.
        end_hz: f64,
        /// Number of frequencies.
        #[serde(default = "thousand")]
        points: usize,
        /// Force amplitude F, N.
        #[serde(default)]
        force_amplitude_n: Option<f64>,
        /// Base amplitude U of a single-mode structure (F = U K), m.
        #[serde(default)]
        base_amplitude_m: Option<f64>,
        /// Excitation point.
        excitation_point: String,
        /// Output point.
        output_point: String,
        /// Mode (1-based).
        #[serde(default = "one_usize")]
        mode: usize,
    },
}

fn one_usize() -> usize {
    1
}
fn four() -> usize {
    4
}
fn thousand() -> usize {
    1000
}

impl ForceSpec {
    /// The force amplitude, N (needs the single-mode stiffness for `base_amplitude_m`).
    pub fn force_n(&self, structure: &StructureSpec) -> Result<f64, String> {
        match (self.force_amplitude_n, self.base_amplitude_m) {
            (Some(f), None) => Ok(f),
            (None, Some(u)) => structure
                .single_mode
                .map(|s| u * s.stiffness_n_m)
                .ok_or_else(|| "base_amplitude_m needs a single_mode structure (R' = U K)".into()),
            _ => Err("give exactly one of force_amplitude_n and base_amplitude_m".into()),
        }
    }
}

impl CoupleScenario {
    /// Loads a scenario; returns it with the structure spec resolved.
    ///
    /// # Errors
    /// I/O, TOML, missing structure.
    pub fn load(path: &Path) -> Result<(Self, StructureSpec), String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let s: CoupleScenario =
            toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        let base = path.parent().unwrap_or(Path::new("."));
        let structure = match (&s.structure, &s.structure_file) {
            (Some(st), None) => st.clone(),
            (None, Some(f)) => load_structure(&resolve(base, f))?.structure,
            _ => return Err("give exactly one of structure_file and [structure]".into()),
        };
        Ok((s, structure))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_keys_are_rejected() {
        let bad =
            "[structure]\n[structure.single_mode]\nmass_kg = 1.0\nstiffness_n_m = 1.0\nmass = 3\n";
        assert!(toml::from_str::<StructureFile>(bad).is_err());
        let good = "[structure]\n[structure.single_mode]\nmass_kg = 1.0\nstiffness_n_m = 1.0\n";
        let s: StructureFile = toml::from_str(good).unwrap();
        assert!(s.structure.build(Path::new(".")).is_ok());
    }
}
