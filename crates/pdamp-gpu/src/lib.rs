//! # pdamp-gpu — the DEM engine on a GPU
//!
//! The velocity-Verlet DEM of `pdamp-dem` [D Sect. 2.3] as WGSL compute kernels in double
//! precision, run through wgpu on Vulkan: on an NVIDIA GPU, or on Mesa's lavapipe CPU driver
//! (which is how CI runs the very same kernels without a GPU).
//!
//! * **Batched mode**: many independent worlds (points of an effective field, packings of an
//!   ensemble) advance together in one launch sequence; every world keeps its own particles,
//!   walls, bodies, gravity and neighbour grid. **Large-bed mode** is a batch of one.
//! * The physics is the CPU engine's: spheres, the normal laws Hertz [D Eq. 2.69], Gonthier
//!   [D Eq. 2.78], Lankarani–Nikravesh [D Eq. 2.77], linear [P Eq. 2–4] and LIGGGHTS'
//!   Hertz–Mindlin, the friction laws regularised sliding [D Eq. 2.85], Coulomb spring–dashpot
//!   [P Eq. 5] and Mindlin (tangential history, kept across neighbour rebuilds), gravity, plane,
//!   box and cylinder walls on translating bodies (forces on the bodies read back), and the
//!   energy ledger (wall work, kinetic, potential, elastic, normal/tangential dissipation).
//! * **Deterministic**: each pair is evaluated by both partners with exactly negated
//!   arithmetic, so every particle gathers its forces itself in a fixed order — no
//!   floating-point atomics; neighbour cells are sorted after binning. The same inputs give the
//!   same bits run to run.
//!
//! Start from a CPU [`pdamp_dem::World`] (built, settled and initialised as usual): a
//! [`GpuBatch`] takes over its full state, contact histories included, so a run continues
//! exactly where the CPU left it; [`GpuBatch::snapshot`] brings the state back.

#![forbid(unsafe_code)]
mod batch;
mod device;
mod error;

pub use batch::{GpuBatch, GpuSnapshot, MemoryEstimate, check_world};
pub use device::GpuDevice;
pub use error::{GpuError, GpuFeature, GpuUnsupported};
