//! The structural model: hex8 mesh + Saint Venant–Kirchhoff material + boundary conditions
//! (clamped nodes = homogeneous Dirichlet, dead surface tractions with time ramps = Neumann,
//! paper eq. 10) + body force, assembled into the semi-discrete eq. 11
//! $\mathbf M\ddot{\mathbf d} + \mathbf F_{int}(\mathbf d) - \mathbf F_{ext} = 0$.
//! Constrained dofs are eliminated; matrices live on the free dofs.

use super::mesh::{Face, HexMesh};
use super::svk::{self, GaussPoint, SvkMaterial};
use crate::SymmetricCsr;

/// Time history of a load factor.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadRamp {
    /// Linear increase from 0 to 1 over this time \[s\] (paper Sect. 2.4: 5 ms).
    pub rise_s: f64,
    /// Time held at 1 after the rise \[s\] (paper: 1 ms); afterwards the load is removed.
    /// `inf` keeps it on.
    pub hold_s: f64,
}

impl LoadRamp {
    /// Load factor at time `t` \[s\].
    pub fn factor(&self, t: f64) -> f64 {
        if t < 0.0 {
            0.0
        } else if t < self.rise_s {
            t / self.rise_s
        } else if t <= self.rise_s + self.hold_s {
            1.0
        } else {
            0.0
        }
    }
}

/// A dead (reference-configuration) traction on a set of boundary faces.
#[derive(Debug, Clone)]
pub struct SurfaceLoad {
    /// Loaded faces.
    pub faces: Vec<Face>,
    /// Traction vector \[Pa\] at load factor 1.
    pub traction_pa: [f64; 3],
    /// Time history.
    pub ramp: LoadRamp,
}

/// Mass matrix kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassKind {
    /// Consistent mass $\int\rho N_aN_b\,dV$.
    Consistent,
    /// Row-sum lumped mass.
    Lumped,
}

/// Kinematics of the solid.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kinematics {
    /// Finite deformation: total-Lagrangian Saint Venant–Kirchhoff, Green–Lagrange strains
    /// (P eq. 8–11; the paper's model).
    #[default]
    Finite,
    /// Small deformation: $\mathbf f_{int} = \mathbf K_0\mathbf d$ with the reference
    /// stiffness, strain energy $\tfrac12\mathbf d^\top\mathbf K_0\mathbf d$ (the first-order
    /// term of the finite model; the modified-Newton tangent is then exact, so a step needs
    /// one solve instead of the ≈ 4 that the rotations of a bending beam cost the finite model).
    Linear,
}

/// Assembled structure on the free dofs.
pub struct Structure {
    /// The mesh.
    pub mesh: HexMesh,
    /// Material.
    pub material: SvkMaterial,
    /// Gauss-point data.
    pub gps: Vec<[GaussPoint; 8]>,
    /// Global dof (3·node + dir) → free index, `usize::MAX` if clamped.
    pub free: Vec<usize>,
    /// Free index → global dof.
    pub free_dofs: Vec<usize>,
    /// Mass matrix on the free dofs (pattern equal to the stiffness pattern).
    pub mass: SymmetricCsr,
    /// The mass matrix per free node (`mass` = `mass_nodal` ⊗ I₃, both kinds): the products
    /// with the mass matrix use it ([`Structure::mass_mul`]), a third of the entries of `mass`,
    /// whose pattern is the stiffness pattern so that effective matrices can be combined.
    pub mass_nodal: SymmetricCsr,
    /// Tangent stiffness at the reference configuration (free dofs).
    pub k0: SymmetricCsr,
    /// Surface loads.
    pub loads: Vec<SurfaceLoad>,
    /// Constant body-force vector (gravity) on all dofs \[N\].
    pub body_force: Vec<f64>,
    /// Per-element triplet positions are rebuilt on demand; the element dof lists.
    elem_free: Vec<[usize; 24]>,
    /// Scratch for element forces.
    scratch: Vec<[f64; 24]>,
    /// Finite or small deformation ([`Structure::set_kinematics`]).
    kinematics: Kinematics,
    /// Scratch of the small-deformation internal force: `d` and `K₀ d` on the free dofs.
    linear_scratch: (Vec<f64>, Vec<f64>),
}

impl Structure {
    /// Assembles mass and reference stiffness; `clamped` lists nodes with all three dofs fixed.
    ///
    /// # Panics
    /// If an element is degenerate.
    pub fn new(
        mesh: HexMesh,
        material: SvkMaterial,
        clamped: &[usize],
        mass_kind: MassKind,
        gravity_m_s2: [f64; 3],
    ) -> Self {
        let gps = svk::precompute(&mesh);
        let ndof = 3 * mesh.nodes.len();
        let mut fixed = vec![false; ndof];
        for &n in clamped {
            for i in 0..3 {
                fixed[3 * n + i] = true;
            }
        }
        let mut free = vec![usize::MAX; ndof];
        let mut free_dofs = Vec::new();
        for d in 0..ndof {
            if !fixed[d] {
                free[d] = free_dofs.len();
                free_dofs.push(d);
            }
        }
        let elem_free: Vec<[usize; 24]> = mesh
            .elements
            .iter()
            .map(|el| {
                let mut f = [0; 24];
                for a in 0..8 {
                    for i in 0..3 {
                        f[3 * a + i] = free[3 * el[a] + i];
                    }
                }
                f
            })
            .collect();
        let rho = material.density_kg_m3;
        let mut tm = Vec::with_capacity(mesh.elements.len() * 576);
        let mut tn = Vec::with_capacity(mesh.elements.len() * 64);
        let mut body_force = vec![0.0; ndof];
        for (e, g) in gps.iter().enumerate() {
            let me = svk::element_mass(g, rho);
            let ef = &elem_free[e];
            for a in 0..8 {
                let row_sum: f64 = me[a].iter().sum();
                // a clamped node has all three dofs fixed: free dofs come in node triples
                if ef[3 * a] != usize::MAX {
                    for b in 0..8 {
                        if ef[3 * b] == usize::MAX {
                            continue;
                        }
                        let v = match mass_kind {
                            MassKind::Consistent => me[a][b],
                            MassKind::Lumped if a == b => row_sum,
                            MassKind::Lumped => 0.0,
                        };
                        tn.push((ef[3 * a] / 3, ef[3 * b] / 3, v));
                    }
                }
                for i in 0..3 {
                    body_force[3 * mesh.elements[e][a] + i] += row_sum * gravity_m_s2[i];
                }
                for b in 0..8 {
                    for i in 0..3 {
                        for j in 0..3 {
                            let (r, c) = (ef[3 * a + i], ef[3 * b + j]);
                            if r == usize::MAX || c == usize::MAX {
                                continue;
                            }
                            let v = match mass_kind {
                                MassKind::Consistent if i == j => me[a][b],
                                MassKind::Lumped if i == j && a == b => row_sum,
                                _ => 0.0,
                            };
                            tm.push((r, c, v));
                        }
                    }
                }
            }
        }
        let nfree = free_dofs.len();
        let mass = SymmetricCsr::assemble(nfree, tm);
        let mass_nodal = SymmetricCsr::assemble(nfree / 3, tn);
        let mut s = Structure {
            mesh,
            material,
            gps,
            free,
            free_dofs,
            mass,
            mass_nodal,
            k0: SymmetricCsr::default(),
            loads: Vec::new(),
            body_force,
            elem_free,
            scratch: Vec::new(),
            kinematics: Kinematics::Finite,
            linear_scratch: (Vec::new(), Vec::new()),
        };
        let zero = vec![0.0; ndof];
        s.k0 = s.tangent(&zero);
        s
    }

    /// `y = M x` on the free dofs, by nodes (equal to `mass.mul`, which adds the zero
    /// entries between directions too). Rows in parallel, each in the same order for any
    /// thread count.
    pub fn mass_mul(&self, x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        let m = &self.mass_nodal;
        y[..3 * m.n]
            .par_chunks_mut(3)
            .with_min_len(512)
            .enumerate()
            .for_each(|(a, y)| {
                let mut s = [0.0; 3];
                for k in m.row_ptr[a]..m.row_ptr[a + 1] {
                    let (v, b) = (m.values[k], 3 * m.col_idx[k]);
                    s[0] += v * x[b];
                    s[1] += v * x[b + 1];
                    s[2] += v * x[b + 2];
                }
                y.copy_from_slice(&s);
            });
    }

    /// `xᵀ M x` for `x` on all dofs (clamped entries ignored), without copying it to the free
    /// dofs; the same sums in the same order as `mass.quad` of the free part.
    pub fn mass_quad_all(&self, x: &[f64]) -> f64 {
        let (m, g) = (&self.mass_nodal, &self.free_dofs);
        let mut s = 0.0;
        for a in 0..m.n {
            let mut t = [0.0; 3];
            for k in m.row_ptr[a]..m.row_ptr[a + 1] {
                let (v, b) = (m.values[k], 3 * m.col_idx[k]);
                for i in 0..3 {
                    t[i] += v * x[g[b + i]];
                }
            }
            for i in 0..3 {
                s += x[g[3 * a + i]] * t[i];
            }
        }
        s
    }

    /// Number of dofs (3 per node, including clamped ones).
    pub fn n_dof(&self) -> usize {
        3 * self.mesh.nodes.len()
    }

    /// Finite or small deformation (default finite, the paper's model).
    pub fn kinematics(&self) -> Kinematics {
        self.kinematics
    }

    /// Chooses finite or small deformation for the internal force and the tangent.
    pub fn set_kinematics(&mut self, k: Kinematics) {
        self.kinematics = k;
    }

    /// `K₀ d` (all dofs, zero at clamped ones) and $\tfrac12\mathbf d^\top\mathbf K_0\mathbf d$
    /// on the free dofs (same sums in the same order for any thread count).
    fn linear_internal_force(&mut self, d: &[f64], out: &mut [f64]) -> f64 {
        let nf = self.free_dofs.len();
        let (df, kd) = &mut self.linear_scratch;
        df.resize(nf, 0.0);
        kd.resize(nf, 0.0);
        for (x, &g) in df.iter_mut().zip(&self.free_dofs) {
            *x = d[g];
        }
        self.k0.mul(df, kd);
        out.iter_mut().for_each(|x| *x = 0.0);
        let mut energy = 0.0;
        for (k, &g) in self.free_dofs.iter().enumerate() {
            out[g] = kd[k];
            energy += df[k] * kd[k];
        }
        0.5 * energy
    }

    /// Tangent stiffness at displacement `d` (all dofs) on the free dofs (with
    /// [`Kinematics::Linear`] the reference stiffness at every `d`).
    pub fn tangent(&self, d: &[f64]) -> SymmetricCsr {
        if self.kinematics == Kinematics::Linear && self.k0.n == self.free_dofs.len() {
            return self.k0.clone();
        }
        let (lam, mu) = self.material.lame();
        let mut t = Vec::with_capacity(self.mesh.elements.len() * 576);
        for (e, el) in self.mesh.elements.iter().enumerate() {
            let mut u = [[0.0; 3]; 8];
            for a in 0..8 {
                u[a] = [d[3 * el[a]], d[3 * el[a] + 1], d[3 * el[a] + 2]];
            }
            let ke = svk::element_tangent(&self.gps[e], &u, lam, mu);
            let ef = &self.elem_free[e];
            for r in 0..24 {
                if ef[r] == usize::MAX {
                    continue;
                }
                for c in 0..24 {
                    if ef[c] != usize::MAX {
                        t.push((ef[r], ef[c], ke[r * 24 + c]));
                    }
                }
            }
        }
        SymmetricCsr::assemble(self.free_dofs.len(), t)
    }

    /// Internal forces (all dofs) and strain energy \[J\] at `d`.
    pub fn internal_force(&mut self, d: &[f64], out: &mut [f64]) -> f64 {
        if self.kinematics == Kinematics::Linear {
            return self.linear_internal_force(d, out);
        }
        svk::internal_force(
            &self.mesh,
            &self.gps,
            d,
            &self.material,
            &mut self.scratch,
            out,
        )
    }

    /// External force at time `t` (surface loads + body force), all dofs \[N\].
    pub fn external_force(&self, t: f64, out: &mut [f64]) {
        out.copy_from_slice(&self.body_force);
        for load in &self.loads {
            let s = load.ramp.factor(t);
            if s == 0.0 {
                continue;
            }
            for f in &load.faces {
                let w = face_weights(&self.mesh.nodes, f);
                for (a, &n) in f.nodes.iter().enumerate() {
                    for i in 0..3 {
                        out[3 * n + i] += s * w[a] * load.traction_pa[i];
                    }
                }
            }
        }
    }

    /// Total mass \[kg\].
    pub fn total_mass(&self) -> f64 {
        svk::element_volumes(&self.mesh).iter().sum::<f64>() * self.material.density_kg_m3
    }
}

/// $\int_A N_a\,dA$ of a bilinear quad face (2 × 2 Gauss) \[m²\].
pub fn face_weights(nodes: &[[f64; 3]], f: &Face) -> [f64; 4] {
    let x: [[f64; 3]; 4] = [
        nodes[f.nodes[0]],
        nodes[f.nodes[1]],
        nodes[f.nodes[2]],
        nodes[f.nodes[3]],
    ];
    let g = 0.577_350_269_189_625_8;
    let mut w = [0.0; 4];
    for (s, t) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
        let qp = super::quad::point(&x, s, t);
        let n = qp.n;
        let c = super::quad::cross(qp.dxds, qp.dxdt);
        let j = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        for k in 0..4 {
            w[k] += n[k] * j;
        }
    }
    w
}
