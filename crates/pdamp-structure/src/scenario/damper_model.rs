//! A damper entry turned into what the coupled run needs: the DEM kinematics of a `dem` damper
//! or the equivalent (effective) model of approaches 2/3.

use super::{DamperSpec, DemDofs, RollingLayerSpec, resolve};
use crate::StructureError;
use crate::effective::{EffectiveDamper, FieldTable, ViscousDamper};
use crate::formulas::{
    ConstantLossFactor, FrictionMechanism, HorizontalDamper, LayeredDamper, RollingDamper,
    clearance_m,
};
use crate::modal::ModalStructure;
use std::path::Path;

impl DamperSpec {
    /// Kinematics of a DEM damper (`dampers[index]`), validated: the point lists have three
    /// entries, `point` is one of the translation points, the keys fit `dofs`.
    ///
    /// # Errors
    /// Messages name the offending key; not a DEM damper.
    pub fn dem_kinematics(
        &self,
        index: usize,
    ) -> Result<crate::dem::DemKinematics, StructureError> {
        use crate::dem::{DemKinematics, RigidKinematics};
        let DamperSpec::Dem {
            point,
            dofs,
            translation_points,
            rotation_points,
            attachment_point_m,
            ..
        } = self
        else {
            return Err(StructureError::invalid(
                format!("dampers[{index}]"),
                "not a DEM damper",
            ));
        };
        let key = |k: &str| format!("dampers[{index}].{k}");
        let three =
            |v: &Option<Vec<String>>, k: &str| -> Result<[Option<String>; 3], StructureError> {
                let v = v.as_ref().ok_or_else(|| {
                    StructureError::invalid(key(k), format!("required for dofs = {dofs:?}"))
                })?;
                if v.len() != 3 {
                    return Err(StructureError::invalid(
                        key(k),
                        format!(
                            "give three point names (x, y, z; \"\" = not moved), got {}",
                            v.len()
                        ),
                    ));
                }
                let o = |s: &String| (!s.trim().is_empty()).then(|| s.trim().to_string());
                Ok([o(&v[0]), o(&v[1]), o(&v[2])])
            };
        match dofs {
            DemDofs::OneDimensional => {
                for (k, set) in [
                    ("translation_points", translation_points.is_some()),
                    ("rotation_points", rotation_points.is_some()),
                    ("attachment_point_m", attachment_point_m.is_some()),
                ] {
                    if set {
                        return Err(StructureError::invalid(
                            key(k),
                            "only with dofs = \"translation\" or \"translation+rotation\"",
                        ));
                    }
                }
                Ok(DemKinematics::OneDimensional)
            }
            DemDofs::Translation | DemDofs::TranslationRotation => {
                let tr = three(translation_points, "translation_points")?;
                if !tr.iter().flatten().any(|p| p == point) {
                    return Err(StructureError::invalid(
                        key("point"),
                        format!("'{point}' must be one of translation_points"),
                    ));
                }
                let rot = if *dofs == DemDofs::TranslationRotation {
                    Some(three(rotation_points, "rotation_points")?)
                } else if rotation_points.is_some() {
                    return Err(StructureError::invalid(
                        key("rotation_points"),
                        "only with dofs = \"translation+rotation\"",
                    ));
                } else {
                    None
                };
                if let Some(a) = attachment_point_m
                    && !a.iter().all(|x| x.is_finite())
                {
                    return Err(StructureError::invalid(
                        key("attachment_point_m"),
                        "must be finite",
                    ));
                }
                Ok(DemKinematics::Rigid(RigidKinematics {
                    translation_points: tr,
                    rotation_points: rot,
                    attachment_point_m: attachment_point_m.map(pdamp_dem::Vec3::from),
                }))
            }
        }
    }

    /// The equivalent model of approaches 2/3 (`None` for DEM); `structure` and the analysed
    /// `mode` (0-based) resolve mode-dependent kinematics (`powder_friction` `angle_points`).
    ///
    /// # Errors
    /// Invalid layer data, unreadable fields.csv, invalid powder-friction keys.
    pub fn effective_model(
        &self,
        base_dir: &Path,
        structure: &crate::modal::ModalStructure,
        mode: usize,
    ) -> Result<Option<Box<dyn EffectiveDamper>>, StructureError> {
        Ok(Some(match self {
            DamperSpec::Viscous {
                damping_n_s_m,
                mass_kg,
                ..
            } => Box::new(ViscousDamper {
                damping_n_s_m: *damping_n_s_m,
                mass_kg: *mass_kg,
            }),
            DamperSpec::Fields {
                path, bed_mass_kg, ..
            } => Box::new(FieldTable::read(&resolve(base_dir, path), *bed_mass_kg)?),
            DamperSpec::Rolling {
                layers,
                smoothing_log_width,
                ..
            } => rolling_model(layers, *smoothing_log_width)?,
            DamperSpec::Horizontal {
                bed_mass_kg,
                rolling_clearance_m,
                bouncing_clearance_m,
                bouncing_mass_ratio,
                ..
            } => Box::new(HorizontalDamper {
                rolling: RollingDamper {
                    bed_mass_kg: *bed_mass_kg,
                    clearance_m: *rolling_clearance_m,
                    smoothing_log_width: None,
                },
                bouncing_clearance_m: *bouncing_clearance_m,
                bouncing_mass_ratio: *bouncing_mass_ratio,
            }),
            DamperSpec::Vertical {
                bed_mass_kg,
                clearance_m: h,
                container_length_m,
                particles,
                max_particles,
                ..
            } => vertical_model(
                *bed_mass_kg,
                *h,
                *container_length_m,
                *particles,
                *max_particles,
            )?,
            DamperSpec::Constant {
                bed_mass_kg,
                effective_loss_factor,
                effective_mass_ratio,
                ..
            } => Box::new(ConstantLossFactor {
                bed_mass_kg: *bed_mass_kg,
                effective_loss_factor: *effective_loss_factor,
                effective_mass_ratio: *effective_mass_ratio,
            }),
            DamperSpec::PowderFriction {
                point,
                mechanism,
                cavity_length_m,
                cavity_width_m,
                friction,
                wall_normal_force_n,
                angle_per_displacement_rad_m,
                angle_points,
                bed_mass_kg,
                effective_mass_kg,
            } => {
                use crate::formulas::PowderFrictionDamper;
                let kappa = powder_friction_angle(
                    point,
                    *mechanism,
                    *cavity_length_m,
                    *angle_per_displacement_rad_m,
                    angle_points.as_deref(),
                    structure,
                    mode,
                )?;
                let d = PowderFrictionDamper {
                    mechanism: *mechanism,
                    cavity_length_m: *cavity_length_m,
                    cavity_width_m: match (mechanism, cavity_width_m) {
                        (FrictionMechanism::Bending, None) => {
                            return Err(StructureError::invalid(
                                "powder_friction",
                                "bending needs cavity_width_m",
                            ));
                        }
                        (_, w) => w.unwrap_or(0.0),
                    },
                    friction: *friction,
                    wall_normal_force_n: *wall_normal_force_n,
                    angle_per_displacement_rad_m: kappa,
                    bed_mass_kg: *bed_mass_kg,
                    effective_mass_kg: *effective_mass_kg,
                };
                d.validate()?;
                Box::new(d)
            }
            DamperSpec::Dem { .. } => return Ok(None),
        }))
    }
}

/// Rolling damper of approach 2 (D Sect. 6): one layer, or layers in parallel; a layer's
/// clearance is given or follows from its container length and particle counts.
fn rolling_model(
    layers: &[RollingLayerSpec],
    smoothing_log_width: Option<f64>,
) -> Result<Box<dyn EffectiveDamper>, StructureError> {
    let mut v: Vec<Box<dyn EffectiveDamper>> = Vec::new();
    for l in layers {
        let h = match (
            l.clearance_m,
            l.container_length_m,
            l.particles,
            l.particles_per_layer,
        ) {
            (Some(h), _, _, _) => h,
            (None, Some(len), Some(n), Some(nmax)) => clearance_m(len, n, nmax),
            _ => {
                return Err(StructureError::invalid(
                    "rolling layer",
                    "give clearance_m or container_length_m + particles + particles_per_layer",
                ));
            }
        };
        v.push(Box::new(RollingDamper {
            bed_mass_kg: l.bed_mass_kg,
            clearance_m: h,
            smoothing_log_width,
        }));
    }
    Ok(if v.len() == 1 {
        v.pop().expect("one")
    } else {
        Box::new(LayeredDamper { layers: v })
    })
}

/// Vertical damper of approach 3: clearance given, or from container length and particle
/// counts (Eq. 7.4).
fn vertical_model(
    bed_mass_kg: f64,
    clearance: Option<f64>,
    container_length_m: Option<f64>,
    particles: Option<f64>,
    max_particles: Option<f64>,
) -> Result<Box<dyn EffectiveDamper>, StructureError> {
    let h = match (clearance, container_length_m, particles, max_particles) {
        (Some(h), None, None, None) => h,
        (None, Some(l), Some(n), Some(nm)) => crate::formulas::clearance_m(l, n, nm),
        _ => {
            return Err(StructureError::invalid(
                "vertical damper",
                "give clearance_m, or container_length_m, particles and \
                 max_particles (Eq. 7.4)",
            ));
        }
    };
    if !(h >= 0.0 && bed_mass_kg > 0.0) {
        return Err(StructureError::invalid(
            "vertical damper",
            "bed_mass_kg > 0 and clearance ≥ 0",
        ));
    }
    Ok(Box::new(crate::formulas::VerticalDamper {
        bed_mass_kg,
        clearance_m: h,
    }))
}

/// Angle per displacement κ of a powder-friction damper: given, or from the analysed `mode`'s
/// shape values at `angle_points` relative to the value at `point`.
fn powder_friction_angle(
    point: &str,
    mechanism: FrictionMechanism,
    cavity_length_m: f64,
    angle_per_displacement_rad_m: Option<f64>,
    angle_points: Option<&[String]>,
    structure: &ModalStructure,
    mode: usize,
) -> Result<f64, StructureError> {
    Ok(match (angle_per_displacement_rad_m, angle_points) {
        (Some(k), None) => k,
        (None, Some(pts)) => {
            let val = |p: &str| -> Result<f64, StructureError> {
                let v = structure
                    .point(p)
                    .map_err(|e| e.context("powder_friction.angle_points"))?;
                v.get(mode).copied().ok_or_else(|| {
                    StructureError::invalid(
                        "powder_friction",
                        format!("mode {} does not exist", mode + 1),
                    )
                })
            };
            let x = val(point)?;
            if x == 0.0 {
                return Err(StructureError::NodeOfMode {
                    point: point.to_string(),
                    mode: mode + 1,
                });
            }
            match (mechanism, pts.len()) {
                (FrictionMechanism::Bending, 2) => 0.5 * (val(&pts[1])? - val(&pts[0])?) / x,
                (FrictionMechanism::Shear, 4) => {
                    ((val(&pts[2])? - val(&pts[0])?) / cavity_length_m
                        - 0.5 * (val(&pts[1])? + val(&pts[3])?))
                        / x
                }
                _ => {
                    return Err(StructureError::invalid(
                        "powder_friction.angle_points",
                        "bending needs [θ_start, θ_end], shear [u_start, θ_start, \
                         u_end, θ_end]",
                    ));
                }
            }
        }
        _ => {
            return Err(StructureError::invalid(
                "powder_friction",
                "give exactly one of angle_per_displacement_rad_m and angle_points",
            ));
        }
    })
}
