use super::contacts::SlabState;
use super::pair_pass::{HmBatch, PairEval, evaluate_pair};
use super::*;
use crate::contact::{ContactModel, FrictionLaw, NormalLaw};
use crate::interaction::InteractionTable;
use crate::material::Material;
use crate::particles::ParticleSet;
use rand::{RngExt, SeedableRng};

/// One contact through the block kernel ([`HmBatch`] with the baseline kernel): the
/// outputs of the first partner, dissipation and stored energy, like `evaluate_pair`.
fn block_one(
    hm: &crate::interaction::HmConstants,
    radii: (f64, f64),
    kin: (&Kin, &Kin),
    d: Vec3,
    st: &mut PairState,
    dt: f64,
) -> (PairEval, f64, f64, f64) {
    let mut slab = vec![SlabState { state: *st }];
    let mut batch = HmBatch::default();
    batch.push(hm, (0, 1), radii, kin, d, st, 0);
    let (mut rf, mut rt) = (vec![Vec3::zeros(); 2], vec![Vec3::zeros(); 2]);
    let mut sums = (0.0, 0.0, 0.0);
    let kernel = crate::hm_block::Kernel::SCALAR;
    let mut acc = BlockAcc {
        lo: 0,
        hi: 2,
        force: &mut rf,
        torque: &mut rt,
        cross: &mut [],
    };
    batch.flush(kernel, dt, &mut slab, &mut acc, &mut sums);
    *st = slab[0].state;
    let eval = PairEval {
        force: rf[0],
        torque_first: rt[0],
        torque_second: rt[1],
    };
    assert_eq!(-rf[1], rf[0]);
    (eval, sums.0, sums.1, sums.2)
}

/// The block Hertz–Mindlin kernel gives the forces, torques, history, dissipation and
/// stored energy of the general pipeline (kinematics + `ContactModel::evaluate` + ledger)
/// within 1e-12 relative, over sequences of random sticking and sliding contacts, for
/// unequal sizes and materials.
#[test]
fn block_hertz_mindlin_equals_general_pipeline() {
    let mats = vec![
        Material::new("steel", 7850.0, 2.1e11, 0.3),
        Material::new("glass", 2500.0, 6.3e10, 0.22),
    ];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for (e, mu) in [(0.7, 0.3), (0.3, 0.05), (0.95, 1.0)] {
        let model = ContactModel {
            normal: NormalLaw::HertzMindlin {
                restitution: e,
                clip_attractive: false,
            },
            friction: FrictionLaw::Mindlin {
                friction_coefficient: mu,
            },
            rolling: None,
            adhesion: None,
        };
        let table = InteractionTable::new(&mats, model);
        let mut p = ParticleSet::default();
        p.push(Vec3::zeros(), 1e-3, 7850.0, 0);
        p.push(Vec3::new(1.9e-3, 0.1e-3, -0.05e-3), 0.8e-3, 2500.0, 1);
        let hm = *table.hm_fast(0, 1).expect("fast path applies");
        let (mut s_fast, mut s_gen) = (PairState::default(), PairState::default());
        let dt = 1e-7;
        let scale = |a: f64, b: f64| a.abs().max(b.abs()).max(1e-30);
        for _ in 0..200 {
            // Random walk of the relative motion (overlap stays positive).
            for k in 0..2 {
                p.velocity[k] = Vec3::new(
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                ) * 0.4;
                p.angular_velocity[k] = Vec3::new(
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                ) * 300.0;
            }
            let jitter = Vec3::new(
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
            ) * 2e-6;
            p.position[1] = Vec3::new(1.75e-3, 0.1e-3, -0.05e-3) + jitter;
            let d = p.position[0] - p.position[1];
            let dist = d.norm();
            assert!(dist < 1.8e-3);
            let (k0, k1) = (Kin::of(&p, 0), Kin::of(&p, 1));
            let radii = (p.radius[0], p.radius[1]);
            let (a, dn_a, dt_a, e_a) = block_one(&hm, radii, (&k0, &k1), d, &mut s_fast, dt);
            let (b, dn_b, dt_b, e_b) =
                evaluate_pair(&p, &table, 0, 1, d, dist, true, &mut s_gen, dt);
            for (x, y) in [
                (a.force, b.force),
                (a.torque_first, b.torque_first),
                (a.torque_second, b.torque_second),
                (s_fast.history.spring_m, s_gen.history.spring_m),
            ] {
                assert!(
                    (x - y).norm() <= 1e-12 * scale(x.norm(), y.norm()),
                    "{x} vs {y}"
                );
            }
            for (x, y) in [(dn_a, dn_b), (dt_a, dt_b), (e_a, e_b)] {
                assert!((x - y).abs() <= 1e-9 * scale(x, y) + 1e-24, "{x} vs {y}");
            }
            let (x, y) = (
                s_fast.history.impact_velocity_m_s,
                s_gen.history.impact_velocity_m_s,
            );
            assert!((x - y).abs() <= 1e-12 * scale(x, y), "{x} vs {y}");
        }
    }
}
