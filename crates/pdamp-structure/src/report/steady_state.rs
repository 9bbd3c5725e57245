//! Steady-state analysis of `pdamp couple`: the harmonic-balance FRF of one equivalent damper
//! (Fig. 3.7 / Eq. 3.44), its damping (Eq. 3.47) and the resonance equilibrium of every mode.

use super::{CoupledRun, extract_modal_parameters, io};
use crate::StructureError;
use crate::forced::{self, ModeCoupling};
use pdamp_io::csv::write_csv_atomic;
use pdamp_plot::{FrfPlot, FrfSeries, frf_plot_with};
use serde_json::json;

/// The `kind = "steady_state"` analysis keys, the force amplitude resolved.
pub(super) struct SteadyStateRequest<'a> {
    /// First frequency, Hz.
    pub start_hz: f64,
    /// Last frequency, Hz.
    pub end_hz: f64,
    /// Number of frequencies (at least 3 are used).
    pub points: usize,
    /// F, N.
    pub force_amplitude_n: f64,
    /// Structure point of the force.
    pub excitation_point: &'a str,
    /// Structure point of the response.
    pub output_point: &'a str,
}

impl CoupledRun<'_> {
    /// The steady-state FRF of the single equivalent damper around mode `k` (0-based), written
    /// to `frf.csv` and `frf`, with its damping and resonance equilibria for `summary.json`.
    pub(super) fn steady_state(
        &self,
        req: &SteadyStateRequest,
        k: usize,
    ) -> Result<serde_json::Value, StructureError> {
        let structure = self.structure;
        let dampers = self.dampers;
        let out = self.out;
        let f = req.force_amplitude_n;
        let (start_hz, end_hz) = (req.start_hz, req.end_hz);
        let m = structure
            .modes
            .get(k)
            .ok_or_else(|| StructureError::rule("mode", "does not exist"))?;
        let mc = ModeCoupling {
            omega_rad_s: m.omega_rad_s(),
            damping_ratio: m.damping_ratio,
            phi_pd: structure.point(&dampers[0].point)?[k],
            phi_ex: structure.point(req.excitation_point)?[k],
            force_amplitude_n: f,
        };
        let phi_out = structure.point(req.output_point)?[k];
        let n = req.points.max(3);
        let freqs: Vec<f64> = (0..n)
            .map(|i| start_hz + (end_hz - start_hz) * i as f64 / (n - 1) as f64)
            .collect();
        let pts = forced::steady_state_frf(&mc, dampers[0].model.as_ref(), &freqs);
        let rows: Vec<Vec<f64>> = pts
            .iter()
            .map(|p| {
                vec![
                    p.frequency_hz,
                    p.modal_amplitude * phi_out.abs() / f,
                    -p.phase_rad,
                    p.amplitude_m,
                    p.modal_mass,
                    p.converged as u8 as f64,
                ]
            })
            .collect();
        write_csv_atomic(
            out.join("frf.csv"),
            &[
                "frequency_hz",
                "magnitude_m_per_n",
                "phase_rad",
                "damper_amplitude_m",
                "modal_mass",
                "converged",
            ],
            &rows,
        )
        .map_err(io)?;
        let (zeta, f_r, x_peak) = forced::steady_state_damping(&mc, &pts)
            .ok_or_else(|| StructureError::numerical("empty FRF"))?;
        let eq = forced::resonance_equilibrium(&mc, dampers[0].model.as_ref(), 200);
        let per_mode = self.equilibrium_per_mode(req.excitation_point, f)?;
        let mag: Vec<f64> = rows.iter().map(|r| r[1]).collect();
        let ph: Vec<f64> = rows.iter().map(|r| r[2].to_degrees()).collect();
        let mut plot = FrfPlot::new(
            freqs.clone(),
            vec![FrfSeries::new(
                "steady state (Fig. 3.7 / Eq. 3.44)",
                mag,
                ph,
            )],
        );
        plot.magnitude_title = "|H| (m/N)".into();
        frf_plot_with(out.join("frf"), &plot).map_err(io)?;
        let hc: Vec<_> = rows
            .iter()
            .map(|r| pdamp_signal::Complex64::from_polar(r[1], r[2]))
            .collect();
        let modal_parameters = extract_modal_parameters(structure, &freqs, &hc);
        Ok(json!({
            "damping_ratio_eq_3_47": zeta,
            "modal_parameters": modal_parameters,
            "resonance_frequency_hz": f_r,
            "peak_damper_amplitude_m": x_peak,
            "non_converged_points": pts.iter().filter(|p| !p.converged).count(),
            "resonance_equilibrium_fig_3_7": eq,
            "resonance_equilibrium_all_modes": per_mode,
            "force_amplitude_n": f,
            "undamped_frequency_hz": m.frequency_hz,
        }))
    }

    /// Fig. 3.7 equilibrium of every mode (D Sect. 8.2.3 treats modes one at a time) with its
    /// frequency reduction.
    fn equilibrium_per_mode(
        &self,
        excitation_point: &str,
        f: f64,
    ) -> Result<Vec<serde_json::Value>, StructureError> {
        let structure = self.structure;
        let dampers = self.dampers;
        let mut per_mode = Vec::new();
        for (j, mj) in structure.modes.iter().enumerate() {
            let cj = ModeCoupling {
                omega_rad_s: mj.omega_rad_s(),
                damping_ratio: mj.damping_ratio,
                phi_pd: structure.point(&dampers[0].point)?[j],
                phi_ex: structure.point(excitation_point)?[j],
                force_amplitude_n: f,
            };
            let e = forced::resonance_equilibrium(&cj, dampers[0].model.as_ref(), 400);
            per_mode.push(json!({
                "mode": j + 1,
                "undamped_frequency_hz": mj.frequency_hz,
                "frequency_reduction_percent": 100.0 * (1.0 - e.frequency_hz / mj.frequency_hz),
                "equilibrium": e,
            }));
        }
        Ok(per_mode)
    }
}
