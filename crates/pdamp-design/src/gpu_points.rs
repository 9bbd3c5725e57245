//! Excitation points of a damper on the GPU backend: one world per point, all advanced together
//! in one batch ([`pdamp_gpu::GpuBatch`]), evaluated with the same complex power method
//! [D Eq. 3.12–3.17] and energy ledger as [`Damper::run_point`] on the CPU.
//!
//! The container's load is turned into the single-bin DFT on the device (per particle, summed at
//! the end), so nothing is read back per step. The points run all their cycles (the early stop
//! on convergence of the CPU path is not offered here).

use crate::damper::{Damper, PointResult, harmonic_amplitude};
use pdamp_dem::{HarmonicTranslation, Motion, World};
use pdamp_gpu::{GpuBatch, GpuDevice};
use pdamp_io::scenario::STANDARD_GRAVITY_M_S2;
use pdamp_signal::Complex64;
use pdamp_signal::complex_power::complex_power;
use std::f64::consts::PI;
use std::sync::Arc;

impl Damper {
    /// Runs the excitation points `(frequency f in Hz, displacement amplitude X in m)` from the
    /// settled state on the GPU, all in one batch (see [`run_points_gpu`]).
    pub fn run_points_gpu(
        &self,
        gpu: &GpuDevice,
        points: &[(f64, f64)],
    ) -> Result<Vec<PointResult>, String> {
        let jobs: Vec<(&Damper, f64, f64)> = points.iter().map(|&(f, x)| (self, f, x)).collect();
        run_points_gpu(gpu, &jobs)
    }
}

/// Runs excitation points `(damper, f in Hz, X in m)` on the GPU, one world each, all in one
/// batch: the points of a field, or one point on the beds of an ensemble (dampers prepared from
/// different packings). The results are those of [`Damper::run_point`] (same time steps, cycles,
/// shortened cycle-end steps, complex power and ledger shares) up to the round-off of another
/// summation order — which a chaotic bed amplifies over the cycles, as it does between any two
/// runs. All dampers must have the same cycles and transient cycles.
pub fn run_points_gpu(
    gpu: &GpuDevice,
    jobs: &[(&Damper, f64, f64)],
) -> Result<Vec<PointResult>, String> {
    let start = std::time::Instant::now();
    let Some(&(first, _, _)) = jobs.first() else {
        return Ok(Vec::new());
    };
    let (cycles, transient_cycles) = (first.cycles, first.transient_cycles);
    if let Some(k) = jobs
        .iter()
        .position(|(d, _, _)| d.cycles != cycles || d.transient_cycles != transient_cycles)
    {
        return Err(format!(
            "GPU points: point {k} has {}/{} cycles/transient cycles, point 0 {cycles}/{transient_cycles}; one batch runs one cycle count",
            jobs[k].0.cycles, jobs[k].0.transient_cycles
        ));
    }
    let points: Vec<(f64, f64)> = jobs.iter().map(|&(_, f, x)| (f, x)).collect();
    let mut worlds: Vec<World> = Vec::with_capacity(points.len());
    for &(this, f, x) in jobs {
        let e = this.direction;
        if !(f > 0.0 && f.is_finite() && x.is_finite()) {
            return Err(format!(
                "excitation point f = {f} Hz, X = {x} m is not valid"
            ));
        }
        let mut w = this.settled.clone();
        w.bodies[this.container].motion = Motion::Prescribed(Arc::new(HarmonicTranslation {
            direction: [e.x, e.y, e.z],
            amplitude_m: x,
            frequency_hz: f,
            phase_rad: 0.0,
        }));
        let period = 1.0 / f;
        let steps_per_cycle = (period / this.time_step_s).ceil().max(1.0);
        w.dt_s = period / steps_per_cycle;
        w.restart_clock();
        worlds.push(w);
    }
    let refs: Vec<&World> = worlds.iter().collect();
    let mut batch = GpuBatch::new(gpu, &refs).map_err(|e| e.to_string())?;
    drop(refs);
    let mut l0 = vec![None; points.len()];
    for cycle in 0..cycles {
        if cycle == transient_cycles {
            for (k, &(this, f, _)) in jobs.iter().enumerate() {
                l0[k] = Some(batch.snapshot(k).map_err(|e| e.to_string())?.ledger);
                let period = 1.0 / f;
                batch.set_load_sampling(
                    k,
                    this.container,
                    2.0 * PI * f,
                    transient_cycles as f64 * period,
                    cycles as f64 * period,
                );
            }
        }
        let ends: Vec<f64> = points
            .iter()
            .map(|&(f, _)| (cycle + 1) as f64 / f)
            .collect();
        batch.run_until(&ends).map_err(|e| {
            format!(
                "GPU batch of {} points, cycle {}: {e}",
                points.len(),
                cycle + 1
            )
        })?;
    }
    let n_eval = cycles - transient_cycles;
    let mut out = Vec::with_capacity(points.len());
    for (k, &(this, frequency_hz, amplitude_m)) in jobs.iter().enumerate() {
        let e = this.direction;
        let omega = 2.0 * PI * frequency_hz;
        let (times, re, im) = batch.load_dft(k).map_err(|e| e.to_string())?;
        let span = times.last().copied().unwrap_or(0.0) - times.first().copied().unwrap_or(0.0);
        if span <= 0.0 {
            return Err(format!("point {k}: no evaluated cycles"));
        }
        // Driving force = container inertia − particle force on the container [D Sect. 3.2.2].
        let inertia: Vec<f64> = times
            .iter()
            .map(|t| -this.container_mass_kg * amplitude_m * omega * omega * (omega * t).sin())
            .collect();
        let velocity: Vec<f64> = times
            .iter()
            .map(|t| amplitude_m * omega * (omega * t).cos())
            .collect();
        let fi = harmonic_amplitude(&times, &inertia, frequency_hz);
        let f_hat = (
            fi.0 - 2.0 * re.dot(&e) / span,
            fi.1 - 2.0 * im.dot(&e) / span,
        );
        let v_hat = harmonic_amplitude(&times, &velocity, frequency_hz);
        let cp = complex_power(
            Complex64::new(f_hat.0, f_hat.1),
            Complex64::new(v_hat.0, v_hat.1),
            frequency_hz,
            this.bed_mass_kg,
            this.container_mass_kg,
        )
        .map_err(|e| format!("complex power at f = {frequency_hz} Hz, X = {amplitude_m} m: {e}"))?;
        let a = l0[k].expect("evaluated cycles");
        let b = batch.snapshot(k).map_err(|e| e.to_string())?.ledger;
        let n = n_eval as f64;
        let d_np = b.dissipated_normal_pp_j - a.dissipated_normal_pp_j;
        let d_nw = b.dissipated_normal_pw_j - a.dissipated_normal_pw_j;
        let d_tp = b.dissipated_tangential_pp_j - a.dissipated_tangential_pp_j;
        let d_tw = b.dissipated_tangential_pw_j - a.dissipated_tangential_pw_j;
        let d = d_np + d_nw + d_tp + d_tw;
        let dw = b.wall_work_j - a.wall_work_j;
        let de = (b.kinetic_j - a.kinetic_j)
            + (b.potential_j - a.potential_j)
            + (b.elastic_j - a.elastic_j);
        let share = |x: f64| if d > 0.0 { x / d } else { 0.0 };
        let acc = amplitude_m * omega * omega;
        out.push(PointResult {
            frequency_hz,
            amplitude_m,
            acceleration_m_s2: acc,
            intensity: acc / STANDARD_GRAVITY_M_S2,
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
            converged: None,
            time_step_s: batch.time_step_s(k),
            steps: batch.steps(k),
            wall_time_s: start.elapsed().as_secs_f64(),
        });
    }
    Ok(out)
}
