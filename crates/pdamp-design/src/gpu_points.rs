//! Excitation points of a damper on the GPU backend: one world per point, all advanced together
//! in one batch ([`pdamp_gpu::GpuBatch`]), evaluated with the same complex power method
//! [D Eq. 3.12–3.17] and energy ledger as [`Damper::run_point`] on the CPU.
//!
//! The container's load is turned into the single-bin DFT on the device (per particle, summed at
//! the end), so nothing is read back per step. The points run all their cycles (the early stop
//! on convergence of the CPU path is not offered here).

use crate::DesignError;
use crate::damper::{Damper, PointResult, harmonic_amplitude};
use pdamp_dem::{HarmonicTranslation, Motion, World};
use pdamp_gpu::{GpuBatch, GpuDevice};
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
    ) -> Result<Vec<PointResult>, DesignError> {
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
) -> Result<Vec<PointResult>, DesignError> {
    let start = std::time::Instant::now();
    let Some(&(first, _, _)) = jobs.first() else {
        return Ok(Vec::new());
    };
    let (cycles, transient_cycles) = (first.cycles, first.transient_cycles);
    if let Some(k) = jobs
        .iter()
        .position(|(d, _, _)| d.cycles != cycles || d.transient_cycles != transient_cycles)
    {
        return Err(DesignError::GpuCycles {
            point: k,
            cycles: jobs[k].0.cycles,
            transient_cycles: jobs[k].0.transient_cycles,
            cycles0: cycles,
            transient_cycles0: transient_cycles,
        });
    }
    let points: Vec<(f64, f64)> = jobs.iter().map(|&(_, f, x)| (f, x)).collect();
    let mut worlds: Vec<World> = Vec::with_capacity(points.len());
    for &(this, f, x) in jobs {
        let e = this.direction;
        if !(f > 0.0 && f.is_finite() && x.is_finite()) {
            return Err(DesignError::InvalidPoint {
                frequency_hz: f,
                amplitude_m: x,
            });
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
    let mut batch = GpuBatch::new(gpu, &refs)?;
    drop(refs);
    let mut l0 = vec![None; points.len()];
    for cycle in 0..cycles {
        if cycle == transient_cycles {
            for (k, &(this, f, _)) in jobs.iter().enumerate() {
                l0[k] = Some(batch.snapshot(k)?.ledger);
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
        batch
            .run_until(&ends)
            .map_err(|source| DesignError::GpuRun {
                points: points.len(),
                cycle: cycle + 1,
                source,
            })?;
    }
    let n_eval = cycles - transient_cycles;
    let mut out = Vec::with_capacity(points.len());
    for (k, &(this, frequency_hz, amplitude_m)) in jobs.iter().enumerate() {
        let e = this.direction;
        let omega = 2.0 * PI * frequency_hz;
        let (times, re, im) = batch.load_dft(k)?;
        let span = times.last().copied().unwrap_or(0.0) - times.first().copied().unwrap_or(0.0);
        if span <= 0.0 {
            return Err(DesignError::NoEvaluatedCycles { point: k });
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
        .map_err(|source| DesignError::ComplexPower {
            frequency_hz,
            amplitude_m,
            source,
        })?;
        let a = l0[k].expect("evaluated cycles");
        let b = batch.snapshot(k)?.ledger;
        out.push(PointResult::evaluate(
            (frequency_hz, amplitude_m),
            &cp,
            (&a, &b),
            n_eval,
            None,
            (batch.time_step_s(k), batch.steps(k)),
            start.elapsed().as_secs_f64(),
        ));
    }
    Ok(out)
}
