//! ParaView output in VTK XML format: particles and meshes as PolyData (`.vtp`) and time series
//! as collections (`.pvd`). Every file is written atomically ([`crate::atomic`]).
//!
//! Particles are points with one vertex cell each and point data arrays, among them `radius_m`.
//! To draw spheres in ParaView apply *Glyph* with glyph type *Sphere*, *Scale Array* = `radius_m`
//! and *Scale Factor* = 2 (the sphere source has radius 0.5), *Glyph Mode* = *All Points*.
//!
//! Data arrays are written as raw binary appended to the file and compressed with zlib
//! ([`VtkEncoding::Binary`], the default and what ParaView itself writes: exact, about a fifth
//! of the ASCII size for a particle frame), as ASCII (shortest round-trip decimal, readable and
//! diffable) or as inline base64 binary ([`VtkEncoding::Base64`]). The binary forms are exact
//! also for NaN/±∞, which VTK's ASCII reader does not accept.

use crate::atomic::write_atomic_with;
use crate::csv::format_f64;
use pdamp_dem::math::Vec3;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Errors of the VTK writers.
#[derive(Debug, thiserror::Error)]
pub enum VtkError {
    /// I/O failure (the message names the path).
    #[error(transparent)]
    Io(#[from] io::Error),
    /// An array has a different length than the number of points.
    #[error("array '{name}' has {found} entries, expected {expected}")]
    LengthMismatch {
        /// Array name.
        name: String,
        /// Number of points.
        expected: usize,
        /// Length of the array.
        found: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// Triangle number.
        triangle: usize,
        /// Offending vertex index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// An array name is empty or used twice.
    #[error("invalid or duplicate array name '{0}'")]
    InvalidName(String),
    /// A time value of a `.pvd` entry is not finite.
    #[error("time value {0} is not finite")]
    InvalidTime(f64),
}

/// Encoding of the data arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VtkEncoding {
    /// `format="appended"`: little-endian raw binary in the file's `<AppendedData
    /// encoding="raw">` section, zlib-compressed in blocks of [`BLOCK_BYTES`]
    /// (`compressor="vtkZLibDataCompressor"`, UInt64 block headers), as VTK's own XML writers
    /// do by default.
    #[default]
    Binary,
    /// `format="ascii"` with shortest round-trip decimal numbers.
    Ascii,
    /// `format="binary"`: inline base64 of a UInt64 byte count followed by little-endian data.
    Base64,
}

/// Uncompressed bytes per compressed block of [`VtkEncoding::Binary`] (VTK's default).
pub const BLOCK_BYTES: usize = 1 << 15;

/// zlib-compresses `data` the way VTK's XML readers expect for `header_type="UInt64"`:
/// the header `[blocks, block size, size of the last block (0: full), compressed size of
/// each block]` as UInt64, followed by the compressed blocks.
fn compressed_blocks(data: &[u8]) -> io::Result<Vec<u8>> {
    use flate2::{Compression, write::ZlibEncoder};
    let blocks: Vec<&[u8]> = data.chunks(BLOCK_BYTES).collect();
    let mut header = Vec::with_capacity(8 * (3 + blocks.len()));
    let mut body = Vec::new();
    header.extend_from_slice(&(blocks.len() as u64).to_le_bytes());
    header.extend_from_slice(&(BLOCK_BYTES as u64).to_le_bytes());
    header.extend_from_slice(&((data.len() % BLOCK_BYTES) as u64).to_le_bytes());
    for b in &blocks {
        let mut e = ZlibEncoder::new(Vec::with_capacity(b.len() / 2), Compression::fast());
        e.write_all(b)?;
        let c = e.finish()?;
        header.extend_from_slice(&(c.len() as u64).to_le_bytes());
        body.extend_from_slice(&c);
    }
    header.extend_from_slice(&body);
    Ok(header)
}

/// A point data array for [`write_particles_vtp`], one entry per particle.
#[derive(Debug, Clone, Copy)]
pub enum PointField<'a> {
    /// Scalars (Float64), e.g. `speed_m_s`.
    Scalar(&'a [f64]),
    /// 3-vectors (Float64, 3 components), e.g. `velocity_m_s`.
    Vector(&'a [Vec3]),
    /// Unsigned integers (UInt32), e.g. `id`, `material`.
    Int(&'a [u32]),
}

impl PointField<'_> {
    fn len(&self) -> usize {
        match self {
            PointField::Scalar(v) => v.len(),
            PointField::Vector(v) => v.len(),
            PointField::Int(v) => v.len(),
        }
    }
}

/// Escapes `& < > " '` for use in an XML attribute value.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && c != '\t' => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard base64 with padding.
fn base64(data: &[u8]) -> String {
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for chunk in data.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(B64[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Numeric payload of one data array.
enum Values<'a> {
    F64(&'a [f64]),
    Vec3(&'a [Vec3]),
    U32(&'a [u32]),
    I64(Vec<i64>),
}

impl Values<'_> {
    fn vtk_type(&self) -> &'static str {
        match self {
            Values::F64(_) | Values::Vec3(_) => "Float64",
            Values::U32(_) => "UInt32",
            Values::I64(_) => "Int64",
        }
    }

    fn components(&self) -> usize {
        if matches!(self, Values::Vec3(_)) {
            3
        } else {
            1
        }
    }

    fn ascii(&self, w: &mut dyn Write) -> io::Result<()> {
        let mut s = String::new();
        let flush = |s: &mut String, w: &mut dyn Write, force: bool| -> io::Result<()> {
            if force || s.len() > 1 << 16 {
                w.write_all(s.as_bytes())?;
                s.clear();
            }
            Ok(())
        };
        let mut count = 0usize;
        let mut sep = |s: &mut String| {
            s.push(if count == 0 { '\n' } else { ' ' });
            count = (count + 1) % 6;
        };
        match self {
            Values::F64(v) => {
                for &x in *v {
                    sep(&mut s);
                    format_f64(x, &mut s);
                    flush(&mut s, w, false)?;
                }
            }
            Values::Vec3(v) => {
                for p in *v {
                    sep(&mut s);
                    format_f64(p.x, &mut s);
                    s.push(' ');
                    format_f64(p.y, &mut s);
                    s.push(' ');
                    format_f64(p.z, &mut s);
                    flush(&mut s, w, false)?;
                }
            }
            Values::U32(v) => {
                for x in *v {
                    sep(&mut s);
                    s.push_str(&x.to_string());
                    flush(&mut s, w, false)?;
                }
            }
            Values::I64(v) => {
                for x in v {
                    sep(&mut s);
                    s.push_str(&x.to_string());
                    flush(&mut s, w, false)?;
                }
            }
        }
        s.push('\n');
        flush(&mut s, w, true)
    }

    fn bytes(&self) -> Vec<u8> {
        let mut b = Vec::new();
        match self {
            Values::F64(v) => v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes())),
            Values::Vec3(v) => v
                .iter()
                .flat_map(|p| p.iter())
                .for_each(|x| b.extend_from_slice(&x.to_le_bytes())),
            Values::U32(v) => v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes())),
            Values::I64(v) => v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes())),
        }
        b
    }
}

/// Writes one `<DataArray>`; with [`VtkEncoding::Binary`] its compressed data go to
/// `appended` (written by [`appended_section`] at the end of the file).
fn data_array(
    w: &mut dyn Write,
    indent: &str,
    name: Option<&str>,
    values: &Values<'_>,
    enc: VtkEncoding,
    appended: &mut Vec<u8>,
) -> io::Result<()> {
    write!(w, "{indent}<DataArray type=\"{}\"", values.vtk_type())?;
    if let Some(n) = name {
        write!(w, " Name=\"{}\"", xml_escape(n))?;
    }
    if values.components() > 1 {
        write!(w, " NumberOfComponents=\"{}\"", values.components())?;
    }
    match enc {
        VtkEncoding::Binary => {
            writeln!(w, " format=\"appended\" offset=\"{}\"/>", appended.len())?;
            appended.extend_from_slice(&compressed_blocks(&values.bytes())?);
            Ok(())
        }
        VtkEncoding::Ascii => {
            write!(w, " format=\"ascii\">")?;
            values.ascii(w)?;
            writeln!(w, "{indent}</DataArray>")
        }
        VtkEncoding::Base64 => {
            let data = values.bytes();
            let mut block = (data.len() as u64).to_le_bytes().to_vec();
            block.extend_from_slice(&data);
            writeln!(w, " format=\"binary\">")?;
            writeln!(w, "{}", base64(&block))?;
            writeln!(w, "{indent}</DataArray>")
        }
    }
}

fn header(w: &mut dyn Write, kind: &str, enc: VtkEncoding) -> io::Result<()> {
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    let compressor = if enc == VtkEncoding::Binary {
        " compressor=\"vtkZLibDataCompressor\""
    } else {
        ""
    };
    writeln!(
        w,
        "<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"{compressor}>"
    )
}

/// Closes the file: the `<AppendedData>` section with the arrays' raw bytes (if any) and
/// `</VTKFile>`.
fn appended_section(w: &mut dyn Write, appended: &[u8]) -> io::Result<()> {
    if !appended.is_empty() {
        // The data begin right after the underscore; offsets count from there.
        write!(w, "  <AppendedData encoding=\"raw\">\n   _")?;
        w.write_all(appended)?;
        writeln!(w, "\n  </AppendedData>")?;
    }
    writeln!(w, "</VTKFile>")
}

/// Writes particles as VTK PolyData (compressed binary, [`VtkEncoding::Binary`]): `Points`,
/// one `Verts` cell per particle and the point data `radius_m` plus `point_data`. See
/// [`write_particles_vtp_with`].
pub fn write_particles_vtp(
    path: impl AsRef<Path>,
    positions: &[Vec3],
    radii: &[f64],
    point_data: &[(&str, PointField<'_>)],
) -> Result<(), VtkError> {
    write_particles_vtp_with(path, positions, radii, point_data, VtkEncoding::default())
}

/// Writes particles as VTK PolyData with the given array encoding. All arrays must have one
/// entry per position; names must be unique, non-empty and differ from `radius_m`.
pub fn write_particles_vtp_with(
    path: impl AsRef<Path>,
    positions: &[Vec3],
    radii: &[f64],
    point_data: &[(&str, PointField<'_>)],
    encoding: VtkEncoding,
) -> Result<(), VtkError> {
    let n = positions.len();
    if radii.len() != n {
        return Err(VtkError::LengthMismatch {
            name: "radius_m".into(),
            expected: n,
            found: radii.len(),
        });
    }
    let mut names = vec!["radius_m"];
    for (name, field) in point_data {
        if name.trim().is_empty() || names.contains(name) {
            return Err(VtkError::InvalidName((*name).to_string()));
        }
        names.push(name);
        if field.len() != n {
            return Err(VtkError::LengthMismatch {
                name: (*name).to_string(),
                expected: n,
                found: field.len(),
            });
        }
    }
    write_atomic_with(path, |w| {
        header(w, "PolyData", encoding)?;
        let mut app = Vec::new();
        writeln!(w, "  <PolyData>")?;
        writeln!(
            w,
            "    <Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
        )?;
        writeln!(w, "      <PointData Scalars=\"radius_m\">")?;
        let ind = "        ";
        data_array(
            w,
            ind,
            Some("radius_m"),
            &Values::F64(radii),
            encoding,
            &mut app,
        )?;
        for (name, field) in point_data {
            let values = match field {
                PointField::Scalar(v) => Values::F64(v),
                PointField::Vector(v) => Values::Vec3(v),
                PointField::Int(v) => Values::U32(v),
            };
            data_array(w, ind, Some(name), &values, encoding, &mut app)?;
        }
        writeln!(w, "      </PointData>")?;
        writeln!(w, "      <Points>")?;
        data_array(
            w,
            ind,
            Some("Points"),
            &Values::Vec3(positions),
            encoding,
            &mut app,
        )?;
        writeln!(w, "      </Points>")?;
        writeln!(w, "      <Verts>")?;
        data_array(
            w,
            ind,
            Some("connectivity"),
            &Values::I64((0..n as i64).collect()),
            encoding,
            &mut app,
        )?;
        data_array(
            w,
            ind,
            Some("offsets"),
            &Values::I64((1..=n as i64).collect()),
            encoding,
            &mut app,
        )?;
        writeln!(w, "      </Verts>")?;
        writeln!(w, "    </Piece>")?;
        writeln!(w, "  </PolyData>")?;
        appended_section(w, &app)
    })?;
    Ok(())
}

/// Writes a triangle mesh (walls, containers) as VTK PolyData with `Polys` (compressed
/// binary, [`VtkEncoding::Binary`]).
pub fn write_mesh_vtp(
    path: impl AsRef<Path>,
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
) -> Result<(), VtkError> {
    write_mesh_vtp_with(path, vertices, triangles, VtkEncoding::default())
}

/// Writes a triangle mesh as VTK PolyData with the given array encoding.
pub fn write_mesh_vtp_with(
    path: impl AsRef<Path>,
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    encoding: VtkEncoding,
) -> Result<(), VtkError> {
    write_mesh_vtp_fields(path, vertices, triangles, &[], encoding)
}

/// Writes a triangle mesh as VTK PolyData with point data (one entry per vertex, e.g. the
/// `displacement_m` of a deformed structure) and the given array encoding.
pub fn write_mesh_vtp_fields(
    path: impl AsRef<Path>,
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    point_data: &[(&str, PointField<'_>)],
    encoding: VtkEncoding,
) -> Result<(), VtkError> {
    let mut names: Vec<&str> = Vec::new();
    for (name, field) in point_data {
        if name.trim().is_empty() || names.contains(name) {
            return Err(VtkError::InvalidName((*name).to_string()));
        }
        names.push(name);
        if field.len() != vertices.len() {
            return Err(VtkError::LengthMismatch {
                name: (*name).to_string(),
                expected: vertices.len(),
                found: field.len(),
            });
        }
    }
    for (t, tri) in triangles.iter().enumerate() {
        if let Some(&index) = tri.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(VtkError::IndexOutOfRange {
                triangle: t,
                index,
                vertices: vertices.len(),
            });
        }
    }
    let (nv, nt) = (vertices.len(), triangles.len());
    write_atomic_with(path, |w| {
        header(w, "PolyData", encoding)?;
        let mut app = Vec::new();
        writeln!(w, "  <PolyData>")?;
        writeln!(
            w,
            "    <Piece NumberOfPoints=\"{nv}\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"{nt}\">"
        )?;
        let ind = "        ";
        if !point_data.is_empty() {
            writeln!(w, "      <PointData>")?;
            for (name, field) in point_data {
                let values = match field {
                    PointField::Scalar(v) => Values::F64(v),
                    PointField::Vector(v) => Values::Vec3(v),
                    PointField::Int(v) => Values::U32(v),
                };
                data_array(w, ind, Some(name), &values, encoding, &mut app)?;
            }
            writeln!(w, "      </PointData>")?;
        }
        writeln!(w, "      <Points>")?;
        data_array(
            w,
            ind,
            Some("Points"),
            &Values::Vec3(vertices),
            encoding,
            &mut app,
        )?;
        writeln!(w, "      </Points>")?;
        writeln!(w, "      <Polys>")?;
        let conn: Vec<i64> = triangles
            .iter()
            .flat_map(|t| t.iter().map(|&i| i64::from(i)))
            .collect();
        data_array(
            w,
            ind,
            Some("connectivity"),
            &Values::I64(conn),
            encoding,
            &mut app,
        )?;
        data_array(
            w,
            ind,
            Some("offsets"),
            &Values::I64((1..=nt as i64).map(|k| 3 * k).collect()),
            encoding,
            &mut app,
        )?;
        writeln!(w, "      </Polys>")?;
        writeln!(w, "    </Piece>")?;
        writeln!(w, "  </PolyData>")?;
        appended_section(w, &app)
    })?;
    Ok(())
}

/// A ParaView time series (`.pvd` collection). Each [`add`](Self::add) rewrites the whole file
/// atomically, so a killed run still leaves a valid series of the frames written so far.
#[derive(Debug, Clone)]
pub struct PvdSeries {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdSeries {
    /// A new, empty series to be written to `path` (nothing is written until the first `add`).
    pub fn new(path: impl AsRef<Path>) -> Self {
        PvdSeries {
            path: path.as_ref().to_path_buf(),
            entries: Vec::new(),
        }
    }

    /// A series that continues with the frames `entries` (from a checkpoint); rewrites the file.
    /// Every frame of `entries` must still exist next to the `.pvd` (a resumed run would
    /// otherwise list frames that are gone).
    pub fn resume(path: impl AsRef<Path>, entries: Vec<(f64, String)>) -> Result<Self, VtkError> {
        let dir = path.as_ref().parent().unwrap_or(Path::new(""));
        if let Some((t, f)) = entries.iter().find(|(_, f)| !dir.join(f).is_file()) {
            return Err(VtkError::Io(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!(
                    "the checkpoint lists the frame {} (t = {t} s) but it is missing: the outputs do not match the checkpoint; rerun with --overwrite",
                    dir.join(f).display()
                ),
            )));
        }
        let s = PvdSeries {
            path: path.as_ref().to_path_buf(),
            entries,
        };
        if !s.entries.is_empty() {
            s.write()?;
        }
        Ok(s)
    }

    /// Appends a frame at `time_s` whose data file is `file`, relative to the `.pvd`'s
    /// directory (e.g. `particles_000042.vtp`), and rewrites the collection.
    pub fn add(&mut self, time_s: f64, file: impl Into<String>) -> Result<(), VtkError> {
        if !time_s.is_finite() {
            return Err(VtkError::InvalidTime(time_s));
        }
        // Clean times for ParaView: a clock summed step by step carries float noise
        // (0.005000000000000001 s); rounded to the picosecond (far below any DEM step).
        let time_s = (time_s * 1e12).round() / 1e12;
        self.entries.push((time_s, file.into()));
        self.write()
    }

    /// Appends a frame made of several parts (e.g. the particles and every wall) at `time_s`
    /// and rewrites the collection once; ParaView shows the parts together.
    pub fn add_frame(&mut self, time_s: f64, files: &[String]) -> Result<(), VtkError> {
        if !time_s.is_finite() {
            return Err(VtkError::InvalidTime(time_s));
        }
        let time_s = (time_s * 1e12).round() / 1e12;
        self.entries
            .extend(files.iter().map(|f| (time_s, f.clone())));
        self.write()
    }

    /// The frames so far as `(time_s, relative file name)`.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// Path of the `.pvd` file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes the collection (atomically).
    pub fn write(&self) -> Result<(), VtkError> {
        write_atomic_with(&self.path, |w| {
            writeln!(w, "<?xml version=\"1.0\"?>")?;
            writeln!(
                w,
                "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">"
            )?;
            writeln!(w, "  <Collection>")?;
            let mut t = String::new();
            // Several files at one time are the parts of one frame (particles, walls, …).
            let mut part = 0usize;
            for (k, (time, file)) in self.entries.iter().enumerate() {
                part = if k > 0 && self.entries[k - 1].0 == *time {
                    part + 1
                } else {
                    0
                };
                t.clear();
                format_f64(*time, &mut t);
                writeln!(
                    w,
                    "    <DataSet timestep=\"{t}\" group=\"\" part=\"{part}\" file=\"{}\"/>",
                    xml_escape(file)
                )?;
            }
            writeln!(w, "  </Collection>")?;
            writeln!(w, "</VTKFile>")
        })?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn test_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("pdamp-io-vtk-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    /// Minimal well-formedness check: balanced, properly nested tags with quoted attributes and
    /// no stray `<` / `&` in text. Returns the element names in document order.
    fn check_xml(s: &str) -> Vec<String> {
        let mut stack: Vec<String> = Vec::new();
        let mut names = Vec::new();
        let mut rest = s;
        assert!(rest.starts_with("<?xml"), "missing prolog");
        rest = &rest[rest.find("?>").unwrap() + 2..];
        let mut root_seen = false;
        while let Some(i) = rest.find('<') {
            let text = &rest[..i];
            for (k, _) in text.match_indices('&') {
                let ent = &text[k..];
                assert!(
                    ["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"]
                        .iter()
                        .any(|e| ent.starts_with(e))
                );
            }
            if stack.is_empty() {
                assert!(text.trim().is_empty(), "text outside root: {text:?}");
            }
            let j = rest[i..].find('>').expect("unterminated tag") + i;
            let tag = &rest[i + 1..j];
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(
                    stack.pop().as_deref(),
                    Some(name.trim()),
                    "mismatched close"
                );
            } else {
                let self_closing = tag.ends_with('/');
                let body = tag.trim_end_matches('/');
                let name = body.split_whitespace().next().unwrap().to_string();
                // Attributes: name="value" pairs.
                let attrs = body[name.len()..].trim();
                let quotes = attrs.matches('"').count();
                assert_eq!(quotes % 2, 0, "unbalanced quotes in <{tag}>");
                assert!(!attrs.contains('<'));
                if stack.is_empty() {
                    assert!(!root_seen, "two roots");
                    root_seen = true;
                }
                names.push(name.clone());
                if !self_closing {
                    stack.push(name);
                }
            }
            rest = &rest[j + 1..];
        }
        assert!(rest.trim().is_empty());
        assert!(stack.is_empty(), "unclosed {stack:?}");
        assert!(root_seen);
        names
    }

    fn attr(s: &str, name: &str) -> String {
        let k = s.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
        s[k..k + s[k..].find('"').unwrap()].to_string()
    }

    fn b64_decode(s: &str) -> Vec<u8> {
        let val = |c: u8| B64.iter().position(|&b| b == c).unwrap() as u32;
        let bytes: Vec<u8> = s.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
        let mut out = Vec::new();
        for q in bytes.chunks(4) {
            let pad = q.iter().filter(|&&c| c == b'=').count();
            let n = q
                .iter()
                .map(|&c| if c == b'=' { 0 } else { val(c) })
                .fold(0, |a, v| (a << 6) | v);
            out.extend_from_slice(&n.to_be_bytes()[1..4 - pad]);
        }
        out
    }

    #[test]
    fn base64_known_vectors() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
        let data: Vec<u8> = (0..=255).collect();
        assert_eq!(b64_decode(&base64(&data)), data);
    }

    #[test]
    fn particles_ascii() {
        let dir = test_dir("p");
        let p = dir.join("particles_000000.vtp");
        let pos = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1e-3, 2.5e-3, -1.0 / 3.0),
            Vec3::new(1.0, 2.0, 3.0),
        ];
        let radii = [5e-4, 6e-4, 7e-4];
        let vel = vec![Vec3::new(1.0, 0.0, 0.0); 3];
        let speed = [1.0, 0.0, 2.0];
        let ids = [7u32, 8, 9];
        write_particles_vtp_with(
            &p,
            &pos,
            &radii,
            &[
                ("velocity_m_s", PointField::Vector(&vel)),
                ("speed_m_s", PointField::Scalar(&speed)),
                ("id", PointField::Int(&ids)),
            ],
            VtkEncoding::Ascii,
        )
        .unwrap();
        let s = fs::read_to_string(&p).unwrap();
        let names = check_xml(&s);
        assert_eq!(names.iter().filter(|n| *n == "DataArray").count(), 7);
        assert_eq!(s.matches("<DataArray").count(), 7);
        assert_eq!(attr(&s, "NumberOfPoints"), "3");
        assert_eq!(attr(&s, "NumberOfVerts"), "3");
        assert!(s.contains("Name=\"radius_m\""));
        assert!(s.contains("type=\"UInt32\" Name=\"id\""));
        // Positions parse back exactly.
        let k = s.find("Name=\"Points\"").unwrap();
        let body = &s[s[k..].find('>').unwrap() + k + 1..];
        let body = &body[..body.find("</DataArray>").unwrap()];
        let xs: Vec<f64> = body
            .split_whitespace()
            .map(|t| t.parse().unwrap())
            .collect();
        let expect: Vec<f64> = pos.iter().flat_map(|v| v.iter().copied()).collect();
        assert_eq!(xs, expect);
        // No temporary files left.
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        // Errors.
        assert!(matches!(
            write_particles_vtp(&p, &pos, &radii[..2], &[]),
            Err(VtkError::LengthMismatch {
                expected: 3,
                found: 2,
                ..
            })
        ));
        assert!(matches!(
            write_particles_vtp(
                &p,
                &pos,
                &radii,
                &[("radius_m", PointField::Scalar(&speed))]
            ),
            Err(VtkError::InvalidName(_))
        ));
        assert!(matches!(
            write_particles_vtp(&p, &pos, &radii, &[("x", PointField::Int(&ids[..1]))]),
            Err(VtkError::LengthMismatch { .. })
        ));
        // Empty set is valid.
        write_particles_vtp_with(&p, &[], &[], &[], VtkEncoding::Ascii).unwrap();
        let s = fs::read_to_string(&p).unwrap();
        check_xml(&s);
        assert_eq!(attr(&s, "NumberOfPoints"), "0");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn particles_base64_exact() {
        let dir = test_dir("b");
        let p = dir.join("b.vtp");
        let pos = vec![
            Vec3::new(f64::NAN, 1.0, -0.0),
            Vec3::new(1e-300, f64::INFINITY, 3.0),
        ];
        let radii = [0.1, 0.2];
        write_particles_vtp_with(
            &p,
            &pos,
            &radii,
            &[("name<&>", PointField::Scalar(&radii))],
            VtkEncoding::Base64,
        )
        .unwrap();
        let s = fs::read_to_string(&p).unwrap();
        check_xml(&s);
        assert!(s.contains("Name=\"name&lt;&amp;&gt;\""));
        assert_eq!(s.matches("format=\"binary\"").count(), 5);
        let k = s.find("Name=\"Points\"").unwrap();
        let body = &s[s[k..].find('>').unwrap() + k + 1..];
        let raw = b64_decode(&body[..body.find("</DataArray>").unwrap()]);
        assert_eq!(u64::from_le_bytes(raw[..8].try_into().unwrap()), 48);
        let back: Vec<u64> = raw[8..]
            .chunks(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let expect: Vec<u64> = pos
            .iter()
            .flat_map(|v| v.iter().map(|x| x.to_bits()))
            .collect();
        assert_eq!(back, expect);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn mesh_and_errors() {
        let dir = test_dir("m");
        let p = dir.join("wall.vtp");
        let v = vec![Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()];
        let t = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
        write_mesh_vtp_with(&p, &v, &t, VtkEncoding::Ascii).unwrap();
        let s = fs::read_to_string(&p).unwrap();
        check_xml(&s);
        assert_eq!(attr(&s, "NumberOfPoints"), "4");
        assert_eq!(attr(&s, "NumberOfPolys"), "4");
        assert_eq!(s.matches("<DataArray").count(), 3);
        assert!(s.contains("\n3 6 9 12\n"));
        write_mesh_vtp_with(&p, &v, &t, VtkEncoding::Base64).unwrap();
        check_xml(&fs::read_to_string(&p).unwrap());
        assert!(matches!(
            write_mesh_vtp(&p, &v, &[[0, 1, 4]]),
            Err(VtkError::IndexOutOfRange {
                triangle: 0,
                index: 4,
                vertices: 4
            })
        ));
        let e = write_mesh_vtp(dir.join("no/such/dir.vtp"), &v, &t).unwrap_err();
        assert!(e.to_string().contains("dir.vtp"), "{e}");
        fs::remove_dir_all(&dir).unwrap();
    }

    /// Reads a `format="appended"` array back: header of UInt64 block counts and sizes, then
    /// zlib blocks (what VTK's reader does), as raw little-endian bytes.
    fn appended_array(file: &[u8], name: &str) -> Vec<u8> {
        use std::io::Read;
        let text = String::from_utf8_lossy(file);
        let tag = format!("Name=\"{name}\"");
        let k = text.find(&tag).unwrap();
        let offset: usize = attr(&text[k..], "offset").parse().unwrap();
        let start = file
            .windows(b"encoding=\"raw\">".len())
            .position(|w| w == b"encoding=\"raw\">")
            .unwrap();
        let underscore = start + file[start..].iter().position(|&b| b == b'_').unwrap();
        let data = &file[underscore + 1 + offset..];
        let word = |i: usize| u64::from_le_bytes(data[8 * i..8 * i + 8].try_into().unwrap());
        let (blocks, block, last) = (word(0) as usize, word(1) as usize, word(2) as usize);
        let mut at = 8 * (3 + blocks);
        let mut out = Vec::new();
        for b in 0..blocks {
            let c = word(3 + b) as usize;
            let mut d = Vec::new();
            flate2::read::ZlibDecoder::new(&data[at..at + c])
                .read_to_end(&mut d)
                .unwrap();
            let expect = if b + 1 == blocks && last != 0 {
                last
            } else {
                block
            };
            assert_eq!(d.len(), expect, "block {b} of {name}");
            out.extend_from_slice(&d);
            at += c;
        }
        out
    }

    #[test]
    fn particles_binary_appended_compressed_exact() {
        let dir = test_dir("z");
        let p = dir.join("z.vtp");
        // 5 000 particles: the Points array (120 kB) spans four compressed blocks.
        let n = 5000;
        let pos: Vec<Vec3> = (0..n)
            .map(|k| Vec3::new(k as f64 * 1e-3, (k as f64).sin(), -1.0 / (k as f64 + 3.0)))
            .collect();
        let mut radii = vec![1e-3; n];
        radii[7] = f64::NAN;
        radii[8] = f64::INFINITY;
        let ids: Vec<u32> = (0..n as u32).rev().collect();
        write_particles_vtp(&p, &pos, &radii, &[("id", PointField::Int(&ids))]).unwrap();
        let bytes = fs::read(&p).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.contains("compressor=\"vtkZLibDataCompressor\""));
        assert_eq!(text.matches("format=\"appended\"").count(), 5);
        let f64s = |b: Vec<u8>| -> Vec<u64> {
            b.chunks(8)
                .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
                .collect()
        };
        let expect: Vec<u64> = pos
            .iter()
            .flat_map(|v| v.iter().map(|x| x.to_bits()))
            .collect();
        assert_eq!(f64s(appended_array(&bytes, "Points")), expect);
        let r: Vec<u64> = radii.iter().map(|x| x.to_bits()).collect();
        assert_eq!(f64s(appended_array(&bytes, "radius_m")), r);
        let back: Vec<u32> = appended_array(&bytes, "id")
            .chunks(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(back, ids);
        let offsets = f64s(appended_array(&bytes, "offsets"));
        assert_eq!(offsets.first(), Some(&1));
        assert_eq!(offsets.last(), Some(&(n as u64)));
        // Smaller than the ASCII file by far.
        let a = dir.join("a.vtp");
        write_particles_vtp_with(
            &a,
            &pos,
            &radii,
            &[("id", PointField::Int(&ids))],
            VtkEncoding::Ascii,
        )
        .unwrap();
        let ascii = fs::metadata(&a).unwrap().len() as usize;
        assert!(bytes.len() * 2 < ascii, "{} vs {ascii}", bytes.len());
        // An empty array is a header with zero blocks; a mesh as well.
        write_particles_vtp(&p, &[], &[], &[]).unwrap();
        assert!(appended_array(&fs::read(&p).unwrap(), "Points").is_empty());
        let v = vec![Vec3::zeros(), Vec3::x(), Vec3::y()];
        write_mesh_vtp(&p, &v, &[[0, 1, 2]]).unwrap();
        let m = fs::read(&p).unwrap();
        assert_eq!(f64s(appended_array(&m, "connectivity")), vec![0, 1, 2]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn pvd_series_valid_after_each_add() {
        let dir = test_dir("s");
        let mut series = PvdSeries::new(dir.join("particles.pvd"));
        for k in 0..3 {
            let file = format!("particles_{k:06}.vtp");
            write_particles_vtp(dir.join(&file), &[Vec3::zeros()], &[1e-3], &[]).unwrap();
            series.add(k as f64 * 2.5e-3, file).unwrap();
            let s = fs::read_to_string(series.path()).unwrap();
            let names = check_xml(&s);
            assert_eq!(names.iter().filter(|n| *n == "DataSet").count(), k + 1);
        }
        let s = fs::read_to_string(series.path()).unwrap();
        assert!(
            s.contains("timestep=\"0.005\" group=\"\" part=\"0\" file=\"particles_000002.vtp\""),
            "{s}"
        );
        assert_eq!(series.entries().len(), 3);
        assert!(matches!(
            series.add(f64::NAN, "x.vtp"),
            Err(VtkError::InvalidTime(_))
        ));
        assert_eq!(series.entries().len(), 3);
        let leftovers = fs::read_dir(&dir)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .contains(".tmp-")
            })
            .count();
        assert_eq!(leftovers, 0);
        fs::remove_dir_all(&dir).unwrap();
    }
}

#[cfg(test)]
mod pvd_tests {
    #[test]
    fn pvd_times_are_clean() {
        let dir = std::env::temp_dir().join(format!("pdamp-pvd-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut s = super::PvdSeries::new(dir.join("a.pvd"));
        s.add(0.1 + 0.2, "f.vtp").unwrap();
        s.add(0.005000000000000001, "g.vtp").unwrap();
        let text = std::fs::read_to_string(dir.join("a.pvd")).unwrap();
        assert!(text.contains("timestep=\"0.3\""), "{text}");
        assert!(text.contains("timestep=\"0.005\""), "{text}");
        // A frame of three parts: particles and two walls.
        s.add_frame(0.01, &["p.vtp".into(), "w0.vtp".into(), "w1.vtp".into()])
            .unwrap();
        let text = std::fs::read_to_string(dir.join("a.pvd")).unwrap();
        assert!(
            text.contains("timestep=\"0.01\" group=\"\" part=\"2\" file=\"w1.vtp\""),
            "{text}"
        );
        assert!(
            text.contains("timestep=\"0.01\" group=\"\" part=\"0\" file=\"p.vtp\""),
            "{text}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
