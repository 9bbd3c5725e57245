//! Particle–wall contacts with the powder law ($r_{eff} = r_i$, $m_{eff} = m_i$): rigid planes
//! (the preparation box and the compression plate) and a per-particle history store keyed by
//! wall or surface-element id.

use super::law::{self, ContactResult};
use super::powder::Powder;

/// History slots of one particle: (wall id, tangential spring); id `u32::MAX` = free.
pub type WallSlots = [(u32, [f64; 3]); 4];

/// Empty slots.
pub const EMPTY_SLOTS: WallSlots = [(u32::MAX, [0.0; 3]); 4];

/// Tangential spring stored for `id` (zero if none).
#[inline]
pub fn slot_get(s: &WallSlots, id: u32) -> [f64; 3] {
    s.iter().find(|x| x.0 == id).map_or([0.0; 3], |x| x.1)
}

/// Stores the spring for `id` (replacing the entry of `id`, else the first free slot; silently
/// drops history if all four are in use).
#[inline]
pub fn slot_put(s: &mut WallSlots, id: u32, g: [f64; 3]) {
    if let Some(x) = s.iter_mut().find(|x| x.0 == id) {
        x.1 = g;
    } else if let Some(x) = s.iter_mut().find(|x| x.0 == u32::MAX) {
        *x = (id, g);
    }
}

/// A rigid plane: points `x` with $(\mathbf x-\mathbf p)\cdot\mathbf n \ge 0$ are inside.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlaneWall {
    /// A point on the plane \[m\].
    pub point: [f64; 3],
    /// Unit normal pointing into the particle domain.
    pub normal: [f64; 3],
    /// Translational velocity [m/s].
    pub velocity: [f64; 3],
}

/// Contact of particle `i` with a wall point: `n` unit normal from the particle centre towards
/// the wall, `gap` surface gap \[m\], `v_wall` wall velocity [m/s]. Returns the result and the
/// torque on the particle.
#[inline]
pub fn particle_wall(
    p: &Powder,
    i: usize,
    n: [f64; 3],
    gap: f64,
    v_wall: [f64; 3],
    gt: &mut [f64; 3],
) -> (ContactResult, [f64; 3]) {
    let vs = p.surface_velocity(i, n);
    let vrel = [vs[0] - v_wall[0], vs[1] - v_wall[1], vs[2] - v_wall[2]];
    let r = law::evaluate(&p.law, n, gap, vrel, p.radius[i], p.mass[i], gt, p.dt);
    let ri = p.radius[i];
    let a = [ri * n[0], ri * n[1], ri * n[2]];
    let f = r.force;
    let t = [
        a[1] * f[2] - a[2] * f[1],
        a[2] * f[0] - a[0] * f[2],
        a[0] * f[1] - a[1] * f[0],
    ];
    (r, t)
}

/// Writes the forces of the rigid `planes` into `p.wall_force`/`p.wall_torque` (overwriting) and
/// books the dissipation; `on_wall[w]` receives the total force the particles exert on plane `w`
/// \[N\] (no allocation per step).
///
/// # Panics
/// If `on_wall` is shorter than `planes`.
pub fn plane_forces(
    p: &mut Powder,
    planes: &[PlaneWall],
    hist: &mut [WallSlots],
    on_wall: &mut [[f64; 3]],
) {
    on_wall[..planes.len()]
        .iter_mut()
        .for_each(|f| *f = [0.0; 3]);
    let range = p
        .law
        .adhesion_range(p.radius.iter().fold(0.0f64, |m, &r| m.max(r)));
    let mut diss = 0.0;
    for i in 0..p.len() {
        let mut f = [0.0; 3];
        let mut t = [0.0; 3];
        for (w, pl) in planes.iter().enumerate() {
            let x = p.pos[i];
            let dist = (x[0] - pl.point[0]) * pl.normal[0]
                + (x[1] - pl.point[1]) * pl.normal[1]
                + (x[2] - pl.point[2]) * pl.normal[2];
            let gap = dist - p.radius[i];
            let id = w as u32;
            if gap > range || (gap > 0.0 && range == 0.0) {
                if slot_get(&hist[i], id) != [0.0; 3] {
                    slot_put(&mut hist[i], id, [0.0; 3]);
                    if let Some(s) = hist[i].iter_mut().find(|s| s.0 == id) {
                        s.0 = u32::MAX;
                    }
                }
                continue;
            }
            let n = [-pl.normal[0], -pl.normal[1], -pl.normal[2]];
            let mut gt = slot_get(&hist[i], id);
            let (r, tq) = particle_wall(p, i, n, gap, pl.velocity, &mut gt);
            slot_put(&mut hist[i], id, gt);
            for k in 0..3 {
                f[k] += r.force[k];
                t[k] += tq[k];
                on_wall[w][k] -= r.force[k];
            }
            diss += r.dissipated_j;
        }
        p.wall_force[i] = f;
        p.wall_torque[i] = t;
    }
    p.ledger.dissipated_pw_j += diss;
}
