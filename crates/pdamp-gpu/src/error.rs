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

/// Something the GPU kernels do not implement (a contact-law, wall or world feature).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum GpuFeature {
    /// Rolling resistance in a contact model.
    #[error("rolling resistance")]
    RollingResistance,
    /// DMT adhesion in a contact model.
    #[error("DMT adhesion")]
    Adhesion,
    /// A `cylinder_outside` wall.
    #[error("a cylinder_outside wall (inner rod)")]
    CylinderOutside,
    /// A triangle-mesh wall.
    #[error("a triangle-mesh wall")]
    MeshWall,
}

/// Why the GPU kernels cannot run a world ([`crate::check_world`]); the text says what they
/// lack, naming the wall, body or materials.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GpuUnsupported {
    /// The world's integrator is not velocity Verlet.
    #[error("an integrator other than velocity Verlet")]
    Integrator,
    /// Some particle has an external force.
    #[error("external particle forces")]
    ExternalForces,
    /// A body is driven from outside (coupling).
    #[error("body '{body}' driven from outside (coupling)")]
    DrivenBody {
        /// The body's name.
        body: String,
    },
    /// A wall of a kind the kernels lack.
    #[error("{feature} ('{wall}' of body '{body}')")]
    Wall {
        /// What the wall needs.
        feature: GpuFeature,
        /// The wall's name.
        wall: String,
        /// The name of its body.
        body: String,
    },
    /// The contact law of a pair of materials needs something the kernels lack.
    #[error("{feature} (materials '{material_a}' and '{material_b}')")]
    ContactLaw {
        /// What the law needs.
        feature: GpuFeature,
        /// Name of the first material.
        material_a: String,
        /// Name of the second material.
        material_b: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unsupported_texts_name_the_wall_or_materials() {
        let e = GpuUnsupported::Wall {
            feature: GpuFeature::MeshWall,
            wall: "lid".into(),
            body: "container".into(),
        };
        assert_eq!(
            e.to_string(),
            "a triangle-mesh wall ('lid' of body 'container')"
        );
        let e = GpuUnsupported::ContactLaw {
            feature: GpuFeature::RollingResistance,
            material_a: "steel".into(),
            material_b: "glass".into(),
        };
        assert_eq!(
            e.to_string(),
            "rolling resistance (materials 'steel' and 'glass')"
        );
        assert_eq!(
            GpuUnsupported::DrivenBody { body: "b".into() }.to_string(),
            "body 'b' driven from outside (coupling)"
        );
    }
}
