//! Axis scales, tick generation and cell-edge (midpoint) computation.

use crate::PlotError;

/// Axis scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scale {
    /// Linear axis.
    #[default]
    Linear,
    /// Base-10 logarithmic axis (values must be > 0).
    Log,
}

impl Scale {
    /// Maps a data value to display space (identity or log10).
    pub fn forward(self, v: f64) -> f64 {
        match self {
            Scale::Linear => v,
            Scale::Log => v.log10(),
        }
    }

    /// Maps a display-space value back to data space.
    pub fn inverse(self, t: f64) -> f64 {
        match self {
            Scale::Linear => t,
            Scale::Log => 10f64.powf(t),
        }
    }

    /// Whether `v` can be drawn on this scale (finite, and > 0 on log axes).
    pub fn accepts(self, v: f64) -> bool {
        v.is_finite() && (self == Scale::Linear || v > 0.0)
    }
}

/// One axis of a plot: title, scale and optional fixed limits.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Axis {
    /// Axis title, with units, e.g. `"frequency (Hz)"`.
    pub title: String,
    /// Linear or logarithmic scale.
    pub scale: Scale,
    /// Fixed `(min, max)` in data units; `None` fits the data.
    pub limits: Option<(f64, f64)>,
}

impl Axis {
    /// Linear axis with the given title and automatic limits.
    pub fn linear(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            scale: Scale::Linear,
            limits: None,
        }
    }

    /// Logarithmic axis with the given title and automatic limits.
    pub fn log(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            scale: Scale::Log,
            limits: None,
        }
    }

    /// Returns the axis with fixed limits `(min, max)` in data units.
    pub fn with_limits(mut self, min: f64, max: f64) -> Self {
        self.limits = Some((min, max));
        self
    }

    /// Checks fixed limits (if any) against the scale.
    pub(crate) fn validate(&self, name: &str) -> Result<(), PlotError> {
        match self.limits {
            Some((lo, hi)) if !(self.scale.accepts(lo) && self.scale.accepts(hi) && lo < hi) => {
                Err(PlotError::InvalidInput(format!(
                    "{name} axis limits [{lo}, {hi}] invalid for {:?} scale",
                    self.scale
                )))
            }
            _ => Ok(()),
        }
    }
}

/// Midpoint between two grid values: arithmetic on linear axes, geometric
/// (`sqrt(a*b)`) on log axes.
pub fn midpoint(a: f64, b: f64, scale: Scale) -> f64 {
    match scale {
        Scale::Linear => 0.5 * (a + b),
        Scale::Log => (a * b).sqrt(),
    }
}

/// Edges of the cells around grid points `centres` (strictly increasing):
/// `n + 1` values, interior edges at the midpoints (geometric on log axes)
/// and the outer edges mirrored about the first/last grid point. A single
/// point gets a cell of width 1 (linear) or one decade (log).
pub fn cell_edges(centres: &[f64], scale: Scale) -> Result<Vec<f64>, PlotError> {
    if centres.is_empty() {
        return Err(PlotError::InvalidInput("empty grid".into()));
    }
    if let Some(bad) = centres.iter().find(|v| !scale.accepts(**v)) {
        return Err(PlotError::InvalidInput(format!(
            "grid value {bad} not drawable on a {scale:?} axis"
        )));
    }
    if centres.windows(2).any(|w| w[0] >= w[1]) {
        return Err(PlotError::InvalidInput(
            "grid values must be strictly increasing".into(),
        ));
    }
    let t: Vec<f64> = centres.iter().map(|v| scale.forward(*v)).collect();
    let n = t.len();
    let mut e = Vec::with_capacity(n + 1);
    if n == 1 {
        e.push(t[0] - 0.5);
        e.push(t[0] + 0.5);
    } else {
        e.push(t[0] - 0.5 * (t[1] - t[0]));
        e.extend(t.windows(2).map(|w| 0.5 * (w[0] + w[1])));
        e.push(t[n - 1] + 0.5 * (t[n - 1] - t[n - 2]));
    }
    Ok(e.into_iter().map(|v| scale.inverse(v)).collect())
}

/// Tick positions (data units) and labels for one axis.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Ticks {
    /// Labelled tick positions.
    pub major: Vec<f64>,
    /// Unlabelled minor tick / light grid positions.
    pub minor: Vec<f64>,
    /// One label per major tick.
    pub labels: Vec<String>,
}

/// Span in decades from which a log axis is labelled at the decades only; narrower
/// log axes are labelled at 1-2-5 × 10ⁿ.
pub const LOG_DECADES_ONLY_FROM: f64 = 2.0;

/// Ticks for `[min, max]` on the given scale.
pub fn ticks(scale: Scale, min: f64, max: f64) -> Ticks {
    match scale {
        Scale::Linear => linear_ticks(min, max, 6),
        Scale::Log => log_ticks(min, max),
    }
}

/// Log-axis ticks for `0 < min < max`: labelled decades `10ⁿ` (thinned to at
/// most ~8 labels) with minor ticks at 2…9 × 10ⁿ. Ranges spanning less than
/// [`LOG_DECADES_ONLY_FROM`] decades (e.g. 1–30, where only "1" and "10" would
/// be labelled) get 1-2-5 ticks (or 1-2-3-…-9 when that gives fewer than
/// three) with plain number labels instead.
pub fn log_ticks(min: f64, max: f64) -> Ticks {
    if !(min > 0.0 && max > min && max.is_finite()) {
        return Ticks::default();
    }
    let (lmin, lmax) = (min.log10(), max.log10());
    let e_lo = (lmin - 1e-9).ceil() as i32;
    let e_hi = (lmax + 1e-9).floor() as i32;
    let inside = |v: f64| v >= min * (1.0 - 1e-9) && v <= max * (1.0 + 1e-9);
    let n_dec = e_hi - e_lo + 1;
    let mut t = Ticks::default();
    if n_dec >= 2 && lmax - lmin >= LOG_DECADES_ONLY_FROM {
        let step = ((n_dec + 7) / 8).max(1);
        for e in e_lo..=e_hi {
            let v = 10f64.powi(e);
            if e.rem_euclid(step) == 0 {
                t.major.push(v);
                t.labels.push(format_decade(e));
            } else {
                t.minor.push(v);
            }
        }
        if step == 1 && n_dec <= 12 {
            for e in (e_lo - 1)..=e_hi {
                for k in 2..=9 {
                    let v = k as f64 * 10f64.powi(e);
                    if inside(v) {
                        t.minor.push(v);
                    }
                }
            }
        }
    } else {
        let f_lo = lmin.floor() as i32;
        let f_hi = lmax.ceil() as i32;
        for mantissas in [
            &[1.0, 2.0, 5.0][..],
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
        ] {
            t = Ticks::default();
            for e in f_lo..=f_hi {
                for k in 1..=9 {
                    let v = k as f64 * 10f64.powi(e);
                    if !inside(v) {
                        continue;
                    }
                    if mantissas.contains(&(k as f64)) {
                        t.major.push(v);
                        t.labels.push(format_number(v));
                    } else {
                        t.minor.push(v);
                    }
                }
            }
            if t.major.len() >= 3 {
                break;
            }
        }
        if t.major.len() < 2 {
            // Very narrow range: fall back to linear ticks.
            return linear_ticks(min, max, 4);
        }
    }
    t.minor.sort_by(f64::total_cmp);
    t
}

/// "Nice" linear ticks (steps 1, 2 or 5 × 10ⁿ) for `[min, max]`, aiming at
/// about `target` labelled ticks, with minor ticks subdividing each step.
pub fn linear_ticks(min: f64, max: f64, target: usize) -> Ticks {
    if !(min.is_finite() && max.is_finite() && max > min) {
        return Ticks::default();
    }
    let raw = (max - min) / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let r = raw / mag;
    let (mant, sub) = if r <= 1.0 {
        (1.0, 5)
    } else if r <= 2.0 {
        (2.0, 4)
    } else if r <= 5.0 {
        (5.0, 5)
    } else {
        (10.0, 5)
    };
    let step = mant * mag;
    let minor_step = step / sub as f64;
    let eps = 1e-9 * step;
    let mut t = Ticks::default();
    let k0 = ((min - eps) / minor_step).ceil() as i64;
    let k1 = ((max + eps) / minor_step).floor() as i64;
    for k in k0..=k1 {
        let v = k as f64 * minor_step;
        if k.rem_euclid(sub) == 0 {
            let v = if v.abs() < eps { 0.0 } else { v };
            t.major.push(v);
        } else {
            t.minor.push(v);
        }
    }
    let big = min.abs().max(max.abs());
    t.labels = t
        .major
        .iter()
        .map(|v| format_linear(*v, step, big))
        .collect();
    t
}

fn superscript(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            '9' => '⁹',
            c => c,
        })
        .collect()
}

/// Label of the decade `10^exp`, e.g. `"10⁻³"`.
pub fn format_decade(exp: i32) -> String {
    format!("10{}", superscript(&exp.to_string()))
}

/// Compact label for a tick value: plain decimals for 10⁻³ ≤ |v| < 10⁵,
/// otherwise `m×10ⁿ`.
pub fn format_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { v.to_string() };
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        // Shortest representation of the value rounded to 6 significant digits.
        let r: f64 = format!("{v:.5e}").parse().unwrap_or(v);
        r.to_string()
    } else {
        scientific(v, 5)
    }
}

fn scientific(v: f64, digits: usize) -> String {
    let s = format!("{v:.digits$e}");
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    let m = if m.contains('.') {
        m.trim_end_matches('0').trim_end_matches('.')
    } else {
        m
    };
    let e: i32 = e.parse().unwrap_or(0);
    if m == "1" {
        format_decade(e)
    } else if m == "-1" {
        format!("-{}", format_decade(e))
    } else {
        format!("{m}×{}", format_decade(e))
    }
}

fn format_linear(v: f64, step: f64, big: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if big >= 1e5 || step < 1e-3 {
        // Significant digits needed to resolve the step.
        let digits = ((v.abs().log10().floor() - step.log10().floor()).max(0.0)) as usize;
        return scientific(v, digits.min(6));
    }
    let decimals = (-(step.log10() + 1e-9).floor()).max(0.0) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_midpoints_are_geometric() {
        let e = cell_edges(&[1.0, 10.0, 100.0], Scale::Log).unwrap();
        let want = [
            10f64.powf(-0.5),
            10f64.sqrt(),
            10f64.powf(1.5),
            10f64.powf(2.5),
        ];
        assert_eq!(e.len(), 4);
        for (a, b) in e.iter().zip(want) {
            assert!((a / b - 1.0).abs() < 1e-12, "{a} vs {b}");
        }
        assert!((midpoint(2.0, 8.0, Scale::Log) - 4.0).abs() < 1e-12);
        assert!((midpoint(2.0, 8.0, Scale::Linear) - 5.0).abs() < 1e-12);
    }

    #[test]
    fn linear_edges_and_errors() {
        let e = cell_edges(&[0.0, 1.0, 3.0], Scale::Linear).unwrap();
        assert_eq!(e, vec![-0.5, 0.5, 2.0, 4.0]);
        assert_eq!(cell_edges(&[5.0], Scale::Linear).unwrap(), vec![4.5, 5.5]);
        assert!(cell_edges(&[1.0, 1.0], Scale::Linear).is_err());
        assert!(cell_edges(&[0.0, 1.0], Scale::Log).is_err());
        assert!(cell_edges(&[], Scale::Log).is_err());
    }

    #[test]
    fn log_ticks_are_decades() {
        let t = log_ticks(3e-4, 2e2);
        assert_eq!(t.major, vec![1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2]);
        assert_eq!(t.labels, ["10⁻³", "10⁻²", "10⁻¹", "10⁰", "10¹", "10²"]);
        assert!(t.minor.iter().any(|v| (v - 5e-4).abs() < 1e-15));
        assert!(
            t.minor
                .iter()
                .all(|v| *v >= 3e-4 * (1.0 - 1e-9) && *v <= 2e2 * (1.0 + 1e-9))
        );
        // Exact decade end points are included.
        let t = log_ticks(1.0, 1000.0);
        assert_eq!(t.major.len(), 4);
    }

    #[test]
    fn wide_log_ranges_are_thinned() {
        let t = log_ticks(1e-12, 1e12);
        assert!(t.major.len() <= 9, "{:?}", t.major);
        assert!(t.major.contains(&1.0));
        assert!(!t.minor.is_empty());
    }

    /// A log axis over 1–30 (1.5 decades) is labelled at 1, 2, 5, 10, 20, not only at the
    /// two decades 1 and 10.
    #[test]
    fn log_axis_under_two_decades_labels_125() {
        let t = log_ticks(1.0, 30.0);
        assert_eq!(t.major, vec![1.0, 2.0, 5.0, 10.0, 20.0]);
        assert!(t.labels.contains(&"2".to_string()) && t.labels.contains(&"5".to_string()));
        // 0.02–3 (2.2 decades) stays at the decades.
        let t = log_ticks(0.02, 3.0);
        assert_eq!(t.labels, ["10⁻¹", "10⁰"]);
    }

    #[test]
    fn narrow_log_range_uses_125() {
        let t = log_ticks(15.0, 120.0);
        assert_eq!(t.major, vec![20.0, 50.0, 100.0]);
        assert_eq!(t.labels, ["20", "50", "100"]);
    }

    #[test]
    fn linear_ticks_are_nice() {
        let t = linear_ticks(0.0, 1.0, 5);
        assert_eq!(t.labels, ["0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        let t = linear_ticks(-180.0, 180.0, 6);
        assert!(t.major.contains(&0.0) && t.major.contains(&-100.0));
        let t = linear_ticks(0.0, 3e-5, 3);
        assert_eq!(t.labels[1], "10⁻⁵");
        assert_eq!(format_number(0.02), "0.02");
        assert_eq!(format_number(2.5e-6), "2.5×10⁻⁶");
    }
}
