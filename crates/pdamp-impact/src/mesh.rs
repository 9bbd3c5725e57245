//! Axisymmetric meshes of the impact model [D Sect. 4.2.2, Fig. 4.5]: a sphere (radius R, centre
//! on the axis, south pole touching the wall at the origin) and a clamped cylinder (the wall,
//! radius and height given; top face z = 0). Coordinates are (r, z), r ≥ 0.
//!
//! Both meshes are refined around the contact point: element size $h_c = a_{ref}/n_c$ inside a
//! zone of `zone_factor`·a_ref (a_ref: the expected contact radius), then growing geometrically
//! to $h_{max}$. The wall is a graded tensor grid. The sphere is an inner rectangle plus a
//! C-shaped ring whose radial lines run from the rectangle's boundary to the surface; near the
//! pole they are almost vertical and the ring is graded towards the surface. Everything scales
//! with R, so a mesh density is a set of ratios.

use std::ops::Range;

/// Mesh density presets (see [`MeshParams`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MeshDensity {
    /// 6 elements per contact radius, h_max = R/8, growth 1.3.
    Coarse,
    /// 10 elements per contact radius, h_max = R/12, growth 1.25 (default).
    #[default]
    Medium,
    /// 16 elements per contact radius, h_max = R/18, growth 1.18.
    Fine,
}

/// Mesh size ratios.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshParams {
    /// Elements per expected contact radius $n_c$ in the contact zone.
    pub elems_per_contact_radius: f64,
    /// Largest element size as a fraction of the sphere radius.
    pub max_size_over_radius: f64,
    /// Geometric growth ratio of the element size outside the contact zone.
    pub growth: f64,
    /// Extent of the uniformly refined zone in units of the contact radius.
    pub zone_factor: f64,
}

impl MeshDensity {
    /// The size ratios of the preset.
    pub fn params(self) -> MeshParams {
        match self {
            MeshDensity::Coarse => MeshParams {
                elems_per_contact_radius: 6.0,
                max_size_over_radius: 1.0 / 8.0,
                growth: 1.3,
                zone_factor: 1.8,
            },
            MeshDensity::Medium => MeshParams {
                elems_per_contact_radius: 10.0,
                max_size_over_radius: 1.0 / 12.0,
                growth: 1.25,
                zone_factor: 1.8,
            },
            MeshDensity::Fine => MeshParams {
                elems_per_contact_radius: 16.0,
                max_size_over_radius: 1.0 / 18.0,
                growth: 1.18,
                zone_factor: 1.8,
            },
        }
    }
}

/// An axisymmetric quad mesh of the sphere and (optionally) the wall.
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Reference radial coordinates of the nodes, m.
    pub r: Vec<f64>,
    /// Reference axial coordinates of the nodes, m.
    pub z: Vec<f64>,
    /// Elements (counter-clockwise node quadruples).
    pub elems: Vec<[u32; 4]>,
    /// Sphere nodes.
    pub sphere_nodes: Range<usize>,
    /// Wall nodes (empty without wall).
    pub wall_nodes: Range<usize>,
    /// Sphere elements.
    pub sphere_elems: Range<usize>,
    /// Wall elements.
    pub wall_elems: Range<usize>,
    /// Sphere surface nodes from the south pole upwards.
    pub sphere_surface: Vec<u32>,
    /// Wall top-face nodes, r increasing.
    pub wall_surface: Vec<u32>,
    /// Radial displacement fixed (axis, clamped contour).
    pub fix_r: Vec<bool>,
    /// Axial displacement fixed (clamped contour).
    pub fix_z: Vec<bool>,
    /// Element size in the contact zone $h_c$, m.
    pub h_contact: f64,
}

/// Graded 1-D positions from 0 to `length`: step `h0` up to `zone`, then growing by `growth` up
/// to `hmax`. The last step is merged if it would be shorter than 40 % of the previous one.
pub fn graded(length: f64, h0: f64, zone: f64, hmax: f64, growth: f64) -> Vec<f64> {
    let hmax = hmax.max(h0);
    let mut xs = vec![0.0];
    let mut h = h0;
    let mut x = 0.0;
    while x < length - 1e-12 * length {
        if x >= zone - 1e-12 * length {
            h = (h * growth).min(hmax);
        }
        x += h;
        xs.push(x.min(length));
    }
    let n = xs.len();
    if n >= 3 {
        let last = xs[n - 1] - xs[n - 2];
        let prev = xs[n - 2] - xs[n - 3];
        if last < 0.4 * prev {
            xs.remove(n - 2);
        }
    }
    *xs.last_mut().unwrap() = length;
    xs
}

struct Builder {
    r: Vec<f64>,
    z: Vec<f64>,
    elems: Vec<[u32; 4]>,
}

impl Builder {
    fn node(&mut self, r: f64, z: f64) -> u32 {
        self.r.push(r);
        self.z.push(z);
        (self.r.len() - 1) as u32
    }
    fn quad(&mut self, mut q: [u32; 4]) {
        let area = {
            let p = |i: usize| (self.r[q[i] as usize], self.z[q[i] as usize]);
            let mut a = 0.0;
            for i in 0..4 {
                let (x0, y0) = p(i);
                let (x1, y1) = p((i + 1) % 4);
                a += x0 * y1 - x1 * y0;
            }
            a
        };
        if area < 0.0 {
            q.swap(1, 3);
        }
        self.elems.push(q);
    }
}

/// Element sizes of a mesh: $h_c$ in the contact zone, growing by `growth` beyond `zone` up to
/// `hmax` (all in m but `growth`).
#[derive(Debug, Clone, Copy)]
struct Sizing {
    hc: f64,
    zone: f64,
    hmax: f64,
    growth: f64,
}

/// The wall's top-face nodes and its clamped contour (outer mantle and bottom).
struct WallNodes {
    surface: Vec<u32>,
    fix_r: Vec<u32>,
    fix_z: Vec<u32>,
}

/// Builds the mesh: sphere of `radius` (m) with its pole at the origin; wall cylinder of
/// `wall_radius` × `wall_height` (m) below z = 0 if `with_wall`. `a_ref` is the expected
/// contact radius (m).
pub fn build(
    radius: f64,
    with_wall: bool,
    wall_radius: f64,
    wall_height: f64,
    a_ref: f64,
    p: &MeshParams,
) -> Mesh {
    let hc = a_ref / p.elems_per_contact_radius;
    let hmax = p.max_size_over_radius * radius;
    let zone = p.zone_factor * a_ref;
    let sz = Sizing {
        hc,
        zone,
        hmax,
        growth: p.growth,
    };
    let mut b = Builder {
        r: Vec::new(),
        z: Vec::new(),
        elems: Vec::new(),
    };
    // ---------------- sphere ----------------
    let rr = radius;
    let inner = sphere_core(&mut b, rr, sz);
    let surface = sphere_shell(&mut b, rr, &inner, sz);
    let n_sphere = b.r.len();
    let e_sphere = b.elems.len();
    // ---------------- wall ----------------
    let wall = if with_wall {
        wall_cylinder(&mut b, wall_radius, wall_height, sz)
    } else {
        WallNodes {
            surface: Vec::new(),
            fix_r: Vec::new(),
            fix_z: Vec::new(),
        }
    };
    let n = b.r.len();
    let mut fix_r = vec![false; n];
    let mut fix_z = vec![false; n];
    for (f, r) in fix_r.iter_mut().zip(&b.r) {
        if r.abs() < 1e-12 * rr {
            *f = true;
        }
    }
    for &i in &wall.fix_r {
        fix_r[i as usize] = true;
    }
    for &i in &wall.fix_z {
        fix_z[i as usize] = true;
    }
    Mesh {
        r: b.r,
        z: b.z,
        elems: b.elems.clone(),
        sphere_nodes: 0..n_sphere,
        wall_nodes: n_sphere..n,
        sphere_elems: 0..e_sphere,
        wall_elems: e_sphere..b.elems.len(),
        sphere_surface: surface,
        wall_surface: wall.surface,
        fix_r,
        fix_z,
        h_contact: hc,
    }
}

/// The sphere's inner rectangle (half width and half height R/2 about the centre, columns
/// graded fine at the axis); returns its boundary points (bottom → right → top) with their
/// surface angles θ (0 = south pole).
fn sphere_core(b: &mut Builder, rr: f64, sz: Sizing) -> Vec<(u32, f64)> {
    let Sizing {
        hc,
        zone,
        hmax,
        growth,
    } = sz;
    let a = 0.5 * rr; // inner rectangle half width / half height
    let zc = rr; // centre
    // The bottom edge maps linearly onto the arc θ ∈ [0, π/4] (arc length (π/4)R over the
    // edge length a), so its spacing is the surface spacing scaled by `sc`.
    let sc = a / (std::f64::consts::FRAC_PI_4 * rr);
    let rs = graded(a, hc * sc, zone * sc, hmax * sc, growth); // rectangle columns (fine at the axis)
    let nz_rect = ((std::f64::consts::FRAC_PI_2 * rr / hmax).ceil() as usize).max(2);
    let zs: Vec<f64> = (0..=nz_rect)
        .map(|j| zc - a + 2.0 * a * j as f64 / nz_rect as f64)
        .collect();
    let nr = rs.len() - 1;
    let mut rect = vec![vec![0u32; nz_rect + 1]; nr + 1];
    for (i, &r) in rs.iter().enumerate() {
        for (j, &z) in zs.iter().enumerate() {
            rect[i][j] = b.node(r, z);
        }
    }
    for i in 0..nr {
        for j in 0..nz_rect {
            b.quad([
                rect[i][j],
                rect[i + 1][j],
                rect[i + 1][j + 1],
                rect[i][j + 1],
            ]);
        }
    }
    // inner boundary points (bottom → right → top) with their surface angles θ (0 = south pole)
    let theta_bottom = |r: f64| std::f64::consts::FRAC_PI_4 * r / a;
    let mut inner: Vec<(u32, f64)> = Vec::new();
    for i in 0..=nr {
        inner.push((rect[i][0], theta_bottom(rs[i])));
    }
    for j in 1..=nz_rect {
        let t = (zs[j] - (zc - a)) / (2.0 * a);
        inner.push((
            rect[nr][j],
            std::f64::consts::FRAC_PI_4 + t * std::f64::consts::FRAC_PI_2,
        ));
    }
    for i in (0..nr).rev() {
        inner.push((rect[i][nz_rect], std::f64::consts::PI - theta_bottom(rs[i])));
    }
    inner
}

/// The sphere's shell between the inner rectangle's boundary `inner` and the surface: rays
/// from each boundary point to the surface point at its angle θ, depth graded from the
/// surface (fine) to the rectangle; returns the surface nodes from the south pole upwards.
fn sphere_shell(b: &mut Builder, rr: f64, inner: &[(u32, f64)], sz: Sizing) -> Vec<u32> {
    let a = 0.5 * rr; // inner rectangle half width / half height
    let zc = rr; // centre
    // depth fractions, graded from the surface (fine) to the rectangle (f = 1)
    let depth = graded(a, sz.hc, sz.zone, sz.hmax, sz.growth);
    let fr: Vec<f64> = depth.iter().map(|d| d / a).collect();
    let nk = fr.len() - 1;
    let mut ring = vec![vec![0u32; nk + 1]; inner.len()];
    let mut surface = Vec::new();
    for (s, &(inode, th)) in inner.iter().enumerate() {
        let (ri, zi) = (b.r[inode as usize], b.z[inode as usize]);
        let (ro, zo) = if s == 0 {
            (0.0, 0.0)
        } else if s == inner.len() - 1 {
            (0.0, 2.0 * rr)
        } else {
            (rr * th.sin(), zc - rr * th.cos())
        };
        for (k, &f) in fr.iter().enumerate() {
            ring[s][k] = if k == nk {
                inode
            } else {
                let r = ro + f * (ri - ro);
                b.node(
                    if s == 0 || s == inner.len() - 1 {
                        0.0
                    } else {
                        r
                    },
                    zo + f * (zi - zo),
                )
            };
        }
        surface.push(ring[s][0]);
    }
    for s in 0..inner.len() - 1 {
        for k in 0..nk {
            b.quad([
                ring[s][k],
                ring[s + 1][k],
                ring[s + 1][k + 1],
                ring[s][k + 1],
            ]);
        }
    }
    surface
}

/// The wall cylinder `wall_radius` × `wall_height` below z = 0, graded fine at the axis and
/// at the top face; returns its top-face nodes and clamped contour.
fn wall_cylinder(b: &mut Builder, wall_radius: f64, wall_height: f64, sz: Sizing) -> WallNodes {
    let mut wall_surface = Vec::new();
    let mut fix_r_nodes = Vec::new();
    let mut fix_z_nodes = Vec::new();
    let wr = graded(wall_radius, sz.hc, sz.zone, sz.hmax, sz.growth);
    let wd = graded(wall_height, sz.hc, sz.zone, sz.hmax, sz.growth);
    let mut grid = vec![vec![0u32; wd.len()]; wr.len()];
    for (i, &r) in wr.iter().enumerate() {
        for (j, &d) in wd.iter().enumerate() {
            grid[i][j] = b.node(r, -d);
        }
    }
    for i in 0..wr.len() - 1 {
        for j in 0..wd.len() - 1 {
            b.quad([
                grid[i][j + 1],
                grid[i + 1][j + 1],
                grid[i + 1][j],
                grid[i][j],
            ]);
        }
    }
    for col in &grid {
        wall_surface.push(col[0]);
    }
    // clamped contour: outer mantle and bottom
    for col in &grid {
        fix_r_nodes.push(*col.last().unwrap());
        fix_z_nodes.push(*col.last().unwrap());
    }
    for &n in grid.last().unwrap() {
        fix_r_nodes.push(n);
        fix_z_nodes.push(n);
    }
    WallNodes {
        surface: wall_surface,
        fix_r: fix_r_nodes,
        fix_z: fix_z_nodes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The meshed sphere volume equals 4/3 πR³ (to the chord error, < 0.4 % on the coarse mesh), the cylinder
    /// volume πR_w²H exactly, and all elements have positive area.
    #[test]
    fn volumes() {
        let r = 0.015;
        let m = build(r, true, r, 2.0 * r, 0.7e-3, &MeshDensity::Coarse.params());
        let vol = |range: Range<usize>| {
            let mut v = 0.0;
            for e in &m.elems[range] {
                // 2π ∫ r dA by the centroid rule on the two triangles
                for tri in [[0, 1, 2], [0, 2, 3]] {
                    let p: Vec<(f64, f64)> = tri
                        .iter()
                        .map(|&i| (m.r[e[i] as usize], m.z[e[i] as usize]))
                        .collect();
                    let a = 0.5
                        * ((p[1].0 - p[0].0) * (p[2].1 - p[0].1)
                            - (p[2].0 - p[0].0) * (p[1].1 - p[0].1));
                    assert!(a > 0.0);
                    v += 2.0 * std::f64::consts::PI * a * (p[0].0 + p[1].0 + p[2].0) / 3.0;
                }
            }
            v
        };
        let vs = vol(m.sphere_elems.clone());
        let exact = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        assert!((vs / exact - 1.0).abs() < 4e-3, "{vs} vs {exact}");
        let vw = vol(m.wall_elems.clone());
        let exact_w = std::f64::consts::PI * r * r * 2.0 * r;
        assert!((vw / exact_w - 1.0).abs() < 1e-12);
        assert!(
            m.r[m.sphere_surface[0] as usize] == 0.0 && m.z[m.sphere_surface[0] as usize] == 0.0
        );
    }
}
