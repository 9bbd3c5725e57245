//! The beam's structure: mesh, clamp, load and cavity interface, and its empty-beam modes.

use super::{BeamSpec, LoadSpec};
use crate::couple::Interface;
use crate::fe::{self, Aabb, HexMesh, LoadRamp, Structure, SurfaceLoad};
use pdamp_fem::EigenError;

/// Builds the structure of the scenario: mesh, clamp (z = 0), pressure on x = 0, gravity.
pub fn build_structure(beam: &BeamSpec, load: &LoadSpec, gravity: [f64; 3]) -> (Structure, usize) {
    let mesh = beam.mesh();
    let tol = 1e-9;
    let clamped = mesh.nodes_on_plane(2, 0.0, tol);
    let faces = mesh.boundary_faces();
    let loaded = HexMesh::faces_on_plane(&faces, &mesh.nodes, 0, 0.0, tol);
    let tip = mesh.nearest_node([0.5 * beam.width_m, 0.5 * beam.width_m, beam.length_m]);
    let mut s = Structure::new(mesh, beam.material, &clamped, beam.mass, gravity);
    s.set_kinematics(beam.kinematics);
    s.loads.push(SurfaceLoad {
        faces: loaded,
        traction_pa: [load.pressure_pa, 0.0, 0.0],
        ramp: LoadRamp {
            rise_s: load.rise_s,
            hold_s: load.hold_s,
        },
    });
    (s, tip)
}

/// Interface faces: boundary faces with all nodes on the cavity box surface.
pub fn cavity_interface(s: &Structure, cavity: &Aabb) -> Interface {
    let tol = 1e-9;
    let faces = s
        .mesh
        .boundary_faces()
        .into_iter()
        .filter(|f| {
            f.nodes
                .iter()
                .all(|&n| cavity.contains(s.mesh.nodes[n], tol))
        })
        .collect();
    Interface::new(faces)
}

/// First bending frequencies \[Hz\] of the empty beam (no powder), `count` lowest modes.
pub fn empty_beam_modes(beam: &BeamSpec, count: usize) -> Result<Vec<f64>, EigenError> {
    let (s, _) = build_structure(
        beam,
        &LoadSpec {
            pressure_pa: 0.0,
            rise_s: 1.0,
            hold_s: 0.0,
        },
        [0.0; 3],
    );
    fe::modes::lowest_modes(&s, count).map(|(f, _)| f)
}

/// First bending frequency of the empty beam from piecewise Timoshenko theory (solid bottom,
/// hollow cavity part, solid top) \[Hz\].
pub fn timoshenko_reference(beam: &BeamSpec) -> f64 {
    use crate::fe::beam_theory::{Segment, timoshenko_f1};
    let inner = beam.width_m - 2.0 * beam.wall_thickness_m;
    let segs = [
        Segment {
            length_m: beam.cavity_offset_m,
            outer_m: beam.width_m,
            inner_m: 0.0,
        },
        Segment {
            length_m: beam.cavity_length_m,
            outer_m: beam.width_m,
            inner_m: inner,
        },
        Segment {
            length_m: beam.length_m - beam.cavity_offset_m - beam.cavity_length_m,
            outer_m: beam.width_m,
            inner_m: 0.0,
        },
    ];
    let m = beam.material;
    timoshenko_f1(
        &segs,
        m.youngs_modulus_pa,
        m.poisson_ratio,
        m.density_kg_m3,
        1320,
        &[],
    )
}
