//! One validation target: a number of the references (value, unit, where it is stated), the
//! computation that gives pdamp's value, the tolerance and the verdict.

use serde::Serialize;

/// How costly a target is to compute: `Quick` rows run in `pdamp validate --quick` and in the
/// default test run (closed forms, milliseconds); `Full` rows are simulations (minutes to hours).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Tier {
    /// Closed forms and sub-second evaluations.
    Quick,
    /// Simulations.
    Full,
}

/// What computes pdamp's value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Category {
    /// An analytical formula of the references as pdamp implements it.
    ClosedForm,
    /// Level I: restitution and contact of one impact.
    Impact,
    /// Level II: DEM points or effective fields of one damper.
    Damper,
    /// Level III: a structure with dampers.
    Structure,
    /// The DEM–FEM model of powder-filled cavities (P).
    Powder,
}

/// The reference's statement of a number.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Reference {
    /// The value as a number (in `unit`).
    pub value: f64,
    /// The value as the reference words it, where it is not a plain number ("≈ 3", "< 0.55").
    pub text: Option<&'static str>,
    /// Unit of `value` (SI, as in pdamp's columns: `m`, `Hz`, `1` for ratios).
    pub unit: &'static str,
    /// Where: document, equation/table/figure and line (`D Tab. 6.2, L2724`).
    pub place: &'static str,
}

/// When pdamp's value counts as reproducing the reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Tolerance {
    /// |pdamp − reference| ≤ `abs` (in the reference's unit).
    Absolute {
        /// The bound.
        abs: f64,
    },
    /// |pdamp − reference| ≤ `rel` |reference|.
    Relative {
        /// The bound, as a fraction.
        rel: f64,
    },
    /// `lo` ≤ pdamp ≤ `hi` (a stated range or inequality of the reference).
    Range {
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
    /// Within `rel` of the reference, or the reference inside pdamp's 95 % confidence interval
    /// (ensemble results).
    RelativeOrCi {
        /// The bound, as a fraction.
        rel: f64,
    },
}

impl Tolerance {
    /// The tolerance as the report prints it, in `unit` (omitted for ratios, unit `1`).
    pub fn describe(&self, unit: &str) -> String {
        let u = if unit == "1" {
            String::new()
        } else {
            format!(" {unit}")
        };
        match *self {
            Tolerance::Absolute { abs } => format!("± {abs:e}{u}"),
            Tolerance::Relative { rel } => format!("± {} %", 100.0 * rel),
            Tolerance::Range { lo, hi } => format!("in [{lo}, {hi}]{u}"),
            Tolerance::RelativeOrCi { rel } => {
                format!("± {} % or inside the 95 % CI", 100.0 * rel)
            }
        }
    }
}

/// pdamp's value of a target.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Measured {
    /// The value (ensemble mean for chaotic results), in the reference's unit.
    pub value: f64,
    /// 95 % confidence interval of the mean, where the value is an ensemble mean.
    pub ci95: Option<(f64, f64)>,
    /// Runs (packings) behind the value (1 for a closed form).
    pub runs: usize,
    /// How pdamp computed it: the library call or the command.
    pub how: String,
}

impl Measured {
    /// A value computed once by `how` (a closed form).
    pub fn exact(value: f64, how: impl Into<String>) -> Self {
        Self {
            value,
            ci95: None,
            runs: 1,
            how: how.into(),
        }
    }
}

/// A computation of a target failed (its message goes into the row's note).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct ComputeError {
    /// What failed.
    pub message: String,
}

impl ComputeError {
    /// An error with this message (the failing library call's error, printed).
    pub fn new(message: impl std::fmt::Display) -> Self {
        Self {
            message: message.to_string(),
        }
    }
}

/// Where a computation finds its inputs and puts its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Context {
    /// The repository's `examples/` folder (structure, coupling and scenario files).
    pub examples_dir: std::path::PathBuf,
    /// A folder for the outputs of the runs ([`Target::evaluate`] gives each target a
    /// subfolder named by its id).
    pub work_dir: std::path::PathBuf,
}

impl Context {
    /// The examples of the repository pdamp was built from, runs under `work_dir`.
    pub fn in_repository(work_dir: &std::path::Path) -> Self {
        Self {
            examples_dir: std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples"),
            work_dir: work_dir.to_path_buf(),
        }
    }

    /// The example file `name`.
    pub fn example(&self, name: &str) -> std::path::PathBuf {
        self.examples_dir.join(name)
    }
}

/// One row of the validation table.
#[derive(Debug, Clone, Copy)]
pub struct Target {
    /// Stable id (`ch6.tab6_2.h_bou_24`).
    pub id: &'static str,
    /// Chapter or part of the references (`D Ch. 6`, `P`).
    pub chapter: &'static str,
    /// What is compared, in words.
    pub quantity: &'static str,
    /// The reference's number.
    pub reference: Reference,
    /// When it counts as reproduced.
    pub tolerance: Tolerance,
    /// What computes it.
    pub category: Category,
    /// How long it takes.
    pub tier: Tier,
    /// Why pdamp differs, where the difference is known and measured (a reference
    /// inconsistency, a model the reference does not state); printed beside a row that is not
    /// reproduced (`None`: [`OPEN`]).
    pub known_cause: Option<&'static str>,
    /// pdamp's computation.
    pub compute: fn(&Context) -> Result<Measured, ComputeError>,
}

/// The note of a row that is not reproduced and whose cause is not known yet.
pub const OPEN: &str = "cause not measured yet (open in the validation campaign)";

/// The verdict on one row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// Inside the tolerance.
    Reproduced,
    /// Outside the tolerance; the row names the cause where it is known.
    NotReproduced,
    /// The computation failed (the row carries the error).
    Error,
    /// Not run (a `Full` row in a `--quick` run).
    NotRun,
}

/// A target with pdamp's value and the verdict.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// The target id.
    pub id: &'static str,
    /// Chapter.
    pub chapter: &'static str,
    /// What is compared.
    pub quantity: &'static str,
    /// The reference's number.
    pub reference: Reference,
    /// The tolerance.
    pub tolerance: Tolerance,
    /// What computed it.
    pub category: Category,
    /// How costly it is.
    pub tier: Tier,
    /// pdamp's value (`None`: not run or failed).
    pub measured: Option<Measured>,
    /// (pdamp − reference)/|reference| (`None` where the reference is 0 or a range, or nothing
    /// ran).
    pub deviation: Option<f64>,
    /// The verdict.
    pub status: Status,
    /// The measured cause of a difference, or the error of a failed computation.
    pub note: Option<String>,
}

impl Target {
    /// Computes the target in `ctx` (unless `run` is false) and judges it.
    pub fn evaluate(&self, ctx: &Context, run: bool) -> Row {
        let mut row = Row {
            id: self.id,
            chapter: self.chapter,
            quantity: self.quantity,
            reference: self.reference,
            tolerance: self.tolerance,
            category: self.category,
            tier: self.tier,
            measured: None,
            deviation: None,
            status: Status::NotRun,
            note: None,
        };
        if !run {
            // a row of the other tier still says what its last measurement found
            row.note = self.known_cause.map(|c| {
                format!(
                    "a simulation row: run by `pdamp validate --full` (docs/validation-full.md); \
                     where it differs from the reference, the measured cause: {c}"
                )
            });
            return row;
        }
        // Every target runs in a folder of its own (targets run in parallel).
        let ctx = Context {
            work_dir: ctx.work_dir.join(self.id),
            ..ctx.clone()
        };
        match (self.compute)(&ctx) {
            Err(e) => {
                row.status = Status::Error;
                row.note = Some(e.message);
            }
            Ok(m) => {
                let r = self.reference.value;
                // (A stated range has no single value to deviate from.)
                let ranged = matches!(self.tolerance, Tolerance::Range { .. });
                row.deviation = (r != 0.0 && !ranged).then(|| (m.value - r) / r.abs());
                row.status = if judge(self.tolerance, r, &m) {
                    Status::Reproduced
                } else {
                    row.note = Some(self.known_cause.unwrap_or(OPEN).to_string());
                    Status::NotReproduced
                };
                row.measured = Some(m);
            }
        }
        row
    }
}

/// Whether `m` reproduces `reference` within `tol` (a non-finite value never does).
pub fn judge(tol: Tolerance, reference: f64, m: &Measured) -> bool {
    let v = m.value;
    if !v.is_finite() {
        return false;
    }
    match tol {
        Tolerance::Absolute { abs } => (v - reference).abs() <= abs,
        Tolerance::Relative { rel } => (v - reference).abs() <= rel * reference.abs(),
        Tolerance::Range { lo, hi } => (lo..=hi).contains(&v),
        Tolerance::RelativeOrCi { rel } => {
            (v - reference).abs() <= rel * reference.abs()
                || m.ci95
                    .is_some_and(|(lo, hi)| (lo..=hi).contains(&reference))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerances_judge_as_stated() {
        let m = |v: f64| Measured::exact(v, "");
        assert!(judge(Tolerance::Absolute { abs: 0.1 }, 1.0, &m(1.09)));
        assert!(!judge(Tolerance::Absolute { abs: 0.1 }, 1.0, &m(1.2)));
        assert!(judge(Tolerance::Relative { rel: 0.3 }, -2.0, &m(-1.5)));
        assert!(!judge(Tolerance::Relative { rel: 0.3 }, 2.0, &m(1.3)));
        assert!(judge(Tolerance::Range { lo: 0.0, hi: 0.55 }, 0.5, &m(0.55)));
        assert!(!judge(
            Tolerance::Range { lo: 0.0, hi: 0.55 },
            0.5,
            &m(0.56)
        ));
        assert!(!judge(Tolerance::Relative { rel: 1e9 }, 1.0, &m(f64::NAN)));
        let ens = Measured {
            value: 0.5,
            ci95: Some((0.3, 1.0)),
            runs: 5,
            how: String::new(),
        };
        assert!(judge(Tolerance::RelativeOrCi { rel: 0.3 }, 0.98, &ens));
        assert!(!judge(Tolerance::RelativeOrCi { rel: 0.3 }, 1.2, &ens));
    }

    #[test]
    fn a_row_not_reproduced_carries_its_known_cause_and_a_failure_its_error() {
        let t = Target {
            id: "t",
            chapter: "D Ch. 0",
            quantity: "q",
            reference: Reference {
                value: 1.0,
                text: None,
                unit: "1",
                place: "nowhere",
            },
            tolerance: Tolerance::Relative { rel: 0.01 },
            category: Category::ClosedForm,
            tier: Tier::Quick,
            known_cause: Some("because"),
            compute: |_| Ok(Measured::exact(2.0, "2")),
        };
        let ctx = Context::in_repository(&std::env::temp_dir());
        let r = t.evaluate(&ctx, true);
        assert_eq!(r.status, Status::NotReproduced);
        assert_eq!(r.note.as_deref(), Some("because"));
        assert_eq!(r.deviation, Some(1.0));
        let not_run = t.evaluate(&ctx, false);
        assert_eq!(not_run.status, Status::NotRun);
        assert!(
            not_run
                .note
                .unwrap()
                .ends_with("where it differs from the reference, the measured cause: because")
        );
        let e = Target {
            compute: |_| Err(ComputeError::new("no")),
            ..t
        };
        let r = e.evaluate(&ctx, true);
        assert_eq!((r.status, r.note.as_deref()), (Status::Error, Some("no")));
    }
}
