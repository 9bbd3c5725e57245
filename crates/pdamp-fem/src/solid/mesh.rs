//! Hex8 meshes: structured boxes with a box-shaped cavity (the beam of paper Sect. 2.4, Fig. 1),
//! import of Gmsh `.msh` (format 2.2 and 4.1, ASCII) and Abaqus `.inp` (`C3D8`/`C3D8R`), and the
//! boundary surface (bilinear quads) the solids expose.
//!
//! Node order of an element: $(\xi,\eta,\zeta)$ = (−,−,−), (+,−,−), (+,+,−), (−,+,−), (−,−,+),
//! (+,−,+), (+,+,+), (−,+,+) — the Gmsh/Abaqus convention.

use super::hex8::CORNERS;
use std::collections::HashMap;

/// Local node lists of the six faces of a hex8, ordered so that the normal
/// $(x_1-x_0)\times(x_3-x_0)$ points out of the element.
pub const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 4, 7, 3],
    [1, 2, 6, 5],
    [0, 1, 5, 4],
    [3, 7, 6, 2],
];

/// A mesh of 8-node hexahedra in the reference configuration \[m\].
#[derive(Debug, Clone, Default)]
pub struct HexMesh {
    /// Node coordinates \[m\].
    pub nodes: Vec<[f64; 3]>,
    /// Element connectivity (node indices, order of the module docs).
    pub elements: Vec<[usize; 8]>,
}

/// One boundary face: a bilinear quad with outward normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Face {
    /// Global node indices, counter-clockwise seen from outside.
    pub nodes: [usize; 4],
    /// The element the face belongs to.
    pub element: usize,
}

/// An axis-aligned box `[min, max]` \[m\].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    /// Lower corner \[m\].
    pub min: [f64; 3],
    /// Upper corner \[m\].
    pub max: [f64; 3],
}

impl Aabb {
    /// Volume \[m³\].
    pub fn volume(&self) -> f64 {
        (0..3).map(|k| self.max[k] - self.min[k]).product()
    }
    /// Whether `p` lies in the closed box enlarged by `tol`.
    pub fn contains(&self, p: [f64; 3], tol: f64) -> bool {
        (0..3).all(|k| p[k] >= self.min[k] - tol && p[k] <= self.max[k] + tol)
    }
}

/// Grid coordinates along one axis: breakpoints `0 = b_0 < b_1 < … ` with `n_k` equal elements
/// between `b_k` and `b_{k+1}`.
fn grid_line(breaks: &[f64], divisions: &[usize]) -> Vec<f64> {
    let mut out = vec![breaks[0]];
    for (k, &n) in divisions.iter().enumerate() {
        let (a, b) = (breaks[k], breaks[k + 1]);
        for i in 1..=n {
            out.push(if i == n {
                b
            } else {
                a + (b - a) * i as f64 / n as f64
            });
        }
    }
    out
}

/// Element counts of a structured box-with-cavity mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxMeshDivisions {
    /// Target element edge length in the walls and solid parts \[m\] (at least one element
    /// across every wall).
    pub wall_element_m: f64,
    /// Target element edge length across the cavity span (x and y) \[m\].
    pub core_element_m: f64,
    /// Target element edge length along z over the cavity \[m\].
    pub length_element_m: f64,
}

fn divisions(len: f64, h: f64) -> usize {
    ((len / h).round() as usize).max(1)
}

impl HexMesh {
    /// Structured hex8 mesh of the box `[0, size]` minus the open box `cavity` (no elements
    /// inside it; `None` gives a solid box). The cavity may touch or cross the outer faces
    /// (a tube results when it spans the full length).
    ///
    /// # Panics
    /// If the cavity is not inside `[0, size]` or the sizes are not positive.
    #[track_caller]
    pub fn box_with_cavity(size: [f64; 3], cavity: Option<Aabb>, div: BoxMeshDivisions) -> Self {
        assert!(size.iter().all(|&s| s > 0.0), "box size must be positive");
        let mut lines: Vec<Vec<f64>> = Vec::new();
        for k in 0..3 {
            let h_core = if k == 2 {
                div.length_element_m
            } else {
                div.core_element_m
            };
            match cavity {
                Some(c) => {
                    assert!(c.min[k] >= 0.0 && c.max[k] <= size[k] && c.min[k] < c.max[k]);
                    let mut b = vec![0.0];
                    let mut d = Vec::new();
                    if c.min[k] > 0.0 {
                        b.push(c.min[k]);
                        d.push(divisions(c.min[k], div.wall_element_m));
                    }
                    b.push(c.max[k]);
                    d.push(divisions(c.max[k] - c.min[k], h_core));
                    if c.max[k] < size[k] {
                        b.push(size[k]);
                        let h = if k == 2 {
                            div.length_element_m.min(div.core_element_m)
                        } else {
                            div.wall_element_m
                        };
                        d.push(divisions(size[k] - c.max[k], h));
                    }
                    lines.push(grid_line(&b, &d));
                }
                None => lines.push(grid_line(&[0.0, size[k]], &[divisions(size[k], h_core)])),
            }
        }
        let n = [lines[0].len(), lines[1].len(), lines[2].len()];
        let id = |i: usize, j: usize, k: usize| i + n[0] * (j + n[1] * k);
        let mut used = vec![usize::MAX; n[0] * n[1] * n[2]];
        let mut mesh = HexMesh::default();
        for k in 0..n[2] - 1 {
            for j in 0..n[1] - 1 {
                for i in 0..n[0] - 1 {
                    let c = [
                        0.5 * (lines[0][i] + lines[0][i + 1]),
                        0.5 * (lines[1][j] + lines[1][j + 1]),
                        0.5 * (lines[2][k] + lines[2][k + 1]),
                    ];
                    if cavity.is_some_and(|cv| cv.contains(c, 0.0)) {
                        continue;
                    }
                    let corners = [
                        (i, j, k),
                        (i + 1, j, k),
                        (i + 1, j + 1, k),
                        (i, j + 1, k),
                        (i, j, k + 1),
                        (i + 1, j, k + 1),
                        (i + 1, j + 1, k + 1),
                        (i, j + 1, k + 1),
                    ];
                    let mut e = [0; 8];
                    for (a, &(ii, jj, kk)) in corners.iter().enumerate() {
                        let g = id(ii, jj, kk);
                        if used[g] == usize::MAX {
                            used[g] = mesh.nodes.len();
                            mesh.nodes.push([lines[0][ii], lines[1][jj], lines[2][kk]]);
                        }
                        e[a] = used[g];
                    }
                    mesh.elements.push(e);
                }
            }
        }
        mesh
    }

    /// Boundary faces (faces owned by exactly one element), in element order.
    pub fn boundary_faces(&self) -> Vec<Face> {
        let mut count: HashMap<[usize; 4], (usize, Face)> = HashMap::new();
        let mut order = Vec::new();
        for (e, el) in self.elements.iter().enumerate() {
            for f in HEX_FACES {
                let nodes = [el[f[0]], el[f[1]], el[f[2]], el[f[3]]];
                let mut key = nodes;
                key.sort_unstable();
                let entry = count.entry(key).or_insert_with(|| {
                    order.push(key);
                    (0, Face { nodes, element: e })
                });
                entry.0 += 1;
            }
        }
        order
            .into_iter()
            .filter_map(|k| {
                let (c, f) = count[&k];
                (c == 1).then_some(f)
            })
            .collect()
    }

    /// Indices of the nodes with coordinate `axis` equal to `value` (within `tol`).
    pub fn nodes_on_plane(&self, axis: usize, value: f64, tol: f64) -> Vec<usize> {
        (0..self.nodes.len())
            .filter(|&i| (self.nodes[i][axis] - value).abs() <= tol)
            .collect()
    }

    /// Faces all of whose nodes lie on the plane `x[axis] = value`.
    pub fn faces_on_plane(
        faces: &[Face],
        nodes: &[[f64; 3]],
        axis: usize,
        value: f64,
        tol: f64,
    ) -> Vec<Face> {
        faces
            .iter()
            .copied()
            .filter(|f| {
                f.nodes
                    .iter()
                    .all(|&n| (nodes[n][axis] - value).abs() <= tol)
            })
            .collect()
    }

    /// Total volume from the 2 × 2 × 2 Gauss rule \[m³\].
    pub fn volume(&self) -> f64 {
        let volumes: Vec<f64> = self
            .elements
            .iter()
            .map(|el| {
                super::hex8::element_gauss_points(&self.nodes, el)
                    .iter()
                    .map(|p| p.wdet)
                    .sum()
            })
            .collect();
        volumes.iter().sum()
    }

    /// The node nearest to `p`.
    pub fn nearest_node(&self, p: [f64; 3]) -> usize {
        let d = |i: usize| {
            (0..3)
                .map(|k| (self.nodes[i][k] - p[k]).powi(2))
                .sum::<f64>()
        };
        (0..self.nodes.len())
            .min_by(|&a, &b| d(a).total_cmp(&d(b)))
            .unwrap_or(0)
    }
}

/// Errors of mesh import. Every message names the line (1-based) and, where there is one, the
/// node or element by its id in the file, and says what to fix.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// Malformed file content.
    #[error("line {line}: {message}")]
    Parse {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A section announces more entries than the rest of the file can hold (nothing is
    /// allocated from such a count).
    #[error(
        "line {line}: announces {announced} {what}, but only {left} lines follow; the file is truncated or the count is wrong"
    )]
    AnnouncedSize {
        /// 1-based line of the count.
        line: usize,
        /// The announced count.
        announced: u64,
        /// What is counted (`nodes`, `elements`, `node blocks`, …).
        what: &'static str,
        /// Lines left in the file after the count.
        left: usize,
    },
    /// An element refers to a node the file does not define.
    #[error(
        "line {line}: element {element} references unknown node {node}; define node {node} in the node section or fix the element's connectivity"
    )]
    UnknownNode {
        /// 1-based line of the element.
        line: usize,
        /// Element id in the file.
        element: i64,
        /// The missing node id.
        node: i64,
    },
    /// An element whose Jacobian determinant is not positive at a corner or Gauss point.
    #[error(
        "line {line}: element {element} is {kind} (det J = {det:.3e} at {at}); hex8 nodes must be ordered (−,−,−), (+,−,−), (+,+,−), (−,+,−), then the same on the top face, with positive volume — reorder its nodes or remove the collapsed element"
    )]
    BadElement {
        /// 1-based line of the element.
        line: usize,
        /// Element id in the file.
        element: i64,
        /// `inverted` (det J < 0) or `degenerate` (det J ≈ 0).
        kind: &'static str,
        /// The offending determinant (in the file's units, before scaling).
        det: f64,
        /// Where: `corner k (node id)` or `Gauss point q`.
        at: String,
    },
    /// The scale factor is not a finite positive number.
    #[error("scale: must be finite and positive, got {0}")]
    BadScale(f64),
    /// The file has no hex8 elements.
    #[error("no hexahedral (8-node) elements found")]
    NoHexes,
    /// A node of a built mesh has a non-finite coordinate ([`HexMesh::validate`]).
    #[error("mesh: node {node} has a non-finite coordinate {coordinates:?}")]
    NonFiniteNode {
        /// 0-based node index.
        node: usize,
        /// Its coordinates.
        coordinates: [f64; 3],
    },
    /// An element of a built mesh refers to a node index beyond the node list
    /// ([`HexMesh::validate`]).
    #[error("mesh: element {element} references node {node}, the mesh has {nodes}")]
    NodeOutOfRange {
        /// 0-based element index.
        element: usize,
        /// The node index it refers to.
        node: usize,
        /// Number of nodes of the mesh.
        nodes: usize,
    },
    /// An element of a built mesh with a non-positive Jacobian determinant
    /// ([`HexMesh::validate`]).
    #[error("mesh: element {element} is {kind} (det J = {det:.3e} at {at})")]
    InvalidElement {
        /// 0-based element index.
        element: usize,
        /// `inverted` (det J < 0) or `degenerate` (det J ≈ 0).
        kind: &'static str,
        /// The offending determinant.
        det: f64,
        /// Where: `corner k` or `Gauss point q`.
        at: String,
    },
}

fn perr(line: usize, message: impl Into<String>) -> MeshError {
    MeshError::Parse {
        line: line + 1,
        message: message.into(),
    }
}

fn nums<T: std::str::FromStr>(s: &str, line: usize) -> Result<Vec<T>, MeshError> {
    s.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse::<T>().map_err(|_| {
                perr(
                    line,
                    format!("cannot parse {:?}", t.chars().take(40).collect::<String>()),
                )
            })
        })
        .collect()
}

/// Parses a node line `id x y z …` (0-based line `l`): an integer id and three finite
/// coordinates.
fn node_line(s: &str, l: usize) -> Result<(i64, [f64; 3]), MeshError> {
    let mut it = s
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty());
    let id = it
        .next()
        .ok_or_else(|| perr(l, "node line needs id x y z"))?;
    let id: i64 = id.parse().map_err(|_| {
        perr(
            l,
            format!(
                "node id {:?} is not an integer",
                id.chars().take(40).collect::<String>()
            ),
        )
    })?;
    let rest: Vec<&str> = it.take(3).collect();
    if rest.len() < 3 {
        return Err(perr(l, format!("node {id}: line needs id x y z")));
    }
    let mut x = [0.0; 3];
    for k in 0..3 {
        let v: f64 = rest[k].parse().map_err(|_| {
            perr(
                l,
                format!(
                    "node {id}: cannot parse coordinate {:?}",
                    rest[k].chars().take(40).collect::<String>()
                ),
            )
        })?;
        if !v.is_finite() {
            return Err(perr(
                l,
                format!(
                    "node {id}: coordinate {} is not finite ({v}); give finite coordinates",
                    ["x", "y", "z"][k]
                ),
            ));
        }
        x[k] = v;
    }
    Ok((id, x))
}

/// Nodes by id with the 0-based line that defined them; a second definition is refused.
#[derive(Default)]
struct NodeTable(HashMap<i64, ([f64; 3], usize)>);

impl NodeTable {
    fn insert(&mut self, id: i64, x: [f64; 3], l: usize) -> Result<(), MeshError> {
        if let Some((_, first)) = self.0.insert(id, (x, l)) {
            return Err(perr(
                l,
                format!(
                    "node {id} is defined twice (first on line {}); node ids must be unique",
                    first + 1
                ),
            ));
        }
        Ok(())
    }
}

/// A hex8 element as read: id, node ids, 0-based line.
struct RawHex {
    id: i64,
    nodes: [i64; 8],
    line: usize,
}

/// Jacobian determinant of a hex8 with corners `x` at the parametric point `xi`.
pub fn jacobian_det(x: &[[f64; 3]; 8], xi: [f64; 3]) -> f64 {
    let (_, dxi) = super::hex8::shape(xi);
    let mut j = [[0.0; 3]; 3];
    for a in 0..8 {
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += dxi[a][r] * x[a][c];
            }
        }
    }
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

/// Checks that a hex8 with corners `x` has a positive Jacobian determinant at its 8 corners
/// and its 8 Gauss points (relative to its size: below 1e-10 of (largest corner distance)³/8
/// counts as degenerate). Returns `(kind, det, where)` of the first failure: `where` is
/// `Ok(corner)` or `Err(gauss point)`.
pub fn check_hex(x: &[[f64; 3]; 8]) -> Result<(), (&'static str, f64, Result<usize, usize>)> {
    let size = (1..8)
        .map(|a| {
            (0..3)
                .map(|k| (x[a][k] - x[0][k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0f64, f64::max);
    let tiny = 1e-10 * size.powi(3) / 8.0;
    let g = 0.577_350_269_189_625_8;
    let points = CORNERS.iter().enumerate().map(|(a, c)| (*c, Ok(a))).chain(
        CORNERS
            .iter()
            .enumerate()
            .map(|(q, c)| ([c[0] * g, c[1] * g, c[2] * g], Err(q))),
    );
    for (xi, at) in points {
        let det = jacobian_det(x, xi);
        if !(det > tiny) {
            let kind = if det < -tiny {
                "inverted"
            } else {
                "degenerate"
            };
            return Err((kind, det, at));
        }
    }
    Ok(())
}

impl HexMesh {
    /// Checks finite coordinates, node indices in range and a positive Jacobian of every
    /// element (see [`check_hex`]); the error names the element (0-based index).
    pub fn validate(&self) -> Result<(), MeshError> {
        if let Some(i) = self
            .nodes
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite()))
        {
            return Err(MeshError::NonFiniteNode {
                node: i,
                coordinates: self.nodes[i],
            });
        }
        for (e, el) in self.elements.iter().enumerate() {
            if let Some(&n) = el.iter().find(|&&n| n >= self.nodes.len()) {
                return Err(MeshError::NodeOutOfRange {
                    element: e,
                    node: n,
                    nodes: self.nodes.len(),
                });
            }
            let x = el.map(|n| self.nodes[n]);
            if let Err((kind, det, at)) = check_hex(&x) {
                let at = match at {
                    Ok(a) => format!("corner {a}"),
                    Err(q) => format!("Gauss point {q}"),
                };
                return Err(MeshError::InvalidElement {
                    element: e,
                    kind,
                    det,
                    at,
                });
            }
        }
        Ok(())
    }
}

/// Compacts a mesh given by node ids: keeps nodes used by elements, scales coordinates,
/// checks every element's Jacobian.
fn compact(nodes: &NodeTable, elems: &[RawHex], scale: f64) -> Result<HexMesh, MeshError> {
    if elems.is_empty() {
        return Err(MeshError::NoHexes);
    }
    let mut map: HashMap<i64, usize> = HashMap::new();
    let mut mesh = HexMesh::default();
    for el in elems {
        let mut e = [0; 8];
        let mut x = [[0.0; 3]; 8];
        for (a, id) in el.nodes.iter().enumerate() {
            let next = mesh.nodes.len();
            let idx = *map.entry(*id).or_insert(next);
            if idx == next {
                let (p, l) = nodes.0.get(id).ok_or(MeshError::UnknownNode {
                    line: el.line + 1,
                    element: el.id,
                    node: *id,
                })?;
                let q = [p[0] * scale, p[1] * scale, p[2] * scale];
                if q.iter().any(|v| !v.is_finite()) {
                    return Err(perr(
                        *l,
                        format!("node {id}: coordinates times the scale {scale} are not finite"),
                    ));
                }
                mesh.nodes.push(q);
            }
            e[a] = idx;
            x[a] = nodes.0[id].0;
        }
        if let Err((kind, det, at)) = check_hex(&x) {
            let at = match at {
                Ok(a) => format!("corner {a} (node {})", el.nodes[a]),
                Err(q) => format!("Gauss point {q}"),
            };
            return Err(MeshError::BadElement {
                line: el.line + 1,
                element: el.id,
                kind,
                det,
                at,
            });
        }
        mesh.elements.push(e);
    }
    Ok(mesh)
}

/// A count announced on 0-based line `l`, checked against the `left` lines that follow (each
/// entry takes at least `per_entry` lines).
fn announced(
    v: i64,
    l: usize,
    what: &'static str,
    left: usize,
    per_entry: usize,
) -> Result<usize, MeshError> {
    if v < 0 {
        return Err(perr(l, format!("negative number of {what} ({v})")));
    }
    let n = v as u64;
    if n.saturating_mul(per_entry as u64) > left as u64 {
        return Err(MeshError::AnnouncedSize {
            line: l + 1,
            announced: n,
            what,
            left,
        });
    }
    Ok(n as usize)
}

/// Reads a Gmsh ASCII mesh (format 2.2 or 4.1); keeps hex8 elements (type 5). Coordinates are
/// multiplied by `scale` (e.g. 1e-3 for a mesh in mm). Refused with the line: non-finite
/// coordinates, duplicate node ids, unknown nodes, inverted or degenerate elements, and counts
/// the rest of the file cannot hold (nothing is allocated from an announced count).
pub fn read_gmsh(text: &str, scale: f64) -> Result<HexMesh, MeshError> {
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(MeshError::BadScale(scale));
    }
    let lines: Vec<&str> = text.lines().collect();
    let line = |l: usize| line_at(&lines, l);
    let mut version = 2.2;
    let mut nodes = NodeTable::default();
    let mut elems = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        match lines[i].trim() {
            "$MeshFormat" => {
                version = nums::<f64>(line(i + 1), i + 1)?
                    .first()
                    .copied()
                    .unwrap_or(2.2);
                if !(2.0..5.0).contains(&version) {
                    return Err(perr(
                        i + 1,
                        format!(
                            "Gmsh format {version} is not supported; export as 2.2 or 4.1 ASCII"
                        ),
                    ));
                }
                i += 2;
            }
            "$Nodes" if version < 4.0 => i = gmsh_nodes_v2(&lines, i, &mut nodes)?,
            "$Nodes" => i = gmsh_nodes_v4(&lines, i, &mut nodes)?,
            "$Elements" if version < 4.0 => i = gmsh_elements_v2(&lines, i, &mut elems)?,
            "$Elements" => i = gmsh_elements_v4(&lines, i, &mut elems)?,
            _ => i += 1,
        }
    }
    compact(&nodes, &elems, scale)
}

/// Line `l` of the file, empty past its end.
fn line_at<'a>(lines: &[&'a str], l: usize) -> &'a str {
    lines.get(l).copied().unwrap_or("")
}

/// Lines of the file after line `l`.
fn lines_left(lines: &[&str], l: usize) -> usize {
    lines.len().saturating_sub(l + 1)
}

/// The `$Nodes` section of format 2.2 starting at line `i` (a count, then `id x y z` lines);
/// returns the line after it.
fn gmsh_nodes_v2(lines: &[&str], i: usize, nodes: &mut NodeTable) -> Result<usize, MeshError> {
    let h = nums::<i64>(line_at(lines, i + 1), i + 1)?;
    let n = announced(
        h.first().copied().unwrap_or(0),
        i + 1,
        "nodes",
        lines_left(lines, i + 1),
        1,
    )?;
    for k in 0..n {
        let l = i + 2 + k;
        let (id, x) = node_line(line_at(lines, l), l)?;
        nodes.insert(id, x, l)?;
    }
    Ok(i + 2 + n)
}

/// The `$Nodes` section of format 4.1 starting at line `i` (node blocks: a header, the tags,
/// then the coordinates); returns the line after it.
fn gmsh_nodes_v4(lines: &[&str], i: usize, nodes: &mut NodeTable) -> Result<usize, MeshError> {
    let h = nums::<i64>(line_at(lines, i + 1), i + 1)?;
    let blocks = announced(
        h.first().copied().unwrap_or(0),
        i + 1,
        "node blocks",
        lines_left(lines, i + 1),
        1,
    )?;
    let mut l = i + 2;
    for _ in 0..blocks {
        let b = nums::<i64>(line_at(lines, l), l)?;
        if b.len() < 4 {
            return Err(perr(
                l,
                "node block header needs entityDim entityTag parametric numNodes",
            ));
        }
        let n = announced(b[3], l, "nodes in the block", lines_left(lines, l), 2)?;
        let mut tags = Vec::new();
        for k in 0..n {
            let v = nums::<i64>(line_at(lines, l + 1 + k), l + 1 + k)?;
            tags.push(
                *v.first()
                    .ok_or_else(|| perr(l + 1 + k, "missing node tag"))?,
            );
        }
        for (k, t) in tags.iter().enumerate() {
            let ll = l + 1 + n + k;
            let (_, x) = node_line(&format!("{t} {}", line_at(lines, ll)), ll)?;
            nodes.insert(*t, x, ll)?;
        }
        l += 1 + 2 * n;
    }
    Ok(l)
}

/// The `$Elements` section of format 2.2 starting at line `i`, keeping the hex8 elements (type
/// 5, after their tags); returns the line after it.
fn gmsh_elements_v2(lines: &[&str], i: usize, elems: &mut Vec<RawHex>) -> Result<usize, MeshError> {
    let h = nums::<i64>(line_at(lines, i + 1), i + 1)?;
    let n = announced(
        h.first().copied().unwrap_or(0),
        i + 1,
        "elements",
        lines_left(lines, i + 1),
        1,
    )?;
    for k in 0..n {
        let l = i + 2 + k;
        let v = nums::<i64>(line_at(lines, l), l)?;
        if v.len() >= 3 && v[1] == 5 {
            let nt = usize::try_from(v[2]).map_err(|_| perr(l, "negative number of tags"))?;
            let c = nt
                .checked_add(3)
                .and_then(|s| v.get(s..s.checked_add(8)?))
                .ok_or_else(|| perr(l, format!("element {}: hex8 needs 8 nodes", v[0])))?;
            elems.push(RawHex {
                id: v[0],
                nodes: c.try_into().map_err(|_| perr(l, "hex8 needs 8 nodes"))?,
                line: l,
            });
        }
    }
    Ok(i + 2 + n)
}

/// The `$Elements` section of format 4.1 starting at line `i` (element blocks; hex8 blocks are
/// kept); returns the line after it.
fn gmsh_elements_v4(lines: &[&str], i: usize, elems: &mut Vec<RawHex>) -> Result<usize, MeshError> {
    let h = nums::<i64>(line_at(lines, i + 1), i + 1)?;
    let blocks = announced(
        h.first().copied().unwrap_or(0),
        i + 1,
        "element blocks",
        lines_left(lines, i + 1),
        1,
    )?;
    let mut l = i + 2;
    for _ in 0..blocks {
        let b = nums::<i64>(line_at(lines, l), l)?;
        if b.len() < 4 {
            return Err(perr(
                l,
                "element block header needs entityDim entityTag elementType numElements",
            ));
        }
        let ty = b[2];
        let n = announced(b[3], l, "elements in the block", lines_left(lines, l), 1)?;
        for k in 0..n {
            let ll = l + 1 + k;
            if ty == 5 {
                let v = nums::<i64>(line_at(lines, ll), ll)?;
                let c = v
                    .get(1..9)
                    .ok_or_else(|| perr(ll, "hex8 needs a tag and 8 nodes"))?;
                elems.push(RawHex {
                    id: v[0],
                    nodes: c.try_into().map_err(|_| perr(ll, "hex8 needs 8 nodes"))?,
                    line: ll,
                });
            }
        }
        l += 1 + n;
    }
    Ok(l)
}

/// Reads the `*NODE` and `*ELEMENT, TYPE=C3D8`/`C3D8R`/`C3D8I` blocks of an Abaqus input file
/// (an element may continue over several lines). Refused with the line: non-finite
/// coordinates, duplicate node ids, elements with more or fewer than 8 nodes, unknown nodes,
/// inverted or degenerate elements.
pub fn read_abaqus_inp(text: &str, scale: f64) -> Result<HexMesh, MeshError> {
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(MeshError::BadScale(scale));
    }
    let mut nodes = NodeTable::default();
    let mut elems = Vec::new();
    #[derive(PartialEq)]
    enum Mode {
        None,
        Node,
        Hex,
    }
    let mut mode = Mode::None;
    let mut pending: Vec<i64> = Vec::new();
    let mut pending_line = 0;
    let unfinished = |pending: &[i64], l: usize| {
        perr(
            l,
            format!(
                "element {}: C3D8 needs an id and 8 nodes, got {} node(s)",
                pending[0],
                pending.len() - 1
            ),
        )
    };
    for (l, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.starts_with("**") || line.is_empty() {
            continue;
        }
        if line.starts_with('*') {
            if !pending.is_empty() {
                return Err(unfinished(&pending, pending_line));
            }
            let up = line.to_ascii_uppercase().replace(' ', "");
            mode = if up.starts_with("*NODE")
                && !up.starts_with("*NODESET")
                && !up.starts_with("*NODEOUTPUT")
            {
                Mode::Node
            } else if up.starts_with("*ELEMENT")
                && (up.contains("TYPE=C3D8,")
                    || up.ends_with("TYPE=C3D8")
                    || up.contains("TYPE=C3D8R")
                    || up.contains("TYPE=C3D8I"))
            {
                Mode::Hex
            } else {
                Mode::None
            };
            continue;
        }
        match mode {
            Mode::Node => {
                let (id, x) = node_line(line, l)?;
                nodes.insert(id, x, l)?;
            }
            Mode::Hex => {
                if pending.is_empty() {
                    pending_line = l;
                }
                pending.extend(nums::<i64>(line, l)?);
                if pending.len() > 9 {
                    return Err(perr(
                        l,
                        format!(
                            "element {}: C3D8 needs an id and 8 nodes, got {} numbers",
                            pending[0],
                            pending.len()
                        ),
                    ));
                }
                if pending.len() == 9 {
                    let mut c = [0i64; 8];
                    c.copy_from_slice(&pending[1..9]);
                    elems.push(RawHex {
                        id: pending[0],
                        nodes: c,
                        line: pending_line,
                    });
                    pending.clear();
                }
            }
            Mode::None => {}
        }
    }
    if !pending.is_empty() {
        return Err(unfinished(&pending, pending_line));
    }
    compact(&nodes, &elems, scale)
}
