//! # pdamp-validation — pdamp against the numbers of its references
//!
//! Every quantitative target of the dissertation (D) and the DEM–FEM paper (P) is one
//! [`Target`]: the reference's value and where it is stated, the computation that gives pdamp's
//! value (a library call, a simulation), a tolerance and, where pdamp is known to differ, the
//! measured cause. [`run`] evaluates them and [`report::write`] writes `validation.md` and
//! `validation.csv`; `pdamp validate --quick|--full --out DIR` is the command, and
//! `docs/validation.md` is its output. Nothing in the table is typed by hand: the pdamp column
//! comes from the computations at the time of the run.
//!
//! The targets are listed by chapter ([`ch4`], [`ch5`], [`ch6`], [`ch7`], [`ch8`]). `Quick`
//! rows (closed forms) run in milliseconds and are checked by the default tests; `Full` rows
//! (simulations: impacts, DEM points and fields, coupled structures, the powder model) are the
//! campaign's next step and are not listed yet.

#![forbid(unsafe_code)]
pub mod ch4;
pub mod ch5;
pub mod ch6;
pub mod ch7;
pub mod ch8;
pub mod decay;
pub mod dem_point;
pub mod paper;
pub mod report;
pub mod target;

pub use target::{
    Category, ComputeError, Context, Measured, Reference, Row, Status, Target, Tier, Tolerance,
};

/// Every target, by chapter.
pub fn targets() -> Vec<Target> {
    let mut t = Vec::new();
    t.extend(ch4::targets());
    t.extend(ch5::targets());
    t.extend(ch6::targets());
    t.extend(ch7::targets());
    t.extend(ch8::targets());
    t.extend(paper::targets());
    t
}

/// Evaluates the targets of `tier` in `ctx` (a `Full` run also runs the `Quick` rows; a
/// `Quick` run lists the `Full` rows as not run) in parallel, in the order of [`targets`].
pub fn run(tier: Tier, ctx: &Context) -> Vec<Row> {
    run_where(tier, ctx, |_| true)
}

/// [`run`] on the targets that `keep` selects (e.g. by id prefix: `pdamp validate --only`).
pub fn run_where(tier: Tier, ctx: &Context, keep: impl Fn(&Target) -> bool + Sync) -> Vec<Row> {
    use rayon::prelude::*;
    targets()
        .into_par_iter()
        .filter(|t| keep(t))
        .map(|t| t.evaluate(ctx, tier == Tier::Full || t.tier == Tier::Quick))
        .collect()
}

/// A reference number stated as such.
pub(crate) const fn stated(value: f64, unit: &'static str, place: &'static str) -> Reference {
    Reference {
        value,
        text: None,
        unit,
        place,
    }
}

/// A reference number the reference words (`≈ 3`, `< 0.55`), with the value compared.
pub(crate) const fn worded(
    value: f64,
    text: &'static str,
    unit: &'static str,
    place: &'static str,
) -> Reference {
    Reference {
        value,
        text: Some(text),
        unit,
        place,
    }
}

/// A closed-form target (`Quick`).
pub(crate) fn closed_form(
    id: &'static str,
    chapter: &'static str,
    quantity: &'static str,
    reference: Reference,
    tolerance: Tolerance,
    compute: fn(&Context) -> Result<Measured, ComputeError>,
) -> Target {
    Target {
        id,
        chapter,
        quantity,
        reference,
        tolerance,
        category: Category::ClosedForm,
        tier: Tier::Quick,
        known_cause: None,
        compute,
    }
}

/// A target computed by a run of pdamp taking under a second (a structure's modes, a
/// steady-state sweep with formula dampers): `Quick`, with the measured cause where pdamp is
/// known to differ.
pub(crate) fn quick_run(
    id: &'static str,
    chapter: &'static str,
    quantity: &'static str,
    reference: Reference,
    tolerance: Tolerance,
    known_cause: Option<&'static str>,
    compute: fn(&Context) -> Result<Measured, ComputeError>,
) -> Target {
    Target {
        category: Category::Structure,
        known_cause,
        ..closed_form(id, chapter, quantity, reference, tolerance, compute)
    }
}

/// A target computed by DEM runs of one damper (ensembles of dropped beds, minutes): `Full`.
pub(crate) fn dem_run(
    id: &'static str,
    chapter: &'static str,
    quantity: &'static str,
    reference: Reference,
    tolerance: Tolerance,
    known_cause: Option<&'static str>,
    compute: fn(&Context) -> Result<Measured, ComputeError>,
) -> Target {
    Target {
        category: Category::Damper,
        tier: Tier::Full,
        known_cause,
        ..closed_form(id, chapter, quantity, reference, tolerance, compute)
    }
}

/// |x| ≤ `abs`.
pub(crate) const fn abs(abs: f64) -> Tolerance {
    Tolerance::Absolute { abs }
}

/// |x − ref| ≤ `rel`·|ref|.
pub(crate) const fn rel(rel: f64) -> Tolerance {
    Tolerance::Relative { rel }
}

/// `Ok(Measured::exact(value, how))`.
pub(crate) fn exact(value: f64, how: &str) -> Result<Measured, ComputeError> {
    Ok(Measured::exact(value, how))
}
