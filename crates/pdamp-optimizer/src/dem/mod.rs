//! Level 3: coupled DEM (approach 1, D Sect. 3.3) on the best designs, with an ensemble of
//! independently dropped beds per design and the 95 % confidence interval of the objective.
//!
//! For every design a damper scenario is written (a box of the design's inner dimensions built
//! from one-sided planes, two-sided shelves between horizontal layers, the study's particle
//! material with its Young's modulus, Poisson's ratio, restitution (Gonthier law) and
//! friction, the container material of `[verification]`), and a coupling scenario with the
//! study's structure and free analysis and that damper as `model = "dem"`. Each packing has its
//! own seed: the drop-down inserts the particles at random and lets them fall in rounds — a
//! horizontal layer is filled under gravity along −x (it collects against a wall, as the
//! rolling layers of D Sect. 5.1 do once they roll) and then turned to −z; a vertical bed falls
//! under −z. The run is `pdamp couple` itself ([`pdamp_structure::report::run_couple`]), so
//! every output of a coupled DEM run (decay.csv, damping.csv, the energy exchange, ParaView
//! frames) lies in `dem/design_N/packing_K/out/`.

mod scenarios;

use crate::DesignError;
use crate::resonance_sweep::{SweepPlan, SweepTarget};
use crate::space::{Design, Space};
use crate::study::ObjectiveSpec;
use pdamp_dem::contact::hertz::hertz_contact_time;
use pdamp_design::ensemble::EnsembleStat;
use pdamp_structure::forced;
use pdamp_structure::free::CoupledDamper;
use pdamp_structure::modal::ModalStructure;
use scenarios::{container_seed, damper_file};
use serde::Serialize;
use std::path::{Path, PathBuf};

pub use scenarios::{couple_scenario, damper_scenario, decay_scenario, sweep_scenario};

/// One design's coupled-DEM result.
#[derive(Debug, Clone, Serialize)]
pub struct DemVerification {
    /// The design's rank among the verified designs (1-based).
    pub rank: usize,
    /// The objective's value: `stroke_m` (min_stroke, smaller is better) or
    /// `mean_damping_ratio` (max_damping: ζ averaged over the amplitude grid and the modes,
    /// larger is better).
    pub objective: &'static str,
    /// The objective of every packing.
    pub values: Vec<f64>,
    /// Mean, spread and 95 % confidence interval of the objective over the packings.
    pub stat: EnsembleStat,
    /// The level-1 (formulas, time simulation) value of the same design.
    pub time_simulation: f64,
    /// max_damping: each mode's ζ̄ over the packings and ζ(X) on the amplitude grid.
    pub modes: Vec<DemModeDamping>,
    /// min_frf_peak, max_resonance_damping: each mode's resonance from the DEM sweeps.
    pub resonances: Vec<DemResonance>,
    /// DEM time step used, s.
    pub time_step_s: f64,
    /// Factor applied to the particles' Young's modulus.
    pub youngs_modulus_scale: f64,
    /// Particles of the beds (all containers).
    pub particles: usize,
    /// Coupled runs made (packings, × modes for max_damping).
    pub runs: usize,
    /// Estimated cost before the runs: particles × DEM steps of all runs.
    pub estimated_particle_steps: f64,
    /// Largest energy closure of the runs (bed ledger and coupling, relative to the energy
    /// dissipated; `pdamp couple`'s `energy_exchange`).
    pub energy_closure: f64,
    /// Wall time of all packings, s.
    pub wall_s: f64,
    /// Where the runs are (relative to the output directory).
    pub dir: String,
}

impl DemVerification {
    /// Whether a larger objective is better (damping) or a smaller one (stroke, peak).
    pub fn larger_is_better(&self) -> bool {
        matches!(
            self.objective,
            "mean_damping_ratio" | "mean_resonance_damping_ratio"
        )
    }
}

impl DemResonance {
    /// Level 1's peak relative to the bare peak on the same sweep as the DEM (the formula
    /// dampers run through the plan's sweep).
    pub fn formula_sweep_relative_peak(&self) -> f64 {
        self.time_simulation.0 * (1.0 + self.sweep.formula_sweep_bias())
    }
}

/// One mode's resonance from the coupled-DEM sweeps of a design (forced objectives,
/// [`crate::resonance_sweep`]).
#[derive(Debug, Clone, Serialize)]
pub struct DemResonance {
    /// Mode number (1-based).
    pub mode: usize,
    /// Peak at the output point relative to the bare structure's, per packing.
    pub relative_peak: Vec<f64>,
    /// Its ensemble statistics.
    pub relative_peak_stat: EnsembleStat,
    /// ζ at resonance (D Eq. 3.47) per packing.
    pub damping_ratio: Vec<f64>,
    /// Its ensemble statistics.
    pub damping_ratio_stat: EnsembleStat,
    /// Frequency of the peak per packing, Hz.
    pub resonance_frequency_hz: Vec<f64>,
    /// Level 1 (steady-state FRF of the formula dampers, D Eq. 3.44): relative peak, ζ,
    /// frequency of the peak (Hz).
    pub time_simulation: (f64, f64, f64),
    /// The sweep the packings ran.
    pub sweep: crate::resonance_sweep::SweepSummary,
    /// Why the sweep was planned again after the first packing, if it was.
    pub replanned: Option<String>,
}

/// One mode's damping from the coupled-DEM decays of a design (max_damping).
#[derive(Debug, Clone, Serialize)]
pub struct DemModeDamping {
    /// Mode number (1-based).
    pub mode: usize,
    /// ζ averaged over the amplitude grid, per packing.
    pub damping_ratio: Vec<f64>,
    /// Its ensemble statistics.
    pub stat: EnsembleStat,
    /// The level-1 value of the same design.
    pub time_simulation: f64,
    /// ζ(X) over the packings on the amplitude grid: (X in m, statistics).
    pub curve: Vec<(f64, EnsembleStat)>,
    /// Smallest and largest cycle amplitude the decays reached (the grid outside it takes the
    /// nearest cycle's ζ), m.
    pub covered_amplitude_m: (f64, f64),
}

/// Largest relative particle velocity expected in the study: twice the damper point's
/// initial velocity amplitude X₀ω, plus a margin, m/s.
pub fn check_velocity_m_s(space: &Space, d: &Design) -> f64 {
    let a = space.peak_acceleration_m_s2(d);
    let k = space.study.free.mode;
    let w = space.structure(d.choice).modes[k].omega_rad_s();
    2.0 * a / w + 0.2
}

/// The DEM time step: `[verification] time_step_s` or 0.08 of the shorter Hertz contact time,
/// particle–particle or particle–container wall, at the check velocity (D Eq. 4.8; pdamp refuses
/// steps above 0.1 of the shortest contact).
pub fn time_step_s(space: &Space, d: &Design) -> f64 {
    time_step_at_s(space, d, check_velocity_m_s(space, d))
}

/// [`time_step_s`] for a largest relative impact velocity `velocity_m_s`.
pub fn time_step_at_s(space: &Space, d: &Design, velocity_m_s: f64) -> f64 {
    let v = &space.study.file.verification;
    if let Some(dt) = v.time_step_s {
        return dt;
    }
    let g = space.geometry(d.choice);
    let m = &space.study.file.materials[d.choice.material];
    let e = m.youngs_modulus_pa * v.youngs_modulus_scale;
    let compliance = (1.0 - m.poisson_ratio * m.poisson_ratio) / e;
    // two particles: E* = 1/(2(1−ν²)/E), R* = r/2, m* = m/2
    let pair = hertz_contact_time(
        1.0 / (2.0 * compliance),
        0.5 * g.radius_m,
        0.5 * g.particle_mass_kg,
        velocity_m_s,
    );
    // a particle on the container wall (flat, at rest): R* = r, m* = m — shorter than the pair's
    // where the wall is much stiffer than softened particles
    let c = &v.container;
    let wall = hertz_contact_time(
        1.0 / (compliance + (1.0 - c.poisson_ratio * c.poisson_ratio) / c.youngs_modulus_pa),
        g.radius_m,
        g.particle_mass_kg,
        velocity_m_s,
    );
    0.08 * pair.min(wall)
}

/// How much longer than the formulas' decay a DEM decay runs: a DEM bed that damps less than
/// the formulas predict still reaches (most of) the bottom of the amplitude range.
pub const DEM_DECAY_MARGIN: f64 = 1.25;

/// One coupled DEM run of a packing: writes the damper scenario of every container (each its
/// own drop) and the coupling scenario to `dir`, runs
/// `pdamp couple` into `dir/out` and returns the history at the output point (`history`:
/// `decay.csv` of a free analysis, `response.csv` of a sweep) and the run's energy closure
/// (the larger of the bed ledger's and the coupling's, from `summary.json`).
fn run_one(
    space: &Space,
    d: &Design,
    dir: &Path,
    seed: u64,
    couple: &str,
    history: &str,
) -> Result<(pdamp_structure::free::TimeHistory, f64), DesignError> {
    std::fs::create_dir_all(dir).map_err(|e| DesignError::output(dir, e))?;
    for j in 0..space.location(d.choice).points.len() {
        let dscn = dir.join(damper_file(j));
        let text = damper_scenario(space, d, container_seed(seed, j));
        pdamp_io::atomic::write_atomic(&dscn, text.as_bytes())
            .map_err(|e| DesignError::output(&dscn, e))?;
    }
    let cscn = dir.join("couple.toml");
    pdamp_io::atomic::write_atomic(&cscn, couple.as_bytes())
        .map_err(|e| DesignError::output(&cscn, e))?;
    let run_out = dir.join("out");
    let _ = std::fs::remove_dir_all(&run_out);
    pdamp_structure::report::run_couple(
        &cscn,
        &run_out,
        pdamp_scenario::run::RunOptions::new(0.0, false),
        &mut |_| {},
    )
    .map_err(|error| DesignError::StructureFile {
        path: cscn.clone(),
        error: Box::new(error),
    })?;
    let sp = run_out.join("summary.json");
    let summary: serde_json::Value = std::fs::read_to_string(&sp)
        .map_err(|e| DesignError::output(&sp, e))
        .and_then(|t| serde_json::from_str(&t).map_err(|e| DesignError::output(&sp, e)))?;
    let e = &summary["energy_exchange"];
    let closure = ["bed_ledger_closure", "coupling_closure"]
        .iter()
        .map(|k| e[*k].as_f64().unwrap_or(f64::NAN))
        .fold(0.0_f64, |a, b| if b.is_nan() { f64::NAN } else { a.max(b) });
    Ok((read_decay(&run_out.join(history))?, closure))
}

/// Runs the coupled DEM of `d` on `[verification] packings` beds in `out/dem/design_RANK` and
/// returns the objective of each: the stroke at the evaluation time (min_stroke), or ζ(X) of
/// every mode from a free decay over the amplitude range (max_damping, one run per mode and
/// packing, [`DecayPlan`](crate::fidelity::DecayPlan) × [`DEM_DECAY_MARGIN`]), or each mode's resonance from a sine sweep
/// (min_frf_peak, max_resonance_damping, [`crate::resonance_sweep`]). `level1` is the design's time-simulation
/// evaluation (compared in the result). The cost (particles × steps) is reported through
/// `progress` before the first run.
///
/// # Errors
/// Input, DEM and output errors (the message names the packing's directory).
pub fn verify_design(
    space: &Space,
    d: &Design,
    rank: usize,
    level1: &crate::fidelity::Evaluation,
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<DemVerification, DesignError> {
    let st = space.study;
    let v = &st.file.verification;
    let rel = PathBuf::from(format!("dem/design_{rank}"));
    let started = std::time::Instant::now();
    let dt = time_step_s(space, d);
    // every container carries the design's bed
    let particles: usize =
        d.particles.iter().sum::<usize>() * space.location(d.choice).points.len();
    let mut result = DemVerification {
        rank,
        objective: "stroke_m",
        values: Vec::new(),
        stat: EnsembleStat::of(&[]),
        time_simulation: level1.stroke_m.unwrap_or(f64::NAN),
        modes: Vec::new(),
        resonances: Vec::new(),
        time_step_s: dt,
        youngs_modulus_scale: v.youngs_modulus_scale,
        particles,
        runs: 0,
        estimated_particle_steps: 0.0,
        energy_closure: 0.0,
        wall_s: 0.0,
        dir: rel.display().to_string(),
    };
    match &st.file.objective {
        ObjectiveSpec::MinStroke { evaluate_at_s } => {
            let k = st.free.mode;
            let period = 1.0 / space.structure(d.choice).modes[k].frequency_hz;
            result.estimated_particle_steps = announce(
                progress,
                &result,
                v.packings,
                v.packings as f64 * evaluate_at_s,
            );
            let couple = couple_scenario(space, d, *evaluate_at_s)?;
            for p in 0..v.packings {
                progress(&format!(
                    "design {rank}, packing {}/{}: coupled DEM",
                    p + 1,
                    v.packings
                ));
                let dir = out.join(&rel).join(format!("packing_{}", p + 1));
                let (hist, closure) =
                    run_one(space, d, &dir, seed(space, p), &couple, "decay.csv")?;
                result.runs += 1;
                result.energy_closure = result.energy_closure.max(closure);
                result.values.push(pdamp_structure::study::stroke_at(
                    &hist,
                    *evaluate_at_s,
                    1.1 * period,
                ));
            }
        }
        ObjectiveSpec::MaxDamping { .. } => {
            damping_decays(space, d, level1, out, &mut result, progress)?;
        }
        ObjectiveSpec::MinFrfPeak { .. } | ObjectiveSpec::MaxResonanceDamping { .. } => {
            resonance_sweeps(space, d, level1, out, &mut result, progress)?;
        }
    }
    result.stat = EnsembleStat::of(&result.values);
    result.wall_s = started.elapsed().as_secs_f64();
    Ok(result)
}

/// The cost of a verification in particle-steps (settling excluded), reported through
/// `progress` before the runs.
fn announce(
    progress: &mut dyn FnMut(&str),
    r: &DemVerification,
    runs: usize,
    simulated_s: f64,
) -> f64 {
    let ps = r.particles as f64 * simulated_s / r.time_step_s;
    progress(&format!(
        "design {}: coupled DEM, {runs} runs of {} particles, {simulated_s:.3} s simulated at \
         dt = {:.2e} s: {ps:.2e} particle-steps (≈ {:.0} min at 5e6 particle-steps/s; bed \
         preparation extra)",
        r.rank,
        r.particles,
        r.time_step_s,
        ps / 5e6 / 60.0
    ));
    ps
}

pub(crate) fn seed(space: &Space, packing: usize) -> u64 {
    pdamp_scenario::prepare::packing_seed(space.study.file.search.seed, packing)
}

/// max_damping: one free decay per packing and mode ([`DecayPlan`] × [`DEM_DECAY_MARGIN`]),
/// ζ(X) per cycle, averaged over the amplitude grid; fills `result`'s values and modes.
fn damping_decays(
    space: &Space,
    d: &Design,
    level1: &crate::fidelity::Evaluation,
    out: &Path,
    result: &mut DemVerification,
    progress: &mut dyn FnMut(&str),
) -> Result<(), DesignError> {
    let st = space.study;
    let v = &st.file.verification;
    let rank = result.rank;
    let rel = PathBuf::from(&result.dir);
    let ObjectiveSpec::MaxDamping {
        modes,
        amplitude_min_m,
        amplitude_max_m,
        amplitudes,
    } = &st.file.objective
    else {
        return Err(DesignError::Solver(
            "damping decays: a max_damping objective".into(),
        ));
    };
    result.objective = "mean_damping_ratio";
    result.time_simulation = -level1.cost;
    let dampers = space.coupled_dampers(d)?;
    let structure = space.structure(d.choice);
    let plans = modes
        .iter()
        .map(|&m| {
            crate::fidelity::damping_decay_plan(
                st,
                structure,
                &dampers,
                m - 1,
                *amplitude_min_m,
                *amplitude_max_m,
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let simulated: f64 = plans
        .iter()
        .map(|p| DEM_DECAY_MARGIN * p.spec.duration_s)
        .sum();
    result.estimated_particle_steps = announce(
        progress,
        result,
        v.packings * plans.len(),
        v.packings as f64 * simulated,
    );
    let grid = crate::fidelity::amplitude_grid(*amplitude_min_m, *amplitude_max_m, *amplitudes);
    let mut per_mode: Vec<Vec<Vec<(f64, f64)>>> = vec![Vec::new(); plans.len()];
    for p in 0..v.packings {
        for (i, (plan, &m)) in plans.iter().zip(modes).enumerate() {
            progress(&format!(
                "design {rank}, packing {}/{}, mode {m}: coupled DEM decay",
                p + 1,
                v.packings
            ));
            let dir = out
                .join(&rel)
                .join(format!("packing_{}", p + 1))
                .join(format!("mode_{m}"));
            let duration = DEM_DECAY_MARGIN * plan.spec.duration_s;
            let couple = decay_scenario(space, d, plan, duration)?;
            let (hist, closure) = run_one(space, d, &dir, seed(space, p), &couple, "decay.csv")?;
            result.runs += 1;
            result.energy_closure = result.energy_closure.max(closure);
            per_mode[i].push(crate::fidelity::damping_curve_of(&hist, plan.period_s)?);
        }
    }
    let mean_of = |curve: &[(f64, f64)]| {
        grid.iter()
            .map(|&x| crate::fidelity::curve_at(curve, x))
            .sum::<f64>()
            / grid.len() as f64
    };
    for (i, &m) in modes.iter().enumerate() {
        let curves = &per_mode[i];
        let zeta: Vec<f64> = curves.iter().map(|c| mean_of(c)).collect();
        let covered = curves
            .iter()
            .flatten()
            .fold((f64::INFINITY, 0.0_f64), |a, c| {
                (a.0.min(c.0), a.1.max(c.0))
            });
        let curve = grid
            .iter()
            .map(|&x| {
                let z: Vec<f64> = curves
                    .iter()
                    .map(|c| crate::fidelity::curve_at(c, x))
                    .collect();
                (x, EnsembleStat::of(&z))
            })
            .collect();
        result.modes.push(DemModeDamping {
            mode: m,
            stat: EnsembleStat::of(&zeta),
            damping_ratio: zeta,
            time_simulation: level1
                .damping_ratio_per_mode
                .get(i)
                .copied()
                .unwrap_or(f64::NAN),
            curve,
            covered_amplitude_m: covered,
        });
    }
    result.values = (0..v.packings)
        .map(|p| {
            result.modes.iter().map(|m| m.damping_ratio[p]).sum::<f64>() / result.modes.len() as f64
        })
        .collect();
    Ok(())
}

/// Level 1's resonance of a mode: the steady-state FRF's peak, ζ at it and the bare
/// structure's peak (m).
type Level1Resonance = (crate::fidelity::FrfResonance, f64, f64);

/// min_frf_peak, max_resonance_damping: per mode a [`SweepPlan`] at level 1's resonance
/// (frequency and ζ of the steady-state FRF); one coupled-DEM sweep per packing and mode. After
/// the first packing a mode's sweep is planned again once, around the DEM's peak and for the
/// smaller ζ, if [`crate::resonance_sweep::replan_reason`] says so, and that packing runs
/// again. Fills `result`'s values (mean relative peak or mean ζ over the modes) and resonances.
fn resonance_sweeps(
    space: &Space,
    d: &Design,
    level1: &crate::fidelity::Evaluation,
    out: &Path,
    result: &mut DemVerification,
    progress: &mut dyn FnMut(&str),
) -> Result<(), DesignError> {
    let st = space.study;
    let v = &st.file.verification;
    let rank = result.rank;
    let rel = PathBuf::from(&result.dir);
    let (ObjectiveSpec::MinFrfPeak {
        modes,
        frequencies,
        band,
    }
    | ObjectiveSpec::MaxResonanceDamping {
        modes,
        frequencies,
        band,
    }) = &st.file.objective
    else {
        return Err(DesignError::Solver(
            "resonance sweeps: a forced objective".into(),
        ));
    };
    let peak_objective = matches!(st.file.objective, ObjectiveSpec::MinFrfPeak { .. });
    result.objective = if peak_objective {
        "relative_peak"
    } else {
        "mean_resonance_damping_ratio"
    };
    result.time_simulation = if peak_objective {
        level1.cost
    } else {
        -level1.cost
    };
    let dampers = space.coupled_dampers(d)?;
    let structure = space.structure(d.choice);
    let (mut plans, level1_modes) =
        plan_resonance_sweeps(space, structure, &dampers, modes, *frequencies, *band)?;
    let simulated: f64 = plans.iter().map(|p| p.summary.duration_s).sum();
    result.estimated_particle_steps = announce(
        progress,
        result,
        v.packings * plans.len(),
        v.packings as f64 * simulated,
    );
    let mut peaks: Vec<Vec<forced::PeakDamping>> = vec![Vec::new(); plans.len()];
    let mut replanned: Vec<Option<String>> = vec![None; plans.len()];
    for p in 0..v.packings {
        for (i, &m) in modes.iter().enumerate() {
            let dir = out
                .join(&rel)
                .join(format!("packing_{}", p + 1))
                .join(format!("mode_{m}"));
            loop {
                let plan = &plans[i];
                progress(&format!(
                    "design {rank}, packing {}/{}, mode {m}: coupled DEM sweep {:.3}–{:.3} Hz \
                     in {:.1} s",
                    p + 1,
                    v.packings,
                    plan.summary.start_hz,
                    plan.summary.end_hz,
                    plan.summary.duration_s
                ));
                let couple = sweep_scenario(space, d, plan)?;
                let (hist, closure) =
                    run_one(space, d, &dir, seed(space, p), &couple, "response.csv")?;
                let pk = plan.peak_of(&hist).ok_or_else(|| {
                    DesignError::Solver(format!(
                        "{}: the sweep's response has no peak",
                        dir.display()
                    ))
                })?;
                let why = crate::resonance_sweep::replan_reason(&plan.summary, &pk);
                if let Some(why) = why.filter(|_| p == 0 && replanned[i].is_none()) {
                    progress(&format!(
                        "design {rank}, mode {m}: sweep planned again: {why}"
                    ));
                    let (steady, zeta, _) = level1_modes[i];
                    let k = m - 1;
                    plans[i] = crate::resonance_sweep::sweep_plan(
                        st,
                        structure,
                        &dampers,
                        k,
                        &steady,
                        SweepTarget {
                            centre_hz: pk.resonance_frequency_hz,
                            band_damping_ratio: zeta.max(pk.damping_ratio),
                            rate_damping_ratio: zeta.min(pk.damping_ratio),
                        },
                    )?;
                    replanned[i] = Some(why);
                    continue;
                }
                result.runs += 1;
                result.energy_closure = result.energy_closure.max(closure);
                peaks[i].push(pk);
                break;
            }
        }
    }
    result.resonances = mode_resonances(modes, &level1_modes, &plans, &peaks, replanned);
    // the objective of every packing: the mean over the modes of the relative peak
    // (min_frf_peak) or of ζ (max_resonance_damping)
    let n = modes.len() as f64;
    result.values = (0..v.packings)
        .map(|p| {
            result
                .resonances
                .iter()
                .map(|r| {
                    if peak_objective {
                        r.relative_peak[p]
                    } else {
                        r.damping_ratio[p]
                    }
                })
                .sum::<f64>()
                / n
        })
        .collect();
    Ok(())
}

/// Level 1's resonance of every objective mode (the steady-state FRF's peak, ζ at it by
/// D Eq. 3.47 and the bare structure's peak) and the first [`SweepPlan`] around it.
fn plan_resonance_sweeps(
    space: &Space,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    modes: &[usize],
    frequencies: usize,
    band: f64,
) -> Result<(Vec<SweepPlan>, Vec<Level1Resonance>), DesignError> {
    let st = space.study;
    let mut plans = Vec::new();
    let mut level1_modes = Vec::new();
    for &m in modes {
        let k = m - 1;
        let steady = crate::fidelity::frf_resonance(st, structure, dampers, k, frequencies, band)?;
        let zeta = crate::fidelity::resonance_damping_ratio(st, structure, k, steady.modal_peak)?;
        let bare = crate::fidelity::bare_peak_m(st, k)?;
        level1_modes.push((steady, zeta, bare));
        plans.push(crate::resonance_sweep::sweep_plan(
            st,
            structure,
            dampers,
            k,
            &steady,
            SweepTarget {
                centre_hz: steady.frequency_hz,
                band_damping_ratio: zeta,
                rate_damping_ratio: zeta,
            },
        )?);
    }
    Ok((plans, level1_modes))
}

/// Each mode's resonance over the packings (relative peak, ζ, frequency) beside level 1's.
fn mode_resonances(
    modes: &[usize],
    level1_modes: &[Level1Resonance],
    plans: &[SweepPlan],
    peaks: &[Vec<forced::PeakDamping>],
    mut replanned: Vec<Option<String>>,
) -> Vec<DemResonance> {
    let mut resonances = Vec::new();
    for (i, &m) in modes.iter().enumerate() {
        let (steady, zeta, bare) = level1_modes[i];
        let rel_peak: Vec<f64> = peaks[i].iter().map(|p| p.max_amplitude_m / bare).collect();
        let zetas: Vec<f64> = peaks[i].iter().map(|p| p.damping_ratio).collect();
        resonances.push(DemResonance {
            mode: m,
            relative_peak_stat: EnsembleStat::of(&rel_peak),
            relative_peak: rel_peak,
            damping_ratio_stat: EnsembleStat::of(&zetas),
            damping_ratio: zetas,
            resonance_frequency_hz: peaks[i].iter().map(|p| p.resonance_frequency_hz).collect(),
            time_simulation: (steady.peak_m / bare, zeta, steady.frequency_hz),
            sweep: plans[i].summary,
            replanned: replanned[i].take(),
        });
    }
    resonances
}

/// Reads `decay.csv` or `response.csv` (time_s, displacement_m, …) of a coupled run.
fn read_decay(path: &Path) -> Result<pdamp_structure::free::TimeHistory, DesignError> {
    let text = std::fs::read_to_string(path).map_err(|e| DesignError::output(path, e))?;
    let mut h = pdamp_structure::free::TimeHistory::default();
    for line in text.lines().skip(1) {
        let mut it = line.split(',');
        let t = it.next().and_then(|x| x.parse::<f64>().ok());
        let x = it.next().and_then(|x| x.parse::<f64>().ok());
        if let (Some(t), Some(x)) = (t, x) {
            h.time_s.push(t);
            h.displacement_m.push(x);
        }
    }
    Ok(h)
}
