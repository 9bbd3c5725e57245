//! STL triangle meshes (binary and ASCII) in and out, via the `stl_io` crate.
//!
//! Reading never panics on malformed input: every failure is an [`StlError`] naming the file.
//! Vertices are welded and the topology is built by [`TriMesh::from_triangles`]; degenerate
//! triangles are rejected with the triangle's index. STL normals are ignored; the orientation
//! comes from the vertex order (counter-clockwise seen from outside the solid), see the
//! orientation notes of [`pdamp_dem::walls::TriMesh`].

use pdamp_dem::math::Vec3;
use pdamp_dem::walls::{MeshError, TriMesh};
use std::io::{Cursor, Read, Seek, Write};
use std::path::{Path, PathBuf};

/// Errors reading or writing STL files.
#[derive(Debug, thiserror::Error)]
pub enum StlError {
    /// The file could not be opened, read or written.
    #[error("cannot access STL file {path}: {source}")]
    Io {
        /// The file (or `<reader>` for streams).
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// The content is not a valid binary or ASCII STL.
    #[error("malformed STL {path}: {message}")]
    Parse {
        /// The file (or `<reader>` for streams).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The triangles do not form a valid mesh (e.g. a degenerate triangle).
    #[error("invalid mesh in STL {path}: {source}")]
    Mesh {
        /// The file (or `<reader>` for streams).
        path: PathBuf,
        /// The mesh error (names the triangle).
        source: MeshError,
    },
}

/// Reads a binary or ASCII STL file into a welded [`TriMesh`].
pub fn read_stl(path: impl AsRef<Path>) -> Result<TriMesh, StlError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| StlError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(bytes, path)
}

/// Reads a binary or ASCII STL from any reader (errors name the source `<reader>`).
pub fn read_stl_from<R: Read>(mut reader: R) -> Result<TriMesh, StlError> {
    let path = Path::new("<reader>");
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|source| StlError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    parse(bytes, path)
}

/// Whether `bytes` has exactly the size of a binary STL with the triangle count of its header.
fn looks_binary(bytes: &[u8]) -> bool {
    if bytes.len() < 84 {
        return false;
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    bytes.len() as u64 == 84 + 50 * n
}

fn parse(mut bytes: Vec<u8>, path: &Path) -> Result<TriMesh, StlError> {
    let perr = |message: String| StlError::Parse {
        path: path.to_path_buf(),
        message,
    };
    // Many exporters write binary files whose 80-byte header starts with "solid"; the size check
    // identifies them, and blanking the (ignored) header keeps stl_io from taking them for ASCII.
    if looks_binary(&bytes) && bytes.starts_with(b"solid") {
        bytes[..5].fill(0);
    }
    if !bytes.starts_with(b"solid") {
        if bytes.len() < 84 {
            return Err(perr(format!(
                "{} bytes is too short for a binary STL and it does not start with \"solid\"",
                bytes.len()
            )));
        }
        if !looks_binary(&bytes) {
            let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]);
            return Err(perr(format!(
                "binary STL header announces {n} triangles ({} bytes) but the file has {} bytes",
                84 + 50 * n as u64,
                bytes.len()
            )));
        }
    }
    let mut cursor = Cursor::new(bytes);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        collect_triangles(&mut cursor)
    }));
    let triangles = match result {
        Ok(Ok(t)) => t,
        Ok(Err(e)) => return Err(perr(e.to_string())),
        Err(_) => return Err(perr("the STL parser failed".to_string())),
    };
    TriMesh::from_triangles(triangles).map_err(|source| StlError::Mesh {
        path: path.to_path_buf(),
        source,
    })
}

fn collect_triangles<R: Read + Seek>(reader: &mut R) -> std::io::Result<Vec<[Vec3; 3]>> {
    let iter = stl_io::create_stl_reader(reader)?;
    let mut out = Vec::new();
    for t in iter {
        let t = t?;
        out.push(
            t.vertices
                .map(|v| Vec3::new(v.0[0] as f64, v.0[1] as f64, v.0[2] as f64)),
        );
    }
    Ok(out)
}

/// Writes `mesh` as a binary STL (single precision, normals from the vertex order), atomically
/// (temporary file in the same folder, then rename).
pub fn write_stl(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<(), StlError> {
    let path = path.as_ref();
    let ioerr = |source| StlError::Io {
        path: path.to_path_buf(),
        source,
    };
    let v = mesh.vertices();
    let f32v = |p: &Vec3| stl_io::Vector::new([p.x as f32, p.y as f32, p.z as f32]);
    let triangles: Vec<stl_io::Triangle> = mesh
        .faces()
        .iter()
        .enumerate()
        .map(|(t, f)| stl_io::Triangle {
            normal: f32v(&mesh.triangle_normal(t)),
            vertices: f.map(|i| f32v(&v[i as usize])),
        })
        .collect();
    let mut buf = Vec::with_capacity(84 + 50 * triangles.len());
    stl_io::write_stl(&mut buf, triangles.iter()).map_err(ioerr)?;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".tmp{}", std::process::id()));
    let tmp = PathBuf::from(tmp);
    let write = || -> std::io::Result<()> {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(&buf)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        ioerr(e)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use pdamp_dem::walls::{Geometry, WallContact};

    fn temp_path(name: &str) -> PathBuf {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        std::env::temp_dir().join(format!("pdamp-stl-{}-{nanos}-{name}", std::process::id()))
    }

    const ASCII_TETRA: &str = "solid tetra
  facet normal 0 0 -1
    outer loop
      vertex 0 0 0
      vertex 0 1 0
      vertex 1 0 0
    endloop
  endfacet
  facet normal 0 -1 0
    outer loop
      vertex 0 0 0
      vertex 1 0 0
      vertex 0 0 1
    endloop
  endfacet
  facet normal -1 0 0
    outer loop
      vertex 0 0 0
      vertex 0 0 1
      vertex 0 1 0
    endloop
  endfacet
  facet normal 0.577 0.577 0.577
    outer loop
      vertex 1 0 0
      vertex 0 1 0
      vertex 0 0 1
    endloop
  endfacet
endsolid tetra
";

    #[test]
    fn stl_ascii_file_is_welded() {
        let path = temp_path("tetra.stl");
        std::fs::write(&path, ASCII_TETRA).unwrap();
        let m = read_stl(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        assert_eq!(
            (m.num_vertices(), m.num_edges(), m.num_triangles()),
            (4, 6, 4)
        );
        // Outward normals of the solid: the bottom face points -z.
        assert!((m.triangle_normal(0) + Vec3::z()).norm() < 1e-12);
        // A sphere below the bottom face touches it (solid obstacle, particles outside).
        let mut out: Vec<WallContact> = Vec::new();
        m.sphere_contacts(&Vec3::new(0.2, 0.2, -0.05), 0.1, 0.0, &mut out);
        assert_eq!(out.len(), 1);
        assert!((out[0].overlap_m - 0.05).abs() < 1e-12);
        assert!((out[0].normal + Vec3::z()).norm() < 1e-12);
    }

    #[test]
    fn stl_binary_roundtrip_box() {
        let m = TriMesh::box_inside(Vec3::new(0.5, 0.25, -1.0), Vec3::new(0.5, 0.25, 0.125));
        let path = temp_path("box.stl");
        write_stl(&path, &m).unwrap();
        let back = read_stl(&path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        assert_eq!(bytes.len(), 84 + 50 * 12);
        assert_eq!(
            (back.num_vertices(), back.num_edges(), back.num_triangles()),
            (8, 18, 12)
        );
        // Values are exact in f32 here, so the mesh is identical.
        assert_eq!(back, m);
        // A binary file whose header starts with "solid" is still read as binary.
        let mut solid_header = bytes.clone();
        solid_header[..6].copy_from_slice(b"solid ");
        let again = read_stl_from(Cursor::new(solid_header)).unwrap();
        assert_eq!(again, m);
    }

    #[test]
    fn stl_malformed_input_is_an_error() {
        let cases: Vec<Vec<u8>> = vec![
            Vec::new(),
            b"solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0\n".to_vec(),
            b"solid x\n facet normal 0 0 1\n outer loop\n vertex a b c\n".to_vec(),
            b"solid x\n garbage\n".to_vec(),
            vec![0u8; 83],
            {
                let mut b = vec![0u8; 84 + 50];
                b[80] = 7; // announces 7 triangles, has 1
                b
            },
            {
                let mut b = vec![0u8; 84];
                b[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
                b
            },
        ];
        for (i, bytes) in cases.into_iter().enumerate() {
            let r = read_stl_from(Cursor::new(bytes));
            assert!(r.is_err(), "case {i} should fail");
        }
        // A binary file with one zero-area triangle: mesh error naming triangle 0.
        let mut b = vec![0u8; 84 + 50];
        b[80] = 1;
        let err = read_stl_from(Cursor::new(b)).unwrap_err();
        assert!(matches!(err, StlError::Mesh { .. }), "{err}");
        assert!(err.to_string().contains("triangle 0"), "{err}");
        // Missing file: I/O error naming the path.
        let path = temp_path("missing.stl");
        let err = read_stl(&path).unwrap_err();
        assert!(err.to_string().contains("missing.stl"), "{err}");
    }

    #[test]
    fn stl_mesh_geometry_serde_roundtrip() {
        let m = TriMesh::box_inside(Vec3::zeros(), Vec3::new(1.0, 2.0, 3.0));
        let g = Geometry::Mesh(m.clone());
        let json = serde_json::to_string(&g).unwrap();
        let back: Geometry = serde_json::from_str(&json).unwrap();
        assert_eq!(back, g);
        let mut a = Vec::new();
        let mut b = Vec::new();
        let x = Vec3::new(0.9, 0.1, -2.5);
        g.sphere_contacts(&x, 0.6, 0.0, &mut a);
        back.sphere_contacts(&x, 0.6, 0.0, &mut b);
        assert_eq!(a, b);
        assert_eq!(a.len(), 2);
        // Analytic walls: normals are normalised on deserialisation.
        let p: Geometry =
            serde_json::from_str(r#"{"type":"plane","point_m":[0,0,0],"normal":[0,3,4]}"#).unwrap();
        match p {
            Geometry::Plane(p) => assert!((p.normal - Vec3::new(0.0, 0.6, 0.8)).norm() < 1e-15),
            _ => unreachable!(),
        }
        let bad = serde_json::from_str::<Geometry>(
            r#"{"type":"cylinder_inside","base_center_m":[0,0,0],"axis":[0,0,0],"radius_m":1,"length_m":1}"#,
        );
        assert!(bad.is_err());
        let bad = serde_json::from_str::<Geometry>(
            r#"{"type":"mesh","vertices":[[0,0,0],[1,0,0],[2,0,0]],"faces":[[0,1,2]]}"#,
        );
        assert!(bad.unwrap_err().to_string().contains("triangle 0"));
    }
}
