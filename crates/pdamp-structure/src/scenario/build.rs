//! The structure built from its spec and reduced to its lowest modes: modal input taken as
//! given, a built-in beam or a Matrix Market model assembled and solved (dense or sparse).

use super::{
    BeamSpec, BuiltStructure, DENSE_MAX_DOF, EigenSolver, MatrixMarketSpec, ModalSpec,
    StructureSpec, SupportKind, resolve,
};
use crate::StructureError;
use crate::fe::{BeamSection, Dof, FeModel, GroundSpring, PointMass};
use crate::matrix_market;
use crate::modal::{ModalBasis, ModalPoint, ModalStructure, Mode, lowest_modes};
use std::f64::consts::TAU;
use std::path::Path;

/// The structure reduced to its lowest modes, before the point shapes are picked.
struct ReducedModel {
    /// Eigenfrequencies and mass-normalised shapes.
    basis: ModalBasis,
    /// Active dof of the model.
    dof_count: usize,
    /// Row of every structure point in the shapes (`None`: fixed dof).
    rows: Vec<Option<usize>>,
    /// Total mass of an FE model, kg.
    total_mass_kg: Option<f64>,
    /// Eigen solver used.
    solver: &'static str,
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
            return given_modes(m);
        }
        let reduced = if let Some(b) = &self.beam {
            self.reduce_beam(b)?
        } else {
            let Some(mm) = self.matrix_market.as_ref() else {
                return Err(StructureError::invalid("structure", "no model section"));
            };
            self.reduce_matrix_market(mm, base_dir)?
        };
        let mut modal = self.point_shapes(&reduced.basis, &reduced.rows);
        self.apply_damping(&mut modal);
        modal.validate()?;
        Ok(BuiltStructure {
            modal,
            total_mass_kg: reduced.total_mass_kg,
            dof_count: Some(reduced.dof_count),
            solver: Some(reduced.solver),
        })
    }

    /// Whether a model of `n` dof is solved by the sparse eigen solver (`solver` key).
    fn wants_sparse(&self, n: usize) -> bool {
        match self.solver {
            EigenSolver::Auto => n > crate::sparse::AUTO_SPARSE_ABOVE_DOF,
            EigenSolver::Dense => false,
            EigenSolver::Sparse => true,
        }
    }

    /// The built-in beam assembled and reduced; points snap to the nearest node.
    fn reduce_beam(&self, b: &BeamSpec) -> Result<ReducedModel, StructureError> {
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
        let (basis, solver) = if self.wants_sparse(n) {
            let basis = crate::sparse::lowest_modes_sparse(
                &a.stiffness,
                &a.mass,
                self.n_modes,
                self.min_frequency_hz,
            )?;
            (basis, "sparse")
        } else {
            check_dense_limit(n)?;
            let a = fe.assemble()?;
            let basis = lowest_modes(&a.stiffness, &a.mass, self.n_modes, self.min_frequency_hz)?;
            (basis, "dense")
        };
        Ok(ReducedModel {
            basis,
            dof_count: n,
            rows,
            total_mass_kg: Some(total),
            solver,
        })
    }

    /// The imported K and M (Matrix Market, paths relative to `base_dir`) checked against each
    /// other and the dof map, and reduced; points are looked up in the dof map.
    fn reduce_matrix_market(
        &self,
        mm: &MatrixMarketSpec,
        base_dir: &Path,
    ) -> Result<ReducedModel, StructureError> {
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
        let k = matrix_market::read_matrix_market(&kp).map_err(|e| named("stiffness", &kp, e))?;
        let m = matrix_market::read_matrix_market(&mp).map_err(|e| named("mass", &mp, e))?;
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
        let map =
            matrix_market::read_dof_map(&dp, k.nrows).map_err(|e| named("dof_map", &dp, e))?;
        matrix_market::check_structural_pair(
            &k,
            &kp.display().to_string(),
            &m,
            &mp.display().to_string(),
            Some(&map),
        )
        .map_err(|e| StructureError::from(e).context("structure.matrix_market"))?;
        let rows = self.dof_map_rows(&map, &dp)?;
        let n = k.nrows;
        let (basis, solver) = if self.wants_sparse(n) {
            let ks = crate::sparse::SymmetricCsr::from_triplets(n, &k.entries, false)
                .map_err(crate::sparse::SparseError::from)?;
            let ms = crate::sparse::SymmetricCsr::from_triplets(n, &m.entries, false)
                .map_err(crate::sparse::SparseError::from)?;
            let basis =
                crate::sparse::lowest_modes_sparse(&ks, &ms, self.n_modes, self.min_frequency_hz)?;
            (basis, "sparse")
        } else {
            check_dense_limit(n)?;
            let basis = lowest_modes(
                &k.to_dense(),
                &m.to_dense(),
                self.n_modes,
                self.min_frequency_hz,
            )?;
            (basis, "dense")
        };
        Ok(ReducedModel {
            basis,
            dof_count: n,
            rows,
            total_mass_kg: None,
            solver,
        })
    }

    /// Row of every structure point (`node`, `dof`) in the dof map `map` read from `dp`.
    fn dof_map_rows(
        &self,
        map: &matrix_market::DofMap,
        dp: &Path,
    ) -> Result<Vec<Option<usize>>, StructureError> {
        let mut rows = Vec::new();
        for (i, p) in self.points.iter().enumerate() {
            let key = format!("structure.points[{i}].node");
            let node = p.node.ok_or_else(|| {
                StructureError::rule(key.clone(), format!("is missing (point '{}')", p.name))
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
        Ok(rows)
    }

    /// The modal structure of the reduced model: f_k = ω_k / 2π, undamped, each point's shape
    /// values from its row (zero for a fixed dof).
    fn point_shapes(&self, basis: &ModalBasis, rows: &[Option<usize>]) -> ModalStructure {
        ModalStructure {
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
                .zip(rows)
                .map(|(p, r)| ModalPoint {
                    name: p.name.clone(),
                    shape: match r {
                        Some(r) => basis.shapes.row(*r).iter().copied().collect(),
                        None => vec![0.0; basis.omega_rad_s.len()], // fixed dof
                    },
                })
                .collect(),
        }
    }

    /// The `[structure.damping]` section applied to the modes: one ratio, per-mode ratios, then
    /// Rayleigh damping.
    fn apply_damping(&self, modal: &mut ModalStructure) {
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
    }
}

/// Modal input (`[structure.modal]`) taken as given: one damping ratio per frequency.
fn given_modes(m: &ModalSpec) -> Result<BuiltStructure, StructureError> {
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
    Ok(BuiltStructure {
        modal: s,
        total_mass_kg: None,
        dof_count: None,
        solver: None,
    })
}

/// More dof than the dense solver takes ([`DENSE_MAX_DOF`]) is an error.
fn check_dense_limit(n: usize) -> Result<(), StructureError> {
    if n > DENSE_MAX_DOF {
        Err(StructureError::DenseLimit {
            dofs: n,
            max: DENSE_MAX_DOF,
        })
    } else {
        Ok(())
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
