//! Level 2: effective fields (approach 2, D Sect. 3.3) of the best designs.
//!
//! For every design the time simulation ranked best (and for every coating of
//! `[damper] coatings`, which only the DEM sees), the damper is built as a DEM bed in its
//! container — the scenario of the coupled-DEM level ([`crate::dem::damper_scenario`]) — and
//! its effective field η̄(Ω, X), m̄/m_bed(Ω, X) [D Eq. 3.13–3.17] is computed by `pdamp fields`
//! at the frequency of every objective mode, over the displacement amplitudes that the damper
//! point goes through (log-spaced), on `[verification] packings` dropped beds. The structure is
//! then simulated as at level 1 with each mode coupled to the field of its frequency instead of
//! the formulas (approach 2, bilinear interpolation, [`FieldTable`]), once per packing's field:
//! the objective's ensemble mean and 95 % confidence interval.
//!
//! The fields lie in a store (`[verification] fields_store`, default `OUT/fields`): one folder
//! per damper named by the digest of its scenario, one subfolder per frequency holding
//! `pdamp fields`' output (finished points in `points/`, packings in `packings/`, the dropped
//! beds in `beds/`). A run that is stopped, a study run again or another study with the same
//! damper reuses every stored point and bed; only the missing points run.
//!
//! Limits, reported with the results: each field has one frequency (the mode's, with the
//! container on the structure); the effective mass of the bed lowers the coupled frequency by
//! a few per cent, which the field does not resolve (it keeps its column), and outside the
//! amplitude grid the edge values hold.

use crate::DesignError;
use crate::fidelity::Evaluation;
use crate::space::{Design, Space};
use crate::spec::VerificationSpec;
use crate::study::ObjectiveSpec;
use pdamp_design::ensemble::EnsembleStat;
use pdamp_structure::effective::FieldTable;
use pdamp_structure::free::CoupledDamper;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The effective field of one objective mode of a design.
#[derive(Debug, Clone, Serialize)]
pub struct ModeField {
    /// Mode (1-based).
    pub mode: usize,
    /// Frequency of the field: the mode's with the container on the structure, Hz.
    pub frequency_hz: f64,
    /// Smallest and largest displacement amplitude of the grid at the damper point, m.
    pub amplitude_range_m: (f64, f64),
    /// Grid points × packings.
    pub points: usize,
    /// Of them, taken from the store.
    pub reused_points: usize,
    /// Range of the ensemble-mean η̄ over the grid.
    pub loss_factor_range: (f64, f64),
    /// Largest 95 % confidence half-width of η̄ over the grid (NaN for one packing).
    pub loss_factor_ci95_max: f64,
    /// The field's folder.
    pub dir: PathBuf,
}

/// One design's level-2 result.
#[derive(Debug, Clone, Serialize)]
pub struct FieldEvaluation {
    /// The design (with its coating).
    pub design: Design,
    /// Rank of the design (without coating) among the time-simulated designs (1-based).
    pub level1_rank: usize,
    /// Name of the coating.
    pub coating: String,
    /// The objective as the report shows it (stroke in m, mean ζ, relative peak).
    pub objective: &'static str,
    /// The objective with each packing's field.
    pub values: Vec<f64>,
    /// Their mean and 95 % confidence interval.
    pub stat: EnsembleStat,
    /// Per objective mode (ζ̄, peaks): mean and CI over the packings.
    pub per_mode: Vec<EnsembleStat>,
    /// The level-1 value of the same design without coating.
    pub time_simulation: f64,
    /// The fields.
    pub fields: Vec<ModeField>,
    /// Particles of the bed (one container).
    pub particles: usize,
    /// DEM time step, s.
    pub time_step_s: f64,
    /// Estimated cost before the runs (particles × steps of the points still to run).
    pub estimated_particle_steps: f64,
    /// Wall time, s.
    pub wall_s: f64,
    /// Why the design has no field (points that failed, e.g. a coating pressed in beyond the
    /// health check's limit); `None` when it has one.
    pub failure: Option<String>,
}

impl FieldEvaluation {
    /// Objective to minimise (as the search's cost); +∞ for a design without a field.
    pub fn cost(&self, space: &Space) -> f64 {
        if self.failure.is_some() || !self.stat.mean.is_finite() {
            f64::INFINITY
        } else if larger_is_better(space) {
            -self.stat.mean
        } else {
            self.stat.mean
        }
    }
}

/// Whether the objective grows with quality (damping) or shrinks (stroke, peak).
pub fn larger_is_better(space: &Space) -> bool {
    matches!(
        space.study.file.objective,
        ObjectiveSpec::MaxDamping { .. } | ObjectiveSpec::MaxResonanceDamping { .. }
    )
}

/// The objective's value as shown (stroke, mean ζ, mean relative peak) from a cost.
fn shown(space: &Space, cost: f64) -> f64 {
    if larger_is_better(space) { -cost } else { cost }
}

/// The 0-based modes whose evaluation a field serves.
fn field_modes(space: &Space) -> Vec<usize> {
    match &space.study.file.objective {
        ObjectiveSpec::MinStroke { .. } => vec![space.study.free.mode],
        ObjectiveSpec::MaxDamping { modes, .. }
        | ObjectiveSpec::MinFrfPeak { modes, .. }
        | ObjectiveSpec::MaxResonanceDamping { modes, .. } => modes.iter().map(|m| m - 1).collect(),
    }
}

/// Amplitudes at the output point that the evaluation of mode `k` goes through: the decay's
/// range (max_damping: 10 % beyond the objective's range; min_stroke: from the release down to
/// half the level-1 stroke) or 0.1–1.2 × the level-1 resonance peak (forced objectives).
fn output_range_m(space: &Space, level1: &Evaluation, k: usize) -> Result<(f64, f64), DesignError> {
    let st = space.study;
    match &st.file.objective {
        ObjectiveSpec::MinStroke { .. } => {
            let s = &st.structure;
            let out = s.point(&st.free.output_point).map_err(DesignError::from)?[k];
            let init = s.point(&st.free.initial_point).map_err(DesignError::from)?[k];
            let x0 = (st.free.initial_displacement_m * out / init).abs();
            let x1 = level1.stroke_m.unwrap_or(x0 / 10.0);
            Ok(((0.5 * x1).max(1e-3 * x0), 1.1 * x0))
        }
        ObjectiveSpec::MaxDamping {
            amplitude_min_m,
            amplitude_max_m,
            ..
        } => Ok((0.9 * amplitude_min_m, 1.1 * amplitude_max_m)),
        ObjectiveSpec::MinFrfPeak { modes, .. }
        | ObjectiveSpec::MaxResonanceDamping { modes, .. } => {
            let i = modes.iter().position(|&m| m == k + 1).unwrap_or(0);
            let p = level1
                .peak_amplitude_per_mode_m
                .get(i)
                .copied()
                .unwrap_or(f64::NAN);
            Ok((0.1 * p, 1.2 * p))
        }
    }
}

/// The damper points' amplitude range for mode `k` of design `d` (the output range scaled by
/// the mode shapes |φ_p/φ_out| of every container point).
fn damper_range_m(
    space: &Space,
    d: &Design,
    level1: &Evaluation,
    k: usize,
) -> Result<(f64, f64), DesignError> {
    let (lo, hi) = output_range_m(space, level1, k)?;
    let s = space.structure(d.choice);
    let out = s
        .point(&space.study.free.output_point)
        .map_err(DesignError::from)?[k]
        .abs()
        .max(1e-300);
    let mut ratio = (f64::INFINITY, 0.0_f64);
    for p in &space.location(d.choice).points {
        let r = s.point(p).map_err(DesignError::from)?[k].abs() / out;
        ratio = (ratio.0.min(r), ratio.1.max(r));
    }
    let (a, b) = ((lo * ratio.0).max(1e-9), (hi * ratio.1).max(2e-9));
    if !(a.is_finite() && b.is_finite() && b > a) {
        return Err(DesignError::Solver(format!(
            "{}: no amplitude range for the field of mode {} ({a:e} … {b:e} m at the damper)",
            crate::design_scenario::describe(space, d),
            k + 1
        )));
    }
    Ok((a, b))
}

/// Where the fields are stored.
pub fn store_dir(space: &Space, out: &Path) -> PathBuf {
    match &space.study.file.verification.fields_store {
        Some(p) if p.is_absolute() => p.clone(),
        Some(p) => space.study.path.parent().unwrap_or(Path::new(".")).join(p),
        None => out.join("fields"),
    }
}

/// The field scenario of design `d` for mode `k` (TOML): the coupled-DEM damper with the
/// field's cycles, the packings and a `[fields]` grid of one frequency and the amplitudes
/// `range`; the time step is that of the largest relative impact velocity of the grid.
fn field_scenario(
    space: &Space,
    d: &Design,
    frequency_hz: f64,
    range: (f64, f64),
) -> Result<(String, f64), DesignError> {
    let v = &space.study.file.verification;
    let w = std::f64::consts::TAU * frequency_hz;
    let velocity = crate::dem::check_velocity_m_s(space, d).max(2.0 * w * range.1 + 0.2);
    let dt = crate::dem::time_step_at_s(space, d, velocity);
    let text = crate::dem::damper_scenario(space, d, space.study.file.search.seed);
    let mut table: toml::Table =
        toml::from_str(&text).map_err(|e| DesignError::Solver(format!("field scenario: {e}")))?;
    let set = |t: &mut toml::Table, section: &str, key: &str, value: toml::Value| {
        if let Some(toml::Value::Table(s)) = t.get_mut(section) {
            s.insert(key.into(), value);
        }
    };
    set(
        &mut table,
        "simulation",
        "time_step_s",
        toml::Value::Float(dt),
    );
    set(
        &mut table,
        "simulation",
        "check_impact_velocity_m_s",
        toml::Value::Float(velocity),
    );
    set_field_excitation(&mut table, v, frequency_hz, range.1);
    let fields = fields_grid(frequency_hz, range, v.field_amplitudes)?;
    table.insert("fields".into(), toml::Value::Table(fields));
    let body =
        toml::to_string(&table).map_err(|e| DesignError::Solver(format!("field scenario: {e}")))?;
    Ok((
        format!(
            "# Effective field (level 2) of a design of {} (pdamp design):\n# {}\n{body}",
            space.study.path.display(),
            crate::design_scenario::describe(space, d)
        ),
        dt,
    ))
}

/// The field's excitation in the damper scenario's `[damper]`: one frequency at the top
/// amplitude `amplitude_m`, the field's cycles and the packings.
fn set_field_excitation(
    table: &mut toml::Table,
    v: &VerificationSpec,
    frequency_hz: f64,
    amplitude_m: f64,
) {
    if let Some(toml::Value::Table(dm)) = table.get_mut("damper") {
        dm.insert("frequency_hz".into(), toml::Value::Float(frequency_hz));
        dm.insert("amplitude_m".into(), toml::Value::Float(amplitude_m));
        dm.insert("cycles".into(), toml::Value::Integer(v.field_cycles.into()));
        dm.insert(
            "transient_cycles".into(),
            toml::Value::Integer(v.field_transient_cycles.into()),
        );
        dm.insert("packings".into(), toml::Value::Integer(v.packings as i64));
    }
}

/// The `[fields]` grid of a field scenario: one frequency and `count` log-spaced amplitudes over
/// `range`.
fn fields_grid(
    frequency_hz: f64,
    range: (f64, f64),
    count: usize,
) -> Result<toml::Table, DesignError> {
    toml::from_str(&format!(
        "frequencies_hz = [{frequency_hz:e}]\namplitudes_m = {{ from = {:e}, to = {:e}, count = \
         {}, spacing = \"log\" \
         }}\n",
        range.0, range.1, count
    ))
    .map_err(|e| DesignError::Solver(format!("field scenario: {e}")))
}

/// Folder of a damper's fields in the store: the digest of its scenario without the grid, the
/// single-point excitation and the comments — what `pdamp fields` itself compares before it
/// reuses a point — so that the same damper (same bed, contact laws and time step) in another
/// study, rank or amplitude range lands in the same folder; points are then reused where their
/// frequency and amplitude match.
fn damper_dir(store: &Path, scenario: &str) -> Result<PathBuf, DesignError> {
    let mut table: toml::Table = toml::from_str(scenario)
        .map_err(|e| DesignError::Solver(format!("field scenario: {e}")))?;
    table.remove("fields");
    if let Some(toml::Value::Table(d)) = table.get_mut("damper") {
        d.remove("frequency_hz");
        d.remove("amplitude_m");
    }
    let physics =
        toml::to_string(&table).map_err(|e| DesignError::Solver(format!("field scenario: {e}")))?;
    let digest = pdamp_io::checkpoint::digest(physics.as_bytes());
    Ok(store.join(format!("damper_{}", &digest[..digest.len().min(16)])))
}

/// The field tables of a finished field folder: the ensemble's packings (or the single field).
fn packing_tables(
    dir: &Path,
    packings: usize,
    bed_mass_kg: f64,
) -> Result<Vec<FieldTable>, DesignError> {
    (0..packings)
        .map(|k| {
            let f = packing_dir(dir, packings, k).join("fields.csv");
            FieldTable::read(&f, bed_mass_kg).map_err(DesignError::from)
        })
        .collect()
}

/// Folder of packing `k`'s field (`pdamp fields`' layout: the field folder itself for one
/// packing, `packings/packing_KKK` of an ensemble).
fn packing_dir(dir: &Path, packings: usize, k: usize) -> PathBuf {
    if packings > 1 {
        dir.join("packings").join(format!("packing_{k:03}"))
    } else {
        dir.to_path_buf()
    }
}

/// Computes (or takes from the store) the fields of design `d` and evaluates the objective with
/// them, once per packing. `level1` is the time-simulation evaluation of the uncoated design,
/// `level1_rank` its rank.
///
/// # Errors
/// Input, DEM and output errors; field points that failed (named; a rerun retries them).
pub fn evaluate_design(
    space: &Space,
    d: &Design,
    level1: &Evaluation,
    level1_rank: usize,
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<FieldEvaluation, DesignError> {
    let started = std::time::Instant::now();
    let st = space.study;
    let v = &st.file.verification;
    let store = store_dir(space, out);
    let particles: usize = d.particles.iter().sum();
    let bed_mass = space.bed_mass_kg(d) / space.location(d.choice).points.len() as f64;
    let modes = field_modes(space);
    // the scenarios first: the cost is announced before anything runs
    let (plans, steps, dt_max) = plan_fields(space, d, level1, &store, &modes)?;
    let coating = st.file.damper.coatings[d.choice.coating].clone();
    progress(&format!(
        "level 2, design {level1_rank} ({coating}): effective fields of {} mode(s), {} \
         amplitudes × {} packings of {particles} particles: ≈ {steps:.2e} particle-steps to run \
         (≈ {:.0} min at 5e6 particle-steps/s; bed preparation extra)",
        modes.len(),
        v.field_amplitudes,
        v.packings,
        steps / 5e6 / 60.0
    ));
    let mut result = FieldEvaluation {
        design: d.clone(),
        level1_rank,
        coating: coating.clone(),
        objective: objective_name(space),
        values: Vec::new(),
        stat: EnsembleStat::of(&[]),
        per_mode: Vec::new(),
        time_simulation: shown(space, level1.cost),
        fields: Vec::new(),
        particles,
        time_step_s: dt_max,
        estimated_particle_steps: steps,
        wall_s: 0.0,
        failure: None,
    };
    let mut tables: Vec<(usize, Vec<FieldTable>)> = Vec::new();
    for (k, f, range, scenario, dir) in plans {
        std::fs::create_dir_all(&dir).map_err(|e| DesignError::output(&dir, e))?;
        let path = dir.join("damper.toml");
        pdamp_io::atomic::write_atomic(&path, scenario.as_bytes())
            .map_err(|e| DesignError::output(&path, e))?;
        // the beds are saved beside the points (`beds/packing_KKK.pdprep`): a rerun reads them
        // instead of dropping them again
        let run = pdamp_scenario::schema::Scenario::load(&path)
            .map_err(|e| format!("{}: {e}", path.display()))
            .and_then(|sc| {
                pdamp_design::report::run_fields_scenario_from(
                    &sc,
                    &dir,
                    &dir,
                    pdamp_design::PointEngine::Cpu(pdamp_design::ThreadSplit::default()),
                    pdamp_design::report::BedSource::Saved(&dir),
                    |_| {},
                    |_, _| {},
                    &pdamp_dem::time_loop::CancelToken::new(),
                )
                .map_err(|e| format!("{}: {e}", dir.display()))
            });
        // a damper that cannot be built, dropped or run has no field: reported as such (the
        // cause named), and the other designs go on
        let failure = match &run {
            Err(e) => Some(format!("the damper's field could not be computed: {e}")),
            Ok(o) if !o.failed.is_empty() => Some(format!(
                "{} of {} field points failed (a rerun retries them; errors in {}/points), \
                 the first: {}",
                o.failed.len(),
                o.points.len(),
                dir.display(),
                o.failed[0].2
            )),
            Ok(_) => None,
        };
        if let Some(failure) = failure {
            progress(&format!(
                "level 2, design {level1_rank} ({coating}): {failure}"
            ));
            result.failure = Some(failure);
            result.wall_s = started.elapsed().as_secs_f64();
            return Ok(result);
        }
        let outcome = run.expect("checked above");
        let eta: Vec<f64> = outcome
            .points
            .iter()
            .map(|p| p.effective_loss_factor)
            .collect();
        let t = packing_tables(&dir, v.packings, bed_mass)?;
        let ci = ci95_max(&t);
        result.fields.push(ModeField {
            mode: k + 1,
            frequency_hz: f,
            amplitude_range_m: range,
            points: outcome.points.len() * v.packings,
            reused_points: outcome.reused,
            loss_factor_range: eta
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |a, &e| {
                    (a.0.min(e), a.1.max(e))
                }),
            loss_factor_ci95_max: ci,
            dir: dir.clone(),
        });
        tables.push((k, t));
    }
    // the objective with every packing's fields
    let (values, per_mode) = objective_with_fields(space, d, &tables)?;
    let n_modes = per_mode.first().map_or(0, |v| v.len());
    result.stat = EnsembleStat::of(&values);
    result.values = values;
    result.per_mode = (0..n_modes)
        .map(|k| EnsembleStat::of(&per_mode.iter().map(|v| v[k]).collect::<Vec<_>>()))
        .collect();
    result.wall_s = started.elapsed().as_secs_f64();
    Ok(result)
}

/// A mode's field to compute: the 0-based mode, its frequency (Hz), the damper's amplitude
/// range (m), the field scenario and its folder in the store.
type FieldPlan = (usize, f64, (f64, f64), String, PathBuf);

/// The field scenario of every mode of design `d` and the cost of the points not yet in the
/// store: the plans, the particle-steps to run and the largest DEM time step.
fn plan_fields(
    space: &Space,
    d: &Design,
    level1: &Evaluation,
    store: &Path,
    modes: &[usize],
) -> Result<(Vec<FieldPlan>, f64, f64), DesignError> {
    let v = &space.study.file.verification;
    let structure = space.structure(d.choice);
    let particles: usize = d.particles.iter().sum();
    let mut plans = Vec::new();
    let mut steps = 0.0;
    let mut dt_max = 0.0_f64;
    for &k in modes {
        let f = structure.modes[k].frequency_hz;
        let range = damper_range_m(space, d, level1, k)?;
        let (scenario, dt) = field_scenario(space, d, f, range)?;
        let dir = damper_dir(store, &scenario)?.join(format!("field_{f:.4}Hz"));
        let pending = (0..v.packings)
            .map(|p| packing_dir(&dir, v.packings, p))
            .flat_map(|pd| {
                (0..v.field_amplitudes).map(move |j| pdamp_design::fields::point_path(&pd, 0, j))
            })
            .filter(|path| !path.exists())
            .count() as f64;
        steps += pending * f64::from(v.field_cycles) / (f * dt) * particles as f64;
        dt_max = dt_max.max(dt);
        plans.push((k, f, range, scenario, dir));
    }
    Ok((plans, steps, dt_max))
}

/// The objective with every packing's fields (each mode coupled to its own field at every
/// container point): the shown value and the per-mode values of every packing.
fn objective_with_fields(
    space: &Space,
    d: &Design,
    tables: &[(usize, Vec<FieldTable>)],
) -> Result<(Vec<f64>, Vec<Vec<f64>>), DesignError> {
    let st = space.study;
    let v = &st.file.verification;
    let structure = space.structure(d.choice);
    let mut values = Vec::new();
    let mut per_mode: Vec<Vec<f64>> = Vec::new();
    for p in 0..v.packings {
        let dampers: Vec<(usize, Vec<CoupledDamper>)> = tables
            .iter()
            .map(|(k, t)| {
                let ds = space
                    .location(d.choice)
                    .points
                    .iter()
                    .map(|pt| CoupledDamper {
                        point: pt.clone(),
                        model: Box::new(t[p].clone()),
                    })
                    .collect();
                (*k, ds)
            })
            .collect();
        let of = |k: usize| -> &[CoupledDamper] {
            dampers
                .iter()
                .find(|(m, _)| *m == k)
                .map_or(&[], |(_, ds)| ds.as_slice())
        };
        let (e, _) = crate::fidelity::time_evaluation_by_mode(st, structure, &of)?;
        values.push(shown(space, e.cost));
        let pm = match st.file.objective {
            ObjectiveSpec::MinFrfPeak { .. } => e.peak_amplitude_per_mode_m,
            _ => e.damping_ratio_per_mode,
        };
        per_mode.push(pm);
    }
    Ok((values, per_mode))
}

/// Largest 95 % half-width of η̄ over the grid points of the packings' tables.
fn ci95_max(tables: &[FieldTable]) -> f64 {
    if tables.len() < 2 {
        return f64::NAN;
    }
    let col = &tables[0].columns;
    let mut worst = 0.0_f64;
    for (c, column) in col.iter().enumerate() {
        for j in 0..column.amplitudes_m.len() {
            let v: Vec<f64> = tables
                .iter()
                .filter_map(|t| t.columns.get(c)?.effective_loss_factor.get(j).copied())
                .collect();
            worst = worst.max(EnsembleStat::of(&v).ci95_half_width);
        }
    }
    worst
}

/// Name of the objective in the outputs.
pub fn objective_name(space: &Space) -> &'static str {
    match space.study.file.objective {
        ObjectiveSpec::MinStroke { .. } => "stroke_m",
        ObjectiveSpec::MaxDamping { .. } => "mean_damping_ratio",
        ObjectiveSpec::MinFrfPeak { .. } => "relative_peak",
        ObjectiveSpec::MaxResonanceDamping { .. } => "mean_resonance_damping_ratio",
    }
}

/// Level 2 on the search's result: the best `field_designs` time-simulated designs (in level-1
/// order, `designs`), each with every coating, ranked by the fields' ensemble mean.
///
/// # Errors
/// See [`evaluate_design`].
pub fn run_level(
    space: &Space,
    designs: &[(&Design, &Evaluation)],
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<FieldEvaluation>, DesignError> {
    let f = &space.study.file;
    let mut results = Vec::new();
    for (i, (d, level1)) in designs
        .iter()
        .take(f.verification.field_designs)
        .enumerate()
    {
        for coating in 0..f.damper.coatings.len() {
            let mut dc = (*d).clone();
            dc.choice.coating = coating;
            results.push(evaluate_design(space, &dc, level1, i + 1, out, progress)?);
        }
    }
    results.sort_by(|a, b| {
        a.cost(space)
            .total_cmp(&b.cost(space))
            .then(a.level1_rank.cmp(&b.level1_rank))
            .then(a.design.cmp(&b.design))
    });
    Ok(results)
}
