//! Statistics of a particle bed at rest: packing fraction, coordination number, bed height and
//! the clearance h it leaves along the excitation [D Eq. 6.1, 7.4, 8.1], measured on the bed
//! rather than assumed.
//!
//! * **Packing fraction** φ = solid volume / volume, by Monte Carlo: uniform points (fixed seed)
//!   in the bed's bounding box that lie in the container's free space (clear of every wall,
//!   [`World::wall_overlap`]) below the bed surface; φ is the fraction of them inside a particle.
//!   `packing_fraction_bulk` takes only points at least 1.5 mean diameters from every wall, the
//!   floor and the surface (the random-packing value of the bulk, without the wall layering);
//!   `packing_fraction` takes all free points below the surface (the container's free volume
//!   up to the bed height, what a designer fills).
//! * **Bed surface**: the mean, over lateral cells of two mean diameters, of the highest
//!   particle top in the cell (along −g).
//! * **Coordination number** Z = 2 C / N with C the touching particle–particle pairs
//!   (centre distance < r_i + r_j); `rattler_fraction` is the share without any contact.
//! * **Clearance** along a direction e: the free length of the container on the line through the
//!   bed's centroid along e, minus the bed's span along e (from the highest particle top: the
//!   smallest gap). Where e lies along −g (a bed filled along the excitation, as D's cylinders
//!   with the axis vertical), also **clearance to the surface**: the free length minus the bed
//!   height (bottom to the mean surface), the volumetric gap of D Eq. 8.1
//!   h = L (1 − n_p/n_p^max) — the cap set at h above the mark the bed was poured to (D L3093)
//!   and the h of X_opt = h/π (D Eq. 8.2). A poured surface is rough: the two differ by about a
//!   diameter (D L3091 finds h_min ≈ r "due to the irregular surface of the particle bed").

use crate::generate::{CellGrid, orthonormal_frame};
use crate::math::Vec3;
use crate::particles::ParticleSet;
use crate::world::World;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Monte Carlo points of [`bed_statistics`] (standard error of φ ≈ 0.5/√n ≈ 1e-3).
pub const PACKING_SAMPLES: usize = 200_000;

/// Statistics of a bed (see the module docs); SI units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BedStatistics {
    /// Number of particles.
    pub particles: usize,
    /// Mass of the bed, kg.
    pub bed_mass_kg: f64,
    /// Solid volume Σ 4/3 π r³, m³.
    pub solid_volume_m3: f64,
    /// Mean particle diameter, m.
    pub mean_diameter_m: f64,
    /// Packing fraction of the container's free volume below the bed surface.
    pub packing_fraction: f64,
    /// Packing fraction of the bulk (≥ 1.5 mean diameters from walls, floor and surface);
    /// `NaN` when the bed is too shallow or narrow to have a bulk.
    pub packing_fraction_bulk: f64,
    /// Free volume of the container below the bed surface, m³.
    pub free_volume_below_surface_m3: f64,
    /// Mean number of particle–particle contacts per particle.
    pub mean_coordination_number: f64,
    /// Mean number of wall contacts per particle.
    pub mean_wall_contacts: f64,
    /// Share of particles without any particle or wall contact.
    pub rattler_fraction: f64,
    /// Lowest particle bottom along −g (`up` = −g/|g|), m.
    pub bed_bottom_m: f64,
    /// Bed surface height along `up` (module docs), m.
    pub bed_surface_m: f64,
    /// Bed height: surface − bottom, m.
    pub bed_height_m: f64,
    /// Excitation direction the next three refer to (unit), if one was given.
    pub direction: Option<[f64; 3]>,
    /// Span of the bed along the direction [lowest, highest] of x·e ∓ r, m.
    pub bed_span_along_direction_m: Option<[f64; 2]>,
    /// Free length of the container through the bed's centroid along the direction (beside an
    /// inner structure that blocks that line: the longest free line through a particle), m.
    pub container_length_along_direction_m: Option<f64>,
    /// Clearance h = free length − bed span along the direction (from the highest particle), m.
    pub clearance_m: Option<f64>,
    /// Clearance to the bed's mean surface, free length − bed height, where the direction lies
    /// along −g [D Eq. 8.1], m (module docs).
    #[serde(default)]
    pub clearance_to_surface_m: Option<f64>,
}

/// Statistics of the bed of `world` (bodies at their current poses, at rest; gravity gives
/// `up`, or +z without gravity), with the clearance along `direction` when given. Deterministic.
pub fn bed_statistics(world: &World, direction: Option<Vec3>) -> BedStatistics {
    let p = &world.particles;
    let n = p.len();
    let g = world.gravity_m_s2;
    let (e1, e2, up) = orthonormal_frame(&(-g)).unwrap_or((Vec3::x(), Vec3::y(), Vec3::z()));
    let solid: f64 = p
        .radius
        .iter()
        .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
        .sum();
    let d_mean = if n > 0 {
        2.0 * p.radius.iter().sum::<f64>() / n as f64
    } else {
        0.0
    };
    let mut s = BedStatistics {
        particles: n,
        bed_mass_kg: p.mass.iter().sum(),
        solid_volume_m3: solid,
        mean_diameter_m: d_mean,
        packing_fraction: f64::NAN,
        packing_fraction_bulk: f64::NAN,
        free_volume_below_surface_m3: f64::NAN,
        mean_coordination_number: f64::NAN,
        mean_wall_contacts: f64::NAN,
        rattler_fraction: f64::NAN,
        bed_bottom_m: f64::NAN,
        bed_surface_m: f64::NAN,
        bed_height_m: f64::NAN,
        direction: None,
        bed_span_along_direction_m: None,
        container_length_along_direction_m: None,
        clearance_m: None,
        clearance_to_surface_m: None,
    };
    if n == 0 {
        return s;
    }
    let r_max = p.max_radius();
    let (mut lo, mut hi) = (p.position[0], p.position[0]);
    for x in &p.position {
        lo = lo.inf(x);
        hi = hi.sup(x);
    }
    let mut grid = CellGrid::new(lo, hi, 2.0 * r_max, n);
    for (i, x) in p.position.iter().enumerate() {
        grid.insert(i as u32, x);
    }

    let (coordination, wall_contacts, rattlers) = contact_counts(world, &grid);
    s.mean_coordination_number = coordination;
    s.mean_wall_contacts = wall_contacts;
    s.rattler_fraction = rattlers;
    let (bottom, surface) = bottom_and_surface(p, (e1, e2, up), d_mean);
    s.bed_bottom_m = bottom;
    s.bed_surface_m = surface;
    s.bed_height_m = surface - bottom;
    let bed_box = (lo.add_scalar(-r_max), hi.add_scalar(r_max));
    let (free_volume, fraction, fraction_bulk) =
        packing_fractions(world, &grid, bed_box, up, (bottom, surface), d_mean);
    s.free_volume_below_surface_m3 = free_volume;
    s.packing_fraction = fraction;
    s.packing_fraction_bulk = fraction_bulk;
    if let Some(d) = direction.filter(|d| d.norm() > 0.0 && d.iter().all(|c| c.is_finite())) {
        clearance_along(world, d.normalize(), up, (lo, hi), &mut s);
    }
    s
}

/// Mean contacts per particle with other particles and with walls, and the fraction of
/// particles without any contact (rattlers).
fn contact_counts(world: &World, grid: &CellGrid) -> (f64, f64, f64) {
    let p = &world.particles;
    let n = p.len();
    let mut pp = vec![0u32; n];
    for i in 0..n {
        grid.for_each_near(&p.position[i], |j| {
            if j > i {
                let rr = p.radius[i] + p.radius[j];
                if (p.position[i] - p.position[j]).norm_squared() < rr * rr {
                    pp[i] += 1;
                    pp[j] += 1;
                }
            }
        });
    }
    let mut scratch = Vec::new();
    let mut wall = vec![0u32; n];
    for (i, c) in wall.iter_mut().enumerate() {
        for b in &world.bodies {
            let xb = b.state.to_body(&p.position[i]);
            for w in &b.walls {
                scratch.clear();
                w.geometry
                    .sphere_contacts(&xb, p.radius[i], 0.0, &mut scratch);
                *c += scratch.iter().filter(|k| k.overlap_m > 0.0).count() as u32;
            }
        }
    }
    (
        pp.iter().map(|&k| k as f64).sum::<f64>() / n as f64,
        wall.iter().map(|&k| k as f64).sum::<f64>() / n as f64,
        (0..n).filter(|&i| pp[i] + wall[i] == 0).count() as f64 / n as f64,
    )
}

/// The bed's lowest particle bottom and its surface along `up`: the mean of the highest tops
/// over a lateral grid of cells two mean diameters wide.
fn bottom_and_surface(
    p: &ParticleSet,
    (e1, e2, up): (Vec3, Vec3, Vec3),
    d_mean: f64,
) -> (f64, f64) {
    let n = p.len();
    let along = |x: &Vec3| [x.dot(&e1), x.dot(&e2), x.dot(&up)];
    let bottom = (0..n)
        .map(|i| p.position[i].dot(&up) - p.radius[i])
        .fold(f64::INFINITY, f64::min);
    let (mut a_lo, mut a_hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for x in &p.position {
        let a = along(x);
        for k in 0..2 {
            a_lo[k] = a_lo[k].min(a[k]);
            a_hi[k] = a_hi[k].max(a[k]);
        }
    }
    let cell = 2.0 * d_mean;
    let cells = |k: usize| (((a_hi[k] - a_lo[k]) / cell).floor() as usize + 1).min(4096);
    let (cx, cy) = (cells(0), cells(1));
    let mut top = vec![f64::NEG_INFINITY; cx * cy];
    for i in 0..n {
        let a = along(&p.position[i]);
        let ix = (((a[0] - a_lo[0]) / cell) as usize).min(cx - 1);
        let iy = (((a[1] - a_lo[1]) / cell) as usize).min(cy - 1);
        let t = &mut top[iy * cx + ix];
        *t = t.max(a[2] + p.radius[i]);
    }
    let filled: Vec<f64> = top.into_iter().filter(|t| t.is_finite()).collect();
    let surface = filled.iter().sum::<f64>() / filled.len() as f64;
    (bottom, surface)
}

/// Packing fraction by Monte Carlo in the bed's bounding box `(box_lo, box_hi)`: the free
/// volume below the surface, the solid fraction of it, and the bulk fraction away from the
/// walls, the bottom and the surface by 1.5 mean diameters (`NaN` with under 1 000 samples).
fn packing_fractions(
    world: &World,
    grid: &CellGrid,
    (box_lo, box_hi): (Vec3, Vec3),
    up: Vec3,
    (bottom, surface): (f64, f64),
    d_mean: f64,
) -> (f64, f64, f64) {
    let p = &world.particles;
    let mut scratch = Vec::new();
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_bed5);
    let margin = 1.5 * d_mean;
    let (mut free, mut free_solid, mut bulk, mut bulk_solid) = (0usize, 0usize, 0usize, 0usize);
    for _ in 0..PACKING_SAMPLES {
        let u = Vec3::new(rng.random(), rng.random(), rng.random());
        let x = box_lo + (box_hi - box_lo).component_mul(&u);
        let h = x.dot(&up);
        if h > surface || world.wall_overlap(&x, 0.0, &mut scratch).is_some() {
            continue;
        }
        let inside = grid.contains_point(&x, &p.position, &p.radius);
        free += 1;
        free_solid += inside as usize;
        if h >= bottom + margin
            && h <= surface - margin
            && world.wall_overlap(&x, margin, &mut scratch).is_none()
        {
            bulk += 1;
            bulk_solid += inside as usize;
        }
    }
    let box_volume = (box_hi - box_lo).product();
    let bulk_fraction = if bulk >= 1000 {
        bulk_solid as f64 / bulk as f64
    } else {
        f64::NAN
    };
    (
        box_volume * free as f64 / PACKING_SAMPLES as f64,
        free_solid as f64 / free.max(1) as f64,
        bulk_fraction,
    )
}

/// The clearance along the unit direction `e`: the bed's span along it, the container's free
/// length through the bed's centroid (marched and bisected to the walls) and their difference
/// (also to the surface when `e` is vertical). Where an inner structure (a cross, a rod) holds
/// the centroid or blocks its line, the length is the longest free line through a particle
/// centre (at most 64 particles, evenly spaced), i.e. the container's length beside the
/// structure.
fn clearance_along(
    world: &World,
    e: Vec3,
    up: Vec3,
    (lo, hi): (Vec3, Vec3),
    s: &mut BedStatistics,
) {
    let p = &world.particles;
    let n = p.len();
    let r_max = p.max_radius();
    let mut scratch = Vec::new();
    let (mut s_lo, mut s_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut centroid = Vec3::zeros();
    for i in 0..n {
        let t = p.position[i].dot(&e);
        s_lo = s_lo.min(t - p.radius[i]);
        s_hi = s_hi.max(t + p.radius[i]);
        centroid += p.position[i];
    }
    centroid /= n as f64;
    let reach = 10.0 * ((hi - lo).norm() + 2.0 * r_max);
    let free_to = |origin: &Vec3, sign: f64, scratch: &mut Vec<_>| -> f64 {
        // March in steps of a quarter radius, then bisect the wall crossing.
        let step = 0.25 * r_max.max(1e-12);
        let is_free = |t: f64, sc: &mut Vec<_>| {
            world
                .wall_overlap(&(origin + e * (sign * t)), 0.0, sc)
                .is_none()
        };
        let mut t = 0.0;
        while t < reach && is_free(t + step, scratch) {
            t += step;
        }
        if t >= reach {
            return f64::INFINITY;
        }
        let (mut a, mut b) = (t, t + step);
        for _ in 0..50 {
            let m = 0.5 * (a + b);
            if is_free(m, scratch) {
                a = m;
            } else {
                b = m;
            }
        }
        a
    };
    let free_length = |origin: &Vec3, scratch: &mut Vec<_>| {
        if world.wall_overlap(origin, 0.0, scratch).is_none() {
            free_to(origin, 1.0, scratch) + free_to(origin, -1.0, scratch)
        } else {
            f64::NAN
        }
    };
    let mut length = free_length(&centroid, &mut scratch);
    // The centroid's line reaches the bed's ends (less a particle radius for a bed pressed
    // against both ends); otherwise a structure stands in it.
    if length.is_nan() || length < s_hi - s_lo - r_max {
        let stride = n.div_ceil(64).max(1);
        length = (0..n)
            .step_by(stride)
            .map(|i| free_length(&p.position[i], &mut scratch))
            .filter(|l| l.is_finite())
            .fold(length, |a, b| if a.is_nan() || b > a { b } else { a });
    }
    s.direction = Some([e.x, e.y, e.z]);
    s.bed_span_along_direction_m = Some([s_lo, s_hi]);
    s.container_length_along_direction_m = Some(length);
    s.clearance_m = Some(length - (s_hi - s_lo));
    if e.dot(&up).abs() > 1.0 - 1e-6 {
        s.clearance_to_surface_m = Some(length - s.bed_height_m);
    }
}
