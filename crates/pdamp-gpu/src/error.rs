//! Typed errors of the GPU backend.

/// What can go wrong on the GPU path; every message names the world, particle, wall or limit.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan adapter with double-precision shaders was found.
    #[error(
        "no GPU adapter with 64-bit float shaders found ({0}); install a Vulkan driver (NVIDIA's, or Mesa's lavapipe: Debian package mesa-vulkan-drivers) or use the CPU engine"
    )]
    NoAdapter(String),
    /// The device could not be opened or lacks a limit the kernels need.
    #[error("GPU device: {0}")]
    Device(String),
    /// The world uses something the GPU kernels do not implement.
    #[error("world {world}: {what} is not supported on the GPU backend; run it on the CPU engine")]
    Unsupported {
        /// Index of the world in the batch.
        world: usize,
        /// What is not supported.
        what: String,
    },
    /// The worlds of a batch disagree on what must be shared.
    #[error("worlds 0 and {world} of the batch differ: {what}")]
    Mismatch {
        /// Index of the world.
        world: usize,
        /// What differs.
        what: String,
    },
    /// The batch would not fit into the device's memory or buffer limits.
    #[error("the batch needs {needed_bytes} bytes in {what}, the device allows {limit_bytes}")]
    TooLarge {
        /// Which buffer or total.
        what: String,
        /// Bytes needed.
        needed_bytes: u64,
        /// Bytes allowed.
        limit_bytes: u64,
    },
    /// A fixed per-particle capacity was exceeded (a denser or more polydisperse bed than sized for).
    #[error(
        "world {world}, particle {particle} (t = {time_s:.6e} s): {what}; the batch was sized for {capacity}, rebuild it with a larger capacity"
    )]
    Capacity {
        /// World of the particle.
        world: usize,
        /// Index of the particle in its world.
        particle: usize,
        /// Simulated time, s.
        time_s: f64,
        /// Which capacity.
        what: &'static str,
        /// The capacity.
        capacity: u32,
    },
    /// A particle's state became NaN or infinite.
    #[error(
        "world {world}, particle {particle}: non-finite state by t = {time_s:.6e} s (time step too large for the contact stiffness, or overlapping start); state kept as of t = {last_good_s:.6e} s is lost on the GPU"
    )]
    NonFinite {
        /// World of the particle.
        world: usize,
        /// Index of the particle in its world.
        particle: usize,
        /// Simulated time at the check, s.
        time_s: f64,
        /// Time of the last successful check, s.
        last_good_s: f64,
    },
    /// A body moves in a way the kernels cannot follow (rotation).
    #[error("world {world}, body '{body}': {what}")]
    Body {
        /// World index.
        world: usize,
        /// Body name.
        body: String,
        /// What is wrong.
        what: String,
    },
}
