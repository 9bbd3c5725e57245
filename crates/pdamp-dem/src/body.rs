//! Rigid bodies that carry the walls, and how they move: fixed, prescribed or driven from outside
//! [D Sect. 2.2.2, 2.4].

use crate::math::{Rotation, Vec3};
use crate::walls::Geometry;
use serde::{Deserialize, Serialize};
use std::fmt::Debug;
use std::sync::Arc;

/// Kinematic state of a rigid body at one instant.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyState {
    /// Position of the body reference point, m.
    pub position_m: Vec3,
    /// Orientation (body frame → world frame).
    pub orientation: Rotation,
    /// Velocity of the reference point, m/s.
    pub velocity_m_s: Vec3,
    /// Angular velocity in the world frame, rad/s.
    pub angular_velocity_rad_s: Vec3,
}

impl BodyState {
    /// A body at rest at `position_m` with identity orientation.
    pub fn at_rest(position_m: Vec3) -> Self {
        Self {
            position_m,
            orientation: Rotation::identity(),
            velocity_m_s: Vec3::zeros(),
            angular_velocity_rad_s: Vec3::zeros(),
        }
    }

    /// Velocity of the material point at world position `p`: $v + \omega \times (p - x)$.
    #[inline]
    pub fn point_velocity(&self, p: &Vec3) -> Vec3 {
        self.velocity_m_s + self.angular_velocity_rad_s.cross(&(p - self.position_m))
    }

    /// World → body frame for a point.
    #[inline]
    pub fn to_body(&self, p: &Vec3) -> Vec3 {
        self.orientation
            .inverse_transform_vector(&(p - self.position_m))
    }

    /// Body → world frame for a point.
    #[inline]
    pub fn point_to_world(&self, p: &Vec3) -> Vec3 {
        self.position_m + self.orientation.transform_vector(p)
    }

    /// Body → world frame for a direction.
    #[inline]
    pub fn vector_to_world(&self, v: &Vec3) -> Vec3 {
        self.orientation.transform_vector(v)
    }
}

/// A prescribed (rheonomic) motion of a rigid body relative to its reference pose.
///
/// Implement this trait for any motion law; `state(t)` must be smooth enough for the integrator.
pub trait PrescribedMotion: Send + Sync + Debug {
    /// Displacement, rotation, velocity and angular velocity at time `t_s`, relative to the
    /// reference pose (position offset and rotation are applied on top of it).
    fn offset(&self, t_s: f64) -> BodyState;
}

/// Harmonic translation $x(t) = X \sin(2\pi f t + \varphi)\,\hat e$ along any direction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HarmonicTranslation {
    /// Direction of motion (normalised on use).
    pub direction: [f64; 3],
    /// Displacement amplitude X, m.
    pub amplitude_m: f64,
    /// Frequency f, Hz.
    pub frequency_hz: f64,
    /// Phase φ, rad.
    #[serde(default)]
    pub phase_rad: f64,
}

impl PrescribedMotion for HarmonicTranslation {
    fn offset(&self, t_s: f64) -> BodyState {
        let e = Vec3::from(self.direction).normalize();
        let w = 2.0 * std::f64::consts::PI * self.frequency_hz;
        let arg = w * t_s + self.phase_rad;
        BodyState {
            position_m: e * (self.amplitude_m * arg.sin()),
            orientation: Rotation::identity(),
            velocity_m_s: e * (self.amplitude_m * w * arg.cos()),
            angular_velocity_rad_s: Vec3::zeros(),
        }
    }
}

/// A body moved from outside one step at a time (a user's own structure model, Python's
/// `World.drive_body`): the translation of the reference point relative to its reference
/// position, known at `t1_s` with its velocity and acceleration and extrapolated
/// quadratically around it, $u(t) = u_1 + v_1 s + \tfrac12 a_1 s^2$, $s = t - t_1$ (the
/// explicit coupling of D Sect. 3.3 evaluates the container at the end of the step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TranslationTrack {
    /// Time the state below belongs to, s.
    pub t1_s: f64,
    /// Displacement $u_1$ from the reference position, m.
    pub displacement_m: Vec3,
    /// Velocity $v_1$, m/s.
    pub velocity_m_s: Vec3,
    /// Acceleration $a_1$, m/s².
    pub acceleration_m_s2: Vec3,
}

impl PrescribedMotion for TranslationTrack {
    fn offset(&self, t_s: f64) -> BodyState {
        let s = t_s - self.t1_s;
        let mut b = BodyState::at_rest(
            self.displacement_m + self.velocity_m_s * s + self.acceleration_m_s2 * (0.5 * s * s),
        );
        b.velocity_m_s = self.velocity_m_s + self.acceleration_m_s2 * s;
        b
    }
}

/// How a rigid body moves.
#[derive(Debug, Clone)]
pub enum Motion {
    /// Does not move.
    Fixed,
    /// Moves as prescribed, relative to the reference pose.
    Prescribed(Arc<dyn PrescribedMotion>),
    /// Pose and velocity are set from outside before every step (structural coupling); the caller
    /// reads back [`RigidBody::contact_force_n`] and [`RigidBody::contact_torque_nm`].
    Driven,
}

/// One wall: a geometry in the body frame and the material it is made of.
#[derive(Debug, Clone, PartialEq)]
pub struct Wall {
    /// Shape in the body frame.
    pub geometry: Geometry,
    /// Index into the world's material table.
    pub material: u16,
    /// Name used in messages and output.
    pub name: String,
}

/// A rigid body carrying walls.
#[derive(Debug, Clone)]
pub struct RigidBody {
    /// Name used in messages and output.
    pub name: String,
    /// Reference pose (the pose at t = 0 for prescribed motion).
    pub reference: BodyState,
    /// Current state.
    pub state: BodyState,
    /// State at the beginning of the current step (for the mean step velocity).
    pub previous: BodyState,
    /// Motion law.
    pub motion: Motion,
    /// Walls attached to the body.
    pub walls: Vec<Wall>,
    /// Total force the particles exert on the body in the last evaluation, N.
    pub contact_force_n: Vec3,
    /// Total torque the particles exert on the body about its reference point, N·m.
    pub contact_torque_nm: Vec3,
}

impl RigidBody {
    /// A body with no walls yet.
    pub fn new(name: &str, reference: BodyState, motion: Motion) -> Self {
        Self {
            name: name.to_string(),
            reference,
            state: reference,
            previous: reference,
            motion,
            walls: Vec::new(),
            contact_force_n: Vec3::zeros(),
            contact_torque_nm: Vec3::zeros(),
        }
    }

    /// Adds a wall and returns `self` for chaining.
    pub fn with_wall(mut self, name: &str, geometry: Geometry, material: u16) -> Self {
        self.walls.push(Wall {
            geometry,
            material,
            name: name.to_string(),
        });
        self
    }

    /// Pose and velocity the motion law prescribes at `t_s` (the current state for fixed and
    /// driven bodies).
    pub fn prescribed_state(&self, t_s: f64) -> BodyState {
        match &self.motion {
            Motion::Fixed => self.reference,
            Motion::Driven => self.state,
            Motion::Prescribed(m) => {
                let o = m.offset(t_s);
                let r = &self.reference;
                BodyState {
                    position_m: r.position_m + o.position_m,
                    orientation: o.orientation * r.orientation,
                    velocity_m_s: r.velocity_m_s + o.velocity_m_s,
                    angular_velocity_rad_s: r.angular_velocity_rad_s + o.angular_velocity_rad_s,
                }
            }
        }
    }

    /// Velocity used for contacts during a step of length `dt` ending in `state`: the mean
    /// velocity over the step (displacement / dt) so that wall work matches the particle
    /// kinematics exactly; angular velocity is the mean of both ends.
    pub fn step_state(&self, dt: f64) -> BodyState {
        let mut s = self.state;
        if dt > 0.0 && !matches!(self.motion, Motion::Fixed) {
            s.velocity_m_s = (self.state.position_m - self.previous.position_m) / dt;
            s.angular_velocity_rad_s =
                0.5 * (self.state.angular_velocity_rad_s + self.previous.angular_velocity_rad_s);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The track gives its state at t1 exactly and extrapolates quadratically around it.
    #[test]
    fn translation_track_is_exact_at_t1_and_quadratic_around_it() {
        let t = TranslationTrack {
            t1_s: 0.25,
            displacement_m: Vec3::new(1e-3, -2e-3, 0.5e-3),
            velocity_m_s: Vec3::new(0.1, 0.0, -0.2),
            acceleration_m_s2: Vec3::new(3.0, 1.0, 0.0),
        };
        let at = t.offset(0.25);
        assert_eq!(at.position_m, t.displacement_m);
        assert_eq!(at.velocity_m_s, t.velocity_m_s);
        let s = 0.01;
        let later = t.offset(0.25 + s);
        let want = t.displacement_m + t.velocity_m_s * s + t.acceleration_m_s2 * (0.5 * s * s);
        assert!((later.position_m - want).norm() < 1e-15);
        assert!((later.velocity_m_s - (t.velocity_m_s + t.acceleration_m_s2 * s)).norm() < 1e-15);
        assert_eq!(later.angular_velocity_rad_s, Vec3::zeros());
    }
}
