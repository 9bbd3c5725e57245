//! TOML input of `pdamp structure modes` and `pdamp couple` (see docs/structure.md). SI units
//! in every key name; unknown keys are errors.

use crate::StructureError;
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
    pub fn build(&self, base_dir: &Path) -> Result<BuiltStructure, StructureError> {
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
            return Err(StructureError::invalid(
                "structure",
                "give exactly one of single_mode, modal, beam, matrix_market",
            ));
        }
        self.validate()?;
        if let Some(s) = &self.single_mode {
            return Ok(BuiltStructure {
                modal: ModalStructure::single_mode(s.mass_kg, s.stiffness_n_m, s.damping_n_s_m),
                total_mass_kg: None,
                dof_count: None,
                solver: None,
            });
        }
        if let Some(m) = &self.modal {
            if m.damping_ratios.len() != m.frequencies_hz.len() {
                return Err(StructureError::invalid(
                    "modal",
                    "damping_ratios needs one value per frequency",
                ));
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
                Err(StructureError::DenseLimit {
                    dofs: n,
                    max: DENSE_MAX_DOF,
                })
            } else {
                Ok(())
            }
        };
        let (basis, n, rows, total, solver): (_, usize, Vec<Option<usize>>, Option<f64>, _) =
            if let Some(b) = &self.beam {
                let (fe, positions) = b.model()?;
                let total = fe.total_mass_kg();
                let mut wanted = Vec::new();
                for (i, p) in self.points.iter().enumerate() {
                    let x = p.position_m.ok_or_else(|| {
                        StructureError::rule(
                            format!("structure.points[{i}].position_m"),
                            format!("is missing (point '{}')", p.name),
                        )
                    })?;
                    let dof = Dof::parse(&p.dof).ok_or_else(|| {
                        StructureError::invalid(
                            format!("structure.points[{i}].dof"),
                            format!("unknown dof '{}'", p.dof),
                        )
                    })?;
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
                let Some(mm) = self.matrix_market.as_ref() else {
                    return Err(StructureError::invalid("structure", "no model section"));
                };
                let (kp, mp, dp) = (
                    resolve(base_dir, &mm.stiffness),
                    resolve(base_dir, &mm.mass),
                    resolve(base_dir, &mm.dof_map),
                );
                let named = |key: &'static str, p: &Path, e: matrix_market::MatrixMarketError| {
                    StructureError::MatrixMarketFile {
                        key,
                        path: match e {
                            matrix_market::MatrixMarketError::Io { .. } => None,
                            _ => Some(p.to_path_buf()),
                        },
                        error: e,
                    }
                };
                let k = matrix_market::read_matrix_market(&kp)
                    .map_err(|e| named("stiffness", &kp, e))?;
                let m =
                    matrix_market::read_matrix_market(&mp).map_err(|e| named("mass", &mp, e))?;
                if k.nrows != m.nrows || k.nrows != k.ncols || m.nrows != m.ncols {
                    return Err(StructureError::invalid(
                        "structure.matrix_market.mass",
                        format!(
                            "K ('{}') is {}×{}, M ('{}') is {}×{}; both must be square and of one \
                             size",
                            kp.display(),
                            k.nrows,
                            k.ncols,
                            mp.display(),
                            m.nrows,
                            m.ncols
                        ),
                    ));
                }
                let map = matrix_market::read_dof_map(&dp, k.nrows)
                    .map_err(|e| named("dof_map", &dp, e))?;
                matrix_market::check_structural_pair(
                    &k,
                    &kp.display().to_string(),
                    &m,
                    &mp.display().to_string(),
                    Some(&map),
                )
                .map_err(|e| StructureError::from(e).context("structure.matrix_market"))?;
                let mut rows = Vec::new();
                for (i, p) in self.points.iter().enumerate() {
                    let key = format!("structure.points[{i}].node");
                    let node = p.node.ok_or_else(|| {
                        StructureError::rule(
                            key.clone(),
                            format!("is missing (point '{}')", p.name),
                        )
                    })?;
                    let dof = Dof::parse(&p.dof).ok_or_else(|| {
                        StructureError::invalid(
                            format!("structure.points[{i}].dof"),
                            format!("unknown dof '{}'", p.dof),
                        )
                    })?;
                    rows.push(Some(map.row(node, dof).ok_or_else(|| {
                        StructureError::invalid(
                            key.clone(),
                            format!(
                                "node {node} {dof:?} of point '{}' is not in the dof map '{}' \
                                 ({} rows); give a node and dof listed there",
                                p.name,
                                dp.display(),
                                map.rows.len()
                            ),
                        )
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
    pub fn model(&self) -> Result<(FeModel, Vec<f64>), StructureError> {
        self.validate()?;
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
                let a = self.area_m2.ok_or_else(|| {
                    StructureError::invalid(
                        "beam",
                        "give width_m and height_m, or area_m2 and second_moment_m4",
                    )
                })?;
                let iz = self
                    .second_moment_m4
                    .ok_or_else(|| StructureError::invalid("beam", "second_moment_m4 missing"))?;
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
            return Err(StructureError::invalid(
                "beam",
                "elements ≥ 1 and length_m > 0",
            ));
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

/// Loads and validates a structure file ([`StructureSpec::validate`]).
///
/// # Errors
/// I/O and TOML errors; invalid values with the file, the key's line and column and the fix.
pub fn load_structure(path: &Path) -> Result<StructureFile, StructureError> {
    let text = std::fs::read_to_string(path).map_err(|e| StructureError::read(path, e))?;
    let f: StructureFile = toml::from_str(&text).map_err(|e| StructureError::toml(path, e))?;
    f.structure
        .validate()
        .map_err(|m| m.located(path, Some(&text)))?;
    Ok(f)
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
    pub fn dem_kinematics(
        &self,
        index: usize,
    ) -> Result<crate::dem::DemKinematics, StructureError> {
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
            return Err(StructureError::invalid(
                format!("dampers[{index}]"),
                "not a DEM damper",
            ));
        };
        let key = |k: &str| format!("dampers[{index}].{k}");
        let three =
            |v: &Option<Vec<String>>, k: &str| -> Result<[Option<String>; 3], StructureError> {
                let v = v.as_ref().ok_or_else(|| {
                    StructureError::invalid(key(k), format!("required for dofs = {dofs:?}"))
                })?;
                if v.len() != 3 {
                    return Err(StructureError::invalid(
                        key(k),
                        format!(
                            "give three point names (x, y, z; \"\" = not moved), got {}",
                            v.len()
                        ),
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
                        return Err(StructureError::invalid(
                            key(k),
                            "only with dofs = \"translation\" or \"translation+rotation\"",
                        ));
                    }
                }
                Ok(DemKinematics::OneDimensional)
            }
            DemDofs::Translation | DemDofs::TranslationRotation => {
                let tr = three(translation_points, "translation_points")?;
                if !tr.iter().flatten().any(|p| p == point) {
                    return Err(StructureError::invalid(
                        key("point"),
                        format!("'{point}' must be one of translation_points"),
                    ));
                }
                let rot = if *dofs == DemDofs::TranslationRotation {
                    Some(three(rotation_points, "rotation_points")?)
                } else if rotation_points.is_some() {
                    return Err(StructureError::invalid(
                        key("rotation_points"),
                        "only with dofs = \"translation+rotation\"",
                    ));
                } else {
                    None
                };
                if let Some(a) = attachment_point_m
                    && !a.iter().all(|x| x.is_finite())
                {
                    return Err(StructureError::invalid(
                        key("attachment_point_m"),
                        "must be finite",
                    ));
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
    ) -> Result<Option<Box<dyn EffectiveDamper>>, StructureError> {
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
                    let h = match (
                        l.clearance_m,
                        l.container_length_m,
                        l.particles,
                        l.particles_per_layer,
                    ) {
                        (Some(h), _, _, _) => h,
                        (None, Some(len), Some(n), Some(nmax)) => clearance_m(len, n, nmax),
                        _ => {
                            return Err(StructureError::invalid(
                                "rolling layer",
                                "give clearance_m or container_length_m + particles + particles_per_layer",
                            ));
                        }
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
                        return Err(StructureError::invalid(
                            "vertical damper",
                            "give clearance_m, or container_length_m, particles and \
                             max_particles (Eq. 7.4)",
                        ));
                    }
                };
                if !(h >= 0.0 && *bed_mass_kg > 0.0) {
                    return Err(StructureError::invalid(
                        "vertical damper",
                        "bed_mass_kg > 0 and clearance ≥ 0",
                    ));
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
                        let val = |p: &str| -> Result<f64, StructureError> {
                            let v = structure
                                .point(p)
                                .map_err(|e| e.context("powder_friction.angle_points"))?;
                            v.get(mode).copied().ok_or_else(|| {
                                StructureError::invalid(
                                    "powder_friction",
                                    format!("mode {} does not exist", mode + 1),
                                )
                            })
                        };
                        let x = val(point)?;
                        if x == 0.0 {
                            return Err(StructureError::NodeOfMode {
                                point: point.clone(),
                                mode: mode + 1,
                            });
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
                                return Err(StructureError::invalid(
                                    "powder_friction.angle_points",
                                    "bending needs [θ_start, θ_end], shear [u_start, θ_start, \
                                     u_end, θ_end]",
                                ));
                            }
                        }
                    }
                    _ => {
                        return Err(StructureError::invalid(
                            "powder_friction",
                            "give exactly one of angle_per_displacement_rad_m and angle_points",
                        ));
                    }
                };
                let d = PowderFrictionDamper {
                    mechanism: *mechanism,
                    cavity_length_m: *cavity_length_m,
                    cavity_width_m: match (mechanism, cavity_width_m) {
                        (FrictionMechanism::Bending, None) => {
                            return Err(StructureError::invalid(
                                "powder_friction",
                                "bending needs cavity_width_m",
                            ));
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
        /// Scale the initial displacement (and velocity) by $1 + m_{bed}/M$ [D Eq. 5.19]: the
        /// excitation that starts the decay gives the structure the same peak acceleration with
        /// and without particles, so the amplitude grows with the added bed mass ($M$: the modal
        /// mass of `mode` at `initial_point`, $m_{bed}$: the dampers' particle mass). For the
        /// Flexor of D Sect. 5.2.1 (78 mm without particles).
        #[serde(default)]
        scale_initial_by_bed_mass: bool,
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

impl AnalysisSpec {
    /// The free-vibration settings of a `kind = "free"` analysis (`None` for the others);
    /// `mode` becomes 0-based.
    pub fn free_vibration_spec(&self) -> Option<crate::free::FreeVibrationSpec> {
        match self {
            AnalysisSpec::Free {
                duration_s,
                time_step_s,
                mode,
                initial_point,
                initial_displacement_m,
                initial_velocity_m_s,
                scale_initial_by_bed_mass,
                output_point,
                update,
                sample_every,
            } => Some(crate::free::FreeVibrationSpec {
                duration_s: *duration_s,
                time_step_s: *time_step_s,
                mode: mode.saturating_sub(1),
                initial_point: initial_point.clone(),
                initial_displacement_m: *initial_displacement_m,
                initial_velocity_m_s: *initial_velocity_m_s,
                output_point: output_point.clone(),
                update: *update,
                sample_every: *sample_every,
                scale_initial_by_bed_mass: *scale_initial_by_bed_mass,
            }),
            _ => None,
        }
    }
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
    ///
    /// # Errors
    /// Not exactly one of the two amplitudes; a base amplitude without a single-mode structure.
    pub fn force_n(&self, structure: &StructureSpec) -> Result<f64, StructureError> {
        match (self.force_amplitude_n, self.base_amplitude_m) {
            (Some(f), None) => Ok(f),
            (None, Some(u)) => structure
                .single_mode
                .map(|s| u * s.stiffness_n_m)
                .ok_or_else(|| {
                    StructureError::rule(
                        "base_amplitude_m",
                        "needs a single_mode structure (R' = U K)",
                    )
                }),
            _ => Err(StructureError::inconsistent(
                "give exactly one of force_amplitude_n and base_amplitude_m",
            )),
        }
    }
}

impl CoupleScenario {
    /// Loads a scenario; returns it with the structure spec resolved.
    ///
    /// # Errors
    /// I/O, TOML, missing structure.
    pub fn load(path: &Path) -> Result<(Self, StructureSpec), StructureError> {
        let text = std::fs::read_to_string(path).map_err(|e| StructureError::read(path, e))?;
        let s: CoupleScenario = toml::from_str(&text).map_err(|e| StructureError::toml(path, e))?;
        let base = path.parent().unwrap_or(Path::new("."));
        let located = |m: StructureError| m.located(path, Some(&text));
        let structure = match (&s.structure, &s.structure_file) {
            (Some(st), None) => {
                st.validate().map_err(located)?;
                st.clone()
            }
            (None, Some(f)) => load_structure(&resolve(base, f))?.structure,
            _ => {
                return Err(located(StructureError::invalid(
                    "structure_file",
                    "give exactly one of structure_file and [structure]",
                )));
            }
        };
        s.validate(&structure).map_err(located)?;
        Ok((s, structure))
    }

    /// The file that holds the scenario's structure (`structure_file` resolved, or the scenario
    /// `path` itself), for locating structure errors.
    pub fn structure_source(&self, path: &Path) -> PathBuf {
        match &self.structure_file {
            Some(f) => resolve(path.parent().unwrap_or(Path::new(".")), f),
            None => path.to_path_buf(),
        }
    }
}

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
    pdamp_io::scenario::ScenarioError::invalid(path, text.as_deref(), message).to_string()
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
            } => {
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
                    positive(&k("smoothing_log_width"), *w, 100.0, "")?;
                }
            }
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
            } => {
                if scenario.as_os_str().is_empty() {
                    return Err(StructureError::invalid(
                        k("scenario"),
                        "give the damper scenario file",
                    ));
                }
                for (j, x) in attachment_point_m.iter().flatten().enumerate() {
                    check_num(
                        &k(&format!("attachment_point_m[{j}]")),
                        *x,
                        x.abs() <= MAX_DISPLACEMENT_M,
                        &format!("in [-{MAX_DISPLACEMENT_M:e}, {MAX_DISPLACEMENT_M:e}] m"),
                    )?;
                }
            }
        }
        Ok(())
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
