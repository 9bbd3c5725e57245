//! The particle set: spherical particles stored as structure of arrays [D Eq. 2.1–2.3].

use crate::math::Vec3;

/// All particles of a simulation, one entry per particle in every column (structure of arrays).
///
/// Inertia of a sphere: $I = \tfrac25 m r^2$ [D Sect. 2, after Eq. 2.2].
#[derive(Debug, Clone, Default)]
pub struct ParticleSet {
    /// Centre positions, m.
    pub position: Vec<Vec3>,
    /// Translational velocities, m/s.
    pub velocity: Vec<Vec3>,
    /// Angular velocities, rad/s.
    pub angular_velocity: Vec<Vec3>,
    /// Applied force of the last evaluation (contacts + gravity + external), N.
    pub force: Vec<Vec3>,
    /// Applied torque of the last evaluation, N·m.
    pub torque: Vec<Vec3>,
    /// External force added every step (e.g. from a coupled solver), N.
    pub external_force: Vec<Vec3>,
    /// Radii, m.
    pub radius: Vec<f64>,
    /// Masses, kg.
    pub mass: Vec<f64>,
    /// Inverse moments of inertia $1/I$, 1/(kg·m²).
    pub inv_inertia: Vec<f64>,
    /// Material index into the world's material table.
    pub material: Vec<u16>,
    /// Stable identifier of each particle (survives reordering).
    pub id: Vec<u32>,
}

impl ParticleSet {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Adds a particle at rest; `density_kg_m3` gives its mass. Returns its index.
    pub fn push(
        &mut self,
        position: Vec3,
        radius: f64,
        density_kg_m3: f64,
        material: u16,
    ) -> usize {
        let mass = 4.0 / 3.0 * std::f64::consts::PI * density_kg_m3 * radius.powi(3);
        let inertia = 0.4 * mass * radius * radius;
        let idx = self.len();
        self.position.push(position);
        self.velocity.push(Vec3::zeros());
        self.angular_velocity.push(Vec3::zeros());
        self.force.push(Vec3::zeros());
        self.torque.push(Vec3::zeros());
        self.external_force.push(Vec3::zeros());
        self.radius.push(radius);
        self.mass.push(mass);
        self.inv_inertia.push(1.0 / inertia);
        self.material.push(material);
        self.id.push(idx as u32);
        idx
    }

    /// Moment of inertia of particle `i`, kg·m².
    pub fn inertia(&self, i: usize) -> f64 {
        1.0 / self.inv_inertia[i]
    }

    /// Largest radius, m (0 when empty).
    pub fn max_radius(&self) -> f64 {
        self.radius.iter().cloned().fold(0.0, f64::max)
    }

    /// Smallest radius, m (∞ when empty).
    pub fn min_radius(&self) -> f64 {
        self.radius.iter().cloned().fold(f64::INFINITY, f64::min)
    }

    /// Total mass, kg.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Translational + rotational kinetic energy, J.
    pub fn kinetic_energy(&self) -> f64 {
        (0..self.len())
            .map(|i| {
                0.5 * self.mass[i] * self.velocity[i].norm_squared()
                    + 0.5 * self.angular_velocity[i].norm_squared() / self.inv_inertia[i]
            })
            .sum()
    }

    /// Potential energy in the gravity field `g` (zero at the origin), J: $-\sum m_i\, g\cdot x_i$.
    pub fn potential_energy(&self, gravity: &Vec3) -> f64 {
        -(0..self.len())
            .map(|i| self.mass[i] * gravity.dot(&self.position[i]))
            .sum::<f64>()
    }

    /// Centre of mass, m.
    pub fn center_of_mass(&self) -> Vec3 {
        let m = self.total_mass();
        (0..self.len())
            .map(|i| self.position[i] * self.mass[i])
            .sum::<Vec3>()
            / m
    }
}
