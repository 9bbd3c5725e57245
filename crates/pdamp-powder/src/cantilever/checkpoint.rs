//! `pdamp powder run` checkpoints: the phase a run is in, its scenario digest, decoding.

use std::path::PathBuf;

use pdamp_io::checkpoint::{self as ck, CheckpointHeader};
use serde::{Deserialize, Serialize};

use super::{CantileverError, CantileverScenario};
use crate::couple::{CoupledEnergy, CoupledState};
use crate::prep::{PrepReport, Preparation};

/// Kind tag of `pdamp powder run` checkpoints (`-2`: the coupled run's particles are a
/// pdamp-dem world; `-3`: the structure state says which precision its tangent factor has;
/// `-5`: the preparation hands a bed made with its own law over to the run's law (`-4`
/// was an intermediate layout of that stage);
/// checkpoints of earlier layouts are refused by name).
pub const CHECKPOINT_KIND: &str = "powder-run-5";

/// Digest identifying a scenario in checkpoints (FNV-1a 64 of its canonical TOML).
pub fn scenario_digest(sc: &CantileverScenario) -> Result<String, CantileverError> {
    let text = toml::to_string(sc).map_err(CantileverError::Digest)?;
    Ok(ck::digest(text.as_bytes()))
}

/// What a checkpoint holds: the preparation in progress, or the coupled run in progress
/// (which starts with the prepared powder), or nothing once the outputs are written.
#[derive(Serialize, Deserialize)]
pub(super) enum Phase {
    Preparing(Box<Preparation>),
    Running(Box<RunState>),
    Finished,
}

/// The coupled run after step `step`: the complete dynamic state and the results so far.
#[derive(Serialize, Deserialize)]
pub(super) struct RunState {
    pub(super) step: u64,
    pub(super) coupled: CoupledState,
    pub(super) prep: Option<PrepReport>,
    pub(super) time_s: Vec<f64>,
    pub(super) tip_m: Vec<f64>,
    pub(super) iterations: Vec<f64>,
    pub(super) energy: Vec<(f64, CoupledEnergy)>,
    pub(super) max_tip_before_release_m: f64,
    pub(super) wall_time_s: f64,
}

/// Where and how often a run checkpoints.
pub(super) struct Checkpointing {
    pub(super) path: PathBuf,
    pub(super) header: CheckpointHeader,
    pub(super) interval_s: f64,
    /// The stop request the run honours (then it checkpoints and ends interrupted).
    pub(super) cancel: pdamp_dem::time_loop::CancelToken,
}

impl Checkpointing {
    pub(super) fn save(&self, phase: &Phase) -> Result<(), CantileverError> {
        ck::save(&self.path, &self.header, phase).map_err(CantileverError::from)
    }
    pub(super) fn interrupted(&self, time_s: f64) -> CantileverError {
        CantileverError::Interrupted(ck::Interrupted {
            time_s,
            path: self.path.clone(),
        })
    }
}

/// Decodes a `pdamp powder run` checkpoint of any scenario and returns its phase and
/// simulated time \[s\] (for inspection and fuzzing; never panics).
pub fn inspect_checkpoint(bytes: &[u8]) -> Result<(&'static str, f64), CantileverError> {
    let phase = ck::decode::<Phase>(bytes, CHECKPOINT_KIND, None).map_err(CantileverError::from)?;
    Ok(match phase {
        Phase::Preparing(p) => ("preparing", p.time_s()),
        Phase::Running(r) => ("running", r.coupled.dynamics.t),
        Phase::Finished => ("finished", f64::NAN),
    })
}

/// Decodes a `pdamp powder run` checkpoint of any scenario that holds a preparation in
/// progress and checks its consistency (for fuzzing; never panics).
pub fn decode_preparation(bytes: &[u8]) -> Result<Preparation, CantileverError> {
    let phase = ck::decode::<Phase>(bytes, CHECKPOINT_KIND, None).map_err(CantileverError::from)?;
    match phase {
        Phase::Preparing(p) => {
            p.check_consistency()?;
            Ok(*p)
        }
        _ => Err(CantileverError::NotPreparation),
    }
}

#[cfg(test)]
mod tests {
    use std::ops::ControlFlow;

    use super::*;
    use crate::fe::Aabb;
    use crate::law::PowderLaw;
    use crate::prep::PrepSettings;
    use crate::psd::LogNormal;

    #[test]
    fn checkpoint_inspection_and_damage() {
        let dir = std::env::temp_dir().join(format!("pdamp-powder-inspect-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(ck::CHECKPOINT_FILE);
        let cavity = Aabb {
            min: [0.0; 3],
            max: [0.006, 0.006, 0.012],
        };
        let s = PrepSettings::default();
        let mut pr = Preparation::new(
            cavity,
            &LogNormal::paper(2e-3),
            PowderLaw::PAPER.coarse_grained(2.0),
            8000.0,
            5e-6,
            &s,
        );
        let mut k = 0;
        let _ = pr.run(&mut |_, _| {}, &mut |_| {
            k += 1;
            if k == 50 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        let header = CheckpointHeader::new(CHECKPOINT_KIND, "digest");
        ck::save(&path, &header, &Phase::Preparing(Box::new(pr.snapshot()))).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let (phase, t) = inspect_checkpoint(&bytes).unwrap();
        assert_eq!(phase, "preparing");
        assert!((t - 50.0 * 5e-6).abs() < 1e-15, "{t}");
        // another scenario, another kind, damage and truncation are refused with a message
        let e = ck::load::<Phase>(&path, CHECKPOINT_KIND, "other")
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("different scenario"), "{e}");
        let e = ck::load::<Phase>(&path, "run", "digest")
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("not 'run'"), "{e}");
        let mut bad = bytes.clone();
        bad[bytes.len() / 2] ^= 1;
        assert!(
            inspect_checkpoint(&bad)
                .unwrap_err()
                .to_string()
                .contains("damaged")
        );
        assert!(inspect_checkpoint(&bytes[..bytes.len() - 100]).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
