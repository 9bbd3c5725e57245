//! ParaView output of a coupled powder run (`pdamp powder run`): the particles and the
//! deformed structure every `run.vtk_interval_s`, as `DIR/particles.pvd` whose frames have two
//! parts, `vtk/powder_NNNNNN.vtp` (points with `radius_m`, `velocity_m_s`, `speed_m_s`) and
//! `vtk/structure_NNNNNN.vtp` (the hex8 mesh's boundary faces as triangles at the deformed
//! node positions, with the point data `displacement_m`).
//!
//! Frames are written at the steps that are multiples of the interval; a resumed run rebuilds
//! the list of the earlier frames from the step it resumes at (they must exist), so the
//! collection equals that of an uninterrupted run.

use crate::couple::Coupled;
use crate::fe::mesh::HexMesh;
use pdamp_dem::math::Vec3;
use pdamp_io::vtk::{PointField, PvdSeries, VtkEncoding};
use std::path::{Path, PathBuf};

/// Why a ParaView frame could not be written (the text starts with `output:`).
#[derive(Debug, thiserror::Error)]
pub enum SnapshotError {
    /// Writing a frame or the collection failed.
    #[error("output: {0}")]
    Vtk(#[from] pdamp_io::vtk::VtkError),
    /// The frame folder could not be created.
    #[error("output: {path}: {source}")]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// The snapshot series of a coupled powder run.
#[derive(Debug)]
pub struct PowderSnapshots {
    dir: PathBuf,
    every_steps: u64,
    dt_s: f64,
    encoding: VtkEncoding,
    series: PvdSeries,
    next_index: usize,
    /// Boundary faces of the mesh as triangles (two per quad).
    triangles: Vec<[u32; 3]>,
}

impl PowderSnapshots {
    /// A series in `dir` (`particles.pvd`, `vtk/`) with a frame every `every_steps` steps of
    /// `dt_s`, for the structure `mesh`.
    pub fn new(dir: &Path, every_steps: u64, dt_s: f64, mesh: &HexMesh) -> Self {
        let triangles = mesh
            .boundary_faces()
            .iter()
            .flat_map(|f| {
                let n = f.nodes.map(|k| k as u32);
                [[n[0], n[1], n[2]], [n[0], n[2], n[3]]]
            })
            .collect();
        PowderSnapshots {
            dir: dir.to_path_buf(),
            every_steps: every_steps.max(1),
            dt_s,
            encoding: VtkEncoding::Binary,
            series: PvdSeries::new(dir.join("particles.pvd")),
            next_index: 0,
            triangles,
        }
    }

    fn files(index: usize) -> Vec<String> {
        vec![
            format!("vtk/powder_{index:06}.vtp"),
            format!("vtk/structure_{index:06}.vtp"),
        ]
    }

    /// Continues a run resumed after step `step` (frames of the multiples of the interval up
    /// to `step` exist).
    pub fn resume_after(&mut self, step: u64) -> Result<(), SnapshotError> {
        let n = (step / self.every_steps + 1) as usize;
        let mut entries = Vec::new();
        for k in 0..n {
            let t = (k as u64 * self.every_steps) as f64 * self.dt_s;
            let t = (t * 1e12).round() / 1e12;
            entries.extend(Self::files(k).into_iter().map(|f| (t, f)));
        }
        self.series = PvdSeries::resume(self.series.path(), entries)?;
        self.next_index = n;
        Ok(())
    }

    /// Writes the frame of step `step` (time `step · dt`) if it is a multiple of the interval.
    pub fn on_step(&mut self, step: u64, c: &Coupled) -> Result<(), SnapshotError> {
        if !step.is_multiple_of(self.every_steps) {
            return Ok(());
        }
        let vtk = self.dir.join("vtk");
        std::fs::create_dir_all(&vtk).map_err(|source| SnapshotError::CreateDir {
            path: vtk.clone(),
            source,
        })?;
        let k = self.next_index;
        let v3 = |a: &[f64; 3]| Vec3::new(a[0], a[1], a[2]);
        let p = &c.world.particles;
        let pos: Vec<Vec3> = p
            .position
            .iter()
            .map(|x| Vec3::new(x.x, x.y, x.z))
            .collect();
        let vel: Vec<Vec3> = p
            .velocity
            .iter()
            .map(|x| Vec3::new(x.x, x.y, x.z))
            .collect();
        let speed: Vec<f64> = vel.iter().map(|v| v.norm()).collect();
        pdamp_io::vtk::write_particles_vtp_with(
            vtk.join(format!("powder_{k:06}.vtp")),
            &pos,
            &p.radius,
            &[
                ("velocity_m_s", PointField::Vector(&vel)),
                ("speed_m_s", PointField::Scalar(&speed)),
            ],
            self.encoding,
        )?;
        let d = &c.dynamics.d;
        let nodes = &c.structure.mesh.nodes;
        let u: Vec<Vec3> = (0..nodes.len())
            .map(|i| Vec3::new(d[3 * i], d[3 * i + 1], d[3 * i + 2]))
            .collect();
        let x: Vec<Vec3> = nodes.iter().zip(&u).map(|(n, u)| v3(n) + u).collect();
        pdamp_io::vtk::write_mesh_vtp_fields(
            vtk.join(format!("structure_{k:06}.vtp")),
            &x,
            &self.triangles,
            &[("displacement_m", PointField::Vector(&u))],
            self.encoding,
        )?;
        self.series
            .add_frame(step as f64 * self.dt_s, &Self::files(k))?;
        self.next_index += 1;
        Ok(())
    }
}
