//! Colours, perceptual colour maps and the saturating value → colour scale.

use crate::PlotError;

/// An sRGB colour with 8-bit channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// Black.
    pub const BLACK: Rgb = Rgb(0, 0, 0);
    /// White.
    pub const WHITE: Rgb = Rgb(255, 255, 255);
}

/// Colour used for missing (NaN) values in maps and scatter fields.
pub const MISSING_COLOR: Rgb = Rgb(160, 160, 160);

/// Default colour cycle for line series (the "tab10" qualitative palette).
pub const PALETTE: [Rgb; 10] = [
    Rgb(31, 119, 180),
    Rgb(255, 127, 14),
    Rgb(44, 160, 44),
    Rgb(214, 39, 40),
    Rgb(148, 103, 189),
    Rgb(140, 86, 75),
    Rgb(227, 119, 194),
    Rgb(127, 127, 127),
    Rgb(188, 189, 34),
    Rgb(23, 190, 207),
];

/// Colour of the `index`-th series in the default cycle.
pub fn palette_color(index: usize) -> Rgb {
    PALETTE[index % PALETTE.len()]
}

// Eleven evenly spaced stops (t = 0, 0.1, …, 1) of the matplotlib perceptual
// maps (CC0); intermediate values are interpolated linearly in sRGB.
const VIRIDIS: [Rgb; 11] = [
    Rgb(0x44, 0x01, 0x54),
    Rgb(0x48, 0x24, 0x75),
    Rgb(0x41, 0x44, 0x87),
    Rgb(0x35, 0x5f, 0x8d),
    Rgb(0x2a, 0x78, 0x8e),
    Rgb(0x21, 0x91, 0x8c),
    Rgb(0x22, 0xa8, 0x84),
    Rgb(0x44, 0xbf, 0x70),
    Rgb(0x7a, 0xd1, 0x51),
    Rgb(0xbd, 0xdf, 0x26),
    Rgb(0xfd, 0xe7, 0x25),
];

const INFERNO: [Rgb; 11] = [
    Rgb(0x00, 0x00, 0x04),
    Rgb(0x16, 0x0b, 0x39),
    Rgb(0x42, 0x0a, 0x68),
    Rgb(0x6a, 0x17, 0x6e),
    Rgb(0x93, 0x26, 0x67),
    Rgb(0xbc, 0x37, 0x54),
    Rgb(0xdd, 0x51, 0x3a),
    Rgb(0xf3, 0x78, 0x19),
    Rgb(0xfc, 0xa5, 0x0a),
    Rgb(0xf6, 0xd7, 0x46),
    Rgb(0xfc, 0xff, 0xa4),
];

const MAGMA: [Rgb; 11] = [
    Rgb(0x00, 0x00, 0x04),
    Rgb(0x14, 0x0e, 0x36),
    Rgb(0x3b, 0x0f, 0x70),
    Rgb(0x64, 0x1a, 0x80),
    Rgb(0x8c, 0x29, 0x81),
    Rgb(0xb7, 0x37, 0x79),
    Rgb(0xde, 0x49, 0x68),
    Rgb(0xf7, 0x70, 0x5c),
    Rgb(0xfe, 0x9f, 0x6d),
    Rgb(0xfe, 0xcf, 0x92),
    Rgb(0xfc, 0xfd, 0xbf),
];

/// A perceptually uniform sequential colour map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorMap {
    /// Dark blue → green → yellow (matplotlib's default).
    #[default]
    Viridis,
    /// Black → purple → orange → light yellow.
    Inferno,
    /// Black → purple → pink → light cream.
    Magma,
}

impl ColorMap {
    fn stops(self) -> &'static [Rgb; 11] {
        match self {
            ColorMap::Viridis => &VIRIDIS,
            ColorMap::Inferno => &INFERNO,
            ColorMap::Magma => &MAGMA,
        }
    }

    /// Colour at normalised position `t` ∈ [0, 1] (clamped; NaN maps to 0).
    pub fn at(self, t: f64) -> Rgb {
        let stops = self.stops();
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let pos = t * (stops.len() - 1) as f64;
        let i = (pos.floor() as usize).min(stops.len() - 2);
        let f = pos - i as f64;
        let (a, b) = (stops[i], stops[i + 1]);
        let lerp = |p: u8, q: u8| (p as f64 + (q as f64 - p as f64) * f).round() as u8;
        Rgb(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
    }

    /// Colour at the top of the map (used for saturated values).
    pub fn top(self) -> Rgb {
        self.stops()[10]
    }

    /// Colour at the bottom of the map.
    pub fn bottom(self) -> Rgb {
        self.stops()[0]
    }
}

/// Maps scalar values onto colours between the limits `vmin` and `vmax`.
///
/// Values above `vmax` saturate to the top colour, values below `vmin` (and,
/// on a log scale, non-positive values) clamp to the bottom colour, and NaN
/// is drawn in [`MISSING_COLOR`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColorScale {
    /// Value mapped to the bottom colour.
    pub vmin: f64,
    /// Value mapped to the top colour; larger values saturate.
    pub vmax: f64,
    /// Logarithmic colour scale (requires `vmin > 0`).
    pub log: bool,
    /// The colour map.
    pub map: ColorMap,
}

impl ColorScale {
    /// Linear viridis scale between `vmin` and `vmax`.
    pub fn linear(vmin: f64, vmax: f64) -> Self {
        Self {
            vmin,
            vmax,
            log: false,
            map: ColorMap::Viridis,
        }
    }

    /// Logarithmic viridis scale between `vmin` and `vmax` (both > 0).
    pub fn log(vmin: f64, vmax: f64) -> Self {
        Self {
            log: true,
            ..Self::linear(vmin, vmax)
        }
    }

    /// Scale whose limits span the finite (and, if `log`, positive) values;
    /// falls back to [0, 1] (log: [0.1, 1]) without usable data.
    pub fn from_data(values: &[f64], log: bool) -> Self {
        let (lo, hi) =
            finite_range(values, log).unwrap_or(if log { (0.1, 1.0) } else { (0.0, 1.0) });
        let (lo, hi) = widen_degenerate(lo, hi, log);
        Self {
            vmin: lo,
            vmax: hi,
            log,
            map: ColorMap::Viridis,
        }
    }

    /// Returns the scale with another colour map.
    pub fn with_map(mut self, map: ColorMap) -> Self {
        self.map = map;
        self
    }

    /// Checks that the limits are finite, ordered and (log) positive.
    pub fn validate(&self) -> Result<(), PlotError> {
        if !(self.vmin.is_finite() && self.vmax.is_finite() && self.vmin < self.vmax) {
            return Err(PlotError::InvalidInput(format!(
                "colour limits must be finite with vmin < vmax, got [{}, {}]",
                self.vmin, self.vmax
            )));
        }
        if self.log && self.vmin <= 0.0 {
            return Err(PlotError::InvalidInput(format!(
                "log colour scale needs vmin > 0, got {}",
                self.vmin
            )));
        }
        Ok(())
    }

    /// Position of `v` on the scale in [0, 1], clamped; `None` for NaN.
    pub fn normalise(&self, v: f64) -> Option<f64> {
        if v.is_nan() {
            return None;
        }
        let t = if self.log {
            if v <= 0.0 {
                return Some(0.0);
            }
            (v.log10() - self.vmin.log10()) / (self.vmax.log10() - self.vmin.log10())
        } else {
            (v - self.vmin) / (self.vmax - self.vmin)
        };
        Some(if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) })
    }

    /// Colour of value `v` (saturating at both ends, grey for NaN).
    pub fn color(&self, v: f64) -> Rgb {
        match self.normalise(v) {
            Some(t) => self.map.at(t),
            None => MISSING_COLOR,
        }
    }
}

/// Min and max of the finite (and, with `positive`, > 0) values.
pub(crate) fn finite_range(values: &[f64], positive: bool) -> Option<(f64, f64)> {
    values
        .iter()
        .copied()
        .filter(|v| v.is_finite() && (!positive || *v > 0.0))
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// Turns an empty range `lo == hi` into a usable one.
pub(crate) fn widen_degenerate(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if lo < hi {
        (lo, hi)
    } else if log {
        (lo / 10f64.sqrt(), hi * 10f64.sqrt())
    } else {
        let d = if lo == 0.0 { 0.5 } else { 0.1 * lo.abs() };
        (lo - d, hi + d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saturates_above_vmax_and_greys_nan() {
        let s = ColorScale::linear(0.0, 1.0);
        assert_eq!(s.color(1.0), ColorMap::Viridis.top());
        assert_eq!(s.color(1.7), ColorMap::Viridis.top());
        assert_eq!(s.color(f64::INFINITY), ColorMap::Viridis.top());
        assert_eq!(s.color(-0.3), ColorMap::Viridis.bottom());
        assert_eq!(s.color(f64::NAN), MISSING_COLOR);
        assert_eq!(s.normalise(f64::NAN), None);
        assert_eq!(s.normalise(0.25), Some(0.25));
        assert_eq!(s.color(0.5), Rgb(0x21, 0x91, 0x8c));
    }

    #[test]
    fn log_scale_maps_decades_evenly() {
        let s = ColorScale::log(1e-3, 1e-1).with_map(ColorMap::Magma);
        assert!((s.normalise(1e-2).unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(s.normalise(0.0), Some(0.0));
        assert_eq!(s.normalise(-1.0), Some(0.0));
        assert_eq!(s.color(10.0), ColorMap::Magma.top());
        assert!(ColorScale::log(0.0, 1.0).validate().is_err());
        assert!(ColorScale::linear(1.0, 1.0).validate().is_err());
        assert!(ColorScale::linear(f64::NAN, 1.0).validate().is_err());
    }

    #[test]
    fn colour_maps_interpolate_monotonically_in_lightness() {
        for m in [ColorMap::Viridis, ColorMap::Inferno, ColorMap::Magma] {
            let luma = |c: Rgb| 0.2126 * c.0 as f64 + 0.7152 * c.1 as f64 + 0.0722 * c.2 as f64;
            let mut prev = -1.0;
            for i in 0..=100 {
                let l = luma(m.at(i as f64 / 100.0));
                assert!(l >= prev - 0.5, "{m:?} not monotone at {i}");
                prev = l;
            }
            assert_eq!(m.at(0.0), m.bottom());
            assert_eq!(m.at(1.0), m.top());
            assert_eq!(m.at(f64::NAN), m.bottom());
        }
    }

    #[test]
    fn from_data_ignores_nan_and_nonpositive_for_log() {
        let s = ColorScale::from_data(&[f64::NAN, -1.0, 0.0, 0.01, 2.0], true);
        assert_eq!((s.vmin, s.vmax), (0.01, 2.0));
        let s = ColorScale::from_data(&[f64::NAN, -1.0, 0.0, 2.0], false);
        assert_eq!((s.vmin, s.vmax), (-1.0, 2.0));
        let s = ColorScale::from_data(&[3.0, 3.0], false);
        assert!(s.vmin < 3.0 && s.vmax > 3.0);
        assert!(ColorScale::from_data(&[], false).validate().is_ok());
    }
}
