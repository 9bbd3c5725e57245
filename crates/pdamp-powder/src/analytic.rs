//! First-order analytical models of paper Sect. 4 (eq. 17–26): frictional work dissipated in a
//! rectangular box (width b, length l) filled with equal spheres of radius R, all in sliding
//! contact, under pure shear (angle φ) and pure bending (corner rotation φ). Wall normal forces
//! $F_{N,x}$, $F_{N,y}$ are shared by the contacts of a row (eq. 17): $F_{N,y,i} = F_{N,y}/N_x$,
//! $F_{N,x,i} = F_{N,x}/N_y$ with $N_x = b/(2R)$, $N_y = l/(2R)$.
//! Both large-N limits are independent of R — the paper's argument for the weak particle-size
//! dependence of the damping (Sect. 3.2).

/// Shear, eq. 18–20 before the large-N approximation: $W = N_x(N_y-1)\mu\frac{F_{N,y}}{N_x}\Delta d$
/// with $\Delta d = 2R\tan\varphi$ [J].
pub fn shear_work_discrete(l: f64, r: f64, mu: f64, f_ny: f64, phi: f64) -> f64 {
    let n_y = l / (2.0 * r);
    (n_y - 1.0) * mu * f_ny * 2.0 * r * phi.tan()
}

/// Shear, eq. 20: $W = l\,\mu F_{N,y}\tan\varphi$ [J] (no R).
pub fn shear_work(l: f64, mu: f64, f_ny: f64, phi: f64) -> f64 {
    l * mu * f_ny * phi.tan()
}

/// Bending, eq. 21–25 with the exact sums: $W = f\,2R\,\mu\frac{F_{N,x}}{N_y}\sum_i y_i$,
/// $\sum_i y_i = (N_x-1)\,2R\,\frac{N_y}{2}\frac{N_y/2+1}{2}$, $f = 4\Delta y_{max}/(bl)$,
/// $\Delta y_{max} = \frac b2\tan\varphi$ [J].
pub fn bending_work_discrete(l: f64, b: f64, r: f64, mu: f64, f_nx: f64, phi: f64) -> f64 {
    let (n_x, n_y) = (b / (2.0 * r), l / (2.0 * r));
    let f = 4.0 * (0.5 * b * phi.tan()) / (b * l);
    let sum_y = (n_x - 1.0) * 2.0 * r * (n_y / 2.0) * (n_y / 2.0 + 1.0) / 2.0;
    f * 2.0 * r * mu * f_nx / n_y * sum_y
}

/// Bending, eq. 26: $W = \frac{f\,b\,l}{8}\mu F_{N,x}$ [J] (no R).
pub fn bending_work(l: f64, b: f64, mu: f64, f_nx: f64, phi: f64) -> f64 {
    let f = 4.0 * (0.5 * b * phi.tan()) / (b * l);
    f * b * l / 8.0 * mu * f_nx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dissipation_is_independent_of_particle_size() {
        let (l, b, mu, f, phi) = (0.11, 0.018, 0.4, 10.0, 1e-3);
        let ws = shear_work(l, mu, f, phi);
        let wb = bending_work(l, b, mu, f, phi);
        // halving R repeatedly: the exact sums approach the R-free limits, error ∝ R
        let mut prev_s = f64::INFINITY;
        let mut prev_b = f64::INFINITY;
        for k in 0..6 {
            let r = 0.5e-3 / 2f64.powi(k); // D50 = 1 mm … 31 µm
            let es = (shear_work_discrete(l, r, mu, f, phi) / ws - 1.0).abs();
            let eb = (bending_work_discrete(l, b, r, mu, f, phi) / wb - 1.0).abs();
            // shear: exactly 2R/l; bending: O(R/b)
            assert!((es - 2.0 * r / l).abs() < 1e-12, "{es}");
            assert!(eb < 4.0 * r / b.min(l) + 2.0 * r / l);
            assert!(es < prev_s && eb < prev_b);
            prev_s = es;
            prev_b = eb;
        }
        // the paper sizes D50 = 0.25, 0.5, 1 mm change the bending work by < 6 % in total
        let w: Vec<f64> = [0.125e-3, 0.25e-3, 0.5e-3]
            .iter()
            .map(|&r| bending_work_discrete(l, b, r, mu, f, phi))
            .collect();
        assert!((w[2] / w[0] - 1.0).abs() < 0.06, "{w:?}");
        // values: eq. 20 and 26
        assert!((ws - l * mu * f * phi.tan()).abs() < 1e-18);
        assert!((wb - 0.25 * b * phi.tan() * mu * f).abs() < 1e-18);
    }
}
