//! Half Verlet list (pairs i < j within $r_i+r_j+$skin) built with a uniform cell grid, with
//! transfer of the tangential-spring history across rebuilds and a reverse index for a
//! deterministic parallel gather. All buffers are reused: no allocation once warmed up.

/// Pair list with per-pair history. Serializable for checkpoints (the scratch buffers, which a
/// rebuild clears or overwrites before reading, are skipped).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct NeighborList {
    /// Skin distance \[m\].
    pub skin: f64,
    /// `start[i]..start[i+1]`: entries with first particle i.
    pub start: Vec<usize>,
    /// First particle of each entry.
    pub pi: Vec<u32>,
    /// Second particle of each entry (sorted within each i).
    pub pj: Vec<u32>,
    /// Tangential spring $\mathbf g_T$ of each entry \[m\].
    pub gt: Vec<[f64; 3]>,
    /// `rev_start[j]..rev_start[j+1]` indexes `rev` = entries whose second particle is j.
    pub rev_start: Vec<usize>,
    /// Entry indices grouped by second particle.
    pub rev: Vec<u32>,
    /// Positions at the last rebuild.
    pub ref_pos: Vec<[f64; 3]>,
    /// Number of rebuilds so far.
    pub rebuilds: u64,
    // scratch
    #[serde(skip)]
    old_start: Vec<usize>,
    #[serde(skip)]
    old_pj: Vec<u32>,
    #[serde(skip)]
    old_gt: Vec<[f64; 3]>,
    #[serde(skip)]
    cell_of: Vec<usize>,
    #[serde(skip)]
    cell_start: Vec<usize>,
    #[serde(skip)]
    cell_items: Vec<u32>,
    #[serde(skip)]
    tmp: Vec<u32>,
}

impl NeighborList {
    /// Empty list with the given skin \[m\].
    pub fn new(skin: f64) -> Self {
        Self {
            skin,
            ..Default::default()
        }
    }

    /// Checks that a deserialized list fits `n` particles (lengths, monotone offsets, indices
    /// in range).
    pub fn check_consistency(&self, n: usize) -> Result<(), String> {
        let bad = |what: &str| Err(format!("pair list: {what}"));
        let ne = self.pj.len();
        if self.pi.len() != ne || self.gt.len() != ne || self.rev.len() != ne {
            return bad("entry arrays of different lengths");
        }
        let offsets_ok = |v: &[usize]| {
            (v.is_empty() && ne == 0)
                || (v.len() == n + 1
                    && v[0] == 0
                    && v[n] == ne
                    && v.windows(2).all(|w| w[0] <= w[1]))
        };
        if !offsets_ok(&self.start) || !offsets_ok(&self.rev_start) {
            return bad("offsets do not match the particles");
        }
        if self.pi.iter().chain(&self.pj).any(|&i| i as usize >= n)
            || self.rev.iter().any(|&e| e as usize >= ne)
        {
            return bad("index out of range");
        }
        if !(self.ref_pos.is_empty() || self.ref_pos.len() == n) {
            return bad("reference positions do not match the particles");
        }
        Ok(())
    }

    /// Whether some particle moved more than skin/2 since the last rebuild.
    pub fn needs_rebuild(&self, pos: &[[f64; 3]]) -> bool {
        if self.ref_pos.len() != pos.len() {
            return true;
        }
        let lim = 0.25 * self.skin * self.skin;
        pos.iter().zip(&self.ref_pos).any(|(a, b)| {
            let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > lim
        })
    }

    /// Rebuilds the list; `extra_range` is added to the search distance (adhesion range).
    pub fn rebuild(&mut self, pos: &[[f64; 3]], radius: &[f64], extra_range: f64) {
        let n = pos.len();
        std::mem::swap(&mut self.old_start, &mut self.start);
        std::mem::swap(&mut self.old_pj, &mut self.pj);
        std::mem::swap(&mut self.old_gt, &mut self.gt);
        let had_old = self.old_start.len() == n + 1;
        self.start.clear();
        self.pi.clear();
        self.pj.clear();
        self.gt.clear();
        let rmax = radius.iter().fold(0.0f64, |m, &r| m.max(r));
        let reach = 2.0 * rmax + self.skin + extra_range;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        // non-finite positions (a run about to fail its health check) must not break the
        // grid: they are left out of the bounds and land in cell 0 without any pair
        for p in pos {
            for k in 0..3 {
                if p[k].is_finite() {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let mut nc = [1usize; 3];
        for k in 0..3 {
            let span = (hi[k] - lo[k]) / reach;
            if n > 0 && span.is_finite() && span > 0.0 {
                nc[k] = (span.floor().min(1023.0) as usize) + 1;
            }
        }
        // at most 8 cells per particle (a bed blown apart must not allocate 1024³ cells);
        // clamping positions into fewer cells keeps every pair (distances are checked)
        let limit = (8 * n).max(4096);
        while nc[0] * nc[1] * nc[2] > limit {
            let k = (0..3).max_by_key(|&k| nc[k]).unwrap_or(0);
            nc[k] = nc[k].div_ceil(2);
        }
        let ncell = nc[0] * nc[1] * nc[2];
        let cell_index = |p: &[f64; 3]| -> [usize; 3] {
            let mut c = [0; 3];
            for k in 0..3 {
                // `as` saturates (NaN → 0): always a valid cell
                c[k] = (((p[k] - lo[k]) / reach).max(0.0) as usize).min(nc[k] - 1);
            }
            c
        };
        self.cell_of.clear();
        self.cell_start.clear();
        self.cell_start.resize(ncell + 1, 0);
        for p in pos {
            let c = cell_index(p);
            let id = c[0] + nc[0] * (c[1] + nc[1] * c[2]);
            self.cell_of.push(id);
            self.cell_start[id + 1] += 1;
        }
        for c in 0..ncell {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.cell_items.clear();
        self.cell_items.resize(n, 0);
        {
            // counting sort (stable: particles in index order within a cell)
            let mut fill = std::mem::take(&mut self.tmp);
            fill.clear();
            fill.extend(self.cell_start[..ncell].iter().map(|&s| s as u32));
            for (i, &c) in self.cell_of.iter().enumerate() {
                self.cell_items[fill[c] as usize] = i as u32;
                fill[c] += 1;
            }
            self.tmp = fill;
        }
        let mut cand: Vec<u32> = Vec::new();
        std::mem::swap(&mut cand, &mut self.tmp);
        for i in 0..n {
            self.start.push(self.pj.len());
            let c = cell_index(&pos[i]);
            cand.clear();
            for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let cc = [c[0] as i64 + dx, c[1] as i64 + dy, c[2] as i64 + dz];
                        if (0..3).any(|k| cc[k] < 0 || cc[k] >= nc[k] as i64) {
                            continue;
                        }
                        let id = cc[0] as usize + nc[0] * (cc[1] as usize + nc[1] * cc[2] as usize);
                        for &j in &self.cell_items[self.cell_start[id]..self.cell_start[id + 1]] {
                            if (j as usize) <= i {
                                continue;
                            }
                            let (a, b) = (pos[i], pos[j as usize]);
                            let d2 = (a[0] - b[0]).powi(2)
                                + (a[1] - b[1]).powi(2)
                                + (a[2] - b[2]).powi(2);
                            let cut = radius[i] + radius[j as usize] + self.skin + extra_range;
                            if d2 < cut * cut {
                                cand.push(j);
                            }
                        }
                    }
                }
            }
            cand.sort_unstable();
            // history transfer by merge with the old (sorted) list of i
            let (mut o, oend) = if had_old {
                (self.old_start[i], self.old_start[i + 1])
            } else {
                (0, 0)
            };
            for &j in &cand {
                while o < oend && self.old_pj[o] < j {
                    o += 1;
                }
                let g = if o < oend && self.old_pj[o] == j {
                    self.old_gt[o]
                } else {
                    [0.0; 3]
                };
                self.pi.push(i as u32);
                self.pj.push(j);
                self.gt.push(g);
            }
        }
        self.start.push(self.pj.len());
        self.tmp = cand;
        // reverse index
        self.rev_start.clear();
        self.rev_start.resize(n + 1, 0);
        for &j in &self.pj {
            self.rev_start[j as usize + 1] += 1;
        }
        for k in 0..n {
            self.rev_start[k + 1] += self.rev_start[k];
        }
        self.rev.clear();
        self.rev.resize(self.pj.len(), 0);
        let mut fill = std::mem::take(&mut self.cell_of);
        fill.clear();
        fill.extend_from_slice(&self.rev_start[..n]);
        for (e, &j) in self.pj.iter().enumerate() {
            self.rev[fill[j as usize]] = e as u32;
            fill[j as usize] += 1;
        }
        self.cell_of = fill;
        self.ref_pos.clear();
        self.ref_pos.extend_from_slice(pos);
        self.rebuilds += 1;
    }
}
