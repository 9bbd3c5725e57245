//! What a contact carries from step to step (its law's history, previous forces and stored
//! energies for the trapezoidal work integral), the wall-contact slot of a particle, the packed
//! kinematics of a particle, and the work bookkeeping of one contact evaluation.

use crate::contact::{ContactForce, ContactHistory};
use crate::math::Vec3;
use rayon::prelude::*;

/// State of one contact carried from step to step: the law's history plus the forces and stored
/// energies of the previous evaluation (for trapezoidal work integration).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairState {
    /// History owned by the contact law.
    pub history: ContactHistory,
    /// Normal force on the first partner at the previous evaluation, N.
    pub normal_force_prev: Vec3,
    /// Tangential force on the first partner at the previous evaluation, N.
    pub tangential_force_prev: Vec3,
    /// Rolling torque on the first partner at the previous evaluation, N·m.
    pub rolling_torque_prev: Vec3,
    /// Stored normal energy at the previous evaluation, J.
    pub normal_energy_prev: f64,
    /// Stored tangential energy at the previous evaluation, J.
    pub tangential_energy_prev: f64,
    /// The partners interacted at the previous evaluation.
    pub active: bool,
}

/// A particle–wall contact slot of one particle.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallSlot {
    /// Body index.
    pub body: u16,
    /// Wall index within the body.
    pub wall: u16,
    /// Feature of the wall geometry.
    pub feature: u32,
    /// Contact normal (world frame) at the last evaluation.
    pub normal: Vec3,
    /// Contact point (world frame) at the last evaluation, m.
    pub point: Vec3,
    /// Force on the particle at the last evaluation, N.
    pub force: Vec3,
    /// Rolling torque on the particle at the last evaluation, N·m.
    pub rolling_torque: Vec3,
    /// Contact state.
    pub state: PairState,
}

/// Work bookkeeping of one contact evaluation; returns (dissipated normal, dissipated tangential).
#[inline]
#[allow(clippy::too_many_arguments)]
pub(super) fn account(
    st: &mut PairState,
    f: &ContactForce,
    fn_vec: Vec3,
    ft: Vec3,
    v_rel: &Vec3,
    w_rel: &Vec3,
    dt: f64,
    active: bool,
) -> (f64, f64) {
    let w_n = -0.5 * (st.normal_force_prev + fn_vec).dot(v_rel) * dt;
    let w_t = -0.5 * (st.tangential_force_prev + ft).dot(v_rel) * dt
        - 0.5 * (st.rolling_torque_prev + f.rolling_torque_nm).dot(w_rel) * dt;
    let d_n = w_n - (f.normal_energy_j - st.normal_energy_prev);
    let d_t = w_t - (f.tangential_energy_j - st.tangential_energy_prev);
    st.normal_force_prev = fn_vec;
    st.tangential_force_prev = ft;
    st.rolling_torque_prev = f.rolling_torque_nm;
    st.normal_energy_prev = f.normal_energy_j;
    st.tangential_energy_prev = f.tangential_energy_j;
    st.active = active;
    (d_n, d_t)
}

pub(super) const CHUNK: usize = 1024;

/// Marks a neighbour pair without an active contact in `pair_contact`.
pub(crate) const NO_CONTACT: u32 = u32::MAX;

/// Particles per chunk of the particle–particle pass.
pub(crate) const PP_CHUNK: usize = 256;

/// Velocity, mass and angular velocity of one particle, packed into one cache line for the
/// contact laws of the pair loop (scratch, refreshed every evaluation).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub(crate) struct Kin {
    pub(super) v: [f64; 3],
    pub(super) m: f64,
    pub(super) w: [f64; 3],
    pub(super) _pad: f64,
}

impl Kin {
    /// Packs velocity `v`, mass `m` and angular velocity `w`.
    #[inline]
    pub(crate) fn new(v: &Vec3, m: f64, w: &Vec3) -> Self {
        Kin {
            v: [v.x, v.y, v.z],
            m,
            w: [w.x, w.y, w.z],
            _pad: 0.0,
        }
    }

    /// The packed state of particle `i`.
    #[inline]
    pub(super) fn of(p: &crate::particles::ParticleSet, i: usize) -> Self {
        let (u, w) = (p.velocity[i], p.angular_velocity[i]);
        Kin {
            v: [u.x, u.y, u.z],
            m: p.mass[i],
            w: [w.x, w.y, w.z],
            _pad: 0.0,
        }
    }
}

/// Packs positions with radii (`xr`) and velocities, masses and spins (`kin`) of the particles:
/// one load, one cache line per contact partner in the pair loop. Both slices hold `p.len()`.
pub(super) fn pack_kinematics(
    p: &crate::particles::ParticleSet,
    xr: &mut [[f64; 4]],
    kin: &mut [Kin],
) {
    xr.par_chunks_mut(CHUNK)
        .zip(kin.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(c, (out, kout))| {
            for (k, (v, kv)) in out.iter_mut().zip(kout.iter_mut()).enumerate() {
                let i = c * CHUNK + k;
                let x = p.position[i];
                *v = [x.x, x.y, x.z, p.radius[i]];
                *kv = Kin::of(p, i);
            }
        });
}
