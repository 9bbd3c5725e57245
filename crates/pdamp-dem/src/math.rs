//! Small vector helpers shared by the engine. All quantities are SI and f64.

/// A 3-vector in metres, m/s, N, … (nalgebra, stack allocated).
pub type Vec3 = nalgebra::Vector3<f64>;
/// A 3×3 matrix (rotation matrices, inertia tensors).
pub type Mat3 = nalgebra::Matrix3<f64>;
/// A unit quaternion for rigid-body orientation.
pub type Rotation = nalgebra::UnitQuaternion<f64>;

/// Gravity of the excitation intensity Γ = A/g [D Eq. 3.11] and of the defaults, m/s²: the
/// dissertation's rounded 9.81 (the conventional standard value is 9.80665).
pub const STANDARD_GRAVITY_M_S2: f64 = 9.81;

/// Component `v` of `a` perpendicular to the unit vector `n`: `a − (a·n) n`.
#[inline]
pub fn tangential_part(a: &Vec3, n: &Vec3) -> Vec3 {
    a - n * a.dot(n)
}
