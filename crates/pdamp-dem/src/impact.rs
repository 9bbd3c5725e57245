//! A single head-on impact of a sphere on an identical sphere or on a rigid flat wall, simulated
//! with the full DEM pipeline and compared with Hertz impact theory
//! (contact time [D Eq. 4.8], maximum overlap [D Eq. 2.80]).

use crate::body::{BodyState, Motion, RigidBody};
use crate::contact::hertz;
use crate::contact::{ContactModel, FrictionLaw, NormalLaw};
use crate::material::{Material, effective_mass, effective_modulus, effective_radius};
use crate::math::Vec3;
use crate::walls::{Geometry, Plane};
use crate::world::World;
use serde::Serialize;

/// The impact partner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Partner {
    /// A rigid, immovable flat wall of the same material.
    Wall,
    /// An identical sphere (both move towards each other with half the impact velocity).
    Sphere,
}

/// Set-up of a head-on impact.
#[derive(Debug, Clone)]
pub struct ImpactSetup {
    /// Partner of the sphere.
    pub partner: Partner,
    /// Sphere radius, m.
    pub radius_m: f64,
    /// Material of sphere (and partner).
    pub material: Material,
    /// Normal contact law.
    pub normal: NormalLaw,
    /// Relative normal impact velocity, m/s.
    pub velocity_m_s: f64,
    /// Time steps per Hertz contact time (resolution), default 2000.
    pub steps_per_contact: f64,
}

/// Measured and theoretical quantities of the impact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ImpactResult {
    /// Coefficient of restitution: relative normal velocity after / before.
    pub restitution: f64,
    /// Duration of positive overlap, s.
    pub contact_time_s: f64,
    /// Largest normal contact force, N.
    pub max_force_n: f64,
    /// Largest overlap, m.
    pub max_overlap_m: f64,
    /// Hertz contact time [D Eq. 4.8], s.
    pub hertz_contact_time_s: f64,
    /// Hertz maximum overlap [D Eq. 2.80], m.
    pub hertz_max_overlap_m: f64,
    /// Hertz maximum force $k_n \delta_{max}^{3/2}$, N.
    pub hertz_max_force_n: f64,
}

/// Runs the impact and measures restitution, contact time, peak force and peak overlap.
pub fn head_on_impact(setup: &ImpactSetup) -> ImpactResult {
    let r = setup.radius_m;
    let v = setup.velocity_m_s;
    let mat = setup.material.clone();
    let m = 4.0 / 3.0 * std::f64::consts::PI * mat.density_kg_m3 * r.powi(3);
    let (r_eff, m_eff) = match setup.partner {
        Partner::Wall => (r, m),
        Partner::Sphere => (effective_radius(r, r), effective_mass(m, m)),
    };
    let e_eff = effective_modulus(&mat, &mat);
    let k_n = hertz::hertz_stiffness(e_eff, r_eff);
    let t_h = hertz::hertz_contact_time(e_eff, r_eff, m_eff, v);
    let d_h = hertz::hertz_max_overlap(k_n, m_eff, v);
    let model = ContactModel {
        normal: setup.normal.clone(),
        friction: FrictionLaw::Frictionless,
        rolling: None,
        adhesion: None,
    };
    let dt = t_h / setup.steps_per_contact.max(50.0);
    let mut w = World::new(vec![mat], model, dt);
    w.gravity_m_s2 = Vec3::zeros();
    let gap0 = 2.0 * v * dt; // touch after about two steps
    match setup.partner {
        Partner::Wall => {
            w.add_particle(Vec3::new(0.0, 0.0, r + gap0), r, 0);
            w.particles.velocity[0] = Vec3::new(0.0, 0.0, -v);
            w.add_body(
                RigidBody::new("wall", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
                    "wall",
                    Geometry::Plane(Plane::new(Vec3::zeros(), Vec3::z(), false)),
                    0,
                ),
            );
        }
        Partner::Sphere => {
            w.add_particle(Vec3::new(0.0, 0.0, r + 0.5 * gap0), r, 0);
            w.add_particle(Vec3::new(0.0, 0.0, -r - 0.5 * gap0), r, 0);
            w.particles.velocity[0] = Vec3::new(0.0, 0.0, -0.5 * v);
            w.particles.velocity[1] = Vec3::new(0.0, 0.0, 0.5 * v);
        }
    }
    w.set_skin(0.5 * r);
    let overlap = |w: &World| match setup.partner {
        Partner::Wall => r - w.particles.position[0].z,
        Partner::Sphere => 2.0 * r - (w.particles.position[0].z - w.particles.position[1].z),
    };
    let rel_vel = |w: &World| match setup.partner {
        Partner::Wall => w.particles.velocity[0].z,
        Partner::Sphere => w.particles.velocity[0].z - w.particles.velocity[1].z,
    };
    let (mut t_start, mut t_end) = (f64::NAN, f64::NAN);
    let (mut max_f, mut max_d) = (0.0f64, 0.0f64);
    let mut prev = (w.time_s, overlap(&w));
    let limit = 20.0 * t_h + 10.0 * dt;
    while w.time_s < limit {
        w.step();
        let d = overlap(&w);
        if d > 0.0 && prev.1 <= 0.0 && t_start.is_nan() {
            t_start = prev.0 + (w.time_s - prev.0) * (-prev.1) / (d - prev.1);
        }
        if d <= 0.0 && prev.1 > 0.0 && !t_start.is_nan() {
            t_end = prev.0 + (w.time_s - prev.0) * prev.1 / (prev.1 - d);
        }
        max_d = max_d.max(d);
        max_f = max_f.max(w.particles.force[0].z.abs());
        prev = (w.time_s, d);
        if !t_end.is_nan() && w.time_s > t_end + 2.0 * dt {
            break;
        }
    }
    ImpactResult {
        restitution: rel_vel(&w) / v,
        contact_time_s: t_end - t_start,
        max_force_n: max_f,
        max_overlap_m: max_d,
        hertz_contact_time_s: t_h,
        hertz_max_overlap_m: d_h,
        hertz_max_force_n: k_n * d_h.powf(1.5),
    }
}

/// Secant stiffness $F_{max}/\delta_{max}$ of the Hertz impact at `velocity_m_s`, N/m: a linear
/// spring of this stiffness gives a comparable contact time and overlap.
pub fn hertz_equivalent_linear_stiffness(
    partner: Partner,
    radius_m: f64,
    material: &Material,
    velocity_m_s: f64,
) -> f64 {
    let m = 4.0 / 3.0 * std::f64::consts::PI * material.density_kg_m3 * radius_m.powi(3);
    let (r_eff, m_eff) = match partner {
        Partner::Wall => (radius_m, m),
        Partner::Sphere => (effective_radius(radius_m, radius_m), effective_mass(m, m)),
    };
    let k_n = hertz::hertz_stiffness(effective_modulus(material, material), r_eff);
    let d = hertz::hertz_max_overlap(k_n, m_eff, velocity_m_s);
    k_n * d.sqrt()
}

/// Normal law of a checked single impact ([`ImpactRequest`]), by the names `pdamp impact
/// --law` and Python's `pdamp.impact(law=…)` take.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImpactLaw {
    /// Elastic Hertz [D Eq. 2.69, 2.70].
    Hertz,
    /// Gonthier et al. with a restitution [D Eq. 2.78, 2.79].
    Gonthier,
    /// Lankarani–Nikravesh with a restitution [D Eq. 2.77].
    LankaraniNikravesh,
    /// Linear spring–dashpot with a restitution [P Eq. (2)–(4)].
    Linear,
    /// Hertz–Mindlin with the LIGGGHTS damping of a restitution.
    HertzMindlin,
}

impl ImpactLaw {
    /// Every law with its name.
    pub const ALL: [(&'static str, ImpactLaw); 5] = [
        ("hertz", ImpactLaw::Hertz),
        ("gonthier", ImpactLaw::Gonthier),
        ("lankarani-nikravesh", ImpactLaw::LankaraniNikravesh),
        ("linear", ImpactLaw::Linear),
        ("hertz-mindlin", ImpactLaw::HertzMindlin),
    ];

    /// The law of a name (`hertz`, `gonthier`, `lankarani-nikravesh`, `linear`,
    /// `hertz-mindlin`; `_` for `-` accepted).
    pub fn from_name(name: &str) -> Option<Self> {
        let n = name.to_ascii_lowercase().replace('_', "-");
        Self::ALL.iter().find(|(k, _)| *k == n).map(|(_, l)| *l)
    }
}

/// A single head-on impact as a user asks for it: every input checked before the run, and a
/// result that resolves no contact refused ([`checked_head_on_impact`]).
#[derive(Debug, Clone)]
pub struct ImpactRequest {
    /// Partner of the sphere.
    pub partner: Partner,
    /// Sphere radius, m.
    pub radius_m: f64,
    /// Material of sphere and partner.
    pub material: Material,
    /// Normal law.
    pub law: ImpactLaw,
    /// Coefficient of restitution of the dissipative laws.
    pub restitution: f64,
    /// Stiffness of the linear law, N/m (default: the Hertz secant stiffness at the peak
    /// overlap, [`hertz_equivalent_linear_stiffness`]).
    pub stiffness_n_m: Option<f64>,
    /// Relative normal impact velocity, m/s.
    pub velocity_m_s: f64,
}

/// A bad input of an [`ImpactRequest`] or an impact that resolved no contact; `key` names the
/// input (`radius_m`, `velocity_m_s`, …; `result` for the outcome) so that the command line
/// can print its flag and Python its keyword.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactError {
    /// The input at fault (or `result`).
    pub key: &'static str,
    /// What is wrong, without the key.
    pub message: String,
}

impl std::fmt::Display for ImpactError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key == "result" || self.key == "material" {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{} {}", self.key, self.message)
        }
    }
}

impl std::error::Error for ImpactError {}

/// Checks `req`, runs the impact (2 000 steps per Hertz contact time) and checks that a contact
/// was resolved (every number finite, ε in [0, 1]).
pub fn checked_head_on_impact(req: &ImpactRequest) -> Result<ImpactResult, ImpactError> {
    let bad = |key, message: String| Err(ImpactError { key, message });
    if let Err(m) = req.material.validate() {
        return bad("material", m.to_string());
    }
    if !(req.radius_m > 0.0 && req.radius_m <= 1.0) {
        return bad(
            "radius_m",
            format!("must lie in (0, 1] m, got {}; check the unit", req.radius_m),
        );
    }
    if !(req.velocity_m_s > 0.0 && req.velocity_m_s <= 1000.0) {
        return bad(
            "velocity_m_s",
            format!("must lie in (0, 1000] m/s, got {}", req.velocity_m_s),
        );
    }
    if !(req.restitution > 0.0 && req.restitution <= 1.0) {
        return bad(
            "restitution",
            format!("must lie in (0, 1], got {}", req.restitution),
        );
    }
    if let Some(k) = req.stiffness_n_m
        && !(k.is_finite() && k > 0.0)
    {
        return bad(
            "stiffness_n_m",
            format!("must be a finite stiffness > 0 N/m, got {k}"),
        );
    }
    let restitution = req.restitution;
    let normal = match req.law {
        ImpactLaw::Hertz => NormalLaw::Hertz,
        ImpactLaw::Gonthier => NormalLaw::Gonthier {
            restitution,
            min_impact_velocity_m_s: 1e-3,
        },
        ImpactLaw::LankaraniNikravesh => NormalLaw::LankaraniNikravesh {
            restitution,
            min_impact_velocity_m_s: 1e-3,
        },
        ImpactLaw::HertzMindlin => NormalLaw::HertzMindlin {
            restitution,
            clip_attractive: false,
        },
        ImpactLaw::Linear => NormalLaw::Linear {
            stiffness_n_m: req.stiffness_n_m.unwrap_or_else(|| {
                hertz_equivalent_linear_stiffness(
                    req.partner,
                    req.radius_m,
                    &req.material,
                    req.velocity_m_s,
                )
            }),
            restitution,
            clip_attractive: false,
        },
    };
    let model = ContactModel {
        normal: normal.clone(),
        friction: Default::default(),
        rolling: None,
        adhesion: None,
    };
    if let Err(m) = model.validate() {
        return bad("law", m.to_string());
    }
    let r = head_on_impact(&ImpactSetup {
        partner: req.partner,
        radius_m: req.radius_m,
        material: req.material.clone(),
        normal,
        velocity_m_s: req.velocity_m_s,
        steps_per_contact: 2000.0,
    });
    let fields = [
        ("restitution", r.restitution),
        ("contact_time_s", r.contact_time_s),
        ("max_force_n", r.max_force_n),
        ("max_overlap_m", r.max_overlap_m),
        ("hertz_contact_time_s", r.hertz_contact_time_s),
        ("hertz_max_overlap_m", r.hertz_max_overlap_m),
        ("hertz_max_force_n", r.hertz_max_force_n),
    ];
    if let Some((name, x)) = fields.iter().find(|(_, x)| !x.is_finite()) {
        return bad(
            "result",
            format!(
                "the impact gave {name} = {x}: no contact was resolved for these inputs; check the radius, the material data and the velocity"
            ),
        );
    }
    if !(0.0..=1.0 + 1e-6).contains(&r.restitution) {
        return bad(
            "result",
            format!(
                "the impact gave ε = {}, outside [0, 1]: the contact was not resolved (time step or stiffness out of range for these inputs)",
                r.restitution
            ),
        );
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel(law: ImpactLaw, velocity_m_s: f64) -> ImpactRequest {
        ImpactRequest {
            partner: Partner::Wall,
            radius_m: 1e-3,
            material: Material::new("steel", 7850.0, 2.1e11, 0.3),
            law,
            restitution: 0.8,
            stiffness_n_m: None,
            velocity_m_s,
        }
    }

    /// Gonthier's law reproduces its ε [D Eq. 2.79] to 1e-6; elastic Hertz its contact time
    /// [D Eq. 4.8] to 3 % and its peak overlap [D Eq. 2.80] to 1e-3.
    #[test]
    fn checked_impact_reproduces_the_closed_forms() {
        let g = checked_head_on_impact(&steel(ImpactLaw::Gonthier, 0.5)).unwrap();
        assert!((g.restitution - 0.8).abs() < 1e-6, "{g:?}");
        let h = checked_head_on_impact(&steel(ImpactLaw::Hertz, 0.5)).unwrap();
        assert!((h.restitution - 1.0).abs() < 1e-6, "{h:?}");
        assert!((h.contact_time_s / h.hertz_contact_time_s - 1.0).abs() < 0.03);
        assert!((h.max_overlap_m / h.hertz_max_overlap_m - 1.0).abs() < 1e-3);
    }

    /// Every bad input is refused before the run, with the input named.
    #[test]
    fn checked_impact_names_the_bad_input() {
        let key = |r: ImpactRequest| checked_head_on_impact(&r).unwrap_err().key;
        assert_eq!(key(steel(ImpactLaw::Hertz, -1.0)), "velocity_m_s");
        assert_eq!(key(steel(ImpactLaw::Hertz, 2000.0)), "velocity_m_s");
        let mut r = steel(ImpactLaw::Hertz, 0.5);
        r.radius_m = 2.0;
        assert_eq!(key(r), "radius_m");
        let mut r = steel(ImpactLaw::Gonthier, 0.5);
        r.restitution = 0.0;
        assert_eq!(key(r), "restitution");
        let mut r = steel(ImpactLaw::Linear, 0.5);
        r.stiffness_n_m = Some(f64::NAN);
        assert_eq!(key(r), "stiffness_n_m");
        let mut r = steel(ImpactLaw::Hertz, 0.5);
        r.material.youngs_modulus_pa = -1.0;
        assert_eq!(key(r), "material");
        let e = checked_head_on_impact(&steel(ImpactLaw::Hertz, -1.0)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "velocity_m_s must lie in (0, 1000] m/s, got -1"
        );
        assert_eq!(
            ImpactLaw::from_name("Lankarani_Nikravesh"),
            Some(ImpactLaw::LankaraniNikravesh)
        );
        assert_eq!(ImpactLaw::from_name("hooke"), None);
    }
}
