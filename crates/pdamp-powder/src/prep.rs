//! Powder preparation (paper Sect. 2.4, Fig. 1a): particles drawn from the size distribution
//! until their volume equals ϕ·V_cavity, placed on a Cartesian grid above the cavity floor,
//! settled under gravity, then compressed by a displacement-controlled plate down to the cavity
//! height, so that the packing density (particle volume / cavity volume) is the prescribed ϕ;
//! finally relaxed with the plate held. The particles are prepared directly in the cavity's
//! coordinates, so "extraction and insertion" is removing the box walls and the plate.

use std::time::Instant;

use crate::dem::wall::{self, EMPTY_SLOTS};
use crate::dem::{LogNormal, PlaneWall, Powder, PowderLaw, Rng};
use crate::fe::Aabb;

/// Preparation settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrepSettings {
    /// Target packing density ϕ = particle volume / cavity volume.
    pub packing_density: f64,
    /// Random seed (sizes and grid jitter).
    pub seed: u64,
    /// Gravity magnification during settling (1 = real gravity; larger settles faster).
    pub settling_gravity_factor: f64,
    /// Plate speed during compression [m/s].
    pub plate_speed_m_s: f64,
    /// Relaxation after compression with the plate held [s].
    pub relax_time_s: f64,
    /// Longest settling time [s].
    pub max_settling_time_s: f64,
}

impl Default for PrepSettings {
    fn default() -> Self {
        Self {
            packing_density: 0.58,
            seed: 1,
            settling_gravity_factor: 20.0,
            plate_speed_m_s: 0.2,
            relax_time_s: 2e-3,
            max_settling_time_s: 0.5,
        }
    }
}

/// Outcome of the preparation.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PrepReport {
    /// Particles.
    pub particles: usize,
    /// Packing density reached after settling (bed height from the highest particle top).
    pub settled_packing_density: f64,
    /// Packing density in the cavity (particle volume / cavity volume).
    pub packing_density: f64,
    /// Whether the settled bed was higher than the cavity (so the plate compressed it).
    pub compressed: bool,
    /// Force on the plate at the end [N].
    pub plate_force_n: f64,
    /// Largest overlap / smaller diameter at the end.
    pub max_relative_overlap: f64,
    /// Simulated preparation time [s].
    pub simulated_time_s: f64,
    /// DEM steps.
    pub steps: u64,
    /// Wall time [s].
    pub wall_time_s: f64,
}

/// Prepares the powder in `cavity` (gravity along −z during preparation, as in the paper).
pub fn prepare(
    cavity: Aabb,
    psd: &LogNormal,
    law: PowderLaw,
    density_kg_m3: f64,
    dt: f64,
    s: &PrepSettings,
    progress: &mut dyn FnMut(&str, f64),
) -> (Powder, PrepReport) {
    let clock = Instant::now();
    let mut rng = Rng::new(s.seed);
    let vcav = cavity.volume();
    let diam = psd.fill_volume(s.packing_density * vcav, &mut rng);
    let spacing = psd.d_max_m * 1.02;
    let (lx, ly) = (cavity.max[0] - cavity.min[0], cavity.max[1] - cavity.min[1]);
    let nx = ((lx / spacing).floor() as usize).max(1);
    let ny = ((ly / spacing).floor() as usize).max(1);
    let ox = cavity.min[0] + 0.5 * (lx - (nx as f64 - 1.0) * spacing);
    let oy = cavity.min[1] + 0.5 * (ly - (ny as f64 - 1.0) * spacing);
    let mut pos = Vec::with_capacity(diam.len());
    for (q, _) in diam.iter().enumerate() {
        let layer = q / (nx * ny);
        let rem = q % (nx * ny);
        let (i, j) = (rem % nx, rem / nx);
        let jit = 0.005 * spacing;
        pos.push([
            ox + i as f64 * spacing + jit * (rng.uniform() - 0.5),
            oy + j as f64 * spacing + jit * (rng.uniform() - 0.5),
            cavity.min[2] + 0.5 * spacing + layer as f64 * spacing,
        ]);
    }
    let radius: Vec<f64> = diam.iter().map(|d| 0.5 * d).collect();
    let g0 = [0.0, 0.0, -9.81];
    let mut p = Powder::new(
        law,
        pos,
        radius,
        density_kg_m3,
        [0.0, 0.0, -9.81 * s.settling_gravity_factor],
        dt,
    );
    let n = p.len();
    let top_start = p
        .pos
        .iter()
        .zip(&p.radius)
        .map(|(x, r)| x[2] + r)
        .fold(cavity.max[2], f64::max)
        + spacing;
    let mut planes = vec![
        PlaneWall {
            point: cavity.min,
            normal: [1.0, 0.0, 0.0],
            velocity: [0.0; 3],
        },
        PlaneWall {
            point: cavity.max,
            normal: [-1.0, 0.0, 0.0],
            velocity: [0.0; 3],
        },
        PlaneWall {
            point: cavity.min,
            normal: [0.0, 1.0, 0.0],
            velocity: [0.0; 3],
        },
        PlaneWall {
            point: cavity.max,
            normal: [0.0, -1.0, 0.0],
            velocity: [0.0; 3],
        },
        PlaneWall {
            point: cavity.min,
            normal: [0.0, 0.0, 1.0],
            velocity: [0.0; 3],
        },
        PlaneWall {
            point: [cavity.min[0], cavity.min[1], top_start],
            normal: [0.0, 0.0, -1.0],
            velocity: [0.0; 3],
        },
    ];
    let mut hist = vec![EMPTY_SLOTS; n];
    let mut steps = 0u64;
    let mut on_wall = [[0.0; 3]; 6];
    let step =
        |p: &mut Powder, planes: &[PlaneWall], hist: &mut Vec<_>, on_wall: &mut [[f64; 3]; 6]| {
            p.predict();
            p.pair_forces();
            wall::plane_forces(p, planes, hist, on_wall);
            p.finish();
        };
    let mtot: f64 = p.mass.iter().sum();
    // settling: until the mean kinetic energy per particle is below 1e-4 of m g_eff d50
    let e_ref = 1e-4 * mtot * 9.81 * s.settling_gravity_factor * psd.d50_m;
    let t_end = s.max_settling_time_s;
    while p.t < t_end {
        for _ in 0..200 {
            step(&mut p, &planes, &mut hist, &mut on_wall);
            steps += 1;
        }
        let ke = p.kinetic_energy();
        progress("settling", p.t / t_end);
        if ke < e_ref && p.t > 10.0 * dt * 200.0 {
            break;
        }
    }
    // switch to real gravity and let the bed relax briefly
    p.gravity = g0;
    let relax_steps = (s.relax_time_s / dt).ceil() as u64;
    for _ in 0..relax_steps {
        step(&mut p, &planes, &mut hist, &mut on_wall);
        steps += 1;
    }
    let bed_top = p
        .pos
        .iter()
        .zip(&p.radius)
        .map(|(x, r)| x[2] + r)
        .fold(f64::NEG_INFINITY, f64::max);
    let area = lx * ly;
    let settled = p.volume() / (area * (bed_top - cavity.min[2]));
    let compressed = bed_top > cavity.max[2];
    // compression: plate from just above the bed down to the cavity top
    let mut plate_force = 0.0;
    if compressed {
        planes[5].point[2] = bed_top;
        planes[5].velocity = [0.0, 0.0, -s.plate_speed_m_s];
        let dist = bed_top - cavity.max[2];
        let nsteps = (dist / (s.plate_speed_m_s * dt)).ceil() as u64;
        let dz = dist / nsteps as f64;
        planes[5].velocity = [0.0, 0.0, -dz / dt];
        for q in 0..nsteps {
            planes[5].point[2] = bed_top - dz * (q + 1) as f64;
            step(&mut p, &planes, &mut hist, &mut on_wall);
            steps += 1;
            if q % 500 == 0 {
                progress("compressing", q as f64 / nsteps as f64);
            }
        }
    }
    planes[5].point[2] = cavity.max[2];
    planes[5].velocity = [0.0; 3];
    for q in 0..relax_steps {
        step(&mut p, &planes, &mut hist, &mut on_wall);
        plate_force = on_wall[5][2];
        steps += 1;
        if q % 500 == 0 {
            progress("relaxing", q as f64 / relax_steps as f64);
        }
    }
    for v in p.vel.iter_mut() {
        *v = [0.0; 3];
    }
    for w in p.omega.iter_mut() {
        *w = [0.0; 3];
    }
    for w in p.wall_force.iter_mut() {
        *w = [0.0; 3];
    }
    let rep = PrepReport {
        particles: n,
        settled_packing_density: settled,
        packing_density: p.volume() / vcav,
        compressed,
        plate_force_n: plate_force,
        max_relative_overlap: p.max_relative_overlap(),
        simulated_time_s: p.t,
        steps,
        wall_time_s: clock.elapsed().as_secs_f64(),
    };
    p.t = 0.0;
    p.ledger = Default::default();
    (p, rep)
}
