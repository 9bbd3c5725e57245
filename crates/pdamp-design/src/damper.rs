//! A single particle damper under harmonic excitation [D Sect. 3.2]: settle the bed once, then
//! for each excitation point move the container as $x_c = X \sin(\Omega t)$ [D Eq. 3.8], drop
//! the transient cycles and evaluate the driving force and container velocity over whole cycles
//! with the complex power method [D Eq. 3.12–3.17].

use crate::DesignError;
use crate::convergence::{ConvergenceSpec, RunningEstimate, has_converged};
use pdamp_dem::math::STANDARD_GRAVITY_M_S2;
use pdamp_dem::time_loop::{CancelToken, LoopControl, LoopEnd, LoopEvent};
use pdamp_dem::{HarmonicTranslation, Motion, Vec3, World};
use pdamp_scenario::schema::Scenario;
use pdamp_signal::Complex64;
use pdamp_signal::complex_power::complex_power;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;

/// A settled damper ready to be excited at any frequency and amplitude.
#[derive(Debug, Clone)]
pub struct Damper {
    /// The settled world (clock at zero, container at its reference pose).
    pub settled: World,
    /// Index of the container body.
    pub container: usize,
    /// Unit excitation direction.
    pub direction: Vec3,
    /// Container mass m_con, kg.
    pub container_mass_kg: f64,
    /// Mass of all particles m_bed, kg.
    pub bed_mass_kg: f64,
    /// Cycles simulated per point (the maximum with a convergence criterion).
    pub cycles: u32,
    /// Leading cycles dropped.
    pub transient_cycles: u32,
    /// Nominal time step (the step is shortened so a cycle has a whole number of steps), s.
    pub time_step_s: f64,
    /// Settling time used, s.
    pub settling_time_s: f64,
    /// Early stop of a point on convergence (`None`: always `cycles` cycles).
    pub convergence: Option<ConvergenceSpec>,
    /// Statistics of the bed as filled, before the container was turned (fills under
    /// `settle.gravity_m_s2`); its clearance is D's h.
    pub fill_statistics: Option<pdamp_dem::bed_statistics::BedStatistics>,
    /// The stop request its points honour (a point then checkpoints, where it keeps
    /// checkpoints, and ends with [`DesignError::PointInterrupted`]); clones share it.
    pub cancel: CancelToken,
}

/// Result of one excitation point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// Excitation frequency f, Hz.
    pub frequency_hz: f64,
    /// Displacement amplitude X, m.
    pub amplitude_m: f64,
    /// Acceleration amplitude A = XΩ², m/s².
    pub acceleration_m_s2: f64,
    /// Intensity Γ = A/g.
    pub intensity: f64,
    /// Velocity amplitude V = XΩ, m/s.
    pub velocity_amplitude_m_s: f64,
    /// Dissipated energy per cycle from the complex power, Ẽ_diss [D Eq. 3.13], J.
    pub dissipated_energy_per_cycle_j: f64,
    /// Loss factor η [D Eq. 3.14].
    pub loss_factor: f64,
    /// Effective loss factor η̄ [D Eq. 3.15].
    pub effective_loss_factor: f64,
    /// Effective particle mass ratio m̄_bed / m_bed [D Eq. 3.17].
    pub effective_mass_ratio: f64,
    /// Real part of the effective moving mass M*_mov [D Eq. 3.16], kg.
    pub effective_moving_mass_re_kg: f64,
    /// Imaginary part of M*_mov, kg.
    pub effective_moving_mass_im_kg: f64,
    /// Dissipated energy per evaluated cycle from the energy ledger, J.
    pub ledger_dissipated_per_cycle_j: f64,
    /// Work of the container walls on the particles per evaluated cycle (ledger), J.
    pub ledger_wall_work_per_cycle_j: f64,
    /// Share of the dissipation in normal particle–particle contacts.
    pub share_normal_pp: f64,
    /// Share in normal particle–wall contacts.
    pub share_normal_pw: f64,
    /// Share in tangential particle–particle contacts.
    pub share_tangential_pp: f64,
    /// Share in tangential particle–wall contacts.
    pub share_tangential_pw: f64,
    /// Energy balance residual over the evaluated cycles relative to the wall work.
    pub energy_closure_relative: f64,
    /// Evaluated cycles (after the transient): `cycles − transient_cycles`, or fewer when the
    /// point stopped early on convergence.
    #[serde(alias = "evaluated_cycles")]
    pub cycles_evaluated: u32,
    /// Whether the convergence criterion was met (`None`: no criterion given, all cycles run).
    #[serde(default)]
    pub converged: Option<bool>,
    /// Time step used, s.
    pub time_step_s: f64,
    /// Accepted time steps.
    pub steps: u64,
    /// Wall-clock time of this point, s.
    pub wall_time_s: f64,
}

/// Follows a point's run step by step (motion-mode recording, progress).
pub trait PointObserver {
    /// Called after every step with the world, the cycle index (from 0) and the phase Ωt mod 2π.
    fn on_step(&mut self, world: &World, cycle: u32, phase_rad: f64, damper: &Damper);

    /// Whether `on_step` reads particle state (velocities, forces, the ledger's kinetic and
    /// potential energy). When false, the point runs with deferred half kicks
    /// ([`World::step_deferred`]: same results, one pass over the particles less per step) and
    /// `on_step` may read only the clock, the bodies and the counters.
    fn reads_particles(&self) -> bool {
        true
    }

    /// What the observer has gathered, for a checkpoint of the point (nothing by default).
    fn save_state(&self) -> Result<Vec<u8>, DesignError> {
        Ok(Vec::new())
    }

    /// Continues from what [`Self::save_state`] wrote.
    fn restore_state(&mut self, _bytes: &[u8]) -> Result<(), DesignError> {
        Ok(())
    }
}

/// Checkpointing of one point inside its run (`pdamp run` of a damper scenario): the state
/// is written to `path` every `interval_s` of wall-clock time and on a stop request
/// (Ctrl-C/SIGTERM); with `resume` the point continues from it and ends with the result of an
/// uninterrupted run.
pub struct PointCheckpointing {
    /// The checkpoint file.
    pub path: std::path::PathBuf,
    /// Digest of the scenario (and the files it reads) the point belongs to.
    pub scenario_digest: String,
    /// Wall-clock seconds between checkpoints (≤ 0: only on a stop request).
    pub interval_s: f64,
    /// Continue from `path` if it holds a point in progress.
    pub resume: bool,
}

impl PointCheckpointing {
    /// The checkpoint `dir/checkpoint.bin` of a point of the scenario with `scenario_digest`,
    /// at the interval and `resume` of `options`.
    pub fn in_dir(
        dir: &Path,
        scenario_digest: &str,
        options: &pdamp_scenario::run::RunOptions,
    ) -> Self {
        Self {
            path: dir.join(pdamp_io::checkpoint::CHECKPOINT_FILE),
            scenario_digest: scenario_digest.to_string(),
            interval_s: options.checkpoint_interval_s,
            resume: options.resume,
        }
    }
}

/// Kind tag of damper-point checkpoints.
pub const POINT_KIND: &str = "damper-point";

/// A damper point in progress (see [`PointCheckpointing`]).
#[derive(serde::Serialize, serde::Deserialize)]
pub struct PointProgress {
    frequency_hz: f64,
    amplitude_m: f64,
    /// Cycle in progress (from 0).
    cycle: u32,
    world: pdamp_dem::state::WorldState,
    times: Vec<f64>,
    force: Vec<f64>,
    velocity: Vec<f64>,
    ledger0: Option<pdamp_dem::EnergyLedger>,
    cycle_start_sample: usize,
    f_sum: (f64, f64),
    v_sum: (f64, f64),
    history: Vec<RunningEstimate>,
    per_cycle: Vec<RunningEstimate>,
    observer: Vec<u8>,
    wall_time_s: f64,
}

/// A damper point's checkpoint: in progress, or finished (outputs written).
#[derive(serde::Serialize, serde::Deserialize)]
pub enum PointCheckpoint {
    /// The point is running.
    Running(Box<PointProgress>),
    /// The point and its outputs are complete.
    Finished,
}

impl PointObserver for () {
    fn on_step(&mut self, _: &World, _: u32, _: f64, _: &Damper) {}

    fn reads_particles(&self) -> bool {
        false
    }
}

/// Complex amplitude $\hat x$ with $x(t) \approx \mathrm{Re}(\hat x e^{i\Omega t})$ of a sampled
/// signal over whole cycles, $\hat x = \frac{2}{T}\int x e^{-i\Omega t}\,dt$ by the trapezoidal
/// rule: exact single-bin DFT for uniform samples over whole periods, and valid for the varying
/// steps of Gear's step control too. Returns (re, im).
pub fn harmonic_amplitude(t_s: &[f64], x: &[f64], frequency_hz: f64) -> (f64, f64) {
    let w = 2.0 * PI * frequency_hz;
    let (mut re, mut im) = (0.0, 0.0);
    for k in 1..t_s.len() {
        let h = t_s[k] - t_s[k - 1];
        let (s0, c0) = (w * t_s[k - 1]).sin_cos();
        let (s1, c1) = (w * t_s[k]).sin_cos();
        re += 0.5 * h * (x[k - 1] * c0 + x[k] * c1);
        im -= 0.5 * h * (x[k - 1] * s0 + x[k] * s1);
    }
    let span = t_s.last().copied().unwrap_or(0.0) - t_s.first().copied().unwrap_or(0.0);
    if span <= 0.0 {
        return (0.0, 0.0);
    }
    (2.0 * re / span, 2.0 * im / span)
}

/// The `[damper]` section of a scenario and the index of its container body.
fn container_of(
    scenario: &Scenario,
) -> Result<(&pdamp_scenario::schema::DamperSpec, usize), DesignError> {
    let spec = scenario
        .damper
        .as_ref()
        .ok_or(DesignError::NoDamperSection)?;
    let container = scenario
        .bodies
        .iter()
        .position(|b| b.name == spec.container_body)
        .ok_or_else(|| DesignError::NoContainerBody {
            body: spec.container_body.clone(),
        })?;
    Ok((spec, container))
}

impl Damper {
    /// Builds the world of a damper scenario and prepares its bed (drop-down, settling) as the
    /// scenario says ([`pdamp_scenario::prepare::prepare_bed`]); `progress` gets the fraction done.
    pub fn from_scenario(
        scenario: &Scenario,
        base_dir: &Path,
        progress: impl FnMut(f64),
    ) -> Result<Self, DesignError> {
        Self::from_scenario_cancellable(scenario, base_dir, progress, &CancelToken::new())
    }

    /// [`Damper::from_scenario`] whose drop-down and points stop when `cancel` is cancelled.
    pub fn from_scenario_cancellable(
        scenario: &Scenario,
        base_dir: &Path,
        mut progress: impl FnMut(f64),
        cancel: &CancelToken,
    ) -> Result<Self, DesignError> {
        // The damper section is checked before the (costly) bed preparation.
        container_of(scenario)?;
        let prepared = pdamp_scenario::prepare::prepare_bed(
            scenario,
            base_dir,
            &mut |_, f| progress(f),
            cancel,
        )
        .map_err(DesignError::from)?;
        Ok(Self::from_prepared(scenario, prepared)?.cancelled_by(cancel))
    }

    /// The same damper, its points stopped by `cancel`.
    pub fn cancelled_by(mut self, cancel: &CancelToken) -> Self {
        self.cancel = cancel.clone();
        self
    }

    /// The damper of `scenario` on a bed prepared already ([`pdamp_scenario::prepare::prepare_bed`],
    /// or one saved by another process and read with [`pdamp_scenario::prepare::load_prepared`]).
    pub fn from_prepared(
        scenario: &Scenario,
        prepared: pdamp_scenario::prepare::PreparedBed,
    ) -> Result<Self, DesignError> {
        let (spec, container) = container_of(scenario)?;
        let mut world = prepared.world;
        world.bodies[container].motion = Motion::Fixed;
        let bed_mass_kg = world.particles.mass.iter().sum();
        Ok(Self {
            container,
            direction: Vec3::from(spec.direction).normalize(),
            container_mass_kg: spec.container_mass_kg,
            bed_mass_kg,
            cycles: spec.cycles,
            transient_cycles: spec.transient_cycles,
            time_step_s: scenario.simulation.time_step_s,
            settling_time_s: prepared.settling_time_s,
            settled: world,
            convergence: spec.convergence.clone(),
            fill_statistics: prepared.fill_statistics,
            cancel: CancelToken::new(),
        })
    }

    /// The clearance h of D Eq. 8.1/8.2 along the excitation: of the bed as filled when it was
    /// turned afterwards, else of the settled bed; to the bed's mean surface where the bed lies
    /// along the excitation (the volumetric h of D Eq. 8.1), else to its highest particle, m.
    pub fn clearance_m(&self) -> Option<f64> {
        let h = |s: &pdamp_dem::bed_statistics::BedStatistics| {
            s.clearance_to_surface_m.or(s.clearance_m)
        };
        self.fill_statistics
            .as_ref()
            .and_then(h)
            .or_else(|| h(&self.bed_statistics()))
    }

    /// Statistics of the settled bed, with the clearance along the excitation direction.
    pub fn bed_statistics(&self) -> pdamp_dem::bed_statistics::BedStatistics {
        pdamp_dem::bed_statistics::bed_statistics(&self.settled, Some(self.direction))
    }

    /// A damper from an already prepared world (tests, programmatic use). The world's clock is
    /// restarted; the container body must exist.
    pub fn from_world(
        mut world: World,
        container: usize,
        direction: Vec3,
        container_mass_kg: f64,
        cycles: u32,
        transient_cycles: u32,
    ) -> Self {
        world.bodies[container].motion = Motion::Fixed;
        world.restart_clock();
        let bed_mass_kg = world.particles.mass.iter().sum();
        let time_step_s = world.dt_s;
        Self {
            settled: world,
            container,
            direction: direction.normalize(),
            container_mass_kg,
            bed_mass_kg,
            cycles,
            transient_cycles,
            time_step_s,
            settling_time_s: 0.0,
            convergence: None,
            fill_statistics: None,
            cancel: CancelToken::new(),
        }
    }

    /// Span of the settled bed along the excitation direction, relative to the container's
    /// reference position: (lowest, highest) of x·e ∓ r over the particles, m. With the
    /// container's inner walls it gives the clearance h of D Eq. 8.1/8.2.
    pub fn bed_span_along_direction_m(&self) -> (f64, f64) {
        let p = &self.settled.particles;
        let origin = self.settled.bodies[self.container].state.position_m;
        (0..p.len()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
            let s = (p.position[i] - origin).dot(&self.direction);
            (lo.min(s - p.radius[i]), hi.max(s + p.radius[i]))
        })
    }

    /// The same damper with an early stop on convergence (`cycles` becomes the maximum).
    pub fn with_convergence(mut self, convergence: Option<ConvergenceSpec>) -> Self {
        self.convergence = convergence;
        self
    }

    /// Runs one excitation point (frequency f, displacement amplitude X) from the settled
    /// state and evaluates it.
    pub fn run_point(
        &self,
        frequency_hz: f64,
        amplitude_m: f64,
        observer: &mut dyn PointObserver,
    ) -> Result<PointResult, DesignError> {
        self.run_point_checkpointed(frequency_hz, amplitude_m, observer, None)
    }

    /// [`Self::run_point`] with checkpoints inside the point (see [`PointCheckpointing`]); a
    /// resumed point gives the result of an uninterrupted one (its wall time aside).
    pub fn run_point_checkpointed(
        &self,
        frequency_hz: f64,
        amplitude_m: f64,
        observer: &mut dyn PointObserver,
        checkpointing: Option<&PointCheckpointing>,
    ) -> Result<PointResult, DesignError> {
        use pdamp_io::checkpoint::{self as ck, CheckpointHeader};
        let start = std::time::Instant::now();
        let omega = 2.0 * PI * frequency_hz;
        let period = 1.0 / frequency_hz;
        let (mut w, steps_per_cycle) = self.driven_world(frequency_hz, amplitude_m, period);
        let e = self.direction;
        let t_eval = self.transient_cycles as f64 * period;
        let n_eval = self.cycles - self.transient_cycles;
        let mut rec = PointRecord::with_capacity((n_eval as f64 * steps_per_cycle) as usize + 2);
        let mut converged = self.convergence.as_ref().map(|_| false);
        let mut n_eval = n_eval;
        let m_con = self.container_mass_kg;
        let container = self.container;
        // A point in progress to continue.
        let mut first_cycle = 0;
        let mut wall_before = 0.0;
        if let Some(p) = load_running_point(checkpointing, frequency_hz, amplitude_m)? {
            let p = *p;
            w.restore_state(p.world).map_err(DesignError::from)?;
            rec = PointRecord {
                times: p.times,
                force: p.force,
                velocity: p.velocity,
                ledger0: p.ledger0,
                cycle_start_sample: p.cycle_start_sample,
                f_sum: p.f_sum,
                v_sum: p.v_sum,
                history: p.history,
                per_cycle: p.per_cycle,
            };
            observer.restore_state(&p.observer)?;
            first_cycle = p.cycle;
            wall_before = p.wall_time_s;
        }
        let resumed_in = (first_cycle > 0 || w.time_s > 0.0).then_some(first_cycle);
        let header = checkpointing.map(|c| CheckpointHeader::new(POINT_KIND, &c.scenario_digest));
        let mut control =
            LoopControl::new(&self.cancel, checkpointing.map_or(0.0, |c| c.interval_s));
        let sample = |w: &World, times: &mut Vec<f64>, force: &mut Vec<f64>, vel: &mut Vec<f64>| {
            let t = w.time_s;
            let (s, c) = (omega * t).sin_cos();
            let a_c = -amplitude_m * omega * omega * s;
            let f_p = w.bodies[container].contact_force_n.dot(&e);
            // Driving force = container inertia − particle force on the container [D Sect. 3.2.2].
            times.push(t);
            force.push(m_con * a_c - f_p);
            vel.push(amplitude_m * omega * c);
        };
        for cycle in first_cycle..self.cycles {
            let t_end = (cycle + 1) as f64 * period;
            // (A point resumed inside this cycle has done its start already.)
            if cycle == self.transient_cycles && resumed_in != Some(cycle) {
                rec.ledger0 = Some(w.ledger);
                rec.cycle_start_sample = rec.times.len();
                sample(&w, &mut rec.times, &mut rec.force, &mut rec.velocity);
            }
            let evaluating = cycle >= self.transient_cycles;
            let mut health = None;
            // An observer that reads particles gets every step complete (then this is
            // `World::step`); otherwise the half kicks are deferred (same results).
            let deferred = !observer.reads_particles();
            let end = w.run_controlled(t_end, deferred, &mut control, |w, event| {
                if event == LoopEvent::Checkpoint {
                    if let (Some(c), Some(h)) = (checkpointing, &header) {
                        let obs = observer.save_state()?;
                        let p = rec.progress(
                            (frequency_hz, amplitude_m),
                            cycle,
                            w.save_state(),
                            obs,
                            wall_before + start.elapsed().as_secs_f64(),
                        );
                        ck::save(&c.path, h, &PointCheckpoint::Running(Box::new(p)))?;
                    }
                    return Ok(ControlFlow::Continue(()));
                }
                if !deferred {
                    w.complete_step();
                }
                if evaluating {
                    sample(w, &mut rec.times, &mut rec.force, &mut rec.velocity);
                }
                let phase = (omega * w.time_s).rem_euclid(2.0 * PI);
                observer.on_step(w, cycle, phase, self);
                if w.counters
                    .steps
                    .is_multiple_of(pdamp_scenario::run::HEALTH_CHECK_STEPS)
                {
                    w.complete_step();
                    if let Err(e) = w.check_health() {
                        health = Some(e);
                        return Ok(ControlFlow::Break(()));
                    }
                }
                Ok::<_, DesignError>(ControlFlow::Continue(()))
            })?;
            let cancelled = end == LoopEnd::Cancelled;
            check_cycle_end(health, cancelled, &w, (frequency_hz, amplitude_m), cycle)?;
            if let Some(c) = &self.convergence
                && evaluating
            {
                rec.add_cycle(self, frequency_hz);
                if has_converged(&rec.history, &rec.per_cycle, c) {
                    converged = Some(true);
                    n_eval = rec.history.len() as u32;
                    break;
                }
            }
        }
        debug_assert!((rec.times[0] - t_eval).abs() < 1e-9 * period.max(1.0));
        let cp = rec.complex_power(self, frequency_hz, amplitude_m)?;
        let l0 = rec.ledger0.expect("evaluated cycles");
        Ok(PointResult::evaluate(
            (frequency_hz, amplitude_m),
            &cp,
            (&l0, &w.ledger),
            n_eval,
            converged,
            (w.dt_s, w.counters.steps),
            wall_before + start.elapsed().as_secs_f64(),
        ))
    }

    /// The settled bed with its container driven harmonically at f and X (whole steps per
    /// period, at most the damper's time step); returns it with the steps per cycle.
    fn driven_world(&self, frequency_hz: f64, amplitude_m: f64, period: f64) -> (World, f64) {
        let mut w = self.settled.clone();
        let e = self.direction;
        w.bodies[self.container].motion = Motion::Prescribed(Arc::new(HarmonicTranslation {
            direction: [e.x, e.y, e.z],
            amplitude_m,
            frequency_hz,
            phase_rad: 0.0,
        }));
        let steps_per_cycle = (period / self.time_step_s).ceil().max(1.0);
        w.dt_s = period / steps_per_cycle;
        w.restart_clock();
        (w, steps_per_cycle)
    }
}

/// The end of cycle `cycle` (0-based) at (f, X): a failed health check, a requested stop or a
/// bed whose kinetic energy diverged ends the point with its error.
fn check_cycle_end(
    health: Option<pdamp_dem::health::HealthError>,
    cancelled: bool,
    w: &World,
    (frequency_hz, amplitude_m): (f64, f64),
    cycle: u32,
) -> Result<(), DesignError> {
    if let Some(source) = health {
        return Err(DesignError::Health {
            frequency_hz,
            amplitude_m,
            cycle: cycle + 1,
            source,
        });
    }
    if cancelled {
        return Err(DesignError::PointInterrupted {
            frequency_hz,
            amplitude_m,
            cycle: cycle + 1,
        });
    }
    if !w.ledger.kinetic_j.is_finite() {
        return Err(DesignError::Unstable {
            frequency_hz,
            amplitude_m,
            cycle: cycle + 1,
        });
    }
    Ok(())
}

/// The point in progress of a resumed run (`None` without one or without `resume`): a finished
/// point or one at another (f, X) is an error.
fn load_running_point(
    checkpointing: Option<&PointCheckpointing>,
    frequency_hz: f64,
    amplitude_m: f64,
) -> Result<Option<Box<PointProgress>>, DesignError> {
    use pdamp_io::checkpoint as ck;
    let resumed = match checkpointing {
        Some(c) if c.resume => {
            match ck::load::<PointCheckpoint>(&c.path, POINT_KIND, &c.scenario_digest)
                .map_err(DesignError::from)?
            {
                Some(PointCheckpoint::Running(p)) => Some(p),
                Some(PointCheckpoint::Finished) => {
                    return Err(DesignError::CheckpointFinished {
                        path: c.path.clone(),
                    });
                }
                None => None,
            }
        }
        _ => None,
    };
    if let Some(p) = &resumed
        && (p.frequency_hz != frequency_hz || p.amplitude_m != amplitude_m)
    {
        return Err(DesignError::CheckpointOtherPoint {
            frequency_hz: p.frequency_hz,
            amplitude_m: p.amplitude_m,
        });
    }
    Ok(resumed)
}

/// What a point records over its evaluated cycles: the sampled driving force and container
/// velocity, the energy ledger at their start and, for the early stop, per evaluated cycle the
/// sums of the single-bin DFT of force and velocity (additive over whole cycles) and the
/// running estimates.
struct PointRecord {
    times: Vec<f64>,
    force: Vec<f64>,
    velocity: Vec<f64>,
    ledger0: Option<pdamp_dem::EnergyLedger>,
    cycle_start_sample: usize,
    f_sum: (f64, f64),
    v_sum: (f64, f64),
    history: Vec<RunningEstimate>,
    per_cycle: Vec<RunningEstimate>,
}

impl PointRecord {
    /// An empty record with room for `samples` samples.
    fn with_capacity(samples: usize) -> Self {
        let times = Vec::with_capacity(samples);
        let force = Vec::with_capacity(times.capacity());
        let velocity = Vec::with_capacity(times.capacity());
        Self {
            times,
            force,
            velocity,
            ledger0: None,
            cycle_start_sample: 0,
            f_sum: (0.0, 0.0),
            v_sum: (0.0, 0.0),
            history: Vec::new(),
            per_cycle: Vec::new(),
        }
    }

    /// The point's checkpoint in cycle `cycle` at (f, X), with the world's and the observer's
    /// state and the wall time so far.
    fn progress(
        &self,
        (frequency_hz, amplitude_m): (f64, f64),
        cycle: u32,
        world: pdamp_dem::state::WorldState,
        observer: Vec<u8>,
        wall_time_s: f64,
    ) -> PointProgress {
        PointProgress {
            frequency_hz,
            amplitude_m,
            cycle,
            world,
            times: self.times.clone(),
            force: self.force.clone(),
            velocity: self.velocity.clone(),
            ledger0: self.ledger0,
            cycle_start_sample: self.cycle_start_sample,
            f_sum: self.f_sum,
            v_sum: self.v_sum,
            history: self.history.clone(),
            per_cycle: self.per_cycle.clone(),
            observer,
            wall_time_s,
        }
    }

    /// The cycle just evaluated added to the early-stop estimates: its harmonic amplitudes of
    /// force and velocity, the running estimate of their mean over the evaluated cycles and
    /// the cycle's own estimate (complex power, D Eq. 3.13–3.17; NaN where undefined).
    fn add_cycle(&mut self, damper: &Damper, frequency_hz: f64) {
        let k0 = self.cycle_start_sample;
        let fc = harmonic_amplitude(&self.times[k0..], &self.force[k0..], frequency_hz);
        let vc = harmonic_amplitude(&self.times[k0..], &self.velocity[k0..], frequency_hz);
        self.cycle_start_sample = self.times.len() - 1;
        self.f_sum = (self.f_sum.0 + fc.0, self.f_sum.1 + fc.1);
        self.v_sum = (self.v_sum.0 + vc.0, self.v_sum.1 + vc.1);
        let n = self.history.len() as f64 + 1.0;
        let estimate = |f: (f64, f64), v: (f64, f64)| {
            complex_power(
                Complex64::new(f.0, f.1),
                Complex64::new(v.0, v.1),
                frequency_hz,
                damper.bed_mass_kg,
                damper.container_mass_kg,
            )
            .map(|cp| RunningEstimate {
                effective_loss_factor: cp.effective_loss_factor,
                effective_mass_ratio: cp.effective_mass_ratio,
            })
            .unwrap_or(RunningEstimate {
                effective_loss_factor: f64::NAN,
                effective_mass_ratio: f64::NAN,
            })
        };
        let (f_sum, v_sum) = (self.f_sum, self.v_sum);
        self.history.push(estimate(
            (f_sum.0 / n, f_sum.1 / n),
            (v_sum.0 / n, v_sum.1 / n),
        ));
        self.per_cycle.push(estimate(fc, vc));
    }

    /// Complex power of the whole evaluated record at (f, X) [D Eq. 3.13–3.17].
    fn complex_power(
        &self,
        damper: &Damper,
        frequency_hz: f64,
        amplitude_m: f64,
    ) -> Result<pdamp_signal::complex_power::ComplexPowerResult, DesignError> {
        let f_hat = harmonic_amplitude(&self.times, &self.force, frequency_hz);
        let v_hat = harmonic_amplitude(&self.times, &self.velocity, frequency_hz);
        complex_power(
            Complex64::new(f_hat.0, f_hat.1),
            Complex64::new(v_hat.0, v_hat.1),
            frequency_hz,
            damper.bed_mass_kg,
            damper.container_mass_kg,
        )
        .map_err(|source| DesignError::ComplexPower {
            frequency_hz,
            amplitude_m,
            source,
        })
    }
}

impl PointResult {
    /// The result of a point (frequency f in Hz, amplitude X in m) from its complex power
    /// [D Eq. 3.13–3.17] and the energy ledger at the start and end of the `n_eval` evaluated
    /// cycles (dissipation per cycle, its shares, the balance), with the time step and steps
    /// taken. Shared by the CPU ([`Damper::run_point`]) and GPU paths.
    pub(crate) fn evaluate(
        (frequency_hz, amplitude_m): (f64, f64),
        cp: &pdamp_signal::complex_power::ComplexPowerResult,
        (l0, l1): (&pdamp_dem::EnergyLedger, &pdamp_dem::EnergyLedger),
        n_eval: u32,
        converged: Option<bool>,
        (time_step_s, steps): (f64, u64),
        wall_time_s: f64,
    ) -> Self {
        let omega = 2.0 * PI * frequency_hz;
        let n = n_eval as f64;
        let d_np = l1.dissipated_normal_pp_j - l0.dissipated_normal_pp_j;
        let d_nw = l1.dissipated_normal_pw_j - l0.dissipated_normal_pw_j;
        let d_tp = l1.dissipated_tangential_pp_j - l0.dissipated_tangential_pp_j;
        let d_tw = l1.dissipated_tangential_pw_j - l0.dissipated_tangential_pw_j;
        let d = d_np + d_nw + d_tp + d_tw;
        let dw = l1.wall_work_j - l0.wall_work_j;
        let de = (l1.kinetic_j - l0.kinetic_j)
            + (l1.potential_j - l0.potential_j)
            + (l1.elastic_j - l0.elastic_j);
        let share = |x: f64| if d > 0.0 { x / d } else { 0.0 };
        let a = amplitude_m * omega * omega;
        PointResult {
            frequency_hz,
            amplitude_m,
            acceleration_m_s2: a,
            intensity: a / STANDARD_GRAVITY_M_S2,
            velocity_amplitude_m_s: amplitude_m * omega,
            dissipated_energy_per_cycle_j: cp.dissipated_energy_per_cycle_j,
            loss_factor: cp.loss_factor,
            effective_loss_factor: cp.effective_loss_factor,
            effective_mass_ratio: cp.effective_mass_ratio,
            effective_moving_mass_re_kg: cp.effective_moving_mass_re_kg,
            effective_moving_mass_im_kg: cp.effective_moving_mass_im_kg,
            ledger_dissipated_per_cycle_j: d / n,
            ledger_wall_work_per_cycle_j: dw / n,
            share_normal_pp: share(d_np),
            share_normal_pw: share(d_nw),
            share_tangential_pp: share(d_tp),
            share_tangential_pw: share(d_tw),
            energy_closure_relative: (dw - de - d) / dw.abs().max(1e-300),
            cycles_evaluated: n_eval,
            converged,
            time_step_s,
            steps,
            wall_time_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonic_amplitude_exact_for_whole_cycles() {
        let f = 7.0;
        let n = 200;
        let t: Vec<f64> = (0..=3 * n).map(|k| k as f64 / (f * n as f64)).collect();
        let w = 2.0 * PI * f;
        // x = 2 cos(Ωt) − 3 sin(Ωt) + 5 + cos(3Ωt) → X̂ = 2 + 3i
        let x: Vec<f64> = t
            .iter()
            .map(|t| 2.0 * (w * t).cos() - 3.0 * (w * t).sin() + 5.0 + (3.0 * w * t).cos())
            .collect();
        let (re, im) = harmonic_amplitude(&t, &x, f);
        assert!((re - 2.0).abs() < 1e-12, "{re}");
        assert!((im - 3.0).abs() < 1e-12, "{im}");
    }

    #[test]
    fn harmonic_amplitude_nonuniform_steps() {
        let f = 3.0;
        let w = 2.0 * PI * f;
        // Uneven steps over two cycles (as Gear's step control gives).
        let mut t = vec![0.0];
        let mut k = 0;
        while *t.last().unwrap() < 2.0 / f {
            let h = (1e-3 * (1.0 + 0.5 * ((k as f64) * 0.37).sin())).min(2.0 / f - t[t.len() - 1]);
            t.push(t[t.len() - 1] + h);
            k += 1;
        }
        let x: Vec<f64> = t.iter().map(|t| 1.5 * (w * t).sin()).collect();
        let (re, im) = harmonic_amplitude(&t, &x, f);
        // sin = Re(−i e^{iΩt}) → X̂ = −1.5 i
        assert!(re.abs() < 1e-4 && (im + 1.5).abs() < 1e-4, "{re} {im}");
    }
}
