//! Particle–particle contact search: a cell grid rebuilds a Verlet (neighbour) list with a skin
//! [D Sect. 2.2, Eq. 2.8], and the list is rebuilt when the two largest displacements since the
//! last build add up to the skin [D Eq. 2.11]. Contact history stored per pair is carried over to
//! the new list.
//!
//! The list is a half list in compressed rows: for particle `i`, the partners `j > i` in
//! ascending order (the pair pass sums both partners' forces in a fixed order, see
//! `forces::force_blocks`).

use crate::math::Vec3;
use rayon::prelude::*;

/// Half neighbour list with per-pair storage.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NeighborList {
    /// Verlet distance (skin) $d_v$, m.
    pub skin_m: f64,
    /// Extra interaction range beyond touching (adhesion), m.
    pub extra_range_m: f64,
    /// Row starts: pairs of particle `i` are `row_start[i]..row_start[i+1]`.
    pub row_start: Vec<u32>,
    /// First partner `i` of each pair.
    pub first: Vec<u32>,
    /// Second partner `j > i` of each pair.
    pub second: Vec<u32>,
    /// Positions at the last build, m.
    pub reference_position: Vec<Vec3>,
    /// Number of builds so far.
    pub builds: u64,
}

/// The two largest of four values, largest first: merges the top two of two sets (exact, in any
/// order of merging).
#[inline]
fn top_two(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    if a[0] >= b[0] {
        [a[0], a[1].max(b[0])]
    } else {
        [b[0], b[1].max(a[0])]
    }
}

/// A neighbour list read from a file does not fit its particles
/// ([`NeighborList::check_consistency`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("neighbour list: {problem}")]
pub struct NeighborListError {
    /// What is wrong, e.g. `rows do not cover the pairs`.
    pub problem: &'static str,
}

impl NeighborList {
    /// Checks the list against `n` particles (a list read from a file): finite skin and range,
    /// rows that cover the pairs in order, pairs `(i, j)` with `i < j < n` in the row of `i`,
    /// reference positions for all particles (or none). The error says what is wrong.
    pub fn check_consistency(&self, n: usize) -> Result<(), NeighborListError> {
        let bad = |what: &'static str| Err(NeighborListError { problem: what });
        let finite_non_negative = |x: f64| x.is_finite() && x >= 0.0;
        if !(finite_non_negative(self.skin_m) && finite_non_negative(self.extra_range_m)) {
            return bad("skin or range not finite and non-negative");
        }
        let m = self.first.len();
        if self.second.len() != m {
            return bad("pair columns of different lengths");
        }
        if !(self.reference_position.is_empty() || self.reference_position.len() == n) {
            return bad("reference positions do not match the particles");
        }
        if self.row_start.is_empty() {
            return if m == 0 {
                Ok(())
            } else {
                bad("pairs without rows")
            };
        }
        if self.row_start.len() != n + 1
            || self.row_start[0] != 0
            || self.row_start[n] as usize != m
            || self.row_start.windows(2).any(|w| w[0] > w[1])
        {
            return bad("rows do not cover the pairs");
        }
        for i in 0..n {
            for k in self.row_start[i] as usize..self.row_start[i + 1] as usize {
                if self.first[k] as usize != i
                    || self.second[k] as usize >= n
                    || self.second[k] <= self.first[k]
                {
                    return bad("a pair is not in its first partner's row");
                }
            }
        }
        Ok(())
    }

    /// An empty list with the given skin.
    pub fn new(skin_m: f64) -> Self {
        Self {
            skin_m,
            ..Default::default()
        }
    }

    /// Number of pairs in the list.
    pub fn num_pairs(&self) -> usize {
        self.first.len()
    }

    /// True if the list must be rebuilt: never built, particle count changed, or the two largest
    /// displacements since the last build sum to at least the skin [D Eq. 2.11].
    pub fn needs_rebuild(&self, position: &[Vec3]) -> bool {
        if self.reference_position.len() != position.len() || self.builds == 0 {
            return true;
        }
        let top = position
            .par_iter()
            .zip(self.reference_position.par_iter())
            .map(|(x, x0)| (x - x0).norm_squared())
            .fold(|| [0.0f64; 2], |top, d| top_two(top, [d, 0.0]))
            .reduce(|| [0.0; 2], top_two);
        top[0].sqrt() + top[1].sqrt() >= self.skin_m
    }

    /// Rebuilds the list with a cell grid. (Contact history is not stored here: the world keeps
    /// its contacts by partner indices, so they survive any rebuild.)
    pub fn rebuild(&mut self, position: &[Vec3], radius: &[f64]) {
        let n = position.len();
        let r_max = radius.iter().cloned().fold(0.0, f64::max);
        let reach = self.skin_m + self.extra_range_m;
        let cell = (2.0 * r_max + reach).max(1e-12);
        let grid = CellGrid::new(position, cell);

        const CHUNK: usize = 512;
        let rows: Vec<(Vec<u32>, Vec<u32>)> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let lo = c * CHUNK;
                let hi = (lo + CHUNK).min(n);
                let mut partners = Vec::new();
                let mut counts = Vec::with_capacity(hi - lo);
                for i in lo..hi {
                    let start = partners.len();
                    let xi = position[i];
                    grid.for_each_near(&xi, |j| {
                        if j > i {
                            let cut = radius[i] + radius[j] + reach;
                            if (position[j] - xi).norm_squared() < cut * cut {
                                partners.push(j as u32);
                            }
                        }
                    });
                    partners[start..].sort_unstable();
                    counts.push((partners.len() - start) as u32);
                }
                (partners, counts)
            })
            .collect();

        self.row_start.clear();
        self.row_start.reserve(n + 1);
        self.row_start.push(0);
        self.first.clear();
        self.second.clear();
        let mut i = 0u32;
        for (partners, counts) in &rows {
            let mut k = 0usize;
            for &c in counts {
                for _ in 0..c {
                    self.first.push(i);
                    self.second.push(partners[k]);
                    k += 1;
                }
                self.row_start.push(self.second.len() as u32);
                i += 1;
            }
        }

        self.reference_position.clear();
        self.reference_position.extend_from_slice(position);
        self.builds += 1;
    }
}

/// A uniform grid of cubic cells over the bounding box of the particles (counting-sorted).
struct CellGrid {
    origin: Vec3,
    inv_cell: f64,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
}

impl CellGrid {
    fn new(position: &[Vec3], cell: f64) -> Self {
        let mut lo = Vec3::repeat(f64::INFINITY);
        let mut hi = Vec3::repeat(f64::NEG_INFINITY);
        // Non-finite positions (a blown-up run) are ignored for the bounds and land in cell 0, so
        // the build terminates and the caller's finiteness checks can report the instability.
        for x in position.iter().filter(|x| x.iter().all(|c| c.is_finite())) {
            lo = lo.inf(x);
            hi = hi.sup(x);
        }
        if !lo.iter().all(|c| c.is_finite()) {
            lo = Vec3::zeros();
            hi = Vec3::zeros();
        }
        // Limit the number of cells (particles flying far away) to a few per particle.
        let mut cell = cell;
        let max_cells = (8 * position.len()).max(64) as f64;
        loop {
            let d = (hi - lo) / cell;
            if (d.x + 1.0) * (d.y + 1.0) * (d.z + 1.0) <= max_cells || !cell.is_finite() {
                break;
            }
            cell *= 1.5;
        }
        let inv_cell = 1.0 / cell;
        let dims = [0, 1, 2].map(|k| (((hi[k] - lo[k]) * inv_cell).floor() as usize) + 1);
        let ncell = dims[0] * dims[1] * dims[2];
        let mut start = vec![0u32; ncell + 1];
        let cell_of: Vec<u32> = position
            .iter()
            .map(|x| {
                let c = [0, 1, 2].map(|k| (((x[k] - lo[k]) * inv_cell) as usize).min(dims[k] - 1));
                (c[0] + dims[0] * (c[1] + dims[1] * c[2])) as u32
            })
            .collect();
        for &c in &cell_of {
            start[c as usize + 1] += 1;
        }
        for k in 0..ncell {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; position.len()];
        for (i, &c) in cell_of.iter().enumerate() {
            items[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        Self {
            origin: lo,
            inv_cell,
            dims,
            start,
            items,
        }
    }

    /// Calls `f(j)` for every particle in the 27 cells around `x`.
    #[inline]
    fn for_each_near(&self, x: &Vec3, mut f: impl FnMut(usize)) {
        let c = [0, 1, 2].map(|k| {
            (((x[k] - self.origin[k]) * self.inv_cell) as isize).clamp(0, self.dims[k] as isize - 1)
        });
        for dz in -1..=1isize {
            let z = c[2] + dz;
            if z < 0 || z >= self.dims[2] as isize {
                continue;
            }
            for dy in -1..=1isize {
                let y = c[1] + dy;
                if y < 0 || y >= self.dims[1] as isize {
                    continue;
                }
                let row = self.dims[0] * (y as usize + self.dims[1] * z as usize);
                let x0 = (c[0] - 1).max(0) as usize;
                let x1 = ((c[0] + 1) as usize).min(self.dims[0] - 1);
                let (s, e) = (
                    self.start[row + x0] as usize,
                    self.start[row + x1 + 1] as usize,
                );
                for &j in &self.items[s..e] {
                    f(j as usize);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Merging top-two pairs in any grouping gives the two largest values.
    #[test]
    fn top_two_merges_exactly() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        for _ in 0..200 {
            let v: Vec<f64> = (0..rng.random_range(1..40))
                .map(|_| rng.random::<f64>())
                .collect();
            let mut sorted = v.clone();
            sorted.sort_by(|a, b| b.total_cmp(a));
            let want = [sorted[0], sorted.get(1).copied().unwrap_or(0.0)];
            let cut = rng.random_range(0..=v.len());
            let part = |s: &[f64]| s.iter().fold([0.0; 2], |t, &d| top_two(t, [d, 0.0]));
            assert_eq!(top_two(part(&v[..cut]), part(&v[cut..])), want);
            assert_eq!(top_two(part(&v[cut..]), part(&v[..cut])), want);
        }
    }

    #[test]
    fn grid_build_terminates_on_non_finite_positions() {
        let pos = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(f64::NAN, 1.0, 0.0),
            Vec3::new(1e-3, 0.0, f64::INFINITY),
            Vec3::new(2e-3, 0.0, 0.0),
        ];
        let g = CellGrid::new(&pos, 1e-3);
        assert_eq!(g.items.len(), 4);
    }

    #[test]
    fn list_matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = 2000;
        let pos: Vec<Vec3> = (0..n)
            .map(|_| {
                Vec3::new(
                    rng.random::<f64>(),
                    rng.random::<f64>(),
                    rng.random::<f64>(),
                ) * 0.05
            })
            .collect();
        let rad: Vec<f64> = (0..n)
            .map(|_| 0.0005 + 0.0005 * rng.random::<f64>())
            .collect();
        let mut list = NeighborList::new(0.0002);
        list.rebuild(&pos, &rad);
        let mut brute = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                let cut = rad[i] + rad[j] + 0.0002;
                if (pos[i] - pos[j]).norm() < cut {
                    brute.push((i as u32, j as u32));
                }
            }
        }
        let got: Vec<(u32, u32)> = list
            .first
            .iter()
            .cloned()
            .zip(list.second.iter().cloned())
            .collect();
        assert_eq!(got, brute);
    }
}
