//! A DEM world stepped from Python (`pdamp.World`): built from a scenario and settled exactly as
//! `pdamp run` does, then advanced by the caller — step by step or up to a time — with the
//! particle state as zero-copy numpy views, the contact loads on the bodies, and driven bodies
//! moved from outside (a user's own structure model coupled to the bed, D Sect. 3.3).

use crate::detach::WorldPool;
use crate::scenario::PyScenario;
use numpy::ndarray::{ArrayView1, ArrayView2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pdamp_dem::health::HealthError;
use pdamp_dem::{Motion, TranslationTrack, Vec3, World};
use pyo3::exceptions::{PyKeyError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::ops::ControlFlow;
use std::sync::Arc;

// The views below read a `Vec<Vec3>` as an (n, 3) array of f64.
const _: () = assert!(std::mem::size_of::<Vec3>() == 3 * std::mem::size_of::<f64>());

/// Steps of one `step(n)` call done without a watcher thread where the world has no pool of
/// its calling thread ([`WorldPool`]); longer calls can be stopped with Ctrl-C while they run.
const SHORT_CALL_STEPS: u64 = 64;

/// A DEM world of a scenario, ready at the start of the main run of `pdamp run` (built,
/// settled as the scenario's `[settle]` says, clock at zero). Stepping it to the scenario's
/// duration gives the numbers of `pdamp run` to the bit.
#[pyclass(name = "World", module = "pdamp._pdamp")]
pub(crate) struct PyWorld {
    world: World,
    pool: WorldPool,
    settling_time_s: f64,
    duration_s: f64,
    /// Bodies the scenario declares driven (only these may be moved by `drive_body`).
    driven: Vec<bool>,
}

impl PyWorld {
    fn wall(&self, body: &str, wall: &str) -> PyResult<(usize, usize)> {
        let b = self.body(body)?;
        let walls = &self.world.bodies[b].walls;
        let w = walls.iter().position(|w| w.name == wall).ok_or_else(|| {
            let names: Vec<&str> = walls.iter().map(|w| w.name.as_str()).collect();
            PyKeyError::new_err(format!(
                "body {body:?} has no wall {wall:?}; its walls are {names:?}"
            ))
        })?;
        Ok((b, w))
    }

    fn body(&self, name: &str) -> PyResult<usize> {
        self.world
            .bodies
            .iter()
            .position(|b| b.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = self.world.bodies.iter().map(|b| b.name.as_str()).collect();
                PyKeyError::new_err(format!(
                    "no body {name:?}; the scenario's bodies are {names:?}"
                ))
            })
    }
}

/// Health check of the world (the particle or contact at fault named).
fn health(w: &World) -> Result<(), HealthError> {
    w.check_health()
}

/// Read-only (n, 3) view of one of the world's vector columns; keeps `owner` alive.
fn vec3_view<'py>(
    owner: &Bound<'py, PyWorld>,
    pick: impl Fn(&pdamp_dem::ParticleSet) -> &[Vec3],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let w = owner.borrow();
    let data = pick(&w.world.particles);
    // SAFETY: Vec3 is three contiguous f64 (asserted above); the memory belongs to the world
    // inside `owner`, which the array keeps alive as its base. The world never reallocates or
    // reorders its particle columns after it is built (no Python method adds or removes
    // particles), so the view stays valid and follows the state as it is stepped.
    let view = unsafe { ArrayView2::from_shape_ptr((data.len(), 3), data.as_ptr().cast::<f64>()) };
    let a = unsafe { PyArray2::borrow_from_array(&view, owner.clone().into_any()) };
    a.getattr("flags")?.setattr("writeable", false)?;
    Ok(a)
}

/// Read-only (n,) view of one of the world's scalar columns; keeps `owner` alive.
fn f64_view<'py>(
    owner: &Bound<'py, PyWorld>,
    pick: impl Fn(&pdamp_dem::ParticleSet) -> &[f64],
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let w = owner.borrow();
    let data = pick(&w.world.particles);
    // SAFETY: as in `vec3_view`.
    let view = unsafe { ArrayView1::from_shape_ptr(data.len(), data.as_ptr()) };
    let a = unsafe { PyArray1::borrow_from_array(&view, owner.clone().into_any()) };
    a.getattr("flags")?.setattr("writeable", false)?;
    Ok(a)
}

/// An (n, 3) numpy copy of vectors.
fn vec3_array<'py>(py: Python<'py>, v: &[Vec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = v.iter().flat_map(|x| [x.x, x.y, x.z]).collect();
    numpy::ndarray::Array2::from_shape_vec((v.len(), 3), flat)
        .expect("n × 3 values")
        .into_pyarray(py)
}

fn vec3(v: [f64; 3]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

#[pymethods]
impl PyWorld {
    /// Builds the world of `scenario` and settles it as `pdamp run` does (unless
    /// `settle=False`); `threads` workers (default: all cores; the numbers do not depend on it).
    /// `drive` gives driven bodies their state at t = 0, `{name: (displacement_m, velocity_m_s,
    /// acceleration_m_s2)}` (default: at rest at the reference pose): the bed settles with the
    /// body held at its reference pose and the main run starts with it in that state, as a
    /// prescribed motion does.
    #[new]
    #[pyo3(signature = (scenario, threads = None, settle = true, progress = None, drive = None))]
    fn new(
        py: Python<'_>,
        scenario: &PyScenario,
        threads: Option<usize>,
        settle: bool,
        progress: Option<Bound<'_, PyAny>>,
        drive: Option<std::collections::BTreeMap<String, [[f64; 3]; 3]>>,
    ) -> PyResult<Self> {
        let sc = &scenario.inner;
        if sc.damper.is_some() {
            return Err(PyValueError::new_err(
                "a damper scenario is run by pdamp.damper_point or pdamp.fields; World takes a plain scenario (pdamp run without [damper])",
            ));
        }
        let pool = WorldPool::new(threads);
        let base = &scenario.base_dir;
        let drive = drive.unwrap_or_default();
        let declared_driven = |name: &str| {
            sc.bodies.iter().any(|s| {
                s.name == name && matches!(s.motion, pdamp_scenario::schema::MotionSpec::Driven)
            })
        };
        if let Some(name) = drive.keys().find(|n| !declared_driven(n)) {
            return Err(PyValueError::new_err(format!(
                "drive: {name:?} is not a driven body of the scenario (motion = {{ type = \"driven\" }})"
            )));
        }
        let work = |poll: &mut dyn FnMut(&str, f64) -> bool| {
            let mut world = sc.build_world(base)?;
            for (name, [u, v, a]) in &drive {
                // declared driven (checked above), so the world has it
                let b = world
                    .bodies
                    .iter()
                    .position(|b| &b.name == name)
                    .ok_or("drive: no body")?;
                if [u, v, a].iter().any(|x| x.iter().any(|c| !c.is_finite())) {
                    return Err(format!("drive: {name:?}: every number must be finite").into());
                }
                // Held during settling like any moving body; from t = 0 on in this state.
                world.bodies[b].motion = Motion::Prescribed(Arc::new(TranslationTrack {
                    t1_s: 0.0,
                    displacement_m: vec3(*u),
                    velocity_m_s: vec3(*v),
                    acceleration_m_s2: vec3(*a),
                }));
            }
            let main_gravity = Vec3::from(sc.simulation.gravity_m_s2);
            let mut t = 0.0;
            if let (true, Some(spec)) = (settle, &sc.settle) {
                let mut bad = None;
                let max = spec.max_duration_s;
                let r = pdamp_scenario::run::settle_with_or_break(
                    &mut world,
                    spec,
                    main_gravity,
                    |w| {
                        if let Err(e) = health(w) {
                            bad = Some(e);
                            return ControlFlow::Break(());
                        }
                        if poll("settling", w.time_s / max) {
                            return ControlFlow::Break(());
                        }
                        ControlFlow::Continue(())
                    },
                );
                if let Some(e) = bad {
                    return Err(format!("settling: {e}").into());
                }
                t = r.ok_or("settling stopped")?;
            }
            // The main run of `pdamp run` starts from here.
            world.initialize();
            Ok((world, t))
        };
        let (world, settling_time_s) = pool.run(py, progress.as_ref(), "settling", false, work)?;
        let driven = world
            .bodies
            .iter()
            .map(|b| declared_driven(&b.name))
            .collect();
        Ok(Self {
            driven,
            world,
            pool,
            settling_time_s,
            duration_s: sc.simulation.duration_s,
        })
    }

    /// Advances by `n` time steps (health-checked as `pdamp run` does every 500 steps).
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, py: Python<'_>, n: u64) -> PyResult<()> {
        let world = &mut self.world;
        let work = move |poll: &mut dyn FnMut(&str, f64) -> bool| {
            for k in 0..n {
                world.step();
                if world
                    .counters
                    .steps
                    .is_multiple_of(pdamp_scenario::run::HEALTH_CHECK_STEPS)
                {
                    health(world)?;
                }
                if poll("stepping", k as f64 / n as f64) {
                    break;
                }
            }
            Ok(())
        };
        self.pool
            .run(py, None, "stepping", n <= SHORT_CALL_STEPS, work)
    }

    /// Steps until the clock reaches `t_s` (default: the scenario's duration; the last step
    /// shortened to land on it), as the main loop of `pdamp run`.
    #[pyo3(signature = (t_s = None, progress = None))]
    fn run_until(
        &mut self,
        py: Python<'_>,
        t_s: Option<f64>,
        progress: Option<Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let t_end = t_s.unwrap_or(self.duration_s);
        if !t_end.is_finite() {
            return Err(PyValueError::new_err(format!(
                "t_s must be a finite time in s, got {t_end}"
            )));
        }
        let world = &mut self.world;
        let t0 = world.time_s;
        let work = |poll: &mut dyn FnMut(&str, f64) -> bool| {
            let mut bad = None;
            world.run_until_or_break_deferred(t_end, |w| {
                if w.counters
                    .steps
                    .is_multiple_of(pdamp_scenario::run::HEALTH_CHECK_STEPS)
                {
                    w.complete_step();
                    if let Err(e) = health(w) {
                        bad = Some(e);
                        return ControlFlow::Break(());
                    }
                }
                if poll("running", (w.time_s - t0) / (t_end - t0).max(1e-300)) {
                    return ControlFlow::Break(());
                }
                ControlFlow::Continue(())
            });
            bad.map_or(Ok(()), |e| Err(e.into()))
        };
        self.pool.run(py, progress.as_ref(), "running", false, work)
    }

    /// Simulated time, s (zero at the start of the main run).
    #[getter]
    fn time_s(&self) -> f64 {
        self.world.time_s
    }

    /// Time step, s.
    #[getter]
    fn dt_s(&self) -> f64 {
        self.world.dt_s
    }

    /// Accepted time steps since the world was built (settling included).
    #[getter]
    fn steps(&self) -> u64 {
        self.world.counters.steps
    }

    /// Duration of the scenario's main run, s.
    #[getter]
    fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// Time the settling took, s.
    #[getter]
    fn settling_time_s(&self) -> f64 {
        self.settling_time_s
    }

    /// Number of particles.
    fn __len__(&self) -> usize {
        self.world.particles.len()
    }

    /// Particle centres, m: a read-only (n, 3) view of the world's memory (no copy; it follows
    /// the world as it is stepped).
    #[getter]
    fn positions_m<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        vec3_view(slf, |p| &p.position)
    }

    /// Particle velocities, m/s (read-only view, no copy).
    #[getter]
    fn velocities_m_s<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        vec3_view(slf, |p| &p.velocity)
    }

    /// Particle angular velocities, rad/s (read-only view, no copy).
    #[getter]
    fn angular_velocities_rad_s<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        vec3_view(slf, |p| &p.angular_velocity)
    }

    /// Total force on each particle (contacts and gravity), N (read-only view, no copy).
    #[getter]
    fn forces_n<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        vec3_view(slf, |p| &p.force)
    }

    /// Particle radii, m (read-only view, no copy).
    #[getter]
    fn radii_m<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        f64_view(slf, |p| &p.radius)
    }

    /// Particle masses, kg (read-only view, no copy).
    #[getter]
    fn masses_kg<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        f64_view(slf, |p| &p.mass)
    }

    /// Names of the bodies (containers, walls), in the scenario's order.
    #[getter]
    fn body_names(&self) -> Vec<String> {
        self.world.bodies.iter().map(|b| b.name.clone()).collect()
    }

    /// Contact force (N) and torque about the body's reference point (N·m) the particles exert
    /// on body `name` in the last step.
    fn body_load(&self, name: &str) -> PyResult<([f64; 3], [f64; 3])> {
        let (f, m) = self.world.body_load(self.body(name)?);
        Ok((f.into(), m.into()))
    }

    /// Position of body `name`'s reference point (m) and its velocity (m/s) now.
    fn body_state(&self, name: &str) -> PyResult<([f64; 3], [f64; 3])> {
        let s = self.world.bodies[self.body(name)?].state;
        Ok((s.position_m.into(), s.velocity_m_s.into()))
    }

    /// Moves a driven body (`motion = { type = "driven" }` in the scenario) from outside: its
    /// displacement from the reference position (m), velocity (m/s) and acceleration (m/s²) at
    /// time `at_s` (default: the end of the next step, as the structure coupling of D Sect. 3.3
    /// hands the container its state at t_{n+1}); between updates the body follows them
    /// quadratically. The starting state at t = 0 is given to the constructor (`drive=`). Read
    /// the bed's reaction with `body_load` after the step.
    #[pyo3(signature = (name, displacement_m, velocity_m_s, acceleration_m_s2 = [0.0; 3], at_s = None))]
    fn drive_body(
        &mut self,
        name: &str,
        displacement_m: [f64; 3],
        velocity_m_s: [f64; 3],
        acceleration_m_s2: [f64; 3],
        at_s: Option<f64>,
    ) -> PyResult<()> {
        let b = self.body(name)?;
        let all = [displacement_m, velocity_m_s, acceleration_m_s2];
        if all.iter().flatten().any(|x| !x.is_finite()) || at_s.is_some_and(|t| !t.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "drive_body({name:?}): every number must be finite"
            )));
        }
        if !self.driven[b] {
            return Err(PyValueError::new_err(format!(
                "body {name:?} is not driven: give it motion = {{ type = \"driven\" }} in the scenario"
            )));
        }
        let track = TranslationTrack {
            t1_s: at_s.unwrap_or(self.world.time_s + self.world.dt_s),
            displacement_m: vec3(displacement_m),
            velocity_m_s: vec3(velocity_m_s),
            acceleration_m_s2: vec3(acceleration_m_s2),
        };
        self.world.bodies[b].motion = Motion::Prescribed(Arc::new(track));
        Ok(())
    }

    /// Vertices of mesh wall `wall` of body `body` (body frame, m), an (n, 3) copy; the
    /// starting point of [`move_wall_vertices`](Self::move_wall_vertices).
    fn wall_vertices<'py>(
        &self,
        py: Python<'py>,
        body: &str,
        wall: &str,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (b, w) = self.wall(body, wall)?;
        match &self.world.bodies[b].walls[w].geometry {
            pdamp_dem::Geometry::Mesh(m) => Ok(vec3_array(py, m.vertices())),
            _ => Err(PyValueError::new_err(format!(
                "wall {wall:?} of body {body:?} is not a triangle mesh (stl or box_outside)"
            ))),
        }
    }

    /// Deforms mesh wall `wall` of body `body`: its vertices at the end of the next step
    /// (an (n, 3) array, body frame, m, the order of `wall_vertices`); the step's contacts see
    /// the mean vertex velocity. Read the loads on the vertices with `wall_nodal_forces` after
    /// the step — a finite-element model of your own coupled to the bed (P Sect. 2.3).
    fn move_wall_vertices(
        &mut self,
        body: &str,
        wall: &str,
        positions: numpy::PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let (b, w) = self.wall(body, wall)?;
        let a = positions.as_array();
        if a.ncols() != 3 {
            return Err(PyValueError::new_err(format!(
                "positions must be an (n, 3) array, got {:?}",
                a.shape()
            )));
        }
        let p: Vec<Vec3> = a
            .rows()
            .into_iter()
            .map(|r| Vec3::new(r[0], r[1], r[2]))
            .collect();
        self.world
            .move_wall_vertices(b, w, &p)
            .map_err(|e| PyValueError::new_err(format!("wall {wall:?}: {e}")))
    }

    /// The loads the particles put on the vertices of mesh wall `wall` of body `body` in the last
    /// step (an (n, 3) array, N, world frame): each contact force split onto its face, edge or
    /// vertex with the barycentric weights of the contact point.
    fn wall_nodal_forces<'py>(
        &self,
        py: Python<'py>,
        body: &str,
        wall: &str,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (b, w) = self.wall(body, wall)?;
        let mut out = Vec::new();
        self.world
            .wall_nodal_forces(b, w, &mut out)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(vec3_array(py, &out))
    }

    /// The energy ledger now, J: the terms of `summary.json`'s `energy` (kinetic, potential,
    /// elastic, wall and external work, dissipation by mechanism, initial values) with
    /// `time_s`, `dissipated_j` and the closure error `closure_error_j` = W_wall −
    /// (ΔE_kin + ΔE_pot + ΔE_el + D).
    fn energy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let l = &self.world.ledger;
        let v = serde_json::to_value(l).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let d = PyDict::new(py);
        d.set_item("time_s", self.world.time_s)?;
        if let serde_json::Value::Object(m) = v {
            for (k, x) in m {
                d.set_item(k, x.as_f64())?;
            }
        }
        d.set_item("dissipated_j", l.dissipated_j())?;
        d.set_item("closure_error_j", l.closure_error_j())?;
        Ok(d)
    }

    /// Checks the world's health (finite state, overlaps, velocities); raises `RuntimeError`
    /// naming the particle or contact at fault.
    fn check_health(&self) -> PyResult<()> {
        health(&self.world).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    fn __repr__(&self) -> String {
        format!(
            "pdamp.World({} particles, {} bodies, t = {} s)",
            self.world.particles.len(),
            self.world.bodies.len(),
            self.world.time_s
        )
    }
}
