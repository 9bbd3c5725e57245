//! Built-in finite elements [D Eq. 3.19]: 3D beams (Euler–Bernoulli or Timoshenko), linear hex8
//! solids, lumped point masses with rigid offsets, grounded springs and fixed dof. Every node has
//! six dof ($u_x, u_y, u_z, \theta_x, \theta_y, \theta_z$); dof that carry neither stiffness nor
//! mass (rotations of solid-only nodes) and fixed dof are removed at assembly.

pub mod beam;
pub mod hex8;
pub mod plate;

use crate::sparse::SparseError;
use crate::sparse::SymmetricCsr;
use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};

pub use beam::BeamSection;
pub use hex8::SolidMaterial;

/// Errors of the finite-element models: invalid properties, degenerate elements, bad node
/// indices.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FeError {
    /// The model has no nodes.
    #[error("FE model has no nodes")]
    NoNodes,
    /// An element or point mass refers to a node that does not exist.
    #[error("{item}: node {node} does not exist ({nodes} nodes)")]
    NoSuchNode {
        /// `beam`, `solid` or `point mass`.
        item: &'static str,
        /// The node index (0-based).
        node: usize,
        /// Nodes of the model.
        nodes: usize,
    },
    /// An error of one element.
    #[error("{kind} {index}: {error}")]
    Element {
        /// `beam` or `solid`.
        kind: &'static str,
        /// The element's index (0-based).
        index: usize,
        /// The element's error.
        error: Box<FeError>,
    },
    /// A point mass is negative or not finite.
    #[error("point mass at node {node}: mass must be ≥ 0")]
    PointMass {
        /// The node (0-based).
        node: usize,
    },
    /// A beam-section property is not finite and positive.
    #[error("beam section: {name} must be finite and > 0, got {value}")]
    Section {
        /// The property.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// The shear coefficient of a Timoshenko section is not positive.
    #[error("beam section: shear_coefficient must be > 0, got {value}")]
    ShearCoefficient {
        /// Its value.
        value: f64,
    },
    /// A beam element has zero (or non-finite) length.
    #[error("beam element of zero length")]
    ZeroLength,
    /// The orientation vector of a beam is parallel to its axis.
    #[error("beam orientation vector {orientation:?} is parallel to the element axis")]
    ParallelOrientation {
        /// The orientation vector.
        orientation: [f64; 3],
    },
    /// A hex8 element is singular at its centre.
    #[error("hex8: singular centre Jacobian")]
    SingularCentreJacobian,
    /// A hex8 element is inverted or degenerate at a Gauss point.
    #[error("hex8: non-positive Jacobian determinant {determinant:e} (check node order)")]
    NonPositiveJacobian {
        /// The determinant.
        determinant: f64,
    },
    /// A hex8 Jacobian is singular at a Gauss point.
    #[error("hex8: singular Jacobian")]
    SingularJacobian,
    /// The incompatible-mode block of a hex8 element is singular.
    #[error("hex8: singular incompatible-mode block")]
    SingularIncompatibleModes,
    /// A plate property is out of range: `plate.key: message`.
    #[error("plate.{key}: {message}")]
    Plate {
        /// The key (`length_m`, `poisson_ratio`, `elements_x, elements_y`).
        key: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The sparse assembly failed.
    #[error(transparent)]
    Sparse(#[from] SparseError),
}

/// One nodal degree of freedom.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dof {
    /// Translation along x.
    Ux,
    /// Translation along y.
    Uy,
    /// Translation along z.
    Uz,
    /// Rotation about x.
    Rx,
    /// Rotation about y.
    Ry,
    /// Rotation about z.
    Rz,
}

impl Dof {
    /// All six dof in node order.
    pub const ALL: [Dof; 6] = [Dof::Ux, Dof::Uy, Dof::Uz, Dof::Rx, Dof::Ry, Dof::Rz];
    /// Translations.
    pub const TRANSLATIONS: [Dof; 3] = [Dof::Ux, Dof::Uy, Dof::Uz];

    /// Position within the node's six dof.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Parses ANSYS/Abaqus-style names: `UX`, `UY`, `UZ`, `ROTX`/`RX`, … or `1`–`6`.
    pub fn parse(s: &str) -> Option<Dof> {
        Some(match s.trim().to_ascii_uppercase().as_str() {
            "UX" | "U1" | "1" => Dof::Ux,
            "UY" | "U2" | "2" => Dof::Uy,
            "UZ" | "U3" | "3" => Dof::Uz,
            "ROTX" | "RX" | "UR1" | "4" => Dof::Rx,
            "ROTY" | "RY" | "UR2" | "5" => Dof::Ry,
            "ROTZ" | "RZ" | "UR3" | "6" => Dof::Rz,
            _ => return None,
        })
    }
}

/// A two-node beam element.
#[derive(Debug, Clone, PartialEq)]
pub struct BeamElement {
    /// Node indices.
    pub nodes: [usize; 2],
    /// Section and material.
    pub section: BeamSection,
    /// Vector in the local x–y plane (defines the section orientation).
    pub orientation: [f64; 3],
}

/// A hex8 solid element.
#[derive(Debug, Clone, PartialEq)]
pub struct SolidElement {
    /// Node indices in hex8 order (see [`hex8`]).
    pub nodes: [usize; 8],
    /// Material.
    pub material: SolidMaterial,
    /// Use incompatible bending modes.
    pub incompatible_modes: bool,
}

/// A rigid lumped mass attached to a node, possibly with an offset (rigid attachment of a
/// damper container, sensor or end mass).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    /// Node the mass is rigidly attached to.
    pub node: usize,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Rotary inertia about the mass centre along global x, y, z, kg·m².
    pub inertia_kg_m2: [f64; 3],
    /// Position of the mass centre relative to the node, m.
    pub offset_m: [f64; 3],
}

/// A spring from a node dof to ground (elastic support).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundSpring {
    /// Node.
    pub node: usize,
    /// Dof.
    pub dof: Dof,
    /// Stiffness, N/m (translation) or N·m/rad (rotation).
    pub stiffness: f64,
}

/// A finite element model.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FeModel {
    /// Node coordinates, m.
    pub nodes: Vec<[f64; 3]>,
    /// Beam elements.
    pub beams: Vec<BeamElement>,
    /// Solid elements.
    pub solids: Vec<SolidElement>,
    /// Point masses.
    pub point_masses: Vec<PointMass>,
    /// Springs to ground.
    pub springs: Vec<GroundSpring>,
    /// Fixed (zero) dof.
    pub fixed: Vec<(usize, Dof)>,
}

/// Assembled matrices on the active dof.
#[derive(Debug, Clone)]
pub struct Assembled {
    /// Stiffness matrix K, N/m.
    pub stiffness: DMatrix<f64>,
    /// Mass matrix M, kg.
    pub mass: DMatrix<f64>,
    /// (node, dof) of each row.
    pub dofs: Vec<(usize, Dof)>,
}

/// Sparse assembled matrices on the active dof.
#[derive(Debug, Clone)]
pub struct AssembledSparse {
    /// Stiffness matrix K, N/m.
    pub stiffness: SymmetricCsr,
    /// Mass matrix M, kg.
    pub mass: SymmetricCsr,
    /// (node, dof) of each row.
    pub dofs: Vec<(usize, Dof)>,
}

impl AssembledSparse {
    /// Row of a (node, dof), if active.
    pub fn row(&self, node: usize, dof: Dof) -> Option<usize> {
        self.dofs.iter().position(|&d| d == (node, dof))
    }
}

impl Assembled {
    /// Row of a (node, dof), if active.
    pub fn row(&self, node: usize, dof: Dof) -> Option<usize> {
        self.dofs.iter().position(|&d| d == (node, dof))
    }
}

impl FeModel {
    /// A straight beam from `start` to `end` meshed with `elements` equal elements; returns
    /// the model and the node indices along the beam.
    pub fn straight_beam(
        start: [f64; 3],
        end: [f64; 3],
        elements: usize,
        section: BeamSection,
        orientation: [f64; 3],
    ) -> Self {
        let mut m = FeModel::default();
        m.add_beam_line(start, end, elements, section, orientation);
        m
    }

    /// Appends a meshed straight beam; returns its node indices (new nodes; the first one is
    /// merged with an existing node at the same position).
    pub fn add_beam_line(
        &mut self,
        start: [f64; 3],
        end: [f64; 3],
        elements: usize,
        section: BeamSection,
        orientation: [f64; 3],
    ) -> Vec<usize> {
        let n = elements.max(1);
        let a = Vector3::from(start);
        let b = Vector3::from(end);
        let mut ids = Vec::with_capacity(n + 1);
        for i in 0..=n {
            let p = a + (b - a) * (i as f64 / n as f64);
            ids.push(self.node_at([p.x, p.y, p.z]));
        }
        for w in ids.windows(2) {
            self.beams.push(BeamElement {
                nodes: [w[0], w[1]],
                section,
                orientation,
            });
        }
        ids
    }

    /// Index of the node at `p` (within 1e-9 m), created if missing.
    pub fn node_at(&mut self, p: [f64; 3]) -> usize {
        if let Some(i) = self.find_node(p, 1e-9) {
            return i;
        }
        self.nodes.push(p);
        self.nodes.len() - 1
    }

    /// The node nearest to `p` if it is within `tol_m`.
    pub fn find_node(&self, p: [f64; 3], tol_m: f64) -> Option<usize> {
        let q = Vector3::from(p);
        self.nodes
            .iter()
            .enumerate()
            .map(|(i, x)| (i, (Vector3::from(*x) - q).norm()))
            .filter(|(_, d)| *d <= tol_m)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// The node nearest to `p`.
    pub fn nearest_node(&self, p: [f64; 3]) -> Option<usize> {
        self.find_node(p, f64::INFINITY)
    }

    /// A block `nx × ny × nz` of hex8 elements spanning the box `origin + [0, size]`.
    pub fn add_solid_block(
        &mut self,
        origin: [f64; 3],
        size: [f64; 3],
        cells: [usize; 3],
        material: SolidMaterial,
        incompatible_modes: bool,
    ) {
        let [nx, ny, nz] = cells.map(|c| c.max(1));
        let mut id = vec![0usize; (nx + 1) * (ny + 1) * (nz + 1)];
        let at = |i: usize, j: usize, k: usize| (k * (ny + 1) + j) * (nx + 1) + i;
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    let p = [
                        origin[0] + size[0] * i as f64 / nx as f64,
                        origin[1] + size[1] * j as f64 / ny as f64,
                        origin[2] + size[2] * k as f64 / nz as f64,
                    ];
                    id[at(i, j, k)] = self.node_at(p);
                }
            }
        }
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    self.solids.push(SolidElement {
                        nodes: [
                            id[at(i, j, k)],
                            id[at(i + 1, j, k)],
                            id[at(i + 1, j + 1, k)],
                            id[at(i, j + 1, k)],
                            id[at(i, j, k + 1)],
                            id[at(i + 1, j, k + 1)],
                            id[at(i + 1, j + 1, k + 1)],
                            id[at(i, j + 1, k + 1)],
                        ],
                        material,
                        incompatible_modes,
                    });
                }
            }
        }
    }

    /// Fixes the given dof of a node.
    pub fn fix(&mut self, node: usize, dofs: &[Dof]) {
        for &d in dofs {
            if !self.fixed.contains(&(node, d)) {
                self.fixed.push((node, d));
            }
        }
    }

    /// Fixes the given dof at every node (e.g. a planar model).
    pub fn fix_all_nodes(&mut self, dofs: &[Dof]) {
        for n in 0..self.nodes.len() {
            self.fix(n, dofs);
        }
    }

    /// Total mass (beams, solids, point masses), kg.
    pub fn total_mass_kg(&self) -> f64 {
        let beams: f64 = self
            .beams
            .iter()
            .map(|b| {
                let l = (Vector3::from(self.nodes[b.nodes[1]])
                    - Vector3::from(self.nodes[b.nodes[0]]))
                .norm();
                b.section.density_kg_m3 * b.section.area_m2 * l
            })
            .sum();
        let solids: f64 = self
            .solids
            .iter()
            .map(|s| {
                let x = s.nodes.map(|n| self.nodes[n]);
                let (_, m) = hex8::matrices(&x, &s.material, false).unwrap_or_default();
                (0..8)
                    .map(|a| (0..8).map(|c| m[(3 * a, 3 * c)]).sum::<f64>())
                    .sum::<f64>()
            })
            .sum();
        beams + solids + self.point_masses.iter().map(|p| p.mass_kg).sum::<f64>()
    }

    /// Element contributions to K and M [D Eq. 3.19] as (row, column, value) triplets on the
    /// full 6-dof-per-node numbering (duplicates to be summed).
    ///
    /// # Errors
    /// Invalid node indices, degenerate elements or invalid properties.
    #[allow(clippy::type_complexity)]
    fn triplets(&self) -> Result<(Vec<(usize, usize, f64)>, Vec<(usize, usize, f64)>), FeError> {
        if self.nodes.is_empty() {
            return Err(FeError::NoNodes);
        }
        let check = |i: usize, what: &'static str| {
            if i >= self.nodes.len() {
                Err(FeError::NoSuchNode {
                    item: what,
                    node: i,
                    nodes: self.nodes.len(),
                })
            } else {
                Ok(())
            }
        };
        let mut k = Vec::new();
        let mut m = Vec::new();
        for (e, b) in self.beams.iter().enumerate() {
            let in_beam = |s: FeError| FeError::Element {
                kind: "beam",
                index: e,
                error: Box::new(s),
            };
            b.section.validate().map_err(in_beam)?;
            check(b.nodes[0], "beam")?;
            check(b.nodes[1], "beam")?;
            let (ke, me) = beam::global_matrices(
                &b.section,
                self.nodes[b.nodes[0]],
                self.nodes[b.nodes[1]],
                b.orientation,
            )
            .map_err(in_beam)?;
            for a in 0..2 {
                for c in 0..2 {
                    for i in 0..6 {
                        for j in 0..6 {
                            let (r, s) = (6 * b.nodes[a] + i, 6 * b.nodes[c] + j);
                            k.push((r, s, ke[(6 * a + i, 6 * c + j)]));
                            m.push((r, s, me[(6 * a + i, 6 * c + j)]));
                        }
                    }
                }
            }
        }
        for (e, s) in self.solids.iter().enumerate() {
            for &nd in &s.nodes {
                check(nd, "solid")?;
            }
            let x = s.nodes.map(|nd| self.nodes[nd]);
            let (ke, me) =
                hex8::matrices(&x, &s.material, s.incompatible_modes).map_err(|msg| {
                    FeError::Element {
                        kind: "solid",
                        index: e,
                        error: Box::new(msg),
                    }
                })?;
            for a in 0..8 {
                for c in 0..8 {
                    for i in 0..3 {
                        for j in 0..3 {
                            let (r, t) = (6 * s.nodes[a] + i, 6 * s.nodes[c] + j);
                            k.push((r, t, ke[(3 * a + i, 3 * c + j)]));
                            m.push((r, t, me[(3 * a + i, 3 * c + j)]));
                        }
                    }
                }
            }
        }
        for p in &self.point_masses {
            check(p.node, "point mass")?;
            if !(p.mass_kg >= 0.0 && p.mass_kg.is_finite()) {
                return Err(FeError::PointMass { node: p.node });
            }
            // Rigid offset r: u_p = u_n + θ × r = u_n − [r]× θ.
            let r = p.offset_m;
            let rx = nalgebra::Matrix3::new(0.0, -r[2], r[1], r[2], 0.0, -r[0], -r[1], r[0], 0.0);
            let mut t = nalgebra::SMatrix::<f64, 3, 6>::zeros();
            t.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&nalgebra::Matrix3::identity());
            t.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-rx));
            let mut mp = t.transpose() * t * p.mass_kg;
            for i in 0..3 {
                mp[(3 + i, 3 + i)] += p.inertia_kg_m2[i];
            }
            for i in 0..6 {
                for j in 0..6 {
                    m.push((6 * p.node + i, 6 * p.node + j, mp[(i, j)]));
                }
            }
        }
        for s in &self.springs {
            check(s.node, "spring")?;
            let i = 6 * s.node + s.dof.index();
            k.push((i, i, s.stiffness));
        }
        for &(nd, _) in &self.fixed {
            check(nd, "support")?;
        }
        Ok((k, m))
    }

    /// Active dof: not fixed and with stiffness or mass on the diagonal. Returns (dofs, the
    /// full-numbering row of each, full row → active index).
    #[allow(clippy::type_complexity)]
    fn active_dofs(
        &self,
        k: &[(usize, usize, f64)],
        m: &[(usize, usize, f64)],
    ) -> (Vec<(usize, Dof)>, Vec<usize>, Vec<Option<usize>>) {
        let n = 6 * self.nodes.len();
        let diag = |t: &[(usize, usize, f64)]| {
            let mut d = vec![0.0f64; n];
            for &(i, j, v) in t {
                if i == j {
                    d[i] += v;
                }
            }
            d
        };
        let (dk, dm) = (diag(k), diag(m));
        let scale_k = dk.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let scale_m = dm.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut dofs = Vec::new();
        let mut rows = Vec::new();
        let mut map = vec![None; n];
        for nd in 0..self.nodes.len() {
            for d in Dof::ALL {
                let i = 6 * nd + d.index();
                if self.fixed.contains(&(nd, d)) {
                    continue;
                }
                if dk[i].abs() <= 1e-14 * scale_k && dm[i].abs() <= 1e-14 * scale_m {
                    continue;
                }
                map[i] = Some(rows.len());
                dofs.push((nd, d));
                rows.push(i);
            }
        }
        (dofs, rows, map)
    }

    /// Assembles K and M [D Eq. 3.19] and removes fixed dof and dof without stiffness and mass
    /// (dense; see [`FeModel::assemble_sparse`] for large models).
    ///
    /// # Errors
    /// Invalid node indices, degenerate elements or invalid properties.
    pub fn assemble(&self) -> Result<Assembled, FeError> {
        let (k, m) = self.triplets()?;
        let (dofs, rows, map) = self.active_dofs(&k, &m);
        let na = rows.len();
        let dense = |t: &[(usize, usize, f64)]| {
            let mut a = DMatrix::<f64>::zeros(na, na);
            for &(i, j, v) in t {
                if let (Some(r), Some(c)) = (map[i], map[j]) {
                    a[(r, c)] += v;
                }
            }
            a
        };
        Ok(Assembled {
            stiffness: dense(&k),
            mass: dense(&m),
            dofs,
        })
    }

    /// Sparse assembly on the active dof (as [`FeModel::assemble`]).
    ///
    /// # Errors
    /// As [`FeModel::assemble`].
    pub fn assemble_sparse(&self) -> Result<AssembledSparse, FeError> {
        let (k, m) = self.triplets()?;
        let (dofs, rows, map) = self.active_dofs(&k, &m);
        let sel = |t: &[(usize, usize, f64)]| {
            let v: Vec<(usize, usize, f64)> = t
                .iter()
                .filter_map(|&(i, j, v)| Some((map[i]?, map[j]?, v)))
                .filter(|e| e.2 != 0.0)
                .collect();
            SymmetricCsr::from_triplets(rows.len(), &v, false)
        };
        Ok(AssembledSparse {
            stiffness: sel(&k)?,
            mass: sel(&m)?,
            dofs,
        })
    }
}
