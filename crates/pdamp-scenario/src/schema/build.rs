//! Building the world of a scenario: bodies and walls, particles placed from files, lattices,
//! random insertion or drop-down, and the checks of the built world.

use super::{
    BedFormat, GeometrySpec, MotionSpec, OpenLidSpec, ParticleGroupSpec, PlacementMethod,
    PlacementSpec, Scenario,
};
use crate::InputError;
use pdamp_dem::generate::{
    Layering, Region, grid_packing, random_insertion_clear_of, tight_packing,
};
use pdamp_dem::time_loop::CancelToken;
use pdamp_dem::walls::Geometry;
use pdamp_dem::{BodyState, Integrator, Motion, ParameterError, RigidBody, Vec3, World};
use std::path::Path;
use std::sync::Arc;

/// What a long preparation reports to (`progress(phase, fraction)`) and the stop request it
/// honours.
type Watch<'a> = (&'a mut dyn FnMut(&str, f64), &'a CancelToken);

impl Scenario {
    /// Builds the world: bodies, walls (STL paths relative to `base_dir`), particles placed
    /// and checked for overlaps, and the time step checked against the contact time. A
    /// `drop_down` group is dropped here (its falls are simulated: see
    /// [`Scenario::build_world_with`] for progress and a quick check without it).
    pub fn build_world(&self, base_dir: &Path) -> Result<World, InputError> {
        self.build_world_with(base_dir, Preparation::Full, &mut |_, _| {})
    }

    /// [`Scenario::build_world`] with `mode`: [`Preparation::Check`] checks a `drop_down` group
    /// for fit (its particles' volume against the region) without dropping it, so that the
    /// world lacks those particles; `progress(phase, fraction)` follows the drop-down.
    pub fn build_world_with(
        &self,
        base_dir: &Path,
        mode: Preparation,
        progress: &mut dyn FnMut(&str, f64),
    ) -> Result<World, InputError> {
        self.build_world_reporting(base_dir, mode, progress, &CancelToken::new())
            .map(|(w, _)| w)
    }

    /// [`Scenario::build_world`] whose drop-down stops when `cancel` is cancelled (the world is
    /// then not built: an error names the drop-down).
    pub fn build_world_cancellable(
        &self,
        base_dir: &Path,
        cancel: &CancelToken,
    ) -> Result<World, InputError> {
        self.build_world_reporting(base_dir, Preparation::Full, &mut |_, _| {}, cancel)
            .map(|(w, _)| w)
    }

    /// [`Scenario::build_world_with`], also returning what each drop-down did (one report per
    /// `drop_down` group, in group order); a drop-down stops when `cancel` is cancelled.
    pub fn build_world_reporting(
        &self,
        base_dir: &Path,
        mode: Preparation,
        progress: &mut dyn FnMut(&str, f64),
        cancel: &CancelToken,
    ) -> Result<(World, Vec<pdamp_dem::drop_down::DropDownReport>), InputError> {
        let mut reports = Vec::new();
        let mut world = self.world_with_bodies(base_dir)?;
        let up = -world.gravity_m_s2;
        let up = if up.norm() > 0.0 {
            up.normalize()
        } else {
            Vec3::z()
        };
        let mut group_of: Vec<usize> = Vec::new();
        let mut settled_bed = false;
        let mut bed_from_file = false;
        let mut bed_state = None;
        let mut placeholders: Vec<(u16, Vec<f64>)> = Vec::new();
        for (g, grp) in self.particles.iter().enumerate() {
            let mat = self.material_index(&grp.material, "particles")?;
            let count = grp
                .resolved_count()
                .map_err(|e| e.under(&format!("particles[{g}].")))?;
            let pl = &grp.placement;
            if pl.method == PlacementMethod::File {
                let path = base_dir.join(pl.path.as_ref().ok_or(ParameterError::invalid(
                    "placement.path",
                    "placement.path missing",
                ))?);
                let (bed, state) = self.read_bed_for_group(g, &path, pl, &grp.material)?;
                self.check_bed_against_group(g, &path, &bed, count, grp)?;
                for i in 0..bed.len() {
                    let m = self
                        .material_index(
                            &bed.materials[bed.material[i] as usize],
                            &format!(
                                "particles[{g}].placement.path: particle {i} of {}",
                                path.display()
                            ),
                        )
                        .map_err(|e| {
                            // located at the key, the particle and file only in the message
                            let key = format!("particles[{g}].placement.path");
                            ParameterError::invalid(key, e.to_string())
                        })?;
                    let id = world.add_particle(bed.position_m[i], bed.radius_m[i], m);
                    world.particles.velocity[id] = bed.velocity_m_s[i];
                    world.particles.angular_velocity[id] = bed.angular_velocity_rad_s[i];
                    group_of.push(g);
                }
                settled_bed = true;
                bed_from_file = true;
                bed_state = state;
                continue;
            }
            let radii = grp
                .size
                .sample_n(count, self.simulation.seed.wrapping_add(g as u64));
            let region = pl.region.as_ref().ok_or(ParameterError::invalid(
                "placement.region",
                "placement.region missing",
            ))?;
            let seed = self.simulation.seed.wrapping_add(1000 + g as u64);
            let fix = |e: pdamp_dem::generate::PackingError| {
                InputError::at_with_hint(
                    format!("particles[{g}].placement.region"),
                    e,
                    "; enlarge the region, or lower the particle count, the radius or \
                     placement.gap_m",
                )
            };
            if pl.method == PlacementMethod::DropDown {
                if mode == Preparation::Check {
                    self.check_drop_down_fits(g, region, &radii)?;
                    placeholders.push((mat, radii));
                    continue;
                }
                let dropped = self.drop_down_group(
                    &world,
                    (g, mat),
                    region,
                    &radii,
                    seed,
                    (progress, cancel),
                )?;
                reports.push(dropped.report.clone());
                // Earlier groups settled further under this one.
                for (i, x) in dropped.earlier_position_m.iter().enumerate() {
                    world.particles.position[i] = *x;
                    world.particles.velocity[i] = dropped.earlier_velocity_m_s[i];
                    world.particles.angular_velocity[i] = dropped.earlier_angular_velocity_rad_s[i];
                }
                settled_bed = true;
                let r_max = radii.iter().cloned().fold(0.0, f64::max);
                let order = pdamp_dem::generate::layer_order(&dropped.position_m, 2.0 * r_max);
                for k in order {
                    let id = world.add_particle(dropped.position_m[k], radii[k], mat);
                    world.particles.velocity[id] = dropped.velocity_m_s[k];
                    world.particles.angular_velocity[id] = dropped.angular_velocity_rad_s[k];
                    group_of.push(g);
                }
                continue;
            }
            let pos = packed_positions(&world, pl, region, &radii, seed, &up).map_err(fix)?;
            // Number the group's particles by layers of cells (spatial neighbours close in
            // memory: the DEM's pair loop then finds its partners in cache).
            let r_max = radii.iter().cloned().fold(0.0, f64::max);
            let order = pdamp_dem::generate::layer_order(&pos, 2.0 * r_max);
            for (x, r) in order.iter().map(|&k| (&pos[k], &radii[k])) {
                let id = world.add_particle(*x, *r, mat);
                world.particles.velocity[id] = Vec3::from(grp.initial_velocity_m_s);
                group_of.push(g);
            }
        }
        // A dropped bed or one from a file is at rest with its contacts: it overlaps its
        // neighbours and the walls by its contact deformation (a few 1e-4 of the radius,
        // refused beyond 5 %). A bed dropped here was simulated under the health check: its
        // wall contacts are accepted to the health check's limit of that wall (a soft wall, a
        // coating, may be pressed in deeper: pdamp_dem::health::wall_overlap_limit).
        let tolerance = if settled_bed { 0.05 } else { 1e-9 };
        check_initial_overlaps(&world, &group_of, tolerance)?;
        check_inside_walls(
            &world,
            &group_of,
            self,
            tolerance,
            settled_bed && !bed_from_file,
        )?;
        add_placeholders(&mut world, placeholders);
        if let Some(state) = bed_state {
            // The saved state continues exactly when the bed was made in this container; a bed
            // from another scenario keeps the positions, velocities and spins set above.
            let _ = world.restore_state(state);
        }
        if let Some(skin) = self.simulation.skin_m {
            world.set_skin(skin);
        }
        self.check_time_step(&world)?;
        Ok((world, reports))
    }

    /// The world of the scenario without particles: materials, contact laws, gravity,
    /// integrator, and the bodies with their walls (STL paths relative to `base_dir`).
    fn world_with_bodies(&self, base_dir: &Path) -> Result<World, InputError> {
        let mut model = self.contact.default.clone();
        model.prepare();
        let mut world = World::new(self.materials.clone(), model, self.simulation.time_step_s);
        for p in &self.contact.pairs {
            let a = self.material_index(&p.materials[0], "contact.pairs")?;
            let b = self.material_index(&p.materials[1], "contact.pairs")?;
            world.set_contact_model(a, b, p.model.clone());
        }
        world.gravity_m_s2 = Vec3::from(self.simulation.gravity_m_s2);
        world.integrator = self.simulation.integrator.clone();
        for (bi, b) in self.bodies.iter().enumerate() {
            let motion = match &b.motion {
                MotionSpec::Fixed => Motion::Fixed,
                MotionSpec::Harmonic(h) => Motion::Prescribed(Arc::new(h.clone())),
                MotionSpec::Driven => Motion::Driven,
            };
            let mut body = RigidBody::new(
                &b.name,
                BodyState::at_rest(Vec3::from(b.position_m)),
                motion,
            );
            for (wi, w) in b.walls.iter().enumerate() {
                let mat = self.material_index(&w.material, "walls")?;
                let geometry = match &w.geometry {
                    GeometrySpec::Plane(g) => Geometry::Plane(g.clone()),
                    GeometrySpec::BoxInside(g) => Geometry::BoxInside(g.clone()),
                    GeometrySpec::CylinderInside(g) => Geometry::CylinderInside(g.clone()),
                    GeometrySpec::CylinderOutside(g) => Geometry::CylinderOutside(g.clone()),
                    GeometrySpec::BoxOutside(b) => {
                        if b.half_extents_m
                            .iter()
                            .any(|h| !(*h > 0.0 && h.is_finite()))
                        {
                            return Err(InputError::message(format!(
                                "bodies[{bi}].walls[{wi}].geometry.half_extents_m must be > 0, got {:?}",
                                b.half_extents_m
                            )));
                        }
                        let mut m = pdamp_dem::walls::TriMesh::box_inside(
                            Vec3::from(b.center_m),
                            Vec3::from(b.half_extents_m),
                        );
                        m.flip_normals();
                        Geometry::Mesh(m)
                    }
                    GeometrySpec::Stl(s) => {
                        let path = base_dir.join(&s.path);
                        let mut mesh = pdamp_io::stl::read_stl(&path).map_err(|e| {
                            InputError::at(format!("bodies[{bi}].walls[{wi}].geometry.path"), e)
                        })?;
                        mesh = mesh
                            .transformed(s.scale, Vec3::from(s.translation_m))
                            .map_err(|e| {
                                InputError::at(
                                    format!("bodies[{bi}].walls[{wi}].geometry.scale"),
                                    e,
                                )
                            })?;
                        if s.flip_normals {
                            mesh.flip_normals();
                        }
                        Geometry::Mesh(mesh)
                    }
                };
                body.walls.push(pdamp_dem::Wall {
                    geometry,
                    material: mat,
                    name: w.name.clone(),
                });
            }
            world.add_body(body);
        }
        Ok(world)
    }

    /// The time step against the shortest contact time of the built world (velocity Verlet).
    fn check_time_step(&self, world: &World) -> Result<(), InputError> {
        if !world.particles.is_empty() {
            let tc = world.min_contact_time_s(self.simulation.check_impact_velocity_m_s);
            let ratio = self.simulation.time_step_s / tc;
            if matches!(world.integrator, Integrator::VelocityVerlet)
                && ratio > self.simulation.max_time_step_ratio
            {
                return Err(InputError::message(format!(
                    "simulation.time_step_s = {:.3e} s is {:.2} of the shortest contact time {:.3e} s (impact at {} m/s); \
                     use at most {:.3e} s (max_time_step_ratio = {})",
                    self.simulation.time_step_s,
                    ratio,
                    tc,
                    self.simulation.check_impact_velocity_m_s,
                    self.simulation.max_time_step_ratio * tc,
                    self.simulation.max_time_step_ratio
                )));
            }
        }
        Ok(())
    }
}

/// How much of a bed [`Scenario::build_world_with`] prepares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preparation {
    /// Everything, drop-downs included.
    Full,
    /// Checks only: `drop_down` groups are checked for fit but not dropped (not in the world).
    Check,
}

/// Densest random packing a drop-down can reach (random close packing of equal spheres).
const RANDOM_CLOSE_PACKING: f64 = 0.64;

impl Scenario {
    /// Reads the bed file of group `g` in its format; the native format also gives the saved
    /// state.
    fn read_bed_for_group(
        &self,
        g: usize,
        path: &Path,
        pl: &PlacementSpec,
        material: &str,
    ) -> Result<(pdamp_dem::Bed, Option<pdamp_dem::WorldState>), InputError> {
        let key = format!("particles[{g}].placement.path");
        let format = BedFormat::of(path, pl.format).map_err(|e| InputError::at(&key, e))?;
        let read = || std::fs::read_to_string(path).map_err(|e| InputError::read(&key, path, e));
        let (bed, state) = match format {
            BedFormat::Native => {
                let f = pdamp_io::bed::load_bed(path).map_err(|e| InputError::at(&key, e))?;
                (f.bed, f.state)
            }
            BedFormat::Lammps => {
                let mut bed = pdamp_io::bed_formats::read_lammps_data(&read()?, &pl.type_materials)
                    .map_err(|e| InputError::file(&key, path, e))?;
                if pl.type_materials.is_empty() {
                    bed.materials = vec![material.to_string()];
                    bed.material.iter_mut().for_each(|m| *m = 0);
                }
                (bed, None)
            }
            BedFormat::Csv => (
                pdamp_io::bed_formats::read_bed_csv(&read()?, material)
                    .map_err(|e| InputError::file(&key, path, e))?,
                None,
            ),
        };
        bed.validate()
            .map_err(|e| InputError::file(&key, path, e))?;
        Ok((bed, state))
    }

    /// A bed must have the group's count and radii inside its size distribution.
    fn check_bed_against_group(
        &self,
        g: usize,
        path: &Path,
        bed: &pdamp_dem::Bed,
        count: usize,
        grp: &ParticleGroupSpec,
    ) -> Result<(), InputError> {
        if bed.len() != count {
            return Err(InputError::message(format!(
                "particles[{g}].count: the scenario asks for {count} particles, the bed '{}' has {}; set count = {}",
                path.display(),
                bed.len(),
                bed.len()
            )));
        }
        let (lo, hi) = (grp.size.min_radius_m(), grp.size.max_radius_m());
        if let Some(i) = bed
            .radius_m
            .iter()
            .position(|&r| r < lo * (1.0 - 1e-9) || r > hi * (1.0 + 1e-9))
        {
            return Err(InputError::message(format!(
                "particles[{g}].size: particle {i} of the bed '{}' has radius {:.6e} m, outside the group's size range [{lo:.6e}, {hi:.6e}] m; make the size match the bed",
                path.display(),
                bed.radius_m[i]
            )));
        }
        Ok(())
    }

    /// A drop-down cannot pack denser than random close packing: refuse a group whose solid
    /// volume exceeds 0.64 of the region's volume.
    fn check_drop_down_fits(
        &self,
        g: usize,
        region: &Region,
        radii: &[f64],
    ) -> Result<(), ParameterError> {
        let solid: f64 = radii
            .iter()
            .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
            .sum();
        let v = region.volume_m3();
        if solid > RANDOM_CLOSE_PACKING * v {
            return Err(ParameterError::from_message(format!(
                "particles[{g}].placement.region: the particles' volume {solid:.4e} m³ is {:.2} of the region's {v:.4e} m³, more than a random packing holds ({RANDOM_CLOSE_PACKING}); enlarge the region or lower the count",
                solid / v
            )));
        }
        Ok(())
    }

    /// Drops group `g` into `world` under the filling gravity ([`Scenario::fill_gravity`]).
    fn drop_down_group(
        &self,
        world: &World,
        (g, mat): (usize, u16),
        region: &Region,
        radii: &[f64],
        seed: u64,
        (progress, cancel): Watch<'_>,
    ) -> Result<pdamp_dem::drop_down::DroppedParticles, InputError> {
        self.check_drop_down_fits(g, region, radii)?;
        let pl = &self.particles[g].placement;
        let gravity = self.fill_gravity();
        let rho = world.materials[mat as usize].density_kg_m3;
        let r_mean = radii.iter().sum::<f64>() / radii.len().max(1) as f64;
        let m_mean = 4.0 / 3.0 * std::f64::consts::PI * rho * r_mean.powi(3);
        let spec = pdamp_dem::drop_down::DropDownSpec {
            region: region.clone(),
            max_attempts_per_particle: 1000,
            seed,
            kinetic_energy_per_particle_j: pl
                .round_kinetic_energy_per_particle_j
                .unwrap_or(0.01 * m_mean * gravity.norm() * r_mean),
            max_round_duration_s: pl.max_round_duration_s.unwrap_or(0.5),
            max_rounds: pl.max_rounds.unwrap_or(200),
            open_lid: pl.open_lid.as_ref().map(OpenLidSpec::to_open_lid),
            inlet: pl.inlet.as_ref().map(|i| pdamp_dem::drop_down::Inlet {
                region: i.region.clone(),
                rate_per_s: i.rate_per_s,
                velocity_m_s: Vec3::from(i.velocity_m_s),
            }),
        };
        let mut w = world.clone();
        w.gravity_m_s2 = gravity;
        let total = radii.len().max(1) as f64;
        pdamp_dem::drop_down::drop_down(&w, radii, mat, &spec, |_, placed| {
            progress("drop-down", placed as f64 / total);
            if cancel.is_cancelled() {
                std::ops::ControlFlow::Break(())
            } else {
                std::ops::ControlFlow::Continue(())
            }
        })
        .map_err(|e| InputError::at(format!("particles[{g}].placement"), e))
    }
}

/// Fails if two particles overlap by more than 1e-9 of the smaller radius at the start.
fn check_initial_overlaps(
    world: &World,
    group_of: &[usize],
    tolerance: f64,
) -> Result<(), ParameterError> {
    let p = &world.particles;
    let n = p.len();
    if n < 2 {
        return Ok(());
    }
    // Sort by x and sweep (O(n log n) for reasonable packings).
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| p.position[a].x.total_cmp(&p.position[b].x));
    let r_max = p.max_radius();
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if p.position[j].x - p.position[i].x > 2.0 * r_max {
                break;
            }
            let d = (p.position[i] - p.position[j]).norm();
            let ov = p.radius[i] + p.radius[j] - d;
            if ov > tolerance * p.radius[i].min(p.radius[j]) {
                let (i, j) = (i.min(j), i.max(j));
                let (gi, gj) = (group_of[i], group_of[j]);
                let fix = if gi != gj {
                    format!(
                        "the placement regions of particles[{gi}] and particles[{gj}] overlap; \
                         make them disjoint"
                    )
                } else {
                    "increase placement.gap_m or use another placement method".to_string()
                };
                return Err(ParameterError::from_message(format!(
                    "particles[{gj}].placement: initial overlap of {:.3e} m between particle {} at {:?} and particle {} at {:?}; {fix}",
                    ov,
                    i,
                    p.position[i].as_slice(),
                    j,
                    p.position[j].as_slice()
                )));
            }
        }
    }
    Ok(())
}

/// Fails if a particle starts overlapping a wall or outside a closed container (boxes and
/// cylinders report a particle outside as a deep overlap; open meshes cannot tell).
/// Particles overlapping a wall by more than `tolerance` of their radius are refused; with
/// `health_limits` (a bed dropped under the health check) each wall's health-check limit
/// applies instead.
fn check_inside_walls(
    world: &World,
    group_of: &[usize],
    sc: &Scenario,
    tolerance: f64,
    health_limits: bool,
) -> Result<(), InputError> {
    let p = &world.particles;
    let mut contacts = Vec::new();
    for (bi, b) in world.bodies.iter().enumerate() {
        let pose = pdamp_dem::BodyState::at_rest(Vec3::from(sc.bodies[bi].position_m));
        for (wi, w) in b.walls.iter().enumerate() {
            for (i, &g) in group_of.iter().enumerate() {
                contacts.clear();
                let x = pose.to_body(&p.position[i]);
                w.geometry
                    .sphere_contacts(&x, p.radius[i], 0.0, &mut contacts);
                let limit = if health_limits {
                    pdamp_dem::health::wall_overlap_limit(
                        &world.materials[p.material[i] as usize],
                        &world.materials[w.material as usize],
                    )
                } else {
                    tolerance
                };
                if let Some(c) = contacts.iter().find(|c| c.overlap_m > limit * p.radius[i]) {
                    let outside = c.overlap_m > p.radius[i];
                    return Err(InputError::message(format!(
                        "particles[{g}].placement.region: particle {i} at {:?} m {} wall '{}' of body '{}' (bodies[{bi}].walls[{wi}]) by {:.3e} m; \
                         keep the region inside the container, at least one radius ({:.3e} m) away from its walls",
                        p.position[i].as_slice(),
                        if outside { "lies outside" } else { "overlaps" },
                        w.name,
                        b.name,
                        c.overlap_m,
                        p.radius[i]
                    )));
                }
            }
        }
    }
    Ok(())
}

/// Lattice or random positions of a group's particles in `region` (random ones clear of the
/// walls of `world`).
fn packed_positions(
    world: &World,
    pl: &PlacementSpec,
    region: &Region,
    radii: &[f64],
    seed: u64,
    up: &Vec3,
) -> Result<Vec<Vec3>, pdamp_dem::generate::PackingError> {
    let up = *up;
    match pl.method {
        PlacementMethod::Grid => grid_packing(region, radii, pl.gap_m, &up),
        PlacementMethod::Tight => tight_packing(region, radii, pl.gap_m, &up),
        _ => {
            let layering = pl.layer_height_m.map(|h| Layering {
                up,
                layer_height_m: h,
            });
            let scratch = std::cell::RefCell::new(Vec::new());
            let blocked = |x: &Vec3, r: f64| {
                world
                    .wall_overlap(x, r, &mut scratch.borrow_mut())
                    .is_some()
            };
            random_insertion_clear_of(region, radii, seed, 1000, layering.as_ref(), &blocked)
        }
    }
}

/// Check mode: the drop-down groups' particles far away in a row (for counts, masses and the
/// time-step check), not dropped.
fn add_placeholders(world: &mut World, placeholders: Vec<(u16, Vec<f64>)>) {
    let far = world
        .bodies
        .iter()
        .flat_map(|b| b.walls.iter().filter_map(|w| w.geometry.bounding_box()))
        .fold(1.0f64, |a, (lo, hi)| a.max(lo.amax()).max(hi.amax()));
    let pitch = 4.0
        * placeholders
            .iter()
            .flat_map(|(_, r)| r.iter())
            .fold(0.0f64, |a, &b| a.max(b));
    let mut x = 1e3 * far;
    for (mat, radii) in placeholders {
        for r in radii {
            world.add_particle(Vec3::new(x, 0.0, 0.0), r, mat);
            x += pitch;
        }
    }
}
