//! ParaView snapshots of a run: particles and wall surfaces per frame, and the `.pvd` series
//! that lists them.

use crate::error::RunError;
use pdamp_dem::{Geometry, Vec3, World};
use pdamp_io::vtk::{
    PointField, PvdSeries, VtkEncoding, write_mesh_vtp_with, write_particles_vtp_with,
};
use std::path::{Path, PathBuf};

/// Writes the particles and all mesh-like walls of `world` as VTK files into `dir`
/// (compressed binary; see [`write_snapshot_with`]).
pub fn write_snapshot(
    world: &World,
    dir: &Path,
    index: usize,
) -> Result<PathBuf, pdamp_io::vtk::VtkError> {
    write_snapshot_with(world, dir, index, VtkEncoding::default())
}

/// Writes the particles and all mesh-like walls of `world` as VTK files into `dir` with the
/// array encoding `encoding` (`output.vtk_format`).
pub fn write_snapshot_with(
    world: &World,
    dir: &Path,
    index: usize,
    encoding: VtkEncoding,
) -> Result<PathBuf, pdamp_io::vtk::VtkError> {
    let p = &world.particles;
    let name = format!("particles_{index:06}.vtp");
    let speed: Vec<f64> = p.velocity.iter().map(|v| v.norm()).collect();
    let mat: Vec<u32> = p.material.iter().map(|&m| m as u32).collect();
    let ids: Vec<u32> = p.id.clone();
    write_particles_vtp_with(
        dir.join(&name),
        &p.position,
        &p.radius,
        &[
            ("velocity_m_s", PointField::Vector(&p.velocity)),
            (
                "angular_velocity_rad_s",
                PointField::Vector(&p.angular_velocity),
            ),
            ("speed_m_s", PointField::Scalar(&speed)),
            ("material", PointField::Int(&mat)),
            ("id", PointField::Int(&ids)),
        ],
        encoding,
    )?;
    for (bi, b) in world.bodies.iter().enumerate() {
        for (wi, w) in b.walls.iter().enumerate() {
            if let Some((verts, tris)) = wall_surface(&w.geometry) {
                let world_verts: Vec<Vec3> =
                    verts.iter().map(|v| b.state.point_to_world(v)).collect();
                write_mesh_vtp_with(
                    dir.join(format!("wall_{bi}_{wi}_{index:06}.vtp")),
                    &world_verts,
                    &tris,
                    encoding,
                )?;
            }
        }
    }
    Ok(PathBuf::from("vtk").join(name))
}

/// A ParaView series of DEM snapshots (particles and every wall with a surface) written every
/// `every_steps` steps of a time loop: `DIR/NAME.pvd` with the files in `DIR/SUBDIR/`. A run
/// resumed at a step continues the series: the earlier frames are those of the earlier
/// multiples of `every_steps` (checked to exist), so no state beyond the step is needed.
#[derive(Debug)]
pub struct SnapshotSeries {
    out: PathBuf,
    subdir: String,
    every_steps: u64,
    encoding: VtkEncoding,
    series: PvdSeries,
    next_index: usize,
}

impl SnapshotSeries {
    /// A series `out/pvd_name` with frames in `out/subdir/`, one every `every_steps` (≥ 1).
    pub fn new(
        out: &Path,
        pvd_name: &str,
        subdir: &str,
        every_steps: u64,
        encoding: VtkEncoding,
    ) -> Self {
        SnapshotSeries {
            out: out.to_path_buf(),
            subdir: subdir.to_string(),
            every_steps: every_steps.max(1),
            encoding,
            series: PvdSeries::new(out.join(pvd_name)),
            next_index: 0,
        }
    }

    /// Steps between frames for a snapshot interval of `interval_s` at time step `dt_s`
    /// (`None`: no snapshots, `interval_s` ≤ 0).
    pub fn every_steps_for(interval_s: f64, dt_s: f64) -> Option<u64> {
        (interval_s > 0.0 && dt_s > 0.0).then(|| ((interval_s / dt_s).round() as u64).max(1))
    }

    fn files(&self, world: &World, index: usize) -> Vec<String> {
        snapshot_files(world, index)
            .into_iter()
            .map(|f| format!("{}/{}", self.subdir, f.trim_start_matches("vtk/")))
            .collect()
    }

    /// Continues a run resumed after step `step` (the frames of the steps `0, every, 2·every,
    /// … ≤ step`, at `k·every·dt_s`, were written by the interrupted run and must exist).
    pub fn resume_after(&mut self, step: u64, dt_s: f64, world: &World) -> Result<(), RunError> {
        let n = (step / self.every_steps + 1) as usize;
        let mut entries = Vec::new();
        for k in 0..n {
            let t = (k as u64 * self.every_steps) as f64 * dt_s;
            let t = (t * 1e12).round() / 1e12;
            entries.extend(self.files(world, k).into_iter().map(|f| (t, f)));
        }
        self.series = PvdSeries::resume(self.series.path(), entries).map_err(RunError::output)?;
        self.next_index = n;
        Ok(())
    }

    /// Writes the frame of step `step` at time `time_s` if `step` is a multiple of the
    /// interval (call it for step 0 too).
    pub fn on_step(&mut self, step: u64, time_s: f64, world: &World) -> Result<(), RunError> {
        if !step.is_multiple_of(self.every_steps) {
            return Ok(());
        }
        let dir = self.out.join(&self.subdir);
        std::fs::create_dir_all(&dir).map_err(|e| {
            RunError::output(pdamp_io::csv::CsvError::Io {
                path: dir.clone(),
                source: e,
            })
        })?;
        let index = self.next_index;
        write_snapshot_with(world, &dir, index, self.encoding).map_err(RunError::output)?;
        let files = self.files(world, index);
        self.series
            .add_frame(time_s, &files)
            .map_err(RunError::output)?;
        self.next_index += 1;
        Ok(())
    }
}

/// The files of snapshot `index` relative to the output directory (`vtk/particles_….vtp`
/// and `vtk/wall_<body>_<wall>_….vtp` of every wall with a surface), as
/// [`write_snapshot`] writes them: the parts of one frame of `particles.pvd`.
pub fn snapshot_files(world: &World, index: usize) -> Vec<String> {
    let mut v = vec![format!("vtk/particles_{index:06}.vtp")];
    for (bi, b) in world.bodies.iter().enumerate() {
        for (wi, w) in b.walls.iter().enumerate() {
            if wall_surface(&w.geometry).is_some() {
                v.push(format!("vtk/wall_{bi}_{wi}_{index:06}.vtp"));
            }
        }
    }
    v
}

/// A triangulated surface of a wall for display (boxes, cylinders, meshes; planes are skipped).
pub fn wall_surface(g: &Geometry) -> Option<(Vec<Vec3>, Vec<[u32; 3]>)> {
    match g {
        Geometry::Mesh(m) => Some((m.vertices().to_vec(), m.faces().to_vec())),
        Geometry::BoxInside(b) => {
            let m = pdamp_dem::walls::TriMesh::box_inside(b.center_m, b.half_extents_m);
            Some((m.vertices().to_vec(), m.faces().to_vec()))
        }
        Geometry::CylinderInside(c) => Some(cylinder_surface(
            c.base_center_m,
            c.axis,
            c.radius_m,
            c.length_m,
        )),
        Geometry::CylinderOutside(c) => Some(cylinder_surface(
            c.base_center_m,
            c.axis,
            c.radius_m,
            c.length_m,
        )),
        Geometry::Plane(_) => None,
    }
}

fn cylinder_surface(base: Vec3, axis: Vec3, r: f64, l: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let a = axis.normalize();
    let t = if a.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let u = a.cross(&t).normalize();
    let v = a.cross(&u);
    let k = 48;
    let mut verts = Vec::new();
    let mut tris = Vec::new();
    for s in 0..k {
        let ph = 2.0 * std::f64::consts::PI * s as f64 / k as f64;
        let d = (u * ph.cos() + v * ph.sin()) * r;
        verts.push(base + d);
        verts.push(base + d + a * l);
    }
    verts.push(base);
    verts.push(base + a * l);
    let (cb, ct) = (2 * k as u32, 2 * k as u32 + 1);
    for s in 0..k as u32 {
        let n = (s + 1) % k as u32;
        tris.push([2 * s, 2 * n, 2 * s + 1]);
        tris.push([2 * n, 2 * n + 1, 2 * s + 1]);
        tris.push([cb, 2 * n, 2 * s]);
        tris.push([ct, 2 * s + 1, 2 * n + 1]);
    }
    (verts, tris)
}
