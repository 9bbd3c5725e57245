//! Random insertion over the whole volume ([D Fig. 2.2c]) or layer by layer ([D Fig. 2.2d]),
//! on a cell grid that finds overlaps in constant time.

use super::error::PackingError;
use super::lattice::check_radii;
use super::region::{Region, orthonormal_frame};
use crate::ParameterError;
use crate::math::Vec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Layer-by-layer random insertion ([D Fig. 2.2d]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layering {
    /// Upward direction (opposite to gravity); need not be unit.
    pub up: Vec3,
    /// Height of one layer (range of centre heights) in m.
    pub layer_height_m: f64,
}

/// Uniform cell grid over a box with linked lists of particle indices (O(1) overlap checks).
pub(crate) struct CellGrid {
    lo: Vec3,
    cell: f64,
    dims: [usize; 3],
    head: Vec<u32>,
    next: Vec<u32>,
}

pub(crate) const EMPTY: u32 = u32::MAX;

impl CellGrid {
    pub(crate) fn new(lo: Vec3, hi: Vec3, min_cell: f64, n: usize) -> Self {
        let ext = hi - lo;
        // Keep the cell count bounded (≤ ~4M cells) for huge regions with tiny particles.
        let cell = min_cell.max((ext.product() / 4.0e6).cbrt());
        let dim = |e: f64| ((e / cell).ceil() as usize).max(1);
        let dims = [dim(ext.x), dim(ext.y), dim(ext.z)];
        CellGrid {
            lo,
            cell,
            dims,
            head: vec![EMPTY; dims[0] * dims[1] * dims[2]],
            next: Vec::with_capacity(n),
        }
    }

    fn coord(&self, x: &Vec3) -> [usize; 3] {
        let mut c = [0usize; 3];
        for i in 0..3 {
            let f = ((x[i] - self.lo[i]) / self.cell).floor();
            c[i] = if f <= 0.0 {
                0
            } else {
                (f as usize).min(self.dims[i] - 1)
            };
        }
        c
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// Adds particle `id` (ids must be added in order 0, 1, 2, …).
    pub(crate) fn insert(&mut self, id: u32, x: &Vec3) {
        let k = self.index(self.coord(x));
        debug_assert_eq!(self.next.len(), id as usize);
        self.next.push(self.head[k]);
        self.head[k] = id;
    }

    /// Whether a sphere (x, r) overlaps any stored particle; valid while r + r_j ≤ cell size.
    pub(crate) fn overlaps(&self, x: &Vec3, r: f64, pos: &[Vec3], radii: &[f64]) -> bool {
        let c = self.coord(x);
        let range = |i: usize| c[i].saturating_sub(1)..=(c[i] + 1).min(self.dims[i] - 1);
        for iz in range(2) {
            for iy in range(1) {
                for ix in range(0) {
                    let mut j = self.head[self.index([ix, iy, iz])];
                    while j != EMPTY {
                        let ju = j as usize;
                        let s = r + radii[ju];
                        if (pos[ju] - x).norm_squared() < s * s {
                            return true;
                        }
                        j = self.next[ju];
                    }
                }
            }
        }
        false
    }
}

impl CellGrid {
    /// Calls `f(j)` for every stored particle in the cells around `x` (the 27 cells).
    pub(crate) fn for_each_near(&self, x: &Vec3, mut f: impl FnMut(usize)) {
        let c = self.coord(x);
        let range = |i: usize| c[i].saturating_sub(1)..=(c[i] + 1).min(self.dims[i] - 1);
        for iz in range(2) {
            for iy in range(1) {
                for ix in range(0) {
                    let mut j = self.head[self.index([ix, iy, iz])];
                    while j != EMPTY {
                        f(j as usize);
                        j = self.next[j as usize];
                    }
                }
            }
        }
    }

    /// Whether the point `x` lies inside any stored particle (valid for points within one cell
    /// of the stored centres' box).
    pub(crate) fn contains_point(&self, x: &Vec3, pos: &[Vec3], radii: &[f64]) -> bool {
        let mut inside = false;
        self.for_each_near(x, |j| {
            if !inside && (pos[j] - x).norm_squared() < radii[j] * radii[j] {
                inside = true;
            }
        });
        inside
    }
}

/// Random placement without overlaps ([D Fig. 2.2c/d]), deterministic for a `seed`
/// (`ChaCha8Rng::seed_from_u64`). Whole-volume insertion places the particles in order of
/// decreasing radius, layered insertion in the given order; position `i` always belongs to
/// `radii[i]`. Each particle gets up to
/// `max_attempts_per_particle` uniformly drawn trial centres (every draw counts as an attempt).
/// Spheres may touch but not overlap each other or the region boundary. Overlap checks use a cell
/// grid with cells ≥ 2 r_max, so each trial costs O(1).
///
/// * `layering = None`: trial centres are uniform over the whole region.
/// * `layering = Some(l)`: the region is cut into slabs of centre heights
///   `[k h, (k+1) h)` above its lowest point along `l.up`; particles go into slab 0 until one fails
///   `max_attempts_per_particle` times, then into slab 1, and so on.
///
/// Errors (naming how many were placed) if a particle finds no free position.
pub fn random_insertion(
    region: &Region,
    radii: &[f64],
    seed: u64,
    max_attempts_per_particle: usize,
    layering: Option<&Layering>,
) -> Result<Vec<Vec3>, PackingError> {
    random_insertion_clear_of(
        region,
        radii,
        seed,
        max_attempts_per_particle,
        layering,
        &|_, _| false,
    )
}

/// [`random_insertion`] that also rejects every trial centre for which `blocked(x, r)` is true —
/// e.g. a sphere that would start inside or across a wall or an inner structure of the
/// container ([`crate::World::wall_overlap`]). A rejected trial counts as an attempt.
pub fn random_insertion_clear_of(
    region: &Region,
    radii: &[f64],
    seed: u64,
    max_attempts_per_particle: usize,
    layering: Option<&Layering>,
    blocked: &dyn Fn(&Vec3, f64) -> bool,
) -> Result<Vec<Vec3>, PackingError> {
    region.validate()?;
    let r_max = check_radii(radii)?;
    if radii.is_empty() {
        return Ok(Vec::new());
    }
    if max_attempts_per_particle == 0 {
        return Err(ParameterError::invalid(
            "max_attempts_per_particle",
            "max_attempts_per_particle must be > 0",
        )
        .into());
    }
    if radii.len() >= EMPTY as usize {
        return Err(PackingError::TooManyParticles { count: radii.len() });
    }
    let (lo, hi) = region.bounding_box();
    let mut grid = CellGrid::new(lo, hi, 2.0 * r_max, radii.len());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Whole-volume insertion tries the largest particles first (they are the hardest to place
    // late); layered insertion keeps the given order so sizes are not segregated by height.
    let mut order: Vec<usize> = (0..radii.len()).collect();
    if layering.is_none() {
        order.sort_by(|&a, &b| radii[b].total_cmp(&radii[a]).then(a.cmp(&b)));
    }
    let ins_radii: Vec<f64> = order.iter().map(|&i| radii[i]).collect();
    let mut pos: Vec<Vec3> = Vec::with_capacity(radii.len());

    let layers = match layering {
        None => None,
        Some(l) => {
            if !(l.layer_height_m.is_finite() && l.layer_height_m > 0.0) {
                let h = l.layer_height_m;
                return Err(
                    ParameterError::out_of_range("layer_height_m", "be finite and > 0", h).into(),
                );
            }
            let (e1, e2, e3) = orthonormal_frame(&l.up).ok_or(ParameterError::invalid(
                "layering.up",
                "layering: up must be finite and non-zero",
            ))?;
            let ext = [
                region.extent_along(&e1),
                region.extent_along(&e2),
                region.extent_along(&e3),
            ];
            let n_layers = (((ext[2].1 - ext[2].0) / l.layer_height_m).ceil() as usize).max(1);
            Some(([e1, e2, e3], ext, l.layer_height_m, n_layers))
        }
    };
    let mut layer = 0usize;

    for (n_placed, (&i, &r)) in order.iter().zip(&ins_radii).enumerate() {
        let placed = loop {
            let mut found = None;
            for _ in 0..max_attempts_per_particle {
                let trial = match &layers {
                    None => region.sample_center(r, &mut rng),
                    Some((e, ext, h, _)) => {
                        let z_lo = (ext[2].0 + layer as f64 * h).max(ext[2].0 + r);
                        let z_hi = (ext[2].0 + (layer + 1) as f64 * h).min(ext[2].1 - r);
                        let (x_lo, x_hi) = (ext[0].0 + r, ext[0].1 - r);
                        let (y_lo, y_hi) = (ext[1].0 + r, ext[1].1 - r);
                        if z_lo > z_hi || x_lo > x_hi || y_lo > y_hi {
                            None
                        } else {
                            let (u, v, w): (f64, f64, f64) =
                                (rng.random(), rng.random(), rng.random());
                            let p = e[0] * (x_lo + (x_hi - x_lo) * u)
                                + e[1] * (y_lo + (y_hi - y_lo) * v)
                                + e[2] * (z_lo + (z_hi - z_lo) * w);
                            region.contains_sphere(&p, r).then_some(p)
                        }
                    }
                };
                let Some(p) = trial else {
                    if layers.is_none() {
                        break; // cannot fit at all
                    }
                    continue;
                };
                if !region.contains_sphere(&p, r) {
                    continue;
                }
                if !grid.overlaps(&p, r, &pos, &ins_radii) && !blocked(&p, r) {
                    found = Some(p);
                    break;
                }
            }
            match (found, &layers) {
                (Some(p), _) => break Some(p),
                (None, Some((_, _, _, n_layers))) if layer + 1 < *n_layers => layer += 1,
                (None, _) => break None,
            }
        };
        let Some(p) = placed else {
            return Err(PackingError::NoFreePosition {
                placed: n_placed,
                requested: radii.len(),
                particle: i,
                radius_m: r,
                attempts: max_attempts_per_particle,
                in_top_layer: layers.is_some(),
            });
        };
        grid.insert(n_placed as u32, &p);
        pos.push(p);
    }
    let mut out = vec![Vec3::zeros(); radii.len()];
    for (&i, p) in order.iter().zip(pos) {
        out[i] = p;
    }
    Ok(out)
}
