//! The uniform cell grid of a triangle mesh: which triangles may lie within reach of a point.

use super::{bbox_of, csr};
use crate::math::Vec3;

/// Uniform grid of triangle ids.
#[derive(Clone)]
pub(super) struct Grid {
    origin: Vec3,
    inv_h: f64,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    pub(super) fn build(vertices: &[Vec3], faces: &[[u32; 3]], bbox: (Vec3, Vec3)) -> Grid {
        let ext = bbox.1 - bbox.0;
        let diag = ext.norm().max(f64::MIN_POSITIVE);
        // Cell size: mean triangle bounding-box extent, coarsened until the grid is small.
        let mean: f64 = faces
            .iter()
            .map(|f| {
                let p = f.map(|i| vertices[i as usize]);
                let (lo, hi) = bbox_of(&p);
                (hi - lo).max()
            })
            .sum::<f64>()
            / faces.len() as f64;
        let mut h = mean.max(diag * 1e-4);
        let max_cells = (8 * faces.len()).max(4096) as f64;
        let count = |h: f64| -> f64 { (0..3).map(|k| (ext[k] / h).floor() + 1.0).product::<f64>() };
        while count(h) > max_cells {
            h *= 1.5;
        }
        let dims = [0, 1, 2].map(|k| (ext[k] / h).floor() as usize + 1);
        let inv_h = 1.0 / h;
        let origin = bbox.0;
        let ncell = dims[0] * dims[1] * dims[2];
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let cell_of = |p: &Vec3, k: usize| -> usize {
            (((p[k] - origin[k]) * inv_h).floor().max(0.0) as usize).min(dims[k] - 1)
        };
        for (t, f) in faces.iter().enumerate() {
            let p = f.map(|i| vertices[i as usize]);
            let (lo, hi) = bbox_of(&p);
            for iz in cell_of(&lo, 2)..=cell_of(&hi, 2) {
                for iy in cell_of(&lo, 1)..=cell_of(&hi, 1) {
                    for ix in cell_of(&lo, 0)..=cell_of(&hi, 0) {
                        let c = ix + dims[0] * (iy + dims[1] * iz);
                        pairs.push((c as u32, t as u32));
                    }
                }
            }
        }
        let (start, items) = csr(ncell, &pairs);
        Grid {
            origin,
            inv_h,
            dims,
            start,
            items,
        }
    }

    /// Pushes the ids of all triangles in cells overlapping the cube `x ± reach` (with repeats).
    pub(super) fn query(&self, x: &Vec3, reach: f64, out: &mut Vec<u32>) {
        let mut lo = [0usize; 3];
        let mut hi = [0usize; 3];
        for k in 0..3 {
            let a = ((x[k] - reach) - self.origin[k]) * self.inv_h;
            let b = ((x[k] + reach) - self.origin[k]) * self.inv_h;
            let n = self.dims[k] as f64;
            if b < 0.0 || a >= n {
                return;
            }
            lo[k] = a.floor().max(0.0) as usize;
            hi[k] = (b.floor().min(n - 1.0)) as usize;
        }
        for iz in lo[2]..=hi[2] {
            for iy in lo[1]..=hi[1] {
                let row = self.dims[0] * (iy + self.dims[1] * iz);
                let s = self.start[row + lo[0]] as usize;
                let e = self.start[row + hi[0] + 1] as usize;
                out.extend_from_slice(&self.items[s..e]);
            }
        }
    }
}
