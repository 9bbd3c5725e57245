//! The hex8 element's reference geometry: trilinear shape functions, the 2 × 2 × 2 Gauss
//! points and the material gradients $\partial N_a/\partial X$ at them (used by the mesh for
//! volumes and Jacobians and by the Saint Venant–Kirchhoff element).

/// Parametric coordinates of the corners in node order (also the signs of the shape
/// functions); the linear hex8 of [`crate::linear`] and the meshes share them.
pub(crate) const CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Trilinear shape functions and their ξ-derivatives.
pub fn shape(xi: [f64; 3]) -> ([f64; 8], [[f64; 3]; 8]) {
    let mut n = [0.0; 8];
    let mut dn = [[0.0; 3]; 8];
    for (a, s) in CORNERS.iter().enumerate() {
        let f = [1.0 + s[0] * xi[0], 1.0 + s[1] * xi[1], 1.0 + s[2] * xi[2]];
        n[a] = f[0] * f[1] * f[2] / 8.0;
        dn[a] = [
            s[0] * f[1] * f[2] / 8.0,
            s[1] * f[0] * f[2] / 8.0,
            s[2] * f[0] * f[1] / 8.0,
        ];
    }
    (n, dn)
}

fn inv3(m: [[f64; 3]; 3]) -> ([[f64; 3]; 3], f64) {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let id = 1.0 / det;
    let inv = [
        [
            (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * id,
            (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * id,
            (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * id,
        ],
        [
            (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * id,
            (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * id,
            (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * id,
        ],
        [
            (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * id,
            (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * id,
            (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * id,
        ],
    ];
    (inv, det)
}

/// Reference-configuration data of one Gauss point: material shape-function gradients
/// $\partial N_a/\partial X$ and the weight $w\,\det J$.
#[derive(Debug, Clone, Copy)]
pub struct GaussPoint {
    /// $\partial N_a / \partial X_K$.
    pub dn: [[f64; 3]; 8],
    /// Integration weight times Jacobian determinant \[m³\].
    pub wdet: f64,
    /// Shape function values (for the mass matrix).
    pub n: [f64; 8],
}

const G: f64 = 0.577_350_269_189_625_8;

/// Gauss-point data of one element with corner nodes `el` (indices into `nodes`).
///
/// # Panics
/// If the element is inverted or degenerate (det J ≤ 0).
pub fn element_gauss_points(nodes: &[[f64; 3]], el: &[usize; 8]) -> [GaussPoint; 8] {
    let x: Vec<[f64; 3]> = el.iter().map(|&i| nodes[i]).collect();
    let mut gps = [GaussPoint {
        dn: [[0.0; 3]; 8],
        wdet: 0.0,
        n: [0.0; 8],
    }; 8];
    for (q, s) in CORNERS.iter().enumerate() {
        let (n, dxi) = shape([s[0] * G, s[1] * G, s[2] * G]);
        let mut j = [[0.0; 3]; 3];
        for a in 0..8 {
            for r in 0..3 {
                for c in 0..3 {
                    j[r][c] += dxi[a][r] * x[a][c];
                }
            }
        }
        let (ji, det) = inv3(j);
        assert!(
            det > 0.0,
            "inverted or degenerate hex8 element (det J = {det})"
        );
        let mut dn = [[0.0; 3]; 8];
        for a in 0..8 {
            for k in 0..3 {
                dn[a][k] = ji[k][0] * dxi[a][0] + ji[k][1] * dxi[a][1] + ji[k][2] * dxi[a][2];
            }
        }
        gps[q] = GaussPoint { dn, wdet: det, n };
    }
    gps
}
