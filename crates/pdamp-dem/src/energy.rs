//! The energy ledger: where the energy of the granular system is and where it went.
//!
//! Work of contact forces is integrated per contact with the trapezoidal rule over each step,
//! $W = \tfrac12 (F^{n} + F^{n+1}) \cdot \Delta s$, which is exactly the work velocity Verlet
//! attributes to the particles; dissipation is the work absorbed by a contact minus the change
//! of the elastic energy it stores. The balance
//! $W_{wall} + W_{ext} = \Delta E_{kin} + \Delta E_{pot} + \Delta E_{el} + D$ therefore closes up
//! to the integrator's own (second-order) error.

use serde::{Deserialize, Serialize};

/// Energy increments of one force evaluation, J.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnergyIncrements {
    /// Work done on the particles by moving walls.
    pub wall_work_j: f64,
    /// Work done by external forces.
    pub external_work_j: f64,
    /// Dissipated in normal direction, particle–particle.
    pub dissipated_normal_pp_j: f64,
    /// Dissipated in normal direction, particle–wall.
    pub dissipated_normal_pw_j: f64,
    /// Dissipated tangentially (friction, rolling), particle–particle.
    pub dissipated_tangential_pp_j: f64,
    /// Dissipated tangentially (friction, rolling), particle–wall.
    pub dissipated_tangential_pw_j: f64,
    /// Elastic energy stored in all contacts at the end of the evaluation (a state, not an increment).
    pub elastic_j: f64,
}

impl std::ops::AddAssign for EnergyIncrements {
    fn add_assign(&mut self, o: Self) {
        self.wall_work_j += o.wall_work_j;
        self.external_work_j += o.external_work_j;
        self.dissipated_normal_pp_j += o.dissipated_normal_pp_j;
        self.dissipated_normal_pw_j += o.dissipated_normal_pw_j;
        self.dissipated_tangential_pp_j += o.dissipated_tangential_pp_j;
        self.dissipated_tangential_pw_j += o.dissipated_tangential_pw_j;
        self.elastic_j += o.elastic_j;
    }
}

/// Running energy balance of a simulation, J. States (kinetic, potential, elastic) are the
/// current values; works and dissipations are cumulative since the ledger was reset.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyLedger {
    /// Translational + rotational kinetic energy of the particles.
    pub kinetic_j: f64,
    /// Gravitational potential energy of the particles.
    pub potential_j: f64,
    /// Elastic energy stored in contacts (normal, tangential springs, adhesion).
    pub elastic_j: f64,
    /// Cumulative work done by moving walls on the particles.
    pub wall_work_j: f64,
    /// Cumulative work of external forces on the particles.
    pub external_work_j: f64,
    /// Cumulative normal dissipation in particle–particle contacts.
    pub dissipated_normal_pp_j: f64,
    /// Cumulative normal dissipation in particle–wall contacts.
    pub dissipated_normal_pw_j: f64,
    /// Cumulative tangential dissipation in particle–particle contacts.
    pub dissipated_tangential_pp_j: f64,
    /// Cumulative tangential dissipation in particle–wall contacts.
    pub dissipated_tangential_pw_j: f64,
    /// Kinetic energy when the ledger was reset.
    pub initial_kinetic_j: f64,
    /// Potential energy when the ledger was reset.
    pub initial_potential_j: f64,
    /// Elastic energy when the ledger was reset.
    pub initial_elastic_j: f64,
}

impl EnergyLedger {
    /// Adds the cumulative increments of one step and sets the stored elastic energy.
    pub fn add(&mut self, inc: &EnergyIncrements) {
        self.wall_work_j += inc.wall_work_j;
        self.external_work_j += inc.external_work_j;
        self.dissipated_normal_pp_j += inc.dissipated_normal_pp_j;
        self.dissipated_normal_pw_j += inc.dissipated_normal_pw_j;
        self.dissipated_tangential_pp_j += inc.dissipated_tangential_pp_j;
        self.dissipated_tangential_pw_j += inc.dissipated_tangential_pw_j;
        self.elastic_j = inc.elastic_j;
    }

    /// Restarts the cumulative terms from the current state (e.g. after settling).
    pub fn reset(&mut self) {
        *self = Self {
            kinetic_j: self.kinetic_j,
            potential_j: self.potential_j,
            elastic_j: self.elastic_j,
            initial_kinetic_j: self.kinetic_j,
            initial_potential_j: self.potential_j,
            initial_elastic_j: self.elastic_j,
            ..Default::default()
        };
    }

    /// Total dissipated in normal direction (pp + pw).
    pub fn dissipated_normal_j(&self) -> f64 {
        self.dissipated_normal_pp_j + self.dissipated_normal_pw_j
    }

    /// Total dissipated tangentially (pp + pw).
    pub fn dissipated_tangential_j(&self) -> f64 {
        self.dissipated_tangential_pp_j + self.dissipated_tangential_pw_j
    }

    /// Total dissipated energy.
    pub fn dissipated_j(&self) -> f64 {
        self.dissipated_normal_j() + self.dissipated_tangential_j()
    }

    /// Mechanical energy of the particles plus the stored contact energy.
    pub fn total_mechanical_j(&self) -> f64 {
        self.kinetic_j + self.potential_j + self.elastic_j
    }

    /// Balance residual $W_{wall} + W_{ext} - (\Delta E_{kin} + \Delta E_{pot} + \Delta E_{el} + D)$, J.
    pub fn closure_error_j(&self) -> f64 {
        self.wall_work_j + self.external_work_j
            - (self.kinetic_j - self.initial_kinetic_j)
            - (self.potential_j - self.initial_potential_j)
            - (self.elastic_j - self.initial_elastic_j)
            - self.dissipated_j()
    }

    /// Energy turnover the residual is measured against: the largest of |W_wall|, |ΔE_kin|,
    /// |ΔE_pot| and |D|, J.
    pub fn turnover_j(&self) -> f64 {
        self.wall_work_j
            .abs()
            .max((self.kinetic_j - self.initial_kinetic_j).abs())
            .max((self.potential_j - self.initial_potential_j).abs())
            .max(self.dissipated_j().abs())
    }
}
