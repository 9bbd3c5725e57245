//! ε(v) curves: one impact model over many velocities (FE impacts in parallel with rayon), and
//! repeated impacts on the same spot.

use rayon::prelude::*;

use crate::fe::{FeImpact, FeOptions, ImpactResult, Partner, effective_pair};
use crate::hertz::{HertzPair, effective_modulus, sphere_mass};
use crate::material::{Material, MaterialModel};
use crate::thornton;
use crate::viscoelastic::{kk_impact, prony_kk_parameters};

/// Impact model of a curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CorModel {
    /// Axisymmetric dynamic FE ([`crate::fe`]).
    Fe(FeOptions),
    /// Elastic Hertz (ε = 1, contact time [D Eq. 4.8], force [D Eq. 2.80]).
    Hertz,
    /// Thornton (1997) with limiting pressure $p_y$ = factor × (smaller initial yield stress).
    Thornton {
        /// $p_y/\sigma_y$ (1.6: first yield, Johnson 1985).
        pressure_factor: f64,
    },
    /// Kuwabara–Kono viscoelastic Hertz ([`crate::viscoelastic`]).
    Viscoelastic,
}

/// One point of an ε(v) curve.
#[derive(Debug, Clone, PartialEq)]
pub struct CorPoint {
    /// Impact velocity, m/s.
    pub velocity_m_s: f64,
    /// Impact number on the same spot (1 = first impact).
    pub impact: usize,
    /// Coefficient of restitution.
    pub restitution: f64,
    /// Contact time, s (NaN where the model gives none).
    pub contact_time_s: f64,
    /// Maximum contact force, N.
    pub max_force_n: f64,
    /// The FE result (FE model only).
    pub fe: Option<ImpactResult>,
}

/// Elastic Hertz pair of the (long-term) elastic constants.
pub fn hertz_pair(sphere: &Material, partner: &Partner, radius: f64) -> HertzPair {
    let m = sphere_mass(radius, sphere.density_kg_m3);
    match partner {
        Partner::Wall(w) => HertzPair {
            e_eff: effective_modulus(
                sphere.youngs_modulus_pa,
                sphere.poisson_ratio,
                w.youngs_modulus_pa,
                w.poisson_ratio,
            ),
            r_eff: radius,
            m_eff: m,
        },
        Partner::Sphere => HertzPair {
            e_eff: effective_modulus(
                sphere.youngs_modulus_pa,
                sphere.poisson_ratio,
                sphere.youngs_modulus_pa,
                sphere.poisson_ratio,
            ),
            r_eff: 0.5 * radius,
            m_eff: 0.5 * m,
        },
    }
}

fn partner_material<'a>(sphere: &'a Material, partner: &'a Partner) -> &'a Material {
    match partner {
        Partner::Wall(w) => w,
        Partner::Sphere => sphere,
    }
}

/// One analytical point.
fn analytical(
    sphere: &Material,
    partner: &Partner,
    radius: f64,
    v: f64,
    model: CorModel,
) -> CorPoint {
    let pair = hertz_pair(sphere, partner, radius);
    let mut p = CorPoint {
        velocity_m_s: v,
        impact: 1,
        restitution: 1.0,
        contact_time_s: pair.contact_time(v),
        max_force_n: pair.max_force(v),
        fe: None,
    };
    match model {
        CorModel::Hertz | CorModel::Fe(_) => {}
        CorModel::Thornton { pressure_factor } => {
            let sy = sphere
                .initial_yield_stress()
                .min(partner_material(sphere, partner).initial_yield_stress());
            if sy.is_finite() {
                let p_y = pressure_factor * sy;
                let vy = thornton::yield_velocity(&pair, p_y);
                p.restitution = thornton::restitution(v, vy);
                if v > vy {
                    // loading: Hertz to δ_y, then F = F_y + π p_y R̄ (δ − δ_y) (Thornton 1997)
                    let dy = pair.max_overlap(vy);
                    let fy = pair.max_force(vy);
                    let w_rest = 0.5 * pair.m_eff * (v * v - vy * vy);
                    let c = std::f64::consts::PI * p_y * pair.r_eff;
                    // w_rest = F_y x + c x²/2
                    let x = (-fy + (fy * fy + 2.0 * c * w_rest).sqrt()) / c;
                    let _ = dy;
                    p.max_force_n = fy + c * x;
                    p.contact_time_s = f64::NAN;
                }
            }
        }
        CorModel::Viscoelastic => {
            let wall = partner_material(sphere, partner);
            let (prony_mat, other) =
                if matches!(wall.model, MaterialModel::ViscoelasticProny { .. }) {
                    (Some(wall), sphere)
                } else if matches!(sphere.model, MaterialModel::ViscoelasticProny { .. }) {
                    (Some(sphere), wall)
                } else {
                    (None, sphere)
                };
            let (pair, a) = match prony_mat {
                Some(pm) => {
                    let MaterialModel::ViscoelasticProny { prony, .. } = &pm.model else {
                        unreachable!()
                    };
                    let rigid = matches!(partner, Partner::Sphere);
                    let other_c = if rigid && std::ptr::eq(pm, sphere) {
                        (1.0 - pm.poisson_ratio.powi(2)) / pm.youngs_modulus_pa // same body
                    } else {
                        (1.0 - other.poisson_ratio.powi(2)) / other.youngs_modulus_pa
                    };
                    prony_kk_parameters(
                        &pair,
                        pm.instantaneous_shear_modulus(),
                        prony,
                        pm.poisson_ratio,
                        other_c,
                        v,
                    )
                }
                None => (
                    pair,
                    sphere.kk_dissipation_time_s.unwrap_or(0.0)
                        + wall.kk_dissipation_time_s.unwrap_or(0.0),
                ),
            };
            let r = kk_impact(&pair, a, v);
            p.restitution = r.restitution;
            p.contact_time_s = r.contact_time_s;
            p.max_force_n = r.max_force_n;
        }
    }
    p
}

/// ε(v) of `model` for each velocity (m/s); with `repeat` > 1 each velocity is followed by
/// repeated impacts on the same spot (FE: material state carried over; analytical models are
/// history-free and repeat the first value). FE velocities run in parallel (rayon). Returns
/// the points ordered by velocity, then impact number.
pub fn cor_curve(
    sphere: &Material,
    partner: &Partner,
    radius: f64,
    velocities: &[f64],
    model: CorModel,
    repeat: usize,
) -> Vec<CorPoint> {
    cor_curve_with(
        sphere,
        partner,
        radius,
        velocities,
        model,
        repeat,
        &|_, _| {},
    )
}

/// [`cor_curve`] calling `on_impact(done, total)` after every impact (from the worker threads).
pub fn cor_curve_with(
    sphere: &Material,
    partner: &Partner,
    radius: f64,
    velocities: &[f64],
    model: CorModel,
    repeat: usize,
    on_impact: &(dyn Fn(usize, usize) + Sync),
) -> Vec<CorPoint> {
    let repeat = repeat.max(1);
    let total = velocities.len() * repeat;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let tick = || {
        on_impact(
            done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
            total,
        )
    };
    let per_v: Vec<Vec<CorPoint>> = velocities
        .par_iter()
        .map(|&v| match model {
            CorModel::Fe(opts) => {
                let mut fe = FeImpact::new(sphere, partner, radius, v, &opts);
                (1..=repeat)
                    .map(|k| {
                        let r = fe.run(v);
                        tick();
                        CorPoint {
                            velocity_m_s: v,
                            impact: k,
                            restitution: r.restitution,
                            contact_time_s: r.contact_time_s,
                            max_force_n: r.max_force_n,
                            fe: Some(r),
                        }
                    })
                    .collect()
            }
            _ => (1..=repeat)
                .map(|k| {
                    tick();
                    CorPoint {
                        impact: k,
                        ..analytical(sphere, partner, radius, v, model)
                    }
                })
                .collect(),
        })
        .collect();
    let _ = effective_pair;
    per_v.into_iter().flatten().collect()
}

/// Most impact velocities of one checked ε(v) curve ([`checked_cor_curve`]).
pub const MAX_VELOCITIES: usize = 1000;
/// Most repeated impacts per velocity of one checked ε(v) curve.
pub const MAX_REPEAT: usize = 100;

/// A bad input of [`checked_cor_curve`] or an impact outside its model's range; `key` names
/// the input (`sphere_radius_m`, `velocities_m_s`, `repeat`, `thornton_pressure_factor`;
/// `result` for the outcome) so that the command line prints its flag and Python its keyword.
#[derive(Debug, Clone, PartialEq)]
pub struct CorError {
    /// The input at fault (or `result`).
    pub key: &'static str,
    /// What is wrong, without the key.
    pub message: String,
}

impl std::fmt::Display for CorError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key == "result" {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{} {}", self.key, self.message)
        }
    }
}

impl std::error::Error for CorError {}

/// [`cor_curve_with`] as a user asks for it (`pdamp cor`, Python `pdamp.cor`): the inputs
/// checked first (radius in (0, 1] m, velocities in (0, 1000] m/s, at most [`MAX_VELOCITIES`],
/// `repeat` in 1..=[`MAX_REPEAT`], Thornton's p_y/σ_y in [1, 10]), the velocities sorted and
/// deduplicated, and afterwards a failed FE impact or an ε outside [0, 1] (a model outside its
/// range) refused with the velocity and impact named.
pub fn checked_cor_curve(
    sphere: &Material,
    partner: &Partner,
    radius_m: f64,
    velocities_m_s: &[f64],
    model: CorModel,
    repeat: usize,
    on_impact: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<CorPoint>, CorError> {
    let bad = |key, message: String| Err(CorError { key, message });
    let vs = check_cor_request(radius_m, velocities_m_s, model, repeat)?;
    let pts = cor_curve_with(sphere, partner, radius_m, &vs, model, repeat, on_impact);
    if let Some((p, why)) = pts.iter().find_map(|p| {
        p.fe.as_ref()
            .and_then(|r| r.failure.as_ref())
            .map(|w| (p, w))
    }) {
        return bad(
            "result",
            format!(
                "FE impact at v = {} m/s (impact {}) failed: {why}",
                p.velocity_m_s, p.impact
            ),
        );
    }
    // Thornton's closed form gives no contact time (NaN, written as such); every other model
    // does.
    let no_contact_time = matches!(model, CorModel::Thornton { .. });
    if let Some(p) = pts.iter().find(|p| {
        !(p.restitution.is_finite()
            && (0.0..=1.0 + 1e-9).contains(&p.restitution)
            && (p.contact_time_s.is_finite() || no_contact_time && p.contact_time_s.is_nan())
            && p.max_force_n.is_finite())
    }) {
        return bad(
            "result",
            format!(
                "the impact model gave ε = {}, contact time {} s, peak force {} N at v = {} m/s (impact {}): outside its range of validity for this sphere and these materials; check the sphere radius, the velocities and the material data",
                p.restitution, p.contact_time_s, p.max_force_n, p.velocity_m_s, p.impact
            ),
        );
    }
    Ok(pts)
}

/// The input checks of [`checked_cor_curve`], for callers that check before they open their
/// outputs; returns the velocities sorted and deduplicated.
pub fn check_cor_request(
    radius_m: f64,
    velocities_m_s: &[f64],
    model: CorModel,
    repeat: usize,
) -> Result<Vec<f64>, CorError> {
    let bad = |key, message: String| Err(CorError { key, message });
    if !(radius_m > 0.0 && radius_m <= 1.0) {
        return bad(
            "sphere_radius_m",
            format!("must lie in (0, 1] m, got {radius_m}; check the unit"),
        );
    }
    if let Some(v) = velocities_m_s
        .iter()
        .find(|v| !(**v > 0.0 && **v <= 1000.0))
    {
        return bad(
            "velocities_m_s",
            format!(
                "must all lie in (0, 1000] m/s (the models are quasi-static: far below the speed of sound), got {v}"
            ),
        );
    }
    if velocities_m_s.is_empty() || velocities_m_s.len() > MAX_VELOCITIES {
        return bad(
            "velocities_m_s",
            format!(
                "{} velocities, give 1 to {MAX_VELOCITIES}",
                velocities_m_s.len()
            ),
        );
    }
    if !(1..=MAX_REPEAT).contains(&repeat) {
        return bad(
            "repeat",
            format!("must lie in 1..={MAX_REPEAT}, got {repeat}"),
        );
    }
    if let CorModel::Thornton { pressure_factor } = model
        && !(pressure_factor.is_finite() && (1.0..=10.0).contains(&pressure_factor))
    {
        return bad(
            "thornton_pressure_factor",
            format!("must lie in [1, 10] (p_y/σ_y; 1.6 = first yield), got {pressure_factor}"),
        );
    }
    let mut vs = velocities_m_s.to_vec();
    vs.sort_by(f64::total_cmp);
    vs.dedup();
    Ok(vs)
}

#[cfg(test)]
mod checked_tests {
    use super::*;
    use crate::material::MaterialSet;

    fn s235() -> Material {
        MaterialSet::builtins().get("s235").unwrap()
    }

    /// Inputs are checked and named; velocities come back sorted and deduplicated; Thornton's
    /// curve is accepted with its NaN contact time; elastic Hertz gives ε = 1.
    #[test]
    fn checked_cor_curve_checks_and_names() {
        let wall = Partner::Wall(s235());
        let key = |r, v: &[f64], m, n| check_cor_request(r, v, m, n).unwrap_err().key;
        assert_eq!(key(2.0, &[0.5], CorModel::Hertz, 1), "sphere_radius_m");
        assert_eq!(
            key(0.003, &[0.5, -1.0], CorModel::Hertz, 1),
            "velocities_m_s"
        );
        assert_eq!(key(0.003, &[], CorModel::Hertz, 1), "velocities_m_s");
        assert_eq!(key(0.003, &[0.5], CorModel::Hertz, 0), "repeat");
        let th = |pressure_factor| CorModel::Thornton { pressure_factor };
        assert_eq!(key(0.003, &[0.5], th(0.5), 1), "thornton_pressure_factor");
        let vs = check_cor_request(0.003, &[1.0, 0.1, 1.0], CorModel::Hertz, 1).unwrap();
        assert_eq!(vs, vec![0.1, 1.0]);
        let pts = checked_cor_curve(&s235(), &wall, 0.003, &[0.5], th(1.6), 1, &|_, _| {}).unwrap();
        assert!(pts[0].contact_time_s.is_nan() && (0.0..1.0).contains(&pts[0].restitution));
        let h = checked_cor_curve(
            &s235(),
            &wall,
            0.003,
            &[0.1, 1.0],
            CorModel::Hertz,
            1,
            &|_, _| {},
        )
        .unwrap();
        assert!(
            h.iter()
                .all(|p| p.restitution == 1.0 && p.contact_time_s > 0.0)
        );
    }
}
