//! Fuzz entry points of the readers of this crate (see docs/reliability.md): each takes
//! arbitrary bytes and must return without panicking, hanging or allocating beyond what the
//! input's size suggests. Shared by `tests/fuzz_readers.rs` (CI, [`pdamp_io::fuzz::fuzz_all`])
//! and any cargo-fuzz target.

use std::ops::ControlFlow;

/// Gmsh `.msh` (2.2 and 4.1 ASCII, [`crate::fe::read_gmsh`]); a mesh that reads must pass
/// [`crate::fe::HexMesh::validate`] and give finite boundary faces and volume.
pub fn gmsh(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    for scale in [1e-3, 1.0] {
        if let Ok(m) = crate::fe::read_gmsh(&text, scale) {
            use_mesh(&m);
        }
    }
}

/// Abaqus `.inp` (`*NODE`, `*ELEMENT, TYPE=C3D8…`, [`crate::fe::read_abaqus_inp`]), checked
/// as [`gmsh`].
pub fn abaqus(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    if let Ok(m) = crate::fe::read_abaqus_inp(&text, 1e-3) {
        use_mesh(&m);
    }
}

fn use_mesh(m: &crate::fe::HexMesh) {
    if let Err(e) = m.validate() {
        panic!("a mesh the reader accepted fails validation: {e}");
    }
    if m.elements.len() <= 4096 {
        let v = m.volume();
        assert!(v.is_finite() && v > 0.0, "accepted mesh with volume {v}");
        let _ = m.boundary_faces();
    }
}

/// `pdamp powder run` checkpoints ([`crate::cantilever::inspect_checkpoint`]), also with a
/// valid trailing digest so that mutated payloads reach the decoder; a preparation that
/// decodes and passes its consistency check is continued for a few steps (a crafted state
/// must fail with an error, not a panic).
pub fn powder_checkpoint(bytes: &[u8]) {
    let _ = crate::cantilever::inspect_checkpoint(bytes);
    if bytes.len() > 24 {
        let mut b = bytes[..bytes.len() - 16].to_vec();
        let sum = pdamp_io::checkpoint::digest(&b);
        b.extend_from_slice(sum.as_bytes());
        let _ = crate::cantilever::inspect_checkpoint(&b);
        if let Ok(mut p) = crate::cantilever::decode_preparation(&b)
            && p.particles() <= 2000
        {
            let mut k = 0;
            let _ = p.run(&mut |_, _| {}, &mut |_| {
                k += 1;
                if k >= 20 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            });
        }
    }
}

/// The readers by name (seed corpora in `fuzz/corpus/<name>/`).
pub const TARGETS: [pdamp_io::fuzz::Target; 3] = [
    ("gmsh", gmsh),
    ("abaqus", abaqus),
    ("powder_checkpoint", powder_checkpoint),
];
