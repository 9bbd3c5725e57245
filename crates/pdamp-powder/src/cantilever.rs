//! The cantilever study of paper Sect. 2.4: a 20 × 20 × 132 mm³ beam (clamped bottom face,
//! z = 0) with an 18 × 18 × 110 mm³ cavity starting 2 mm above the clamp (1 mm walls), filled
//! with powder at packing density ϕ, bent by a surface load q on the face x = 0 (q = 0.1 N/mm²,
//! resultant 264 N) ramped over 5 ms, held 1 ms and released; the tip displacement (top centre
//! point, x) decays freely. Scenario files: `examples/powder_cantilever_*.toml`, keys in
//! `docs/powder.md`.
//!
//! [`run_in_dir`] checkpoints a run (preparation and coupled run) into `DIR/checkpoint.bin`
//! and continues it with `resume`; the outputs then equal those of an uninterrupted run byte
//! for byte (wall times aside), see docs/reliability.md.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use pdamp_io::checkpoint::{self as ck, CheckpointHeader, CheckpointTimer};
pub use pdamp_io::run::RunOptions;
use serde::{Deserialize, Serialize};

use crate::couple::{Coupled, CoupledEnergy, CoupledState, CouplingSettings, Interface};
use crate::damping::{self, TableOneRatios};
use crate::dem::{LogNormal, PowderLaw};
use crate::fe::{
    self, Aabb, BoxMeshDivisions, Dynamics, GenAlpha, HexMesh, LoadRamp, MassKind, Rayleigh,
    Structure, SurfaceLoad, SvkMaterial,
};
use crate::prep::{PrepReport, PrepSettings, Preparation};

fn d_len() -> f64 {
    0.132
}
fn d_width() -> f64 {
    0.020
}
fn d_wall() -> f64 {
    0.001
}
fn d_cav_len() -> f64 {
    0.110
}
fn d_cav_off() -> f64 {
    0.002
}
fn d_rho_inf() -> f64 {
    0.8
}
fn d_mass() -> MassKind {
    MassKind::Consistent
}

/// The beam (paper Sect. 2.4, Table A.3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamSpec {
    /// Beam length [m] (0.132).
    #[serde(default = "d_len")]
    pub length_m: f64,
    /// Outer width of the square section [m] (0.020).
    #[serde(default = "d_width")]
    pub width_m: f64,
    /// Wall thickness around the cavity [m] (0.001).
    #[serde(default = "d_wall")]
    pub wall_thickness_m: f64,
    /// Cavity length [m] (0.110).
    #[serde(default = "d_cav_len")]
    pub cavity_length_m: f64,
    /// Distance of the cavity from the clamped face [m] (0.002).
    #[serde(default = "d_cav_off")]
    pub cavity_offset_m: f64,
    /// Material (Table A.3: 175 GPa, 0.27, 8000 kg/m³).
    #[serde(default = "d_mat")]
    pub material: SvkMaterial,
    /// Element size in the walls [m].
    pub wall_element_m: f64,
    /// Element size across the cavity [m].
    pub core_element_m: f64,
    /// Element size along the beam [m].
    pub length_element_m: f64,
    /// Mass matrix (`consistent` or `lumped`).
    #[serde(default = "d_mass")]
    pub mass: MassKind,
    /// Spectral radius ρ∞ of generalized-α (Table A.3: 0.8).
    #[serde(default = "d_rho_inf")]
    pub rho_inf: f64,
    /// Optional Rayleigh damping (off by default).
    #[serde(default)]
    pub rayleigh: Rayleigh,
}

fn d_mat() -> SvkMaterial {
    SvkMaterial::STEEL_316L
}

impl BeamSpec {
    /// Cavity box [m].
    pub fn cavity(&self) -> Aabb {
        let t = self.wall_thickness_m;
        Aabb {
            min: [t, t, self.cavity_offset_m],
            max: [
                self.width_m - t,
                self.width_m - t,
                self.cavity_offset_m + self.cavity_length_m,
            ],
        }
    }
    /// The hex8 mesh.
    pub fn mesh(&self) -> HexMesh {
        HexMesh::box_with_cavity(
            [self.width_m, self.width_m, self.length_m],
            Some(self.cavity()),
            BoxMeshDivisions {
                wall_element_m: self.wall_element_m,
                core_element_m: self.core_element_m,
                length_element_m: self.length_element_m,
            },
        )
    }
    fn validate(&self) -> Result<(), String> {
        let pos = |v: f64, k: &str| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(format!("beam.{k}: must be positive"))
            }
        };
        pos(self.length_m, "length_m")?;
        pos(self.width_m, "width_m")?;
        pos(self.wall_thickness_m, "wall_thickness_m")?;
        pos(self.cavity_length_m, "cavity_length_m")?;
        pos(self.wall_element_m, "wall_element_m")?;
        pos(self.core_element_m, "core_element_m")?;
        pos(self.length_element_m, "length_element_m")?;
        pos(
            self.material.youngs_modulus_pa,
            "material.youngs_modulus_pa",
        )?;
        pos(self.material.density_kg_m3, "material.density_kg_m3")?;
        if !(-1.0..0.5).contains(&self.material.poisson_ratio) {
            return Err("beam.material.poisson_ratio: must be in [-1, 0.5)".into());
        }
        if 2.0 * self.wall_thickness_m >= self.width_m {
            return Err("beam.wall_thickness_m: must be less than half of width_m".into());
        }
        if !(self.cavity_offset_m > 0.0
            && self.cavity_offset_m + self.cavity_length_m < self.length_m)
        {
            return Err("beam.cavity_offset_m: cavity must lie strictly inside the beam (0 < offset, offset + cavity_length_m < length_m)".into());
        }
        if !(0.0..=1.0).contains(&self.rho_inf) {
            return Err("beam.rho_inf: must be in [0, 1]".into());
        }
        Ok(())
    }
}

/// The surface load on the face x = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Pressure q [Pa] (0.1 N/mm² = 1e5 Pa), pushing in +x.
    pub pressure_pa: f64,
    /// Linear rise time [s] (5e-3).
    pub rise_s: f64,
    /// Hold time [s] (1e-3), then released.
    pub hold_s: f64,
}

fn d_ref_d50() -> f64 {
    1e-3
}
fn d_density() -> f64 {
    8000.0
}

/// The powder (paper Table A.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PowderSpec {
    /// Size distribution; cut-offs default to Table A.2 scaled to `d50_m`.
    pub d50_m: f64,
    /// σ of ln D (0.2707).
    #[serde(default = "d_sigma")]
    pub sigma: f64,
    /// Particle density [kg/m³] (8000).
    #[serde(default = "d_density")]
    pub density_kg_m3: f64,
    /// Contact law at the reference size `reference_d50_m` (Table A.2 values for 1 mm).
    pub law: PowderLaw,
    /// Size the law parameters refer to [m]; with f = d50_m / reference_d50_m the stiffness is
    /// scaled k' = f k and the surface energy γ' = f² γ (coarse-graining, Sect. 2.4/3.6).
    #[serde(default = "d_ref_d50")]
    pub reference_d50_m: f64,
    /// Preparation.
    pub prep: PrepSettings,
}

fn d_sigma() -> f64 {
    0.2707
}

impl PowderSpec {
    /// Size distribution.
    pub fn psd(&self) -> LogNormal {
        LogNormal {
            sigma: self.sigma,
            ..LogNormal::paper(self.d50_m)
        }
    }
    /// Law after coarse-graining.
    pub fn scaled_law(&self) -> PowderLaw {
        self.law.coarse_grained(self.d50_m / self.reference_d50_m)
    }
}

fn d_grav() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

/// Run control.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Simulated time after preparation [s] (paper: 0.03).
    pub duration_s: f64,
    /// Time step of DEM and FE [s] (paper: 2.5e-6 for D50 = 1 mm).
    pub time_step_s: f64,
    /// Gravity [m/s²] in beam coordinates (clamp at z = 0): [0,0,-9.81] upright (default),
    /// [0,0,9.81] upside down, [-9.81,0,0] horizontal with gravity along the excitation.
    #[serde(default = "d_grav")]
    pub gravity_m_s2: [f64; 3],
    /// Coupling settings (ε of eq. 16 = 1e-3).
    #[serde(default)]
    pub coupling: CouplingSettings,
    /// Sampling interval of tip.csv [s] (0 = every step).
    #[serde(default)]
    pub output_interval_s: f64,
}

/// A cantilever scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CantileverScenario {
    /// Beam.
    pub beam: BeamSpec,
    /// Load.
    pub load: LoadSpec,
    /// Powder; absent = empty beam.
    pub powder: Option<PowderSpec>,
    /// Run.
    pub run: RunSpec,
}

impl CantileverScenario {
    /// Parses and validates TOML; errors name the key.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let s: Self = toml::from_str(text).map_err(|e| e.to_string())?;
        s.validate()?;
        Ok(s)
    }

    /// Checks value ranges; the error names the key.
    pub fn validate(&self) -> Result<(), String> {
        self.beam.validate()?;
        if !(self.load.pressure_pa.is_finite()) {
            return Err("load.pressure_pa: must be finite".into());
        }
        if !(self.load.rise_s > 0.0) {
            return Err("load.rise_s: must be positive".into());
        }
        if !(self.load.hold_s >= 0.0) {
            return Err("load.hold_s: must be ≥ 0".into());
        }
        if !(self.run.duration_s > 0.0) {
            return Err("run.duration_s: must be positive".into());
        }
        if !(self.run.time_step_s > 0.0 && self.run.time_step_s < self.run.duration_s) {
            return Err("run.time_step_s: must be positive and below duration_s".into());
        }
        if !(self.run.coupling.tolerance > 0.0) {
            return Err("run.coupling.tolerance: must be positive".into());
        }
        if self.run.coupling.max_iterations == 0 {
            return Err("run.coupling.max_iterations: must be ≥ 1".into());
        }
        if let Some(p) = &self.powder {
            p.law.validate("powder.law.")?;
            p.psd().validate("powder.")?;
            if !(p.density_kg_m3 > 0.0) {
                return Err("powder.density_kg_m3: must be positive".into());
            }
            if !(p.reference_d50_m > 0.0) {
                return Err("powder.reference_d50_m: must be positive".into());
            }
            if !(p.prep.packing_density > 0.0 && p.prep.packing_density < 0.74) {
                return Err("powder.prep.packing_density: must be in (0, 0.74)".into());
            }
            if !(p.prep.settling_gravity_factor >= 1.0) {
                return Err("powder.prep.settling_gravity_factor: must be ≥ 1".into());
            }
            if !(p.prep.plate_speed_m_s > 0.0) {
                return Err("powder.prep.plate_speed_m_s: must be positive".into());
            }
            if !(p.prep.relax_time_s >= 0.0 && p.prep.max_settling_time_s > 0.0) {
                return Err(
                    "powder.prep.relax_time_s / max_settling_time_s: must be ≥ 0 / positive".into(),
                );
            }
            let gap = self.beam.width_m - 2.0 * self.beam.wall_thickness_m;
            if p.psd().d_max_m * 1.02 > gap {
                return Err("powder.d50_m: particles larger than the cavity".into());
            }
        }
        Ok(())
    }
}

/// Builds the structure of the scenario: mesh, clamp (z = 0), pressure on x = 0, gravity.
pub fn build_structure(beam: &BeamSpec, load: &LoadSpec, gravity: [f64; 3]) -> (Structure, usize) {
    let mesh = beam.mesh();
    let tol = 1e-9;
    let clamped = mesh.nodes_on_plane(2, 0.0, tol);
    let faces = mesh.boundary_faces();
    let loaded = HexMesh::faces_on_plane(&faces, &mesh.nodes, 0, 0.0, tol);
    let tip = mesh.nearest_node([0.5 * beam.width_m, 0.5 * beam.width_m, beam.length_m]);
    let mut s = Structure::new(mesh, beam.material, &clamped, beam.mass, gravity);
    s.loads.push(SurfaceLoad {
        faces: loaded,
        traction_pa: [load.pressure_pa, 0.0, 0.0],
        ramp: LoadRamp {
            rise_s: load.rise_s,
            hold_s: load.hold_s,
        },
    });
    (s, tip)
}

/// Interface faces: boundary faces with all nodes on the cavity box surface.
pub fn cavity_interface(s: &Structure, cavity: &Aabb) -> Interface {
    let tol = 1e-9;
    let faces = s
        .mesh
        .boundary_faces()
        .into_iter()
        .filter(|f| {
            f.nodes
                .iter()
                .all(|&n| cavity.contains(s.mesh.nodes[n], tol))
        })
        .collect();
    Interface::new(faces)
}

/// Time series and results of a run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CantileverResult {
    /// Sample times [s].
    #[serde(skip)]
    pub time_s: Vec<f64>,
    /// Tip displacement in x [m].
    #[serde(skip)]
    pub tip_m: Vec<f64>,
    /// Coupling iterations of the sampled steps.
    #[serde(skip)]
    pub iterations: Vec<f64>,
    /// Energy samples.
    #[serde(skip)]
    pub energy: Vec<(f64, CoupledEnergy)>,
    /// Table-1 damping ratios.
    pub damping: TableOneRatios,
    /// Largest tip displacement before release [m].
    pub max_tip_before_release_m: f64,
    /// Preparation report (None for an empty beam).
    pub prep: Option<PrepReport>,
    /// Particles.
    pub particles: usize,
    /// Structural dofs / elements.
    pub structure_dofs: usize,
    /// Elements.
    pub elements: usize,
    /// Interface dofs $n^{ps}_{dof}$.
    pub interface_dofs: usize,
    /// Steps.
    pub steps: u64,
    /// Mean fixed-point iterations per step.
    pub mean_iterations: f64,
    /// Largest iteration count of a step.
    pub max_iterations: usize,
    /// Wall time of the coupled run (without preparation) [s].
    pub wall_time_s: f64,
    /// Mass of the structure and of the powder [kg].
    pub structure_mass_kg: f64,
    /// Powder mass [kg].
    pub powder_mass_kg: f64,
    /// Largest |balance − balance(0)| / max stored energy over the run.
    pub energy_closure: f64,
}

/// Kind tag of `pdamp powder run` checkpoints.
pub const CHECKPOINT_KIND: &str = "powder-run";

/// Digest identifying a scenario in checkpoints (FNV-1a 64 of its canonical TOML).
pub fn scenario_digest(sc: &CantileverScenario) -> Result<String, String> {
    let text = toml::to_string(sc).map_err(|e| format!("scenario: {e}"))?;
    Ok(ck::digest(text.as_bytes()))
}

/// What a checkpoint holds: the preparation in progress, or the coupled run in progress
/// (which starts with the prepared powder), or nothing once the outputs are written.
#[derive(Serialize, Deserialize)]
enum Phase {
    Preparing(Box<Preparation>),
    Running(Box<RunState>),
    Finished,
}

/// The coupled run after step `step`: the complete dynamic state and the results so far.
#[derive(Serialize, Deserialize)]
struct RunState {
    step: u64,
    coupled: CoupledState,
    prep: Option<PrepReport>,
    time_s: Vec<f64>,
    tip_m: Vec<f64>,
    iterations: Vec<f64>,
    energy: Vec<(f64, CoupledEnergy)>,
    max_tip_before_release_m: f64,
    wall_time_s: f64,
}

/// Where and how often a run checkpoints.
struct Checkpointing {
    path: PathBuf,
    header: CheckpointHeader,
    interval_s: f64,
}

impl Checkpointing {
    fn save(&self, phase: &Phase) -> Result<(), String> {
        ck::save(&self.path, &self.header, phase)
    }
    fn interrupted(&self, time_s: f64) -> String {
        ck::Interrupted {
            time_s,
            path: self.path.clone(),
        }
        .to_string()
    }
}

/// Decodes a `pdamp powder run` checkpoint of any scenario and returns its phase and
/// simulated time [s] (for inspection and fuzzing; never panics).
pub fn inspect_checkpoint(bytes: &[u8]) -> Result<(&'static str, f64), String> {
    Ok(match ck::decode::<Phase>(bytes, CHECKPOINT_KIND, None)? {
        Phase::Preparing(p) => ("preparing", p.time_s()),
        Phase::Running(r) => ("running", r.coupled.dynamics.t),
        Phase::Finished => ("finished", f64::NAN),
    })
}

/// Runs the scenario (preparation + coupled run) without files. `progress(stage, fraction)`.
pub fn run(
    sc: &CantileverScenario,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, String> {
    sc.validate()?;
    run_core(sc, None, None, progress)
}

/// Runs the scenario and writes its outputs ([`write_outputs`]) into `dir`, checkpointing
/// into `DIR/checkpoint.bin` every `options.checkpoint_interval_s` of wall-clock time, once
/// the preparation is finished (unless the interval is 0) and on a stop request
/// ([`pdamp_io::checkpoint::request_stop`], the CLI's Ctrl-C/SIGTERM), which ends the run with
/// an error starting with [`pdamp_io::checkpoint::INTERRUPTED`]. With `options.resume` the run
/// continues from the checkpoint (a checkpoint of another scenario is refused) and the
/// outputs equal those of an uninterrupted run byte for byte, wall times aside; resuming a
/// finished run returns its summary.
pub fn run_in_dir(
    sc: &CantileverScenario,
    dir: &Path,
    options: RunOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, String> {
    sc.validate()?;
    let digest = scenario_digest(sc)?;
    let c = Checkpointing {
        path: dir.join(ck::CHECKPOINT_FILE),
        header: CheckpointHeader::new(CHECKPOINT_KIND, &digest),
        interval_s: options.checkpoint_interval_s,
    };
    let resumed: Option<Phase> = if options.resume {
        ck::load(&c.path, CHECKPOINT_KIND, &digest)?
    } else {
        None
    };
    if let Some(Phase::Finished) = resumed {
        let path = dir.join("summary.json");
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let js: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        return serde_json::from_value(js["result"].clone())
            .map_err(|e| format!("{}: {e}", path.display()));
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let r = run_core(sc, Some(&c), resumed, progress)?;
    write_outputs(dir, sc, &r)?;
    c.save(&Phase::Finished)?;
    Ok(r)
}

fn run_core(
    sc: &CantileverScenario,
    ckp: Option<&Checkpointing>,
    resumed: Option<Phase>,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, String> {
    let (mut s, tip) = build_structure(&sc.beam, &sc.load, sc.run.gravity_m_s2);
    let dt = sc.run.time_step_s;
    let cavity = sc.beam.cavity();
    let _stoppable = ckp.map(|_| ck::StoppableSection::enter());
    let mut timer = CheckpointTimer::new(ckp.map_or(0.0, |c| c.interval_s));
    let (mut preparing, mut running) = (None, None);
    match resumed {
        Some(Phase::Preparing(p)) => {
            p.check_consistency()?;
            preparing = Some(*p);
        }
        Some(Phase::Running(r)) => running = Some(*r),
        Some(Phase::Finished) | None => {}
    }
    // preparation (fresh, continued, or done before the checkpoint)
    let prepared = match (&running, &sc.powder) {
        (Some(_), _) => None,
        (None, Some(p)) => {
            let mut pr = preparing.take().unwrap_or_else(|| {
                Preparation::new(
                    cavity,
                    &p.psd(),
                    p.scaled_law(),
                    p.density_kg_m3,
                    dt,
                    &p.prep,
                )
            });
            let mut err = None;
            let flow = pr.run(progress, &mut |pr| {
                let Some(c) = ckp else {
                    return ControlFlow::Continue(());
                };
                let stop = ck::stop_requested();
                if stop || timer.due() {
                    if let Err(e) = c.save(&Phase::Preparing(Box::new(pr.snapshot()))) {
                        err = Some(e);
                        return ControlFlow::Break(());
                    }
                    if stop {
                        return ControlFlow::Break(());
                    }
                }
                ControlFlow::Continue(())
            });
            if let Some(e) = err {
                return Err(e);
            }
            if flow.is_break() {
                let c = ckp.ok_or("preparation stopped")?;
                return Err(c.interrupted(pr.time_s()));
            }
            let (pw, rep) = pr.finish();
            Some((pw, Some(rep)))
        }
        (None, None) => Some((
            crate::dem::Powder::new(
                PowderLaw::PAPER,
                Vec::new(),
                Vec::new(),
                8000.0,
                [0.0; 3],
                dt,
            ),
            None,
        )),
    };
    let n = s.n_dof();
    let dynamics = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(sc.beam.rho_inf),
        dt,
        vec![0.0; n],
        vec![0.0; n],
        sc.beam.rayleigh,
    )
    .map_err(|e| e.to_string())?;
    let interface = cavity_interface(&s, &cavity);
    let structure_mass = s.total_mass();
    let elements = s.mesh.elements.len();
    let nsteps = (sc.run.duration_s / dt).round() as u64;
    let result = |c: &Coupled, prep: Option<PrepReport>| CantileverResult {
        time_s: vec![0.0],
        tip_m: vec![0.0],
        iterations: vec![0.0],
        energy: vec![(0.0, c.energy())],
        damping: TableOneRatios::default(),
        max_tip_before_release_m: 0.0,
        prep,
        particles: c.powder.len(),
        structure_dofs: c.structure.n_dof(),
        elements,
        interface_dofs: c.interface.n_dof(),
        steps: nsteps,
        mean_iterations: 0.0,
        max_iterations: 0,
        wall_time_s: 0.0,
        structure_mass_kg: structure_mass,
        powder_mass_kg: c.powder.mass.iter().sum(),
        energy_closure: 0.0,
    };
    let (mut c, mut res, first) = match (running, prepared) {
        (Some(st), _) => {
            let c = Coupled::from_state(s, dynamics, interface, sc.run.coupling, st.coupled)?;
            let res = CantileverResult {
                time_s: st.time_s,
                tip_m: st.tip_m,
                iterations: st.iterations,
                energy: st.energy,
                max_tip_before_release_m: st.max_tip_before_release_m,
                wall_time_s: st.wall_time_s,
                ..result(&c, st.prep)
            };
            (c, res, st.step + 1)
        }
        (None, Some((mut powder, prep))) => {
            powder.gravity = sc.run.gravity_m_s2;
            let c = Coupled::new(s, dynamics, powder, interface, sc.run.coupling);
            let res = result(&c, prep);
            (c, res, 1)
        }
        (None, None) => return Err("internal: neither a prepared powder nor a checkpoint".into()),
    };
    let wall_before = res.wall_time_s;
    let clock = Instant::now();
    let wall = |clock: &Instant| wall_before + clock.elapsed().as_secs_f64();
    let state = |c: &Coupled, res: &CantileverResult, step: u64, wall_time_s: f64| {
        Phase::Running(Box::new(RunState {
            step,
            coupled: c.save_state(),
            prep: res.prep.clone(),
            time_s: res.time_s.clone(),
            tip_m: res.tip_m.clone(),
            iterations: res.iterations.clone(),
            energy: res.energy.clone(),
            max_tip_before_release_m: res.max_tip_before_release_m,
            wall_time_s,
        }))
    };
    // the prepared powder is checkpointed at once (preparation can take long)
    if let Some(cp) = ckp
        && first == 1
        && sc.powder.is_some()
        && cp.interval_s > 0.0
    {
        cp.save(&state(&c, &res, 0, wall(&clock)))?;
    }
    let every = ((sc.run.output_interval_s / dt).round() as u64).max(1);
    let e_every = (nsteps / 2000).max(1);
    let t_release = sc.load.rise_s + sc.load.hold_s;
    for q in first..=nsteps {
        let it = c.step().map_err(|e| e.to_string())?;
        let t = c.dynamics.t;
        let x = c.dynamics.d[3 * tip];
        if t <= t_release {
            res.max_tip_before_release_m = res.max_tip_before_release_m.max(x.abs());
        }
        if q % every == 0 {
            res.time_s.push(t);
            res.tip_m.push(x);
            res.iterations.push(it as f64);
        }
        if q % e_every == 0 || q == 1 {
            res.energy.push((t, c.energy()));
        }
        if q % 200 == 0 {
            progress("coupled run", q as f64 / nsteps as f64);
        }
        if let Some(cp) = ckp {
            let stop = ck::stop_requested();
            if stop || timer.due() {
                cp.save(&state(&c, &res, q, wall(&clock)))?;
                if stop {
                    return Err(cp.interrupted(t));
                }
            }
        }
    }
    res.wall_time_s = wall(&clock);
    res.mean_iterations = c.total_iterations as f64 / c.steps.max(1) as f64;
    res.max_iterations = c.max_iterations_seen;
    res.damping = damping::table_one(&res.time_s, &res.tip_m, t_release);
    let b0 = res.energy[1.min(res.energy.len() - 1)].1.balance_j; // after step 1: wall springs known
    let emax = res
        .energy
        .iter()
        .map(|(_, e)| {
            e.structure_kinetic_j
                + e.structure_strain_j
                + e.particle_kinetic_j
                + e.contact_elastic_j
        })
        .fold(1e-300, f64::max);
    res.energy_closure = res
        .energy
        .iter()
        .skip(1)
        .map(|(_, e)| (e.balance_j - b0).abs())
        .fold(0.0, f64::max)
        / emax;
    Ok(res)
}

/// Writes tip.csv, envelope.csv, energy.csv, the tip plot and (last) summary.json into `dir`.
pub fn write_outputs(
    dir: &Path,
    sc: &CantileverScenario,
    r: &CantileverResult,
) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let rows: Vec<[f64; 3]> = (0..r.time_s.len())
        .map(|i| [r.time_s[i], r.tip_m[i], r.iterations[i]])
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("tip.csv"),
        &["time_s", "tip_displacement_m", "coupling_iterations"],
        rows,
    )
    .map_err(|e| e.to_string())?;
    let t_rel = sc.load.rise_s + sc.load.hold_s;
    let ext = damping::local_extrema(&r.time_s, &r.tip_m, t_rel);
    let env: Vec<[f64; 2]> = ext
        .iter()
        .map(|&i| [r.time_s[i], r.tip_m[i].abs()])
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("envelope.csv"),
        &["time_s", "peak_abs_displacement_m"],
        env.iter(),
    )
    .map_err(|e| e.to_string())?;
    let erows: Vec<[f64; 9]> = r
        .energy
        .iter()
        .map(|(t, e)| {
            [
                *t,
                e.structure_kinetic_j,
                e.structure_strain_j,
                e.particle_kinetic_j,
                e.particle_potential_j,
                e.contact_elastic_j,
                e.dissipated_j,
                e.load_work_j,
                e.balance_j,
            ]
        })
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("energy.csv"),
        &[
            "time_s",
            "structure_kinetic_j",
            "structure_strain_j",
            "particle_kinetic_j",
            "particle_potential_j",
            "contact_elastic_j",
            "dissipated_j",
            "load_work_j",
            "balance_j",
        ],
        erows,
    )
    .map_err(|e| e.to_string())?;
    let ms: Vec<f64> = r.time_s.iter().map(|t| t * 1e3).collect();
    let mm: Vec<f64> = r.tip_m.iter().map(|x| x * 1e3).collect();
    let mut plot = pdamp_plot::LinePlot::new(
        pdamp_plot::Axis::linear("time (ms)"),
        pdamp_plot::Axis::linear("tip displacement x (mm)"),
    );
    plot.series.push(pdamp_plot::Series::new("", ms, mm));
    pdamp_plot::line_plot(dir.join("tip"), &plot).map_err(|e| e.to_string())?;
    // last: a run directory with summary.json is complete (the study skips it)
    let summary = serde_json::json!({ "result": r, "scenario": sc });
    pdamp_io::atomic::write_atomic(
        dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .map_err(|e| e.to_string())?
            .as_bytes(),
    )
    .map_err(|e| e.to_string())?;
    Ok(())
}

/// First bending frequencies [Hz] of the empty beam (no powder), `count` lowest modes.
pub fn empty_beam_modes(beam: &BeamSpec, count: usize) -> Result<Vec<f64>, String> {
    let (s, _) = build_structure(
        beam,
        &LoadSpec {
            pressure_pa: 0.0,
            rise_s: 1.0,
            hold_s: 0.0,
        },
        [0.0; 3],
    );
    fe::modes::lowest_modes(&s, count, 300)
        .map(|(f, _)| f)
        .map_err(|e| e.to_string())
}

/// First bending frequency of the empty beam from piecewise Timoshenko theory (solid bottom,
/// hollow cavity part, solid top) [Hz].
pub fn timoshenko_reference(beam: &BeamSpec) -> f64 {
    use crate::fe::beam_theory::{Segment, timoshenko_f1};
    let inner = beam.width_m - 2.0 * beam.wall_thickness_m;
    let segs = [
        Segment {
            length_m: beam.cavity_offset_m,
            outer_m: beam.width_m,
            inner_m: 0.0,
        },
        Segment {
            length_m: beam.cavity_length_m,
            outer_m: beam.width_m,
            inner_m: inner,
        },
        Segment {
            length_m: beam.length_m - beam.cavity_offset_m - beam.cavity_length_m,
            outer_m: beam.width_m,
            inner_m: 0.0,
        },
    ];
    let m = beam.material;
    timoshenko_f1(
        &segs,
        m.youngs_modulus_pa,
        m.poisson_ratio,
        m.density_kg_m3,
        1320,
        &[],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoint_inspection_and_damage() {
        let dir = std::env::temp_dir().join(format!("pdamp-powder-inspect-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(ck::CHECKPOINT_FILE);
        let cavity = Aabb {
            min: [0.0; 3],
            max: [0.006, 0.006, 0.012],
        };
        let s = PrepSettings::default();
        let mut pr = Preparation::new(
            cavity,
            &LogNormal::paper(2e-3),
            PowderLaw::PAPER.coarse_grained(2.0),
            8000.0,
            5e-6,
            &s,
        );
        let mut k = 0;
        let _ = pr.run(&mut |_, _| {}, &mut |_| {
            k += 1;
            if k == 50 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        let header = CheckpointHeader::new(CHECKPOINT_KIND, "digest");
        ck::save(&path, &header, &Phase::Preparing(Box::new(pr.snapshot()))).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let (phase, t) = inspect_checkpoint(&bytes).unwrap();
        assert_eq!(phase, "preparing");
        assert!((t - 50.0 * 5e-6).abs() < 1e-15, "{t}");
        // another scenario, another kind, damage and truncation are refused with a message
        let e = ck::load::<Phase>(&path, CHECKPOINT_KIND, "other")
            .err()
            .unwrap();
        assert!(e.contains("different scenario"), "{e}");
        let e = ck::load::<Phase>(&path, "run", "digest").err().unwrap();
        assert!(e.contains("not 'run'"), "{e}");
        let mut bad = bytes.clone();
        bad[bytes.len() / 2] ^= 1;
        assert!(inspect_checkpoint(&bad).unwrap_err().contains("damaged"));
        assert!(inspect_checkpoint(&bytes[..bytes.len() - 100]).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
