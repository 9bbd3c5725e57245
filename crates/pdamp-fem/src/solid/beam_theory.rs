//! Beam-theory reference for the first bending frequency of a clamped–free beam with piecewise
//! constant square (solid or hollow) cross-sections: Euler–Bernoulli closed form for a uniform
//! beam, and a Timoshenko beam (shear deformation and rotary inertia, shear coefficients of
//! Cowper 1966: solid square $\kappa = \frac{10(1+\nu)}{12+11\nu}$, thin-walled square tube
//! $\kappa = \frac{20(1+\nu)}{48+39\nu}$) solved with 2-node elements (reduced shear integration)
//! on a fine mesh.

/// One axial segment of the beam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Segment length \[m\].
    pub length_m: f64,
    /// Outer width of the square section \[m\].
    pub outer_m: f64,
    /// Inner (cavity) width \[m\]; 0 for a solid section.
    pub inner_m: f64,
}

impl Segment {
    fn area(&self) -> f64 {
        self.outer_m.powi(2) - self.inner_m.powi(2)
    }
    fn inertia(&self) -> f64 {
        (self.outer_m.powi(4) - self.inner_m.powi(4)) / 12.0
    }
    fn kappa(&self, nu: f64) -> f64 {
        if self.inner_m > 0.0 {
            20.0 * (1.0 + nu) / (48.0 + 39.0 * nu)
        } else {
            10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
        }
    }
}

/// Euler–Bernoulli first cantilever frequency of a uniform beam \[Hz\]:
/// $f_1 = \frac{(1.875104)^2}{2\pi L^2}\sqrt{EI/(\rho A)}$.
pub fn euler_bernoulli_f1(s: &Segment, e: f64, rho: f64) -> f64 {
    let b = 1.875_104_068_711_961;
    b * b / (2.0 * std::f64::consts::PI * s.length_m.powi(2))
        * (e * s.inertia() / (rho * s.area())).sqrt()
}

/// First bending frequency \[Hz\] of a cantilever (clamped at the start of the first segment) of
/// Timoshenko segments, `elements` beam elements in total; `extra_mass_per_length` [kg/m] adds
/// non-structural mass on each segment (e.g. a rigidly moving filling).
pub fn timoshenko_f1(
    segments: &[Segment],
    e: f64,
    nu: f64,
    rho: f64,
    elements: usize,
    extra_mass_per_length: &[f64],
) -> f64 {
    let total: f64 = segments.iter().map(|s| s.length_m).sum();
    let g = e / (2.0 * (1.0 + nu));
    let nn = elements + 1;
    let n = 2 * nn; // (w, θ) per node
    let mut k = vec![0.0; n * n];
    let mut m = vec![0.0; n * n];
    let h = total / elements as f64;
    for el in 0..elements {
        let xc = (el as f64 + 0.5) * h;
        let mut acc = 0.0;
        let mut seg = segments.len() - 1;
        for (i, s) in segments.iter().enumerate() {
            if xc < acc + s.length_m {
                seg = i;
                break;
            }
            acc += s.length_m;
        }
        let s = segments[seg];
        let (a, i_, kap) = (s.area(), s.inertia(), s.kappa(nu));
        let mu = rho * a + extra_mass_per_length.get(seg).copied().unwrap_or(0.0);
        let dofs = [2 * el, 2 * el + 1, 2 * el + 2, 2 * el + 3];
        // bending: EI/h * [θ1-θ2]²; shear (1-point): κGA h * ((w2-w1)/h - (θ1+θ2)/2)²
        let mut ke = [[0.0; 4]; 4];
        let eb = e * i_ / h;
        ke[1][1] += eb;
        ke[3][3] += eb;
        ke[1][3] -= eb;
        ke[3][1] -= eb;
        let bs = [-1.0 / h, -0.5, 1.0 / h, -0.5];
        for r in 0..4 {
            for c in 0..4 {
                ke[r][c] += kap * g * a * h * bs[r] * bs[c];
            }
        }
        // lumped translational and rotary mass
        let mut me = [[0.0; 4]; 4];
        me[0][0] = mu * h / 2.0;
        me[2][2] = mu * h / 2.0;
        me[1][1] = rho * i_ * h / 2.0;
        me[3][3] = rho * i_ * h / 2.0;
        for r in 0..4 {
            for c in 0..4 {
                k[dofs[r] * n + dofs[c]] += ke[r][c];
                m[dofs[r] * n + dofs[c]] += me[r][c];
            }
        }
    }
    // clamp node 0: drop dofs 0, 1
    let nf = n - 2;
    let kf: Vec<f64> = (0..nf * nf)
        .map(|q| k[(q / nf + 2) * n + q % nf + 2])
        .collect();
    let mf: Vec<f64> = (0..nf).map(|q| m[(q + 2) * n + q + 2]).collect();
    // the lowest mode of the clamped pencil by faer's dense eigensolver
    let kd = faer::Mat::<f64>::from_fn(nf, nf, |i, j| kf[i * nf + j]);
    let md = faer::Mat::<f64>::from_fn(nf, nf, |i, j| if i == j { mf[i] } else { 0.0 });
    let modes = crate::dense_lowest_modes(kd.as_ref(), md.as_ref(), 1, 0.0)
        .expect("a clamped beam with positive lumped masses has a lowest mode");
    modes.omega_rad_s[0] / (2.0 * std::f64::consts::PI)
}
