//! Dirichlet–Neumann partitioned DEM–FEM coupling (paper Sect. 2.3, Algorithm 1) on the
//! pdamp-dem engine.
//!
//! The particles are the Dirichlet partition: for given interface displacements
//! $\mathbf d^{ps}$ the particle operator $\mathcal P$ returns the contact forces. They live in a
//! [`pdamp_dem::World`] whose body 0 carries the interface $\Gamma^{ps}$ as a deformable
//! triangle-mesh wall: its vertices are the interface nodes (every bilinear face split into two
//! triangles), moved to $\mathbf X + \mathbf d^{ps}$ before the step, so that the wall contacts
//! of the step see the mean surface velocity $(\mathbf d^{ps}_{n+1}-\mathbf d_n)/\Delta t$ (the
//! wall work then matches the trapezoidal interface work on the structure). The reaction on the
//! structure is the contact forces split onto the vertices of the touched feature with the
//! barycentric weights of the contact point — consistent nodal loads, the triangle counterpart
//! of eq. 15. The structure is the Neumann partition: $\mathcal S^{-1}$ solves the
//! generalized-α step under those loads. Fixed-point iterations with Aitken relaxation
//! (Küttler & Wall 2008, paper ref. \[34\]) run until eq. 16,
//! $|\Delta\mathbf d^{ps}_{n+1,k+1}|/(\Delta t\sqrt{n^{ps}_{dof}}) < \epsilon$.
//!
//! Within one step the particle–particle forces do not depend on $\mathbf d^{ps}$ (velocity
//! Verlet positions are explicit), so an iteration repeats only the particle–wall pass, from the
//! wall contact history at the start of the step ([`pdamp_dem::World::repeat_wall_pass`]).
//! Contacts with several faces (edges, corners, coplanar neighbours) follow the mesh wall's
//! rules of pdamp-dem: one contact per locally closest feature, no double counting.

use pdamp_dem::wall_repeat::WallRepeatError;
use pdamp_dem::walls::{Geometry, MeshError, TriMesh};
use pdamp_dem::{BodyState, Motion, RigidBody, Vec3, World, WorldState};

use crate::bed::{PowderBed, WALL_MATERIAL, powder_world};
use crate::fe::{Aabb, Dynamics, DynamicsError, DynamicsState, Face, Structure};
use crate::health::{self, HealthError, Symptom};
use crate::law::PowderLaw;

/// Steps between the overlap checks of the coupled run (positions, velocities and the
/// container are checked every step).
pub const OVERLAP_CHECK_EVERY: u64 = 100;

/// The body of the world that carries the interface, and its mesh wall.
const BODY: usize = 0;
const WALL: usize = 0;

/// The interface $\Gamma^{ps}$: boundary faces of the structure in contact with the powder.
#[derive(Debug, Clone)]
pub struct Interface {
    /// Interface faces (normals pointing into the cavity).
    pub faces: Vec<Face>,
    /// Unique interface nodes, ascending.
    pub nodes: Vec<usize>,
}

impl Interface {
    /// Builds the interface from faces; collects their nodes.
    pub fn new(faces: Vec<Face>) -> Self {
        let mut nodes: Vec<usize> = faces.iter().flat_map(|f| f.nodes).collect();
        nodes.sort_unstable();
        nodes.dedup();
        Self { faces, nodes }
    }
    /// $n^{ps}_{dof}$.
    pub fn n_dof(&self) -> usize {
        3 * self.nodes.len()
    }
}

/// Coupling settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingSettings {
    /// ε of eq. 16 [m/s] (paper: 1e-3).
    pub tolerance: f64,
    /// Maximum fixed-point iterations per step.
    pub max_iterations: usize,
    /// Aitken relaxation (otherwise fixed relaxation `initial_relaxation`).
    pub aitken: bool,
    /// First relaxation factor of each step.
    pub initial_relaxation: f64,
    /// Newton tolerance of the structure's step inside each coupling iteration: largest
    /// residual entry over the largest force term; `None`: that of
    /// [`pdamp_fem::solid::NewtonSettings`] (1e-10). (An option, so that a scenario without it
    /// keeps its digest: TOML leaves `None` out.)
    #[serde(default)]
    pub structure_tolerance: Option<f64>,
}

impl Default for CouplingSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-3,
            max_iterations: 50,
            aitken: true,
            initial_relaxation: 1.0,
            structure_tolerance: None,
        }
    }
}

/// Errors of the coupled step.
#[derive(Debug, thiserror::Error)]
pub enum CoupleError {
    /// Structural solve failed.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// A health check failed (non-finite state, a particle outside the cavity, a runaway
    /// overlap), see [`crate::health`].
    #[error(transparent)]
    Health(#[from] Box<HealthError>),
    /// The interface mesh could not be built or moved (a degenerate face).
    #[error("interface mesh: {0}")]
    Mesh(#[from] MeshError),
    /// The repeated wall pass of an iteration failed (a defect: it is always prepared).
    #[error("coupling iteration: {0}")]
    Repeat(#[from] WallRepeatError),
    /// A checkpoint state does not fit the scenario.
    #[error("{0}")]
    State(String),
    /// The particles' state does not fit the world (pdamp-dem).
    #[error(transparent)]
    WorldState(#[from] pdamp_dem::state::StateError),
    /// The contact law of a checkpoint state is out of range.
    #[error(transparent)]
    Law(#[from] crate::error::ParameterError),
    /// Fixed point did not converge.
    #[error(
        "coupling did not converge at t = {t_s} s: eq. 16 measure {measure:e} after {iterations} iterations"
    )]
    NotConverged {
        /// Time \[s\].
        t_s: f64,
        /// Final value of the eq. 16 measure [m/s].
        measure: f64,
        /// Iterations.
        iterations: usize,
    },
}

/// Energies of the coupled system \[J\].
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CoupledEnergy {
    /// Structure kinetic energy.
    pub structure_kinetic_j: f64,
    /// Structure strain energy.
    pub structure_strain_j: f64,
    /// Particle kinetic (translational + rotational).
    pub particle_kinetic_j: f64,
    /// Particle gravitational potential.
    pub particle_potential_j: f64,
    /// Elastic energy of particle–particle and particle–wall springs.
    pub contact_elastic_j: f64,
    /// Dissipated in contacts (dashpots, sliding).
    pub dissipated_j: f64,
    /// Work of the structural loads and body forces (not the interface forces).
    pub load_work_j: f64,
    /// Stored + dissipated − load work (constant for an exact scheme).
    pub balance_j: f64,
}

/// The interface as a triangle mesh at the reference configuration (each bilinear face
/// split into two triangles along its diagonal 0–2, normals into the cavity) and the
/// structure's node of every mesh vertex.
fn interface_mesh(
    structure: &Structure,
    interface: &Interface,
) -> Result<(TriMesh, Vec<usize>), CoupleError> {
    let nodes = &structure.mesh.nodes;
    let local: std::collections::HashMap<usize, u32> = interface
        .nodes
        .iter()
        .enumerate()
        .map(|(k, &a)| (a, k as u32))
        .collect();
    let vertices: Vec<Vec3> = interface
        .nodes
        .iter()
        .map(|&a| Vec3::new(nodes[a][0], nodes[a][1], nodes[a][2]))
        .collect();
    let mut triangles = Vec::with_capacity(2 * interface.faces.len());
    for f in &interface.faces {
        let q = f.nodes.map(|a| local[&a]);
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
    }
    let mesh = TriMesh::from_indexed(vertices, triangles)?;
    // The mesh keeps the vertices it uses, welded: find each one's node by its coordinates.
    let by_position: std::collections::HashMap<[u64; 3], usize> = interface
        .nodes
        .iter()
        .map(|&a| (nodes[a].map(f64::to_bits), a))
        .collect();
    let vertex_node = mesh
        .vertices()
        .iter()
        .map(|v| {
            by_position
                .get(&[v.x, v.y, v.z].map(f64::to_bits))
                .copied()
                .ok_or_else(|| {
                    CoupleError::State(format!(
                        "interface: two nodes share the position {:?} m (welded into one mesh \
                         vertex); the interface must not touch itself",
                        [v.x, v.y, v.z]
                    ))
                })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((mesh, vertex_node))
}

/// The world of a coupled run without its particles: materials and contact law of `law`,
/// gravity, time step, and the interface mesh wall on a fixed body (when the interface has
/// faces). Returns the world and the structure's node of every mesh vertex.
fn empty_world(
    structure: &Structure,
    interface: &Interface,
    law: &PowderLaw,
    density_kg_m3: f64,
    gravity: [f64; 3],
    dt: f64,
) -> Result<(World, Vec<usize>), CoupleError> {
    let mut w = powder_world(law, density_kg_m3, gravity, dt);
    let mut vertex_node = Vec::new();
    if !interface.faces.is_empty() {
        let (mesh, map) = interface_mesh(structure, interface)?;
        vertex_node = map;
        w.add_body(
            RigidBody::new(
                "structure",
                BodyState::at_rest(Vec3::zeros()),
                Motion::Fixed,
            )
            .with_wall("interface", Geometry::Mesh(mesh), WALL_MATERIAL),
        );
    }
    w.set_wall_pass_repeatable(true);
    Ok((w, vertex_node))
}

/// Wall time of the coupled steps by partition, s: the particles (drift, forces, wall passes
/// and their repetitions, kicks, health checks), the structural solves, and the coupling
/// itself (nodal loads, residuals, relaxation, interface work, commit).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepTiming {
    /// Particles (pdamp-dem), s.
    pub particles_wall_time_s: f64,
    /// Structural solves (generalized-α Newton), s.
    pub structure_wall_time_s: f64,
    /// The coupling's own work, s.
    pub coupling_wall_time_s: f64,
}

/// The dynamic state of a [`Coupled`] system between steps, for checkpoints: the structure's
/// time integration, the particles (pdamp-dem state with contact histories), the interface mesh
/// where the last step left it, the interface force and work, the fixed-point work vectors and
/// the iteration counters. The structure, the interface and the factorization are rebuilt from
/// the scenario.
#[derive(Clone, serde::Serialize, serde::Deserialize)]
pub struct CoupledState {
    /// Structure.
    pub dynamics: DynamicsState,
    /// Particles.
    pub world: WorldState,
    /// Contact law and particle density.
    pub law: PowderLaw,
    density_kg_m3: f64,
    /// Interface mesh vertices (m).
    vertices: Vec<[f64; 3]>,
    counters: [u64; 4],
    f_ps: Vec<f64>,
    interface_work_j: f64,
    dk: Vec<f64>,
    f_trial: Vec<f64>,
    r_prev: Vec<f64>,
    r_cur: Vec<f64>,
    omega: f64,
}

/// The coupled particle–structure system.
pub struct Coupled {
    /// Structure.
    pub structure: Structure,
    /// Its time integration.
    pub dynamics: Dynamics,
    /// The particles; body 0 carries the interface as a deformable mesh wall.
    pub world: World,
    /// The powder's contact law.
    pub law: PowderLaw,
    /// Density of the particles (kg/m³).
    pub density_kg_m3: f64,
    /// The interface.
    pub interface: Interface,
    /// Settings.
    pub settings: CouplingSettings,
    /// Fixed-point iterations of the last step.
    pub last_iterations: usize,
    /// Sum of iterations over all steps.
    pub total_iterations: u64,
    /// Largest iteration count of a step.
    pub max_iterations_seen: usize,
    /// Steps done.
    pub steps: u64,
    /// Interface force on the structure at the committed state (all dofs) \[N\].
    pub f_ps: Vec<f64>,
    /// Work of the interface forces on the structure \[J\].
    pub interface_work_j: f64,
    /// The closed container of the particles in the reference configuration (the cavity);
    /// when set, a particle centre outside it (enlarged by the largest interface displacement)
    /// stops the run with [`Symptom::Escaped`]. `None` (default): open interfaces such as a
    /// plate.
    pub container: Option<Aabb>,
    /// Wall time of the steps of this process by partition (not in checkpoints).
    pub timing: StepTiming,
    /// Structure node of every mesh vertex, and the vertices (last iterate), m.
    vertex_node: Vec<usize>,
    vertices: Vec<Vec3>,
    nodal: Vec<Vec3>,
    dk: Vec<f64>,
    f_trial: Vec<f64>,
    r_prev: Vec<f64>,
    r_cur: Vec<f64>,
    omega: f64,
}

impl Coupled {
    /// Couples the particles of `bed` (inside the cavity; their law, gravity, velocities,
    /// spins and particle–particle contacts) with the structure over `interface`, at the
    /// structure's time step.
    pub fn new(
        structure: Structure,
        dynamics: Dynamics,
        bed: PowderBed,
        interface: Interface,
        settings: CouplingSettings,
    ) -> Result<Self, CoupleError> {
        let g = bed.world.gravity_m_s2;
        let (mut world, vertex_node) = empty_world(
            &structure,
            &interface,
            &bed.law,
            bed.density_kg_m3,
            [g.x, g.y, g.z],
            dynamics.dt,
        )?;
        world.adopt_particles(&bed.world.save_state())?;
        world.initialize();
        let mut c = Self::assemble(
            structure,
            dynamics,
            world,
            bed.law,
            bed.density_kg_m3,
            interface,
        );
        c.settings = settings;
        if let Some(t) = settings.structure_tolerance {
            c.dynamics.newton.tolerance = t;
        }
        c.vertex_node = vertex_node;
        c.vertices = c.reference_vertices();
        Ok(c)
    }

    fn assemble(
        structure: Structure,
        dynamics: Dynamics,
        world: World,
        law: PowderLaw,
        density_kg_m3: f64,
        interface: Interface,
    ) -> Self {
        let ndof = structure.n_dof();
        Self {
            structure,
            dynamics,
            world,
            law,
            density_kg_m3,
            interface,
            settings: CouplingSettings::default(),
            last_iterations: 0,
            total_iterations: 0,
            max_iterations_seen: 0,
            steps: 0,
            f_ps: vec![0.0; ndof],
            interface_work_j: 0.0,
            container: None,
            timing: StepTiming::default(),
            vertex_node: Vec::new(),
            vertices: Vec::new(),
            nodal: Vec::new(),
            dk: vec![0.0; ndof],
            f_trial: vec![0.0; ndof],
            r_prev: Vec::new(),
            r_cur: Vec::new(),
            omega: 1.0,
        }
    }

    /// The mesh vertices at the reference configuration.
    fn reference_vertices(&self) -> Vec<Vec3> {
        let nodes = &self.structure.mesh.nodes;
        self.vertex_node
            .iter()
            .map(|&a| Vec3::from(nodes[a]))
            .collect()
    }

    /// The number of particles.
    pub fn particles(&self) -> usize {
        self.world.particles.len()
    }

    /// Total particle mass, kg.
    pub fn particle_mass_kg(&self) -> f64 {
        self.world.particles.total_mass()
    }

    /// The wall force on particle `i` in the last evaluation, N.
    pub fn wall_force(&self, i: usize) -> [f64; 3] {
        let f: Vec3 = self.world.wall_contacts()[i].iter().map(|s| s.force).sum();
        [f.x, f.y, f.z]
    }

    /// The state for a checkpoint (see [`CoupledState`]).
    pub fn save_state(&self) -> CoupledState {
        CoupledState {
            dynamics: self.dynamics.save_state(),
            world: self.world.save_state(),
            law: self.law,
            density_kg_m3: self.density_kg_m3,
            vertices: self.vertices.iter().map(|v| [v.x, v.y, v.z]).collect(),
            counters: [
                self.last_iterations as u64,
                self.total_iterations,
                self.max_iterations_seen as u64,
                self.steps,
            ],
            f_ps: self.f_ps.clone(),
            interface_work_j: self.interface_work_j,
            dk: self.dk.clone(),
            f_trial: self.f_trial.clone(),
            r_prev: self.r_prev.clone(),
            r_cur: self.r_cur.clone(),
            omega: self.omega,
        }
    }

    /// Rebuilds a system from a checkpoint state (see [`CoupledState`]); `structure`,
    /// `dynamics` (its state is replaced) and `interface` come from the scenario. A state that
    /// does not fit them is refused.
    pub fn from_state(
        structure: Structure,
        mut dynamics: Dynamics,
        interface: Interface,
        settings: CouplingSettings,
        st: CoupledState,
    ) -> Result<Self, CoupleError> {
        let bad = |what: &str| CoupleError::State(what.to_string());
        dynamics.restore_state(st.dynamics)?;
        st.law.validate("coupling state: law.")?;
        let ndof = structure.n_dof();
        if [&st.f_ps, &st.dk, &st.f_trial]
            .iter()
            .any(|v| v.len() != ndof)
            || !(st.density_kg_m3 > 0.0 && st.density_kg_m3.is_finite())
        {
            return Err(bad(
                "coupling state does not match the structure (degrees of freedom or density)",
            ));
        }
        let (mut world, vertex_node) = empty_world(
            &structure,
            &interface,
            &st.law,
            st.density_kg_m3,
            [0.0; 3], // the state's gravity is restored below
            dynamics.dt,
        )?;
        if st.vertices.len() != vertex_node.len() {
            return Err(bad("coupling state: the interface mesh does not match"));
        }
        let vertices: Vec<Vec3> = st.vertices.iter().map(|v| Vec3::from(*v)).collect();
        if !vertices.is_empty() {
            world.move_wall_vertices(BODY, WALL, &vertices)?;
        }
        world.set_particles_of(&st.world)?;
        world.restore_state(st.world)?;
        let mut c = Self::assemble(
            structure,
            dynamics,
            world,
            st.law,
            st.density_kg_m3,
            interface,
        );
        let [last, total, max, steps] = st.counters;
        c.settings = settings;
        if let Some(t) = settings.structure_tolerance {
            c.dynamics.newton.tolerance = t;
        }
        c.vertex_node = vertex_node;
        c.vertices = vertices;
        c.last_iterations = last as usize;
        c.total_iterations = total;
        c.max_iterations_seen = max as usize;
        c.steps = steps;
        c.f_ps = st.f_ps;
        c.interface_work_j = st.interface_work_j;
        c.dk = st.dk;
        c.f_trial = st.f_trial;
        c.r_prev = st.r_prev;
        c.r_cur = st.r_cur;
        c.omega = st.omega;
        Ok(c)
    }

    /// Moves the mesh to the interface displacements `self.dk` (the first move of a step, or
    /// a replaced one).
    fn move_interface(&mut self, again: bool) -> Result<(), CoupleError> {
        if self.vertex_node.is_empty() {
            return Ok(());
        }
        let nodes = &self.structure.mesh.nodes;
        for (v, &a) in self.vertices.iter_mut().zip(&self.vertex_node) {
            *v = Vec3::new(
                nodes[a][0] + self.dk[3 * a],
                nodes[a][1] + self.dk[3 * a + 1],
                nodes[a][2] + self.dk[3 * a + 2],
            );
        }
        if again {
            self.world
                .move_wall_vertices_again(BODY, WALL, &self.vertices)?;
        } else {
            self.world.move_wall_vertices(BODY, WALL, &self.vertices)?;
        }
        Ok(())
    }

    /// The particle operator's reaction: the nodal loads of the last wall pass into `f_trial`.
    fn gather_interface_loads(&mut self) -> Result<(), CoupleError> {
        if self.vertex_node.is_empty() {
            return Ok(());
        }
        self.world.wall_nodal_forces(BODY, WALL, &mut self.nodal)?;
        for (f, &a) in self.nodal.iter().zip(&self.vertex_node) {
            self.f_trial[3 * a] = f.x;
            self.f_trial[3 * a + 1] = f.y;
            self.f_trial[3 * a + 2] = f.z;
        }
        Ok(())
    }

    /// Sum of the particle wall forces and of the nodal interface forces of the committed step
    /// (interface equilibrium: their sum vanishes since the barycentric weights sum to one)
    /// \[N\].
    pub fn interface_force_sums(&self) -> ([f64; 3], [f64; 3]) {
        let fp: Vec3 = self
            .world
            .wall_contacts()
            .iter()
            .flat_map(|s| s.iter().map(|s| s.force))
            .sum();
        let mut fs = [0.0; 3];
        for &a in &self.interface.nodes {
            for k in 0..3 {
                fs[k] += self.f_ps[3 * a + k];
            }
        }
        ([fp.x, fp.y, fp.z], fs)
    }

    /// One coupled time step (Algorithm 1); returns the number of fixed-point iterations.
    pub fn step(&mut self) -> Result<usize, CoupleError> {
        let dt = self.dynamics.dt;
        let nps = self.interface.n_dof();
        // predictor of the interface displacements
        {
            let d = &self.dynamics;
            for &a in &self.interface.nodes {
                for k in 0..3 {
                    let g = 3 * a + k;
                    self.dk[g] = d.d[g] + dt * d.v[g];
                }
            }
        }
        let clock = std::time::Instant::now();
        let mut lap = clock;
        let mut split = |t: &mut f64| {
            let now = std::time::Instant::now();
            *t += (now - lap).as_secs_f64();
            lap = now;
        };
        let mut timing = self.timing;
        split(&mut timing.coupling_wall_time_s);
        self.move_interface(false)?;
        self.world.step_deferred();
        self.check_particles()?;
        if self.steps.is_multiple_of(OVERLAP_CHECK_EVERY) {
            health::check_world_overlaps(&self.world).map_err(|s| self.failure(s))?;
        }
        split(&mut timing.particles_wall_time_s);
        self.r_prev.resize(nps, 0.0);
        self.r_cur.resize(nps, 0.0);
        let mut omega = self.settings.initial_relaxation;
        let mut k = 0;
        loop {
            self.gather_interface_loads()?;
            split(&mut timing.coupling_wall_time_s);
            let solved = self
                .dynamics
                .solve(&mut self.structure, Some(&self.f_trial), k == 0);
            split(&mut timing.structure_wall_time_s);
            if let Err(e) = solved {
                // a diverged structure (or particles) is a health failure, not a solver one
                if self.dynamics.d1.iter().any(|x| !x.is_finite())
                    || self.f_trial.iter().any(|x| !x.is_finite())
                {
                    return Err(self.structure_failure().into());
                }
                return Err(e.into());
            }
            k += 1;
            let mut norm2 = 0.0;
            for (q, &a) in self.interface.nodes.iter().enumerate() {
                for c in 0..3 {
                    let g = 3 * a + c;
                    let r = self.dynamics.d1[g] - self.dk[g];
                    self.r_cur[3 * q + c] = r;
                    norm2 += r * r;
                }
            }
            let measure = norm2.sqrt() / (dt * (nps.max(1) as f64).sqrt());
            if !measure.is_finite() {
                return Err(self.structure_failure().into());
            }
            if measure < self.settings.tolerance {
                break;
            }
            if k >= self.settings.max_iterations {
                return Err(CoupleError::NotConverged {
                    t_s: self.dynamics.t + dt,
                    measure,
                    iterations: k,
                });
            }
            if self.settings.aitken && k > 1 {
                let mut num = 0.0;
                let mut den = 0.0;
                for q in 0..nps {
                    let dr = self.r_cur[q] - self.r_prev[q];
                    num += self.r_prev[q] * dr;
                    den += dr * dr;
                }
                if den > 0.0 {
                    omega = -omega * num / den;
                }
            }
            for (q, &a) in self.interface.nodes.iter().enumerate() {
                for c in 0..3 {
                    self.dk[3 * a + c] += omega * self.r_cur[3 * q + c];
                }
            }
            std::mem::swap(&mut self.r_prev, &mut self.r_cur);
            self.move_interface(true)?;
            split(&mut timing.coupling_wall_time_s);
            self.world.repeat_wall_pass()?;
            split(&mut timing.particles_wall_time_s);
        }
        self.omega = omega;
        // commit: interface work (trapezoidal), structure, the particles' second half kick
        let mut w = 0.0;
        for &a in &self.interface.nodes {
            for c in 0..3 {
                let g = 3 * a + c;
                w += 0.5
                    * (self.dynamics.d1[g] - self.dynamics.d[g])
                    * (self.f_trial[g] + self.f_ps[g]);
            }
        }
        self.interface_work_j += w;
        self.dynamics.commit();
        std::mem::swap(&mut self.f_ps, &mut self.f_trial);
        split(&mut timing.coupling_wall_time_s);
        self.world.complete_step();
        split(&mut timing.particles_wall_time_s);
        self.timing = timing;
        self.last_iterations = k;
        self.total_iterations += k as u64;
        self.max_iterations_seen = self.max_iterations_seen.max(k);
        self.steps += 1;
        Ok(k)
    }

    /// The health error of `symptom` now.
    fn failure(&self, symptom: Symptom) -> Box<HealthError> {
        Box::new(HealthError::of_world(
            self.world.time_s,
            "coupled run",
            symptom,
            &self.world,
            &self.law,
        ))
    }

    /// Health of the particles after the drift of a step: finite states and centres inside
    /// the container (if set); the overlaps are checked every [`OVERLAP_CHECK_EVERY`] steps.
    fn check_particles(&self) -> Result<(), Box<HealthError>> {
        let margin = self.container.map(|b| {
            let dmax = self
                .interface
                .nodes
                .iter()
                .flat_map(|&a| (0..3).map(move |k| 3 * a + k))
                .map(|g| self.dynamics.d[g].abs())
                .fold(0.0, f64::max);
            let size = (0..3).map(|k| b.max[k] - b.min[k]).fold(0.0, f64::max);
            (b, dmax + 1e-9 * size)
        });
        health::check_world_particles(&self.world, margin.as_ref().map(|(b, m)| (b, *m)))
            .map_err(|(_, s)| self.failure(s))
    }

    /// The health error of a non-finite structural state (first non-finite trial dof).
    fn structure_failure(&self) -> Box<HealthError> {
        if let Err((_, s)) = health::check_world_particles(&self.world, None) {
            return self.failure(s);
        }
        let node = self
            .dynamics
            .d1
            .iter()
            .position(|x| !x.is_finite())
            .map_or(0, |g| g / 3);
        let element = self
            .structure
            .mesh
            .elements
            .iter()
            .position(|el| el.contains(&node));
        self.failure(Symptom::NonFiniteStructure { node, element })
    }

    /// Energies of the committed state.
    pub fn energy(&self) -> CoupledEnergy {
        let l = &self.world.ledger;
        let mut e = CoupledEnergy {
            structure_kinetic_j: self.dynamics.kinetic_energy(&self.structure),
            structure_strain_j: self.dynamics.strain_energy,
            particle_kinetic_j: l.kinetic_j,
            particle_potential_j: l.potential_j,
            contact_elastic_j: l.elastic_j,
            dissipated_j: l.dissipated_j(),
            load_work_j: self.dynamics.external_work - self.interface_work_j,
            balance_j: 0.0,
        };
        e.balance_j = e.structure_kinetic_j
            + e.structure_strain_j
            + e.particle_kinetic_j
            + e.particle_potential_j
            + e.contact_elastic_j
            + e.dissipated_j
            - e.load_work_j;
        e
    }
}
