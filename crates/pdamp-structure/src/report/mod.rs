//! Runs of `pdamp structure modes` and `pdamp couple`: CSV tables, `summary.json` and plots.
//! The swept-sine analysis of `pdamp couple` is in `sweep`, the steady-state one in
//! `steady_state`.

mod steady_state;
mod sweep;

use steady_state::SteadyStateRequest;

use crate::StructureError;
use crate::dem::{CouplingCheckpoint, DemCoupling};
use crate::design::damping_ratio_modal;
use crate::forced::{self, Sweep, SweepSpec};
use crate::free::{self, CoupledDamper, FreeVibrationSpec, TimeHistory};
use crate::modal::ModalStructure;
use crate::modal_fit;
use crate::scenario::{AnalysisSpec, CoupleScenario, DamperSpec, ForceSpec, load_structure};
use pdamp_io::csv::write_csv_atomic;
use pdamp_plot::{Axis, LinePlot, Marker, Series, line_plot};
use pdamp_scenario::schema::VtkFormat;
use serde_json::json;
use std::f64::consts::TAU;
use std::path::Path;

fn io<E: Into<StructureError>>(e: E) -> StructureError {
    e.into()
}

/// `pdamp structure modes`: builds and reduces the structure, writes `modes.csv`
/// (`mode,frequency_hz,damping_ratio,phi_<point>…`) and returns a JSON summary.
///
/// # Errors
/// Input, solver and I/O errors.
pub fn run_modes(structure_path: &Path, out: &Path) -> Result<serde_json::Value, StructureError> {
    let file = load_structure(structure_path)?;
    let base = structure_path.parent().unwrap_or(Path::new("."));
    let built = file
        .structure
        .build(base)
        .map_err(|m| crate::scenario::locate_error(structure_path, m))?;
    std::fs::create_dir_all(out).map_err(io)?;
    let s = &built.modal;
    let names: Vec<String> = s
        .points
        .iter()
        .map(|p| format!("phi_{}_per_sqrt_kg", p.name))
        .collect();
    let mut header: Vec<&str> = vec!["mode", "frequency_hz", "damping_ratio"];
    header.extend(names.iter().map(|s| s.as_str()));
    let rows: Vec<Vec<f64>> = s
        .modes
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let mut r = vec![(k + 1) as f64, m.frequency_hz, m.damping_ratio];
            r.extend(s.points.iter().map(|p| p.shape[k]));
            r
        })
        .collect();
    write_csv_atomic(out.join("modes.csv"), &header, &rows).map_err(io)?;
    let summary = json!({
        "modes": s.modes,
        "points": s.points,
        "total_mass_kg": built.total_mass_kg,
        "active_dof": built.dof_count,
        "eigen_solver": built.solver,
    });
    pdamp_io::atomic::write_atomic(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .map_err(io)?
            .as_bytes(),
    )
    .map_err(io)?;
    Ok(summary)
}

/// [`run_couple`] without checkpoints.
///
/// # Errors
/// See [`run_couple`].
pub fn run_couple_default(
    path: &Path,
    out: &Path,
    progress: &mut dyn FnMut(f64),
) -> Result<serde_json::Value, StructureError> {
    let options = pdamp_scenario::run::RunOptions::new(0.0, false);
    run_couple(path, out, options, progress)
}

/// `pdamp couple`: runs the scenario's analysis and writes its outputs to `out`.
///
/// # Errors
/// Input, simulation and I/O errors.
pub fn run_couple(
    path: &Path,
    out: &Path,
    options: pdamp_scenario::run::RunOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<serde_json::Value, StructureError> {
    let (scn, structure_spec) = CoupleScenario::load(path)?;
    let mut inputs = std::fs::read(path).map_err(|e| StructureError::read(path, e))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let structure = structure_spec
        .build(base)
        .map_err(|m| crate::scenario::locate_error(&scn.structure_source(path), m))?
        .modal;
    check_dem_not_mixed(&scn)?;
    let (dem_beds, bed_vtk) = load_dem_beds(&scn, base, &mut inputs)?;
    let beds: Vec<crate::dem::DemBed> = dem_beds
        .iter()
        .map(|(p, d, o)| crate::dem::DemBed {
            damper: d,
            point: p,
            coupling: o,
        })
        .collect();
    let dem = (!beds.is_empty()).then_some(beds.as_slice());
    let ck = coupling_checkpoint(out, &inputs, &options, bed_vtk);
    let dampers = equivalent_dampers(&scn, path, base, &structure)?;
    // Only now, with the dampers validated: bad input leaves no output directory behind.
    std::fs::create_dir_all(out).map_err(io)?;
    let approach = approach_label(&scn, dem.is_some());
    let started = std::time::Instant::now();
    let run = CoupledRun {
        structure: &structure,
        dampers: &dampers,
        dem,
        checkpoint: &ck,
        resume: options.resume,
        out,
    };
    let mut summary = match &scn.analysis {
        AnalysisSpec::Free { .. } => {
            let spec = scn.analysis.free_vibration_spec().expect("a free analysis");
            run.free_vibration(&scn, &spec, progress)?
        }
        AnalysisSpec::Sweep {
            start_hz,
            end_hz,
            duration_s,
            law,
            force_amplitude_n,
            base_amplitude_m,
            excitation_point,
            output_point,
            time_step_s,
            sample_every,
            window_cycles,
            mode,
            segments,
            segment_overlap,
        } => {
            let f = ForceSpec {
                force_amplitude_n: *force_amplitude_n,
                base_amplitude_m: *base_amplitude_m,
            }
            .force_n(&structure_spec)?;
            let sweep = Sweep {
                start_hz: *start_hz,
                end_hz: *end_hz,
                duration_s: *duration_s,
                law: *law,
            };
            let spec = SweepSpec {
                sweep,
                force_amplitude_n: f,
                excitation_point: excitation_point.clone(),
                output_point: output_point.clone(),
                time_step_s: *time_step_s,
                sample_every: *sample_every,
            };
            if *segments <= 1 {
                run.single_sweep(&spec, *window_cycles, mode.saturating_sub(1), progress)?
            } else {
                // Frequency-domain approach [D Sect. 3.3.2]: overlapping segments from rest,
                // start-up transients cut off, FRFs combined by peak hold.
                let plan = forced::segment_sweep(&sweep, *segments, *segment_overlap);
                run.segmented_sweep(
                    &spec,
                    &plan,
                    *window_cycles,
                    mode.saturating_sub(1),
                    progress,
                )?
            }
        }
        AnalysisSpec::SteadyState {
            start_hz,
            end_hz,
            points,
            force_amplitude_n,
            base_amplitude_m,
            excitation_point,
            output_point,
            mode,
        } => {
            if dampers.len() != 1 {
                return Err(StructureError::rule(
                    "steady_state",
                    "needs exactly one equivalent damper (approach 2 or 3)",
                ));
            }
            let f = ForceSpec {
                force_amplitude_n: *force_amplitude_n,
                base_amplitude_m: *base_amplitude_m,
            }
            .force_n(&structure_spec)?;
            run.steady_state(
                &SteadyStateRequest {
                    start_hz: *start_hz,
                    end_hz: *end_hz,
                    points: *points,
                    force_amplitude_n: f,
                    excitation_point,
                    output_point,
                },
                mode.saturating_sub(1),
            )?
        }
    };
    let obj = summary.as_object_mut().expect("object");
    obj.insert("approach".into(), json!(approach));
    obj.insert("modes".into(), json!(structure.modes));
    obj.insert("wall_time_s".into(), json!(started.elapsed().as_secs_f64()));
    obj.insert(
        "efficiency_eq_3_51".into(),
        json!(damper_efficiency(&structure, &dampers)?),
    );
    pdamp_io::atomic::write_atomic(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .map_err(io)?
            .as_bytes(),
    )
    .map_err(io)?;
    Ok(summary)
}

/// The structure, dampers and output settings one analysis of `pdamp couple` runs with.
struct CoupledRun<'a> {
    /// The reduced structure.
    structure: &'a ModalStructure,
    /// The equivalent dampers (approaches 2/3; empty with DEM beds).
    dampers: &'a [CoupledDamper],
    /// The DEM beds (approach 1), `None` without.
    dem: Option<&'a [crate::dem::DemBed<'a>]>,
    /// Checkpoint file, digest and ParaView output of the coupled DEM run.
    checkpoint: &'a CouplingCheckpoint,
    /// `--resume`: continue from the checkpoint.
    resume: bool,
    /// The output directory.
    out: &'a Path,
}

/// DEM dampers (approach 1) cannot be mixed with the other damper models in one scenario.
fn check_dem_not_mixed(scn: &CoupleScenario) -> Result<(), StructureError> {
    let dem_count = scn
        .dampers
        .iter()
        .filter(|d| matches!(d, DamperSpec::Dem { .. }))
        .count();
    if dem_count > 0 && dem_count < scn.dampers.len() {
        return Err(StructureError::inconsistent(
            "DEM dampers (approach 1) cannot be mixed with other damper models in a scenario: \
             make every damper `model = \"dem\"` or none",
        ));
    }
    Ok(())
}

/// A DEM bed of the scenario: its structure point, the settled damper and its coupling.
type LoadedBed = (String, pdamp_design::Damper, DemCoupling);

/// ParaView output of a bed scenario's `[output]`: the interval, s, and the format.
type BedVtkOutput = (f64, VtkFormat);

/// The DEM beds (one per damper, each its own scenario and seed; paths relative to `base`),
/// every damper scenario appended to `inputs` (the checkpoint digest); the first bed's
/// `[output]` interval and format give the ParaView output.
fn load_dem_beds(
    scn: &CoupleScenario,
    base: &Path,
    inputs: &mut Vec<u8>,
) -> Result<(Vec<LoadedBed>, Option<BedVtkOutput>), StructureError> {
    let mut bed_vtk = None;
    let mut dem_beds: Vec<LoadedBed> = Vec::new();
    for (i, spec) in scn.dampers.iter().enumerate() {
        let DamperSpec::Dem {
            point,
            scenario,
            compensate_static_weight,
            ..
        } = spec
        else {
            continue;
        };
        let kinematics = spec.dem_kinematics(i)?;
        let p = if scenario.is_absolute() {
            scenario.clone()
        } else {
            base.join(scenario)
        };
        let in_damper = |e: StructureError| e.context(format!("dampers[{i}]: {}", p.display()));
        let sc = pdamp_scenario::schema::Scenario::load(&p).map_err(|e| in_damper(e.into()))?;
        inputs.extend_from_slice(sc.to_toml().as_bytes());
        if bed_vtk.is_none() {
            bed_vtk = Some((sc.output.vtk_interval_s, sc.output.vtk_format));
        }
        let d =
            pdamp_design::Damper::from_scenario(&sc, p.parent().unwrap_or(Path::new(".")), |_| {})
                .map_err(|e| in_damper(StructureError::Design(Box::new(e))))?;
        dem_beds.push((
            point.clone(),
            d,
            DemCoupling {
                compensate_static_weight: *compensate_static_weight,
                kinematics,
            },
        ));
    }
    Ok((dem_beds, bed_vtk))
}

/// The checkpoint of the coupled run in `out`: its digest over every input file (`inputs`), the
/// interval and `--resume` of `options`, the first bed's ParaView output (`bed_vtk`: interval
/// and format) in `particles.pvd` and `vtk/`.
fn coupling_checkpoint(
    out: &Path,
    inputs: &[u8],
    options: &pdamp_scenario::run::RunOptions,
    bed_vtk: Option<BedVtkOutput>,
) -> CouplingCheckpoint {
    CouplingCheckpoint {
        path: out.join(pdamp_io::checkpoint::CHECKPOINT_FILE),
        inputs_digest: pdamp_io::checkpoint::digest(inputs),
        interval_s: options.checkpoint_interval_s,
        resume: options.resume,
        cancel: options.cancel.clone(),
        bed_vtk: bed_vtk.map(|(interval_s, format)| crate::dem::BedVtk {
            dir: out.to_path_buf(),
            pvd_name: "particles.pvd".into(),
            subdir: "vtk".into(),
            interval_s,
            encoding: format.into(),
        }),
    }
}

/// The equivalent model of every non-DEM damper for the analysed mode (paths relative to
/// `base`; errors located in the scenario `path`).
fn equivalent_dampers(
    scn: &CoupleScenario,
    path: &Path,
    base: &Path,
    structure: &ModalStructure,
) -> Result<Vec<CoupledDamper>, StructureError> {
    let analysis_mode = match &scn.analysis {
        AnalysisSpec::Free { mode, .. }
        | AnalysisSpec::Sweep { mode, .. }
        | AnalysisSpec::SteadyState { mode, .. } => mode.saturating_sub(1),
    };
    let mut dampers = Vec::new();
    for (i, d) in scn.dampers.iter().enumerate() {
        if let Some(m) = d
            .effective_model(base, structure, analysis_mode)
            .map_err(|e| crate::scenario::locate_error(path, e.context(format!("dampers[{i}]"))))?
        {
            dampers.push(CoupledDamper {
                point: d.point().to_string(),
                model: m,
            });
        }
    }
    Ok(dampers)
}

/// The damper approach of the scenario, for `summary.json`.
fn approach_label(scn: &CoupleScenario, dem: bool) -> &'static str {
    if dem {
        "1 (full DEM)"
    } else if scn
        .dampers
        .iter()
        .any(|d| matches!(d, DamperSpec::Fields { .. }))
    {
        "2 (effective fields)"
    } else if scn.dampers.is_empty() {
        "none (bare structure)"
    } else {
        "2/3 (equivalent damper)"
    }
}

/// Efficiency ζ(η̄ = 1) of each damper per mode [D Eq. 3.51] with m̄ ≈ m_bed.
fn damper_efficiency(
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
) -> Result<Vec<serde_json::Value>, StructureError> {
    let mut eff = Vec::new();
    for d in dampers {
        let phi = structure.point(&d.point)?;
        let mb = d.model.bed_mass_kg();
        let z: Vec<f64> = phi
            .iter()
            .map(|p| damping_ratio_modal(*p, mb, mb, 1.0))
            .collect();
        eff.push(json!({"point": d.point, "bed_mass_kg": mb, "damping_ratio_at_unit_loss_factor_per_mode": z}));
    }
    Ok(eff)
}

impl CoupledRun<'_> {
    /// A free-vibration analysis: DEM beds or equivalent dampers, then its outputs.
    fn free_vibration(
        &self,
        scn: &CoupleScenario,
        spec: &FreeVibrationSpec,
        progress: &mut dyn FnMut(f64),
    ) -> Result<serde_json::Value, StructureError> {
        let (hist, energy) = match &self.dem {
            Some(beds) => {
                let (h, e) = crate::dem::run_dem_free_beds(
                    self.structure,
                    beds,
                    spec,
                    progress,
                    Some(self.checkpoint),
                )?;
                (h, Some(e))
            }
            None => (
                free::run_free_vibration(self.structure, self.dampers, spec)?,
                None,
            ),
        };
        let mut v = free_outputs(self.structure, scn, spec, &hist, self.out)?;
        if let Some(e) = energy {
            v["energy_exchange"] = energy_exchange_json(&e);
        }
        Ok(v)
    }
}

fn free_outputs(
    structure: &ModalStructure,
    scn: &CoupleScenario,
    spec: &FreeVibrationSpec,
    hist: &TimeHistory,
    out: &Path,
) -> Result<serde_json::Value, StructureError> {
    let rows: Vec<[f64; 3]> = (0..hist.time_s.len())
        .map(|i| [hist.time_s[i], hist.displacement_m[i], hist.velocity_m_s[i]])
        .collect();
    write_csv_atomic(
        out.join("decay.csv"),
        &["time_s", "displacement_m", "velocity_m_s"],
        &rows,
    )
    .map_err(io)?;
    let f_k = structure.modes[spec.mode].frequency_hz;
    let which = scn.analysis.decay_peaks();
    let peaks = free::signed_decay_peaks(hist, 0.5 / f_k, which)?;
    let cyc = free::damping_per_cycle(&peaks);
    let drows: Vec<[f64; 4]> = cyc
        .iter()
        .map(|c| {
            [
                c.mean_amplitude_m,
                c.damping_ratio,
                c.frequency_hz,
                c.time_s,
            ]
        })
        .collect();
    write_csv_atomic(
        out.join("damping.csv"),
        &[
            "mean_amplitude_m",
            "damping_ratio",
            "frequency_hz",
            "time_s",
        ],
        &drows,
    )
    .map_err(io)?;
    let urows: Vec<[f64; 6]> = hist
        .updates
        .iter()
        .map(|u| {
            [
                u.time_s,
                u.damper as f64,
                u.amplitude_m,
                u.frequency_hz,
                u.effective_mass_kg,
                u.damping_n_s_m,
            ]
        })
        .collect();
    write_csv_atomic(
        out.join("updates.csv"),
        &[
            "time_s",
            "damper",
            "amplitude_m",
            "frequency_hz",
            "effective_mass_kg",
            "damping_n_s_m",
        ],
        &urows,
    )
    .map_err(io)?;
    // Plots: decay with the envelope of the evaluated peaks and the bare structure's envelope.
    let z = structure.modes[spec.mode].damping_ratio;
    let w = TAU * f_k;
    // With D Eq. 5.19 the run starts from the scaled displacement: the output point's first
    // sample (the initial point's, where they are the same point).
    let x0 = match (spec.scale_initial_by_bed_mass, hist.displacement_m.first()) {
        (true, Some(x)) if spec.output_point == spec.initial_point => x.abs(),
        _ => spec.initial_displacement_m.abs(),
    };
    let (label, sign) = match which {
        free::DecayPeaks::Positive => ("envelope (positive peaks)", 1.0),
        free::DecayPeaks::Negative => ("envelope (negative peaks)", -1.0),
    };
    let env: Vec<f64> = hist
        .time_s
        .iter()
        .map(|t| sign * x0 * (-z * w * t).exp())
        .collect();
    let mut p = LinePlot::new(Axis::linear("time (s)"), Axis::linear("displacement (m)"));
    p.series.push(Series::new(
        "output point",
        hist.time_s.clone(),
        hist.displacement_m.clone(),
    ));
    p.series.push(
        Series::new(
            label,
            peaks.iter().map(|p| p.0).collect(),
            peaks.iter().map(|p| sign * p.1).collect(),
        )
        .with_marker(Marker::Circle),
    );
    let mut bare = Series::new("structure only", hist.time_s.clone(), env);
    bare.dashed = true;
    p.series.push(bare);
    line_plot(out.join("decay"), &p).map_err(io)?;
    let mut q = LinePlot::new(
        Axis::linear("mean amplitude (m)"),
        Axis::linear("damping ratio ζ (-)"),
    );
    q.series.push(
        Series::new(
            "log decrement (Eq. 3.41)",
            cyc.iter().map(|c| c.mean_amplitude_m).collect(),
            cyc.iter().map(|c| c.damping_ratio).collect(),
        )
        .with_marker(Marker::Circle),
    );
    line_plot(out.join("damping"), &q).map_err(io)?;
    let last = hist.displacement_m.len().saturating_sub(1);
    let max_z = cyc.iter().map(|c| c.damping_ratio).fold(f64::NAN, f64::max);
    Ok(json!({
        "analysis": "free",
        "decay_peaks": which,
        "cycles": cyc.len(),
        "initial_amplitude_m": x0,
        "final_peak_amplitude_m": peaks.last().map(|p| p.1),
        "final_time_s": hist.time_s.get(last),
        "max_damping_ratio": max_z,
        "first_cycle": cyc.first(),
        "last_cycle": cyc.last(),
        "updates": hist.updates.len(),
    }))
}

/// The energy exchange of a coupled DEM run for `summary.json`, with its two closures: the
/// bed's ledger, $|W_{walls} - \Delta E_{bed} - E_{diss}|$, and the coupling,
/// $|W_{s\to b} - W_{walls}|$ (the structure's work on the bed against the walls' work on the
/// particles), each relative to the energy dissipated in the bed.
pub fn energy_exchange_json(e: &crate::dem::DemEnergy) -> serde_json::Value {
    let scale = e.dissipated_j.abs().max(e.wall_work_j.abs()).max(1e-300);
    json!({
        "structure_work_on_bed_j": e.structure_work_on_bed_j,
        "wall_work_j": e.wall_work_j,
        "bed_energy_change_j": e.bed_energy_change_j,
        "dissipated_j": e.dissipated_j,
        "structure_energy_change_j": e.structure_energy_change_j,
        "bed_ledger_closure": (e.wall_work_j - e.bed_energy_change_j - e.dissipated_j).abs() / scale,
        "coupling_closure": (e.structure_work_on_bed_j - e.wall_work_j).abs() / scale,
    })
}

/// Modal parameters of an FRF for `summary.json`: for every structural mode inside the band,
/// a rational fraction polynomial fit ([`modal_fit::rfp_fit`], one mode + residual terms) of the
/// points between the midpoints to the neighbouring modes (local fits stay robust when one mode
/// is strongly nonlinear), and the half-power bandwidth in the same band.
fn extract_modal_parameters(
    structure: &ModalStructure,
    frequencies_hz: &[f64],
    h: &[pdamp_signal::Complex64],
) -> serde_json::Value {
    if frequencies_hz.len() < 8 {
        return json!(null);
    }
    let (lo, hi) = frequencies_hz
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &f| (a.min(f), b.max(f)));
    let mut centers: Vec<f64> = structure
        .modes
        .iter()
        .map(|m| m.frequency_hz)
        .filter(|&f| f >= lo && f <= hi)
        .collect();
    if centers.is_empty() {
        // no structural mode inside: the FRF's largest peak
        let (i, _) = h
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))
            .expect("non-empty");
        centers.push(frequencies_hz[i]);
    }
    let mag: Vec<f64> = h.iter().map(|c| c.norm()).collect();
    let hp = modal_fit::half_power_per_mode(frequencies_hz, &mag, &centers);
    let modes: Vec<_> = centers
        .iter()
        .enumerate()
        .map(|(k, &fc)| {
            let a = if k == 0 {
                lo
            } else {
                0.5 * (centers[k - 1] + fc)
            };
            let b = if k + 1 == centers.len() {
                hi
            } else {
                0.5 * (centers[k + 1] + fc)
            };
            let idx: Vec<usize> = (0..frequencies_hz.len())
                .filter(|&i| frequencies_hz[i] >= a && frequencies_hz[i] <= b)
                .collect();
            let f: Vec<f64> = idx.iter().map(|&i| frequencies_hz[i]).collect();
            let hh: Vec<_> = idx.iter().map(|&i| h[i]).collect();
            let fit = modal_fit::rfp_fit(&f, &hh, 1);
            let m = fit.as_ref().ok().and_then(|r| {
                r.modes
                    .iter()
                    .min_by(|x, y| {
                        (x.frequency_hz - fc)
                            .abs()
                            .total_cmp(&(y.frequency_hz - fc).abs())
                    })
                    .copied()
            });
            json!({
                "structural_frequency_hz": fc,
                "band_hz": [a, b],
                "frequency_hz": m.map(|m| m.frequency_hz),
                "damping_ratio": m.map(|m| m.damping_ratio),
                "modal_constant_re": m.map(|m| m.modal_constant_re),
                "modal_constant_im": m.map(|m| m.modal_constant_im),
                "fit_relative_error": fit.as_ref().ok().map(|r| r.relative_error),
                "fit_error": fit.err().map(|e| e.to_string()),
                "half_power_frequency_hz": hp[k].map(|r| r.resonance_frequency_hz),
                "half_power_damping_ratio": hp[k].map(|r| r.damping_ratio),
            })
        })
        .collect();
    json!({
        "method": "rational fraction polynomial per mode band (Sanathanan–Koerner reweighted) + half-power bandwidth",
        "modes": modes,
    })
}
