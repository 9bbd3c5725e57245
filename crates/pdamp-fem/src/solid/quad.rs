//! The bilinear quad of a hex8 face: shape functions, the point and its tangents at (s, t).
//! Used for surface loads (Gauss integration over faces) and for the closest-point projection of
//! particles onto the interface (paper eq. 15).

/// Bilinear shape functions $N_a(s, t)$, nodes counter-clockwise from (−1, −1).
#[inline]
pub fn shape(s: f64, t: f64) -> [f64; 4] {
    [
        (1.0 - s) * (1.0 - t) / 4.0,
        (1.0 + s) * (1.0 - t) / 4.0,
        (1.0 + s) * (1.0 + t) / 4.0,
        (1.0 - s) * (1.0 + t) / 4.0,
    ]
}

/// A point of a quad with corners `x`: position, shape functions and the tangents ∂x/∂s, ∂x/∂t.
#[derive(Debug, Clone, Copy)]
pub struct QuadPoint {
    /// Shape function values.
    pub n: [f64; 4],
    /// Position, m.
    pub x: [f64; 3],
    /// ∂x/∂s.
    pub dxds: [f64; 3],
    /// ∂x/∂t.
    pub dxdt: [f64; 3],
}

/// Evaluates the quad with corners `x` at (s, t).
#[inline]
pub fn point(x: &[[f64; 3]; 4], s: f64, t: f64) -> QuadPoint {
    let n = shape(s, t);
    let ds = [
        -(1.0 - t) / 4.0,
        (1.0 - t) / 4.0,
        (1.0 + t) / 4.0,
        -(1.0 + t) / 4.0,
    ];
    let dt = [
        -(1.0 - s) / 4.0,
        -(1.0 + s) / 4.0,
        (1.0 + s) / 4.0,
        (1.0 - s) / 4.0,
    ];
    let mut p = QuadPoint {
        n,
        x: [0.0; 3],
        dxds: [0.0; 3],
        dxdt: [0.0; 3],
    };
    for k in 0..4 {
        for q in 0..3 {
            p.x[q] += n[k] * x[k][q];
            p.dxds[q] += ds[k] * x[k][q];
            p.dxdt[q] += dt[k] * x[k][q];
        }
    }
    p
}

/// Cross product.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[cfg(test)]
mod tests {
    #[test]
    fn skewed_quad_point_and_tangents() {
        // x(s, t) = (s + 0.25 s t, t, 0.5 s) on the quad spanned by these corners.
        let x = [
            [-0.75, -1.0, -0.5],
            [0.75, -1.0, 0.5],
            [1.25, 1.0, 0.5],
            [-1.25, 1.0, -0.5],
        ];
        let (s, t) = (0.3, -0.6);
        let p = super::point(&x, s, t);
        let exact = [s + 0.25 * s * t, t, 0.5 * s];
        for q in 0..3 {
            assert!((p.x[q] - exact[q]).abs() < 1e-15);
        }
        assert!((p.dxds[0] - (1.0 + 0.25 * t)).abs() < 1e-15);
        assert!((p.dxdt[0] - 0.25 * s).abs() < 1e-15);
        assert!((p.n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }
}
