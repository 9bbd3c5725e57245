//! Checkpoints of a coupled DEM run ([`super::CouplingCheckpoint`]): the state after a step —
//! modal integrator, every bed's world and last raw load, the history and the energy exchange.

use super::{BedRun, DemEnergy};
use crate::StructureError;
use crate::free::TimeHistory;
use crate::integrate::ModalIntegrator;
use nalgebra::DVector;
use pdamp_dem::WorldState;
use serde::{Deserialize, Serialize};

/// Kind tag of coupled-DEM checkpoints.
pub(super) const COUPLE_KIND: &str = "couple-dem";

/// State of [`coupled_run`] after a step.
#[derive(Serialize, Deserialize)]
pub(super) struct CoupledState {
    step: usize,
    time_s: f64,
    q: DVector<f64>,
    v: DVector<f64>,
    a: DVector<f64>,
    world: WorldState,
    time: Vec<f64>,
    displacement: Vec<f64>,
    velocity: Vec<f64>,
    force: Vec<f64>,
    #[serde(default)]
    energy: DemEnergy,
    #[serde(default)]
    q_load: Option<DVector<f64>>,
    /// The worlds of the beds after the first (several DEM dampers).
    #[serde(default)]
    more_worlds: Vec<WorldState>,
    /// Their last raw loads.
    #[serde(default)]
    more_q_load: Vec<DVector<f64>>,
}

impl CoupledState {
    /// The state after `step`: the integrator, every bed's world and last raw load, the
    /// history so far and the energy exchange.
    pub(super) fn capture(
        step: usize,
        it: &ModalIntegrator,
        runs: &[BedRun],
        hist: &TimeHistory,
        energy: DemEnergy,
    ) -> Self {
        CoupledState {
            step,
            time_s: it.time_s,
            q: it.q.clone(),
            v: it.v.clone(),
            a: it.a.clone(),
            world: runs[0].w.save_state(),
            time: hist.time_s.clone(),
            displacement: hist.displacement_m.clone(),
            velocity: hist.velocity_m_s.clone(),
            force: hist.force_n.clone(),
            energy,
            q_load: Some(runs[0].q_raw.clone()),
            more_worlds: runs[1..].iter().map(|r| r.w.save_state()).collect(),
            more_q_load: runs[1..].iter().map(|r| r.q_raw.clone()).collect(),
        }
    }

    /// Restores a checkpoint (read from `path`) into the beds, the integrator, the history and
    /// the energy exchange; returns the first step still to run.
    pub(super) fn restore(
        self,
        path: &std::path::Path,
        runs: &mut [BedRun],
        it: &mut ModalIntegrator,
        hist: &mut TimeHistory,
        energy: &mut DemEnergy,
    ) -> Result<usize, StructureError> {
        let st = self;
        if st.more_worlds.len() + 1 != runs.len() {
            return Err(StructureError::invalid(
                path.display().to_string(),
                format!(
                    "a checkpoint of {} DEM bed(s), the scenario has {}",
                    st.more_worlds.len() + 1,
                    runs.len()
                ),
            ));
        }
        let worlds = std::iter::once(st.world).chain(st.more_worlds);
        for (r, ws) in runs.iter_mut().zip(worlds) {
            r.w.restore_state(ws).map_err(StructureError::State)?;
        }
        (it.time_s, it.q, it.v, it.a) = (st.time_s, st.q, st.v, st.a);
        hist.time_s = st.time;
        hist.displacement_m = st.displacement;
        hist.velocity_m_s = st.velocity;
        hist.force_n = st.force;
        *energy = st.energy;
        let loads = st.q_load.into_iter().chain(st.more_q_load);
        for (r, ql) in runs.iter_mut().zip(loads) {
            r.q_raw = ql;
        }
        Ok(st.step + 1)
    }
}
