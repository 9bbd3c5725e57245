//! What a cantilever scenario will cost (particles, elements, steps, memory, CPU time),
//! estimated before anything is allocated.

use serde::Serialize;

use super::CantileverScenario;

/// Memory per structural element, estimated (Gauss data, mass and stiffness matrices) [B].
pub(super) const BYTES_PER_ELEMENT: f64 = 10e3;
/// Memory per particle, estimated (state, pair list, wall contacts, checkpoint copy) [B].
const BYTES_PER_PARTICLE: f64 = 2e3;
/// CPU time per particle and step, measured on the paper runs (≈ 1/3 of 56–140 ms per step
/// for 32 000 particles) [s].
const CPU_S_PER_PARTICLE_STEP: f64 = 1e-6;
/// CPU time per structural dof and coupled step (≈ 2/3 of a step for 19 008 dofs) [s].
const CPU_S_PER_DOF_STEP: f64 = 3e-6;

/// What a scenario will cost, estimated before anything is allocated
/// ([`CantileverScenario::estimate`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CostEstimate {
    /// Particles (mean particle volume of the truncated distribution).
    pub particles: f64,
    /// Structural elements (upper bound).
    pub elements: f64,
    /// Structural dofs (upper bound).
    pub dofs: f64,
    /// Coupled steps.
    pub steps: f64,
    /// Preparation steps (upper bound: settling and relaxation limits).
    pub prep_steps: f64,
    /// Memory \[B\].
    pub memory_bytes: f64,
    /// CPU time \[s\] (one core).
    pub cpu_s: f64,
}

impl std::fmt::Display for CostEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "≈ {:.3e} particles, {:.3e} elements, {:.3e} coupled steps and ≤ {:.3e} preparation steps: ≈ {:.2} GB of memory and ≈ {:.1} h of one core",
            self.particles,
            self.elements,
            self.steps,
            self.prep_steps,
            self.memory_bytes / 1e9,
            self.cpu_s / 3600.0
        )
    }
}

impl CantileverScenario {
    /// Work and memory of the scenario, estimated without allocating anything (f64 so that
    /// absurd inputs do not overflow).
    pub fn estimate(&self) -> CostEstimate {
        let (elements, nodes) = self.beam.mesh_size();
        let dt = self.run.time_step_s;
        let steps = (self.run.duration_s / dt).round();
        let (particles, prep_steps) = match &self.powder {
            Some(p) => {
                let n =
                    p.prep.packing_density * self.beam.cavity().volume() / p.psd().mean_volume_m3();
                let s = &p.prep;
                // settling ≤ max_settling_time_s, relaxation ≤ relax + max_settling, holding;
                // compression: the bed top is at most the cavity's length above the top
                let comp = self.beam.cavity_length_m / (s.plate_speed_m_s * dt);
                (
                    n,
                    (2.0 * s.max_settling_time_s + 2.0 * s.relax_time_s) / dt + comp,
                )
            }
            None => (0.0, 0.0),
        };
        let dofs = 3.0 * nodes;
        CostEstimate {
            particles,
            elements,
            dofs,
            steps,
            prep_steps,
            memory_bytes: elements * BYTES_PER_ELEMENT + particles * BYTES_PER_PARTICLE,
            cpu_s: steps * (particles * CPU_S_PER_PARTICLE_STEP + dofs * CPU_S_PER_DOF_STEP)
                + prep_steps * particles * CPU_S_PER_PARTICLE_STEP,
        }
    }
}
