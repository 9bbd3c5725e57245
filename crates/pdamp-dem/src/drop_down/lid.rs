//! Filling with the lid open ([`OpenLid`](super::OpenLid)): the walls that end at the region's
//! top extended by the headroom, a temporary lid plane above, and the lid closed down to the
//! real top once the bed is in (tapping the container where set).

use super::{DropDownError, DropDownReport, DropDownSpec, OpenLid};
use crate::generate::Region;
use crate::math::Vec3;
use crate::walls::{CylinderInside, CylinderOutside, Geometry, Plane};
use crate::{BodyState, HarmonicTranslation, Motion, PrescribedMotion, RigidBody, World};
use std::ops::ControlFlow;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// The container opened for a fill with the lid open ([`open_container`]).
pub(super) struct OpenContainer {
    /// The insertion region extended by the headroom.
    pub(super) fill_region: Region,
    /// The real top of the container along −g (world frame), m.
    top_m: f64,
    /// The top while pouring, m.
    raised_m: f64,
    /// Index of the temporary lid body.
    lid_body: usize,
    /// Bodies whose walls were extended (tapped while the lid closes).
    containers: Vec<usize>,
}

/// Extends every wall of `w` that closes the container between the top of `region` along `up`
/// and `headroom_m` above it to the raised top ([`raised_top`]) and adds a temporary lid plane
/// there (a driven body of the first such wall's material).
pub(super) fn open_container(
    w: &mut World,
    region: &Region,
    up: &Vec3,
    headroom_m: f64,
    tolerance_m: f64,
) -> Result<OpenContainer, DropDownError> {
    let fill_region = region.raised(up, headroom_m).ok_or_else(|| {
        DropDownError::Invalid(
            "open_lid: the region must be a box with an edge along the filling gravity or a \
             cylinder with its axis along it"
                .into(),
        )
    })?;
    let top_m = region.extent_along(up).1;
    let mut containers = Vec::new();
    let mut lid_material = None;
    for (bi, b) in w.bodies.iter_mut().enumerate() {
        let pose = b.state;
        for wall in &mut b.walls {
            if let Some(g) = raised_top(&wall.geometry, &pose, up, top_m, headroom_m, tolerance_m) {
                if !matches!(g, Geometry::CylinderOutside(_)) {
                    lid_material.get_or_insert(wall.material);
                }
                wall.geometry = g;
                if !containers.contains(&bi) {
                    containers.push(bi);
                }
            }
        }
    }
    let Some(material) = lid_material else {
        return Err(DropDownError::Invalid(format!(
            "open_lid: no wall ends at the region's top ({top_m:.6e} m along the filling \
             gravity's up direction); the lid must be the top face of a box_inside or \
             cylinder_inside, or a plane facing down, level with the top of placement.region"
        )));
    };
    let raised_m = top_m + headroom_m;
    let lid = RigidBody::new(
        "open-lid fill: lid",
        BodyState::at_rest(Vec3::zeros()),
        Motion::Fixed,
    )
    .with_wall(
        "lid",
        Geometry::Plane(Plane::new(up * raised_m, -up, false)),
        material,
    );
    let lid_body = w.add_body(lid);
    Ok(OpenContainer {
        fill_region,
        top_m,
        raised_m,
        lid_body,
        containers,
    })
}

/// The geometry `g` of a body at `pose` extended to `top + h` along `up` (world frame) if one
/// of its faces closes the container between `top` and `top + h` (a `box_inside` cover, the
/// cap wall of a coated container a little behind its coating): the top face of a `box_inside`
/// with an edge along `up`, the top disc of a `cylinder_inside` with its axis along `up`, the
/// top end of an inner rod (`cylinder_outside`) along `up`, a one-sided plane facing down;
/// `None` for any other wall or a face elsewhere.
fn raised_top(
    g: &Geometry,
    pose: &BodyState,
    up: &Vec3,
    top: f64,
    h: f64,
    tolerance: f64,
) -> Option<Geometry> {
    let up_b = pose.orientation.inverse_transform_vector(up);
    let top_b = top - pose.position_m.dot(up);
    let aligned = |c: f64| c.abs() > 1.0 - 1e-9;
    // How far a face at `face` moves: up to `top + h`, if it closes the container there.
    let lift =
        |face: f64| (face >= top_b - tolerance && face < top_b + h).then_some(top_b + h - face);
    // A cylinder (base centre, unit axis, length) along `up` whose upper end closes the
    // container: the base centre and length that reach the raised top.
    let cylinder_raised = |base: &Vec3, axis: &Vec3, length: f64| {
        let a = axis.dot(&up_b);
        if !aligned(a) {
            return None;
        }
        let b = base.dot(&up_b);
        let d = lift(if a > 0.0 { b + length } else { b })?;
        let base = if a < 0.0 { base + up_b * d } else { *base };
        Some((base, length + d))
    };
    match g {
        Geometry::BoxInside(b) => {
            let k = (0..3).find(|&k| aligned(up_b[k]))?;
            let sign = up_b[k].signum();
            let d = lift(b.center_m[k] * sign + b.half_extents_m[k])?;
            let mut raised = b.clone();
            raised.center_m[k] += sign * 0.5 * d;
            raised.half_extents_m[k] += 0.5 * d;
            Some(Geometry::BoxInside(raised))
        }
        Geometry::CylinderInside(c) => {
            let (base_center_m, length_m) = cylinder_raised(&c.base_center_m, &c.axis, c.length_m)?;
            Some(Geometry::CylinderInside(CylinderInside {
                base_center_m,
                length_m,
                ..c.clone()
            }))
        }
        Geometry::CylinderOutside(c) => {
            // An inner rod that reaches the lid reaches the raised lid.
            let (base_center_m, length_m) = cylinder_raised(&c.base_center_m, &c.axis, c.length_m)?;
            Some(Geometry::CylinderOutside(CylinderOutside {
                base_center_m,
                length_m,
                ..c.clone()
            }))
        }
        Geometry::Plane(p) if !p.two_sided && p.normal.dot(&up_b) < -(1.0 - 1e-9) => {
            let d = lift(p.point_m.dot(&up_b))?;
            let mut raised = p.clone();
            raised.point_m += up_b * d;
            Some(Geometry::Plane(raised))
        }
        _ => None,
    }
}

/// Motion of the temporary lid: `offset_m` (f64 bits, set by [`close_lid`] between steps) along
/// `up` from its raised place, plus the tapping `(ω, amplitude, start)` of the container.
#[derive(Debug)]
struct LidMotion {
    up: Vec3,
    offset_m: Arc<AtomicU64>,
    tap: Option<(f64, f64, f64)>,
}

impl PrescribedMotion for LidMotion {
    fn offset(&self, t_s: f64) -> BodyState {
        let (shake, shake_v) = self.tap.map_or((0.0, 0.0), |(omega, a, t0)| {
            let arg = omega * (t_s - t0);
            (a * arg.sin(), a * omega * arg.cos())
        });
        BodyState {
            position_m: self.up * (f64::from_bits(self.offset_m.load(Ordering::Relaxed)) + shake),
            orientation: crate::math::Rotation::identity(),
            velocity_m_s: self.up * shake_v,
            angular_velocity_rad_s: Vec3::zeros(),
        }
    }
}

/// The particle with the highest top along `up`: `(index, top)`.
fn highest_top(w: &World, up: &Vec3) -> (usize, f64) {
    let p = &w.particles;
    (0..p.len())
        .map(|i| (i, p.position[i].dot(up) + p.radius[i]))
        .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a })
}

/// Closes the lid of an opened container (module docs): down to the highest particle top at
/// once, then at `close_speed_m_s` while the particles push on it with less than their weight
/// (tapping the container where set), to the real top; the containers end at rest in their
/// reference poses after whole tapping cycles, and the bed falls calm under the closed lid.
#[allow(clippy::too_many_arguments)]
pub(super) fn close_lid(
    w: &mut World,
    o: &OpenContainer,
    l: &OpenLid,
    up: &Vec3,
    spec: &DropDownSpec,
    report: &mut DropDownReport,
    hook: &mut impl FnMut(&World, usize) -> ControlFlow<()>,
    placed: usize,
) -> Result<(), DropDownError> {
    let (_, bed_top) = highest_top(w, up);
    report.bed_top_above_lid_m = Some(bed_top - o.top_m);
    let t0 = w.time_s;
    let g = w.gravity_m_s2.norm();
    let hold_n = w.particles.total_mass() * g;
    // (ω, amplitude, period) of the tapping.
    let tap = l.tapping.map(|t| {
        let omega = 2.0 * std::f64::consts::PI * t.frequency_hz;
        (
            omega,
            t.intensity * g / (omega * omega),
            1.0 / t.frequency_hz,
        )
    });
    let mut level = bed_top.clamp(o.top_m, o.raised_m);
    let snap_m = 0.01 * w.particles.min_radius();
    let mut steps = 0u64;
    let check = |w: &World, steps: u64, hook: &mut dyn FnMut(&World, usize) -> ControlFlow<()>| {
        if steps.is_multiple_of(200) {
            w.check_health()
                .map_err(|e| DropDownError::Health(e.to_string()))?;
            if hook(w, placed).is_break() {
                return Err(DropDownError::Interrupted);
            }
        }
        Ok(())
    };
    // The lid follows `level` (shared with its motion law) and the tapping of the container, so
    // that its step velocity matches its displacement (the energy ledger books its work).
    let lid_level = Arc::new(AtomicU64::new((level - o.raised_m).to_bits()));
    w.bodies[o.lid_body].motion = Motion::Prescribed(Arc::new(LidMotion {
        up: *up,
        offset_m: lid_level.clone(),
        tap: tap.map(|(omega, a, _)| (omega, a, t0)),
    }));
    if level > o.top_m {
        if let Some((omega, amplitude_m, _)) = tap {
            for &b in &o.containers {
                w.bodies[b].motion = Motion::Prescribed(Arc::new(HarmonicTranslation {
                    direction: [up.x, up.y, up.z],
                    amplitude_m,
                    frequency_hz: omega / (2.0 * std::f64::consts::PI),
                    phase_rad: -omega * t0,
                }));
            }
        }
        let mut end_s = f64::INFINITY;
        while w.time_s < end_s - 0.5 * w.dt_s {
            lid_level.store((level - o.raised_m).to_bits(), Ordering::Relaxed);
            w.step();
            steps += 1;
            check(w, steps, hook)?;
            if w.bodies[o.lid_body].contact_force_n.dot(up) < hold_n {
                level = (level - l.close_speed_m_s * w.dt_s).max(o.top_m);
            }
            if level - o.top_m <= snap_m {
                // Within the contacts' elastic give: the lid is screwed home.
                level = o.top_m;
            }
            let elapsed = w.time_s - t0;
            if level <= o.top_m && end_s.is_infinite() {
                // Closed: finish the tapping cycle so that the container ends at rest in place.
                end_s = match tap {
                    Some((_, _, period)) => t0 + (elapsed / period - 1e-9).ceil() * period,
                    None => w.time_s,
                };
            }
            if end_s.is_infinite() && elapsed > l.max_close_duration_s {
                return Err(DropDownError::LidNotClosed {
                    above_m: level - o.top_m,
                    particle: highest_top(w, up).0,
                    duration_s: elapsed,
                });
            }
        }
        for &b in &o.containers {
            w.bodies[b].motion = Motion::Fixed;
        }
    }
    // The lid in its place; the bed falls calm under it.
    w.bodies[o.lid_body].motion = Motion::Prescribed(Arc::new(LidMotion {
        up: *up,
        offset_m: Arc::new(AtomicU64::new((o.top_m - o.raised_m).to_bits())),
        tap: None,
    }));
    let t_calm = w.time_s;
    let n = w.particles.len().max(1) as f64;
    loop {
        w.step();
        steps += 1;
        check(w, steps, hook)?;
        if w.time_s - t_calm >= spec.max_round_duration_s
            || w.ledger.kinetic_j / n < spec.kinetic_energy_per_particle_j
        {
            break;
        }
    }
    report.steps += steps;
    report.simulated_time_s += w.time_s - t0;
    report.lid_closing_time_s = w.time_s - t0;
    Ok(())
}
