//! The run: preparation of the powder, the coupled run and its checkpoints.

use pdamp_dem::time_loop::{self, CancelToken, Flow, LoopControl, LoopEnd, LoopEvent};
use std::ops::ControlFlow;
use std::path::Path;
use std::time::Instant;

use pdamp_io::checkpoint::{self as ck, CheckpointHeader};

use super::checkpoint::{CHECKPOINT_KIND, Checkpointing, Phase, RunState, scenario_digest};
use super::outputs::{create_dir, write_outputs};
use super::{
    CantileverError, CantileverResult, CantileverScenario, PowderSpec, RunOptions, build_structure,
    cavity_interface,
};
use crate::bed::PowderBed;
use crate::couple::{Coupled, CoupledEnergy};
use crate::damping::{self, TableOneRatios};
use crate::error::ParameterError;
use crate::fe::{Aabb, Dynamics, GenAlpha, Structure};
use crate::health::HealthError;
use crate::law::PowderLaw;
use crate::prep::{PrepReport, Preparation};

/// Runs the scenario (preparation + coupled run) without files. `progress(stage, fraction)`.
pub fn run(
    sc: &CantileverScenario,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, CantileverError> {
    sc.validate()?;
    run_core(sc, None, None, None, progress)
}

/// Runs the scenario and writes its outputs ([`write_outputs`]) into `dir`, checkpointing
/// into `DIR/checkpoint.bin` every `options.checkpoint_interval_s` of wall-clock time, once
/// the preparation is finished (unless the interval is 0) and when `options.cancel` is
/// cancelled (the CLI's Ctrl-C/SIGTERM), which ends the run with
/// [`CantileverError::Interrupted`]. With `options.resume` the run
/// continues from the checkpoint (a checkpoint of another scenario is refused) and the
/// outputs equal those of an uninterrupted run byte for byte, wall times aside; resuming a
/// finished run returns its summary.
pub fn run_in_dir(
    sc: &CantileverScenario,
    dir: &Path,
    options: RunOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, CantileverError> {
    sc.validate()?;
    if !(options.checkpoint_interval_s >= 0.0 && options.checkpoint_interval_s.is_finite()) {
        return Err(ParameterError::out_of_range(
            "--checkpoint-interval-s",
            options.checkpoint_interval_s,
            "must be finite and ≥ 0 (0 = only on Ctrl-C)",
        )
        .into());
    }
    let digest = scenario_digest(sc)?;
    let c = Checkpointing {
        path: dir.join(ck::CHECKPOINT_FILE),
        header: CheckpointHeader::new(CHECKPOINT_KIND, &digest),
        interval_s: options.checkpoint_interval_s,
        cancel: options.cancel.clone(),
    };
    let resumed: Option<Phase> = if options.resume {
        ck::load(&c.path, CHECKPOINT_KIND, &digest).map_err(CantileverError::from)?
    } else {
        None
    };
    if let Some(Phase::Finished) = resumed {
        let path = dir.join("summary.json");
        let text = std::fs::read_to_string(&path).map_err(|source| CantileverError::File {
            path: path.clone(),
            source,
        })?;
        let json = |source| CantileverError::Json {
            path: path.clone(),
            source,
        };
        let js: serde_json::Value = serde_json::from_str(&text).map_err(json)?;
        return serde_json::from_value(js["result"].clone()).map_err(json);
    }
    create_dir(dir)?;
    let r = run_core(sc, Some(&c), resumed, Some(dir), progress)?;
    write_outputs(dir, sc, &r)?;
    c.save(&Phase::Finished)?;
    Ok(r)
}

/// The run; with `vtk_dir` the ParaView frames of [`crate::vtk::PowderSnapshots`] go there.
fn run_core(
    sc: &CantileverScenario,
    ckp: Option<&Checkpointing>,
    resumed: Option<Phase>,
    vtk_dir: Option<&Path>,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, CantileverError> {
    let (s, tip) = build_structure(&sc.beam, &sc.load, sc.run.gravity_m_s2);
    let dt = sc.run.time_step_s;
    let cavity = sc.beam.cavity();
    // Without checkpoints a run is not stopped (it has nowhere to continue from).
    let cancel = ckp.map_or_else(CancelToken::new, |c| c.cancel.clone());
    let _armed = ckp.map(|_| cancel.arm());
    let mut control = LoopControl::new(&cancel, ckp.map_or(0.0, |c| c.interval_s));
    let (preparing, running) = resumed_phase(resumed)?;
    // preparation (fresh, continued, or done before the checkpoint)
    let prepared = match (&running, &sc.powder) {
        (Some(_), _) => None,
        (None, Some(p)) => Some(prepare_powder(
            p,
            cavity,
            dt,
            ckp,
            preparing,
            &mut control,
            progress,
        )?),
        (None, None) => Some((
            PowderBed::at_rest(PowderLaw::PAPER, &[], &[], 8000.0, [0.0; 3], dt),
            None,
        )),
    };
    let mut start = start_coupled(sc, s, cavity, running, prepared)?;
    coupled_steps(sc, ckp, &mut control, &mut start, tip, vtk_dir, progress)?;
    let CoupledStart { c, mut res, .. } = start;
    let t_release = sc.load.rise_s + sc.load.hold_s;
    finish_result(&c, &mut res, t_release);
    Ok(res)
}

/// Splits a resumed checkpoint into the preparation in progress (checked for consistency) or
/// the coupled run in progress.
fn resumed_phase(
    resumed: Option<Phase>,
) -> Result<(Option<Preparation>, Option<RunState>), CantileverError> {
    let (mut preparing, mut running) = (None, None);
    match resumed {
        Some(Phase::Preparing(p)) => {
            p.check_consistency()?;
            preparing = Some(*p);
        }
        Some(Phase::Running(r)) => running = Some(*r),
        Some(Phase::Finished) | None => {}
    }
    Ok((preparing, running))
}

/// Prepares the powder in the cavity (fresh, or continued from `preparing`), checkpointing
/// it when due and stopping on request; returns the prepared bed and its report.
fn prepare_powder(
    p: &PowderSpec,
    cavity: Aabb,
    dt: f64,
    ckp: Option<&Checkpointing>,
    preparing: Option<Preparation>,
    control: &mut LoopControl,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<(PowderBed, Option<PrepReport>), CantileverError> {
    let mut pr = preparing.unwrap_or_else(|| {
        Preparation::new(
            cavity,
            &p.psd(),
            p.scaled_law(),
            p.density_kg_m3,
            dt,
            &p.scaled_prep(),
        )
    });
    let mut err = None;
    let flow = pr.run(progress, &mut |pr| {
        let Some(c) = ckp else {
            return ControlFlow::Continue(());
        };
        control
            .checkpoint_or_stop(|| c.save(&Phase::Preparing(Box::new(pr.snapshot()))))
            .unwrap_or_else(|e| {
                err = Some(e);
                ControlFlow::Break(())
            })
    });
    let flow = flow?;
    if let Some(e) = err {
        return Err(e);
    }
    if flow.is_break() {
        let c = ckp.ok_or(CantileverError::PreparationStopped)?;
        return Err(c.interrupted(pr.time_s()));
    }
    let (pw, rep) = pr.finish();
    Ok((pw, Some(rep)))
}

/// The coupled system ready to take step `first`, with the results so far.
struct CoupledStart {
    c: Coupled,
    res: CantileverResult,
    first: u64,
    nsteps: u64,
}

/// Builds the structure's dynamics and the coupled system, from the checkpointed run state
/// or from the prepared powder, with the results so far.
fn start_coupled(
    sc: &CantileverScenario,
    mut s: Structure,
    cavity: Aabb,
    running: Option<RunState>,
    prepared: Option<(PowderBed, Option<PrepReport>)>,
) -> Result<CoupledStart, CantileverError> {
    let dt = sc.run.time_step_s;
    let n = s.n_dof();
    let dynamics = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(sc.beam.rho_inf),
        dt,
        vec![0.0; n],
        vec![0.0; n],
        sc.beam.rayleigh,
    )?;
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
        particles: c.particles(),
        structure_dofs: c.structure.n_dof(),
        elements,
        interface_dofs: c.interface.n_dof(),
        steps: nsteps,
        mean_iterations: 0.0,
        max_iterations: 0,
        wall_time_s: 0.0,
        structure_mass_kg: structure_mass,
        powder_mass_kg: c.particle_mass_kg(),
        energy_closure: 0.0,
        coupled_step_wall_time_s: Default::default(),
    };
    let (c, res, first) = match (running, prepared) {
        (Some(st), _) => {
            let mut c = Coupled::from_state(s, dynamics, interface, sc.run.coupling, st.coupled)?;
            c.container = sc.powder.is_some().then_some(cavity);
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
            powder.world.gravity_m_s2 = pdamp_dem::Vec3::from(sc.run.gravity_m_s2);
            let mut c = Coupled::new(s, dynamics, powder, interface, sc.run.coupling)?;
            c.container = sc.powder.is_some().then_some(cavity);
            let res = result(&c, prep);
            (c, res, 1)
        }
        (None, None) => return Err(CantileverError::NoStart),
    };
    Ok(CoupledStart {
        c,
        res,
        first,
        nsteps,
    })
}

/// Takes the coupled steps `first..=nsteps`: samples the tip, checks the energy health,
/// writes the ParaView frames and checkpoints when due or on a stop request; sets the wall
/// time of the run.
fn coupled_steps(
    sc: &CantileverScenario,
    ckp: Option<&Checkpointing>,
    control: &mut LoopControl,
    start: &mut CoupledStart,
    tip: usize,
    vtk_dir: Option<&Path>,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<(), CantileverError> {
    let dt = sc.run.time_step_s;
    let CoupledStart {
        c,
        res,
        first,
        nsteps,
    } = start;
    let (first, nsteps) = (*first, *nsteps);
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
        cp.save(&state(c, res, 0, wall(&clock)))?;
    }
    let mut snapshots = match vtk_dir {
        Some(d) if sc.run.vtk_interval_s > 0.0 => {
            let every = ((sc.run.vtk_interval_s / dt).round() as u64).max(1);
            Some(crate::vtk::PowderSnapshots::new(
                d,
                every,
                dt,
                &c.structure.mesh,
            ))
        }
        _ => None,
    };
    if let Some(s) = snapshots.as_mut() {
        if first > 1 {
            s.resume_after(first - 1)?;
        } else {
            s.on_step(0, c)?;
        }
    }
    let every = ((sc.run.output_interval_s / dt).round() as u64).max(1);
    let e_every = (nsteps / 2000).max(1);
    let t_release = sc.load.rise_s + sc.load.hold_s;
    let mut q = first - 1;
    let end = time_loop::run(control, |event| {
        if event == LoopEvent::Checkpoint {
            if let Some(cp) = ckp {
                cp.save(&state(c, res, q, wall(&clock)))?;
            }
            return Ok(Flow::Continue);
        }
        if q == nsteps {
            return Ok(Flow::Finished);
        }
        q += 1;
        let it = c.step()?;
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
            let e = c.energy();
            res.energy.push((t, e));
            check_energy_health(c, &res.energy)?;
        }
        if let Some(s) = snapshots.as_mut() {
            s.on_step(q, c)?;
        }
        if q % 200 == 0 {
            progress("coupled run", q as f64 / nsteps as f64);
        }
        Ok::<_, CantileverError>(Flow::Continue)
    })?;
    if end == LoopEnd::Cancelled
        && let Some(cp) = ckp
    {
        return Err(cp.interrupted(c.dynamics.t));
    }
    res.wall_time_s = wall(&clock);
    Ok(())
}

/// The run's statistics: coupling iterations, Table-1 damping ratios (release at
/// `t_release`) and the energy closure (largest drift of the balance from its value after
/// step 1 over the largest stored energy).
fn finish_result(c: &Coupled, res: &mut CantileverResult, t_release: f64) {
    res.coupled_step_wall_time_s = c.timing;
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
}

/// The energy health check of the coupled run ([`crate::health::check_energy`]): the
/// cumulative dissipation must not be negative beyond a tenth of the largest energy so far,
/// and the balance must not grow by more than half of it (from its value after step 1, when
/// the wall springs are known).
fn check_energy_health(
    c: &Coupled,
    energy: &[(f64, CoupledEnergy)],
) -> Result<(), Box<HealthError>> {
    let Some((_, e)) = energy.last() else {
        return Ok(());
    };
    let b0 = energy[1.min(energy.len() - 1)].1.balance_j;
    let scale = energy
        .iter()
        .map(|(_, e)| {
            e.structure_kinetic_j
                + e.structure_strain_j
                + e.particle_kinetic_j
                + e.contact_elastic_j
        })
        .chain(std::iter::once(e.load_work_j.abs()))
        .fold(0.0, f64::max);
    crate::health::check_energy(e.dissipated_j, e.balance_j - b0, scale).map_err(|s| {
        Box::new(HealthError::of_world(
            c.world.time_s,
            "coupled run",
            s,
            &c.world,
            &c.law,
        ))
    })
}
