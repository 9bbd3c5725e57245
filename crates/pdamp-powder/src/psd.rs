//! Log-normal particle size distributions with cut-offs (paper Table A.2): the scenario's
//! description, sampled by pdamp-dem's [`SizeDistribution`] from a seeded ChaCha8 generator, so
//! that particle sets depend only on the seed.

use crate::error::ParameterError;
use pdamp_dem::generate::SizeDistribution;

/// Log-normal diameter distribution $\ln D \sim \mathcal N(\ln D_{50}, \sigma^2)$, truncated to
/// $[D_{min}, D_{max}]$ by rejection.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogNormal {
    /// Median diameter $D_{50}$ \[m\].
    pub d50_m: f64,
    /// Standard deviation of $\ln D$ (Table A.2: 0.2707).
    pub sigma: f64,
    /// Smallest diameter \[m\] (Table A.2: 2 r_min = 0.706828 mm for D50 = 1 mm).
    pub d_min_m: f64,
    /// Largest diameter \[m\] (Table A.2: 2 r_max = 1.41477 mm).
    pub d_max_m: f64,
}

impl LogNormal {
    /// The scaled distribution of Table A.2 for median `d50_m` (cut-offs scaled likewise).
    pub fn paper(d50_m: f64) -> Self {
        Self {
            d50_m,
            sigma: 0.2707,
            d_min_m: d50_m * 0.706_828,
            d_max_m: d50_m * 1.414_770,
        }
    }
    /// The same distribution as pdamp-dem's [`SizeDistribution`] (in radii), which samples it.
    pub fn distribution(&self) -> SizeDistribution {
        SizeDistribution::LogNormal {
            median_diameter_m: self.d50_m,
            sigma: self.sigma,
            min_radius_m: Some(0.5 * self.d_min_m),
            max_radius_m: Some(0.5 * self.d_max_m),
        }
    }

    /// Diameters drawn until their total volume reaches `volume_m3` (the last one overshoots
    /// by less than one particle volume), \[m\].
    pub fn fill_volume<R: rand::Rng + ?Sized>(&self, volume_m3: f64, rng: &mut R) -> Vec<f64> {
        let dist = self.distribution();
        let mut out = Vec::new();
        let mut v = 0.0;
        while v < volume_m3 {
            let d = 2.0 * dist.sample(rng);
            v += std::f64::consts::PI / 6.0 * d * d * d;
            out.push(d);
        }
        out
    }
    /// Checks ranges (finite values; σ ≤ 1 so that the truncated sampling terminates
    /// quickly); the error names the key.
    pub fn validate(&self, prefix: &str) -> Result<(), ParameterError> {
        if !(self.d50_m > 0.0 && self.d50_m.is_finite()) {
            return Err(ParameterError::out_of_range(
                format!("{prefix}d50_m"),
                self.d50_m,
                "must be a finite positive diameter",
            ));
        }
        if !(self.sigma >= 0.0 && self.sigma <= 1.0) {
            return Err(ParameterError::out_of_range(
                format!("{prefix}sigma"),
                self.sigma,
                "must be in [0, 1] (Table A.2: 0.2707)",
            ));
        }
        if !(self.d_min_m > 0.0 && self.d_min_m <= self.d50_m) {
            return Err(ParameterError::invalid(
                format!("{prefix}d_min_m"),
                "must be in (0, d50_m]",
            ));
        }
        if !(self.d_max_m >= self.d50_m && self.d_max_m.is_finite()) {
            return Err(ParameterError::invalid(
                format!("{prefix}d_max_m"),
                "must be finite and ≥ d50_m",
            ));
        }
        Ok(())
    }

    /// Mean particle volume of the truncated distribution \[m³\] (midpoint rule in ln D).
    pub fn mean_volume_m3(&self) -> f64 {
        let (a, b) = (self.d_min_m.ln(), self.d_max_m.ln());
        let (mu, s) = (self.d50_m.ln(), self.sigma);
        if s == 0.0 || !(b > a) {
            return std::f64::consts::PI / 6.0 * self.d50_m.powi(3);
        }
        let n = 400;
        let (mut w, mut v) = (0.0, 0.0);
        for q in 0..n {
            let l = a + (b - a) * (q as f64 + 0.5) / n as f64;
            let p = (-0.5 * ((l - mu) / s).powi(2)).exp();
            w += p;
            v += p * (3.0 * l).exp();
        }
        std::f64::consts::PI / 6.0 * v / w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn lognormal_percentiles_match_table_a2() {
        // Untruncated: D90/D50 = exp(1.2816 σ) = 1.4148 → D90 = 0.0375828 mm for D50 = 0.0265646.
        let d90 = 0.0265646 * (1.281_551_6 * 0.2707f64).exp();
        assert!((d90 - 0.0375828).abs() < 2e-6, "{d90}");
        let psd = LogNormal::paper(1e-3);
        let dist = psd.distribution();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let mut d: Vec<f64> = (0..20000).map(|_| 2.0 * dist.sample(&mut rng)).collect();
        d.sort_by(f64::total_cmp);
        // truncation is symmetric in ln D, so the median stays D50 (sampling error ≈ 0.5 %)
        assert!((d[10000] / 1e-3 - 1.0).abs() < 0.01, "{}", d[10000]);
        assert!(d[0] >= psd.d_min_m && d[19999] <= psd.d_max_m);
        // the mean volume of the samples against the quadrature of `mean_volume_m3` (1 %)
        let v: f64 = d
            .iter()
            .map(|d| std::f64::consts::PI / 6.0 * d.powi(3))
            .sum::<f64>()
            / d.len() as f64;
        assert!((v / psd.mean_volume_m3() - 1.0).abs() < 0.01, "{v}");
    }
}
