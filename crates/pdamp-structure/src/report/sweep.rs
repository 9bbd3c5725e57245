//! Swept-sine analysis of `pdamp couple`: one run or overlapping segments (checkpointed
//! with DEM beds), the FRF, and the sweep's CSV tables, plots and summary.

use super::{CoupledRun, energy_exchange_json, extract_modal_parameters, io};
use crate::StructureError;
use crate::dem::{CouplingCheckpoint, run_dem_sweep_beds};
use crate::forced::{self, Sweep, SweepSegment, SweepSpec};
use crate::free::TimeHistory;
use crate::modal::ModalStructure;
use pdamp_io::csv::write_csv_atomic;
use pdamp_plot::{Axis, FrfPlot, FrfSeries, LinePlot, Series, frf_plot_with, line_plot};
use serde_json::json;
use std::path::Path;

impl CoupledRun<'_> {
    /// A sweep in one run: DEM beds or equivalent dampers, its FRF from `window_cycles`
    /// windows, then its outputs (`mode` 0-based).
    pub(super) fn single_sweep(
        &self,
        spec: &SweepSpec,
        window_cycles: usize,
        mode: usize,
        progress: &mut dyn FnMut(f64),
    ) -> Result<serde_json::Value, StructureError> {
        let structure = self.structure;
        let (hist, energy) = match &self.dem {
            Some(beds) => {
                let (h, e) =
                    run_dem_sweep_beds(structure, beds, spec, progress, Some(self.checkpoint))?;
                (h, Some(e))
            }
            None => (forced::run_sweep(structure, self.dampers, spec)?, None),
        };
        let frf = forced::sweep_frf(&hist, &spec.sweep, window_cycles);
        let mut v = sweep_outputs(structure, spec, &[(hist, spec.sweep)], frf, mode, self.out)?;
        if let Some(e) = energy {
            v["energy_exchange"] = energy_exchange_json(&e);
        }
        Ok(v)
    }

    /// A segmented sweep [D Sect. 3.3.2]: every segment of `plan` run from rest, its FRF kept
    /// inside the segment's band (`frf_segments.csv`), the FRFs combined by peak hold.
    pub(super) fn segmented_sweep(
        &self,
        spec: &SweepSpec,
        plan: &[SweepSegment],
        window_cycles: usize,
        mode: usize,
        progress: &mut dyn FnMut(f64),
    ) -> Result<serde_json::Value, StructureError> {
        let structure = self.structure;
        let ck = self.checkpoint;
        let n = plan.len() as f64;
        let mut runs = Vec::new();
        let mut seg_frfs = Vec::new();
        let mut seg_rows = Vec::new();
        // DEM segments are checkpointed: the finished segments' histories in
        // checkpoint.bin (kind "couple-dem-segments", rewritten atomically after every
        // segment), the running segment in checkpoint_segment_<i>.bin (the coupled-run
        // checkpoint, own digest per segment); --resume skips the finished ones and
        // continues the running one, ending bit for bit as an uninterrupted run.
        let mut done: Vec<SegmentHistory> = match (&self.dem, self.resume) {
            (Some(_), true) => {
                pdamp_io::checkpoint::load(&ck.path, SEGMENTS_KIND, &ck.inputs_digest)
                    .map_err(StructureError::from)?
                    .unwrap_or_default()
            }
            _ => Vec::new(),
        };
        for (i, sg) in plan.iter().enumerate() {
            let sspec = SweepSpec {
                sweep: sg.sweep,
                ..spec.clone()
            };
            let hist = match &self.dem {
                Some(_) if i < done.len() => done[i].clone().into_history(),
                Some(beds) => {
                    let cki = CouplingCheckpoint {
                        path: self.out.join(format!("checkpoint_segment_{i}.bin")),
                        inputs_digest: pdamp_io::checkpoint::digest(
                            format!("{} segment {i}", ck.inputs_digest).as_bytes(),
                        ),
                        bed_vtk: ck.bed_vtk.clone().map(|b| crate::dem::BedVtk {
                            pvd_name: format!("particles_segment_{}.pvd", i + 1),
                            subdir: format!("vtk/segment_{}", i + 1),
                            ..b
                        }),
                        ..ck.clone()
                    };
                    let (h, _) = run_dem_sweep_beds(
                        structure,
                        beds,
                        &sspec,
                        &mut |f| progress((i as f64 + f) / n),
                        Some(&cki),
                    )?;
                    done.push(SegmentHistory::from_history(&h));
                    pdamp_io::checkpoint::save(
                        &ck.path,
                        &pdamp_io::checkpoint::CheckpointHeader::new(
                            SEGMENTS_KIND,
                            &ck.inputs_digest,
                        ),
                        &done,
                    )
                    .map_err(StructureError::from)?;
                    let _ = std::fs::remove_file(&cki.path);
                    h
                }
                None => forced::run_sweep(structure, self.dampers, &sspec)?,
            };
            let frf: Vec<_> = forced::sweep_frf(&hist, &sg.sweep, window_cycles)
                .into_iter()
                .filter(|p| p.frequency_hz >= sg.keep_from_hz && p.frequency_hz <= sg.keep_to_hz)
                .collect();
            for p in &frf {
                seg_rows.push([
                    (i + 1) as f64,
                    p.frequency_hz,
                    p.h_m_per_n.norm(),
                    p.h_m_per_n.arg(),
                ]);
            }
            seg_frfs.push(frf);
            runs.push((hist, sg.sweep));
        }
        write_csv_atomic(
            self.out.join("frf_segments.csv"),
            &["segment", "frequency_hz", "magnitude_m_per_n", "phase_rad"],
            &seg_rows,
        )
        .map_err(io)?;
        let frf = forced::peak_hold(&seg_frfs);
        let mut v = sweep_outputs(structure, spec, &runs, frf, mode, self.out)?;
        v["segment_plan"] = json!(plan);
        Ok(v)
    }
}

/// Checkpoint kind of the finished segments of a segmented DEM sweep.
const SEGMENTS_KIND: &str = "couple-dem-segments";

/// The response of one finished sweep segment (checkpointed).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
struct SegmentHistory {
    time_s: Vec<f64>,
    displacement_m: Vec<f64>,
    velocity_m_s: Vec<f64>,
    force_n: Vec<f64>,
}

impl SegmentHistory {
    fn from_history(h: &TimeHistory) -> Self {
        Self {
            time_s: h.time_s.clone(),
            displacement_m: h.displacement_m.clone(),
            velocity_m_s: h.velocity_m_s.clone(),
            force_n: h.force_n.clone(),
        }
    }
    fn into_history(self) -> TimeHistory {
        TimeHistory {
            time_s: self.time_s,
            displacement_m: self.displacement_m,
            velocity_m_s: self.velocity_m_s,
            force_n: self.force_n,
            updates: Vec::new(),
        }
    }
}

/// Outputs of a sweep: `runs` are the (history, sweep) of the whole sweep or of its segments,
/// `frf` the (peak-held) FRF.
fn sweep_outputs(
    structure: &ModalStructure,
    spec: &SweepSpec,
    runs: &[(TimeHistory, Sweep)],
    frf: Vec<forced::FrfPoint>,
    mode: usize,
    out: &Path,
) -> Result<serde_json::Value, StructureError> {
    let k = mode.min(structure.modes.len() - 1);
    let phi_ex = structure.point(&spec.excitation_point)?[k];
    let phi_out = structure.point(&spec.output_point)?[k];
    // Eq. 3.47 from the run with the largest peak (the segment through the resonance)
    let mut pk: Option<forced::PeakDamping> = None;
    let mut peak_run = 0;
    for (i, (h, sw)) in runs.iter().enumerate() {
        let p = forced::peak_damping(
            h,
            sw,
            spec.force_amplitude_n,
            phi_ex,
            phi_out,
            structure.modes[k].omega_rad_s(),
            None,
        );
        if let Some(p) = p
            && pk.is_none_or(|q| p.max_amplitude_m > q.max_amplitude_m)
        {
            pk = Some(p);
            peak_run = i;
        }
    }
    let hist = &runs
        .get(peak_run)
        .ok_or_else(|| StructureError::numerical("no sweep run"))?
        .0;
    let rows: Vec<[f64; 3]> = (0..hist.time_s.len())
        .map(|i| [hist.time_s[i], hist.displacement_m[i], hist.force_n[i]])
        .collect();
    write_csv_atomic(
        out.join("response.csv"),
        &["time_s", "displacement_m", "force_n"],
        &rows,
    )
    .map_err(io)?;
    let frows: Vec<[f64; 3]> = frf
        .iter()
        .map(|p| [p.frequency_hz, p.h_m_per_n.norm(), p.h_m_per_n.arg()])
        .collect();
    write_csv_atomic(
        out.join("frf.csv"),
        &["frequency_hz", "magnitude_m_per_n", "phase_rad"],
        &frows,
    )
    .map_err(io)?;
    let f: Vec<f64> = frf.iter().map(|p| p.frequency_hz).collect();
    let mag: Vec<f64> = frf.iter().map(|p| p.h_m_per_n.norm()).collect();
    let mut plot = FrfPlot::new(
        f.clone(),
        vec![FrfSeries::new(
            "sweep FRF (Eq. 3.42)",
            mag.clone(),
            frows.iter().map(|r| r[2].to_degrees()).collect(),
        )],
    );
    plot.magnitude_title = "|H| (m/N)".into();
    if f.len() >= 2 {
        frf_plot_with(out.join("frf"), &plot).map_err(io)?;
    }
    let hp = pdamp_signal::frf::half_power_damping(&f, &mag, None).ok();
    let rfp = hp.and_then(|h| {
        let band: Vec<_> = frf
            .iter()
            .copied()
            .filter(|p| p.h_m_per_n.norm() > 0.5 * h.peak_magnitude)
            .collect();
        forced::rfp_single_mode(&band)
    });
    let mut p = LinePlot::new(Axis::linear("time (s)"), Axis::linear("displacement (m)"));
    p.series.push(Series::new(
        "output point",
        hist.time_s.clone(),
        hist.displacement_m.clone(),
    ));
    line_plot(out.join("response"), &p).map_err(io)?;
    let hc: Vec<_> = frf.iter().map(|p| p.h_m_per_n).collect();
    let modal_parameters = extract_modal_parameters(structure, &f, &hc);
    Ok(json!({
        "analysis": "sweep",
        "force_amplitude_n": spec.force_amplitude_n,
        "half_power": hp,
        "rational_fraction_polynomial": rfp,
        "modal_parameters": modal_parameters,
        "peak_damping_eq_3_47": pk,
        "frf_points": frf.len(),
        "segments": runs.len(),
        "response_csv_segment": peak_run + 1,
    }))
}
