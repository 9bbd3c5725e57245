//! Hex8 meshes: structured boxes with a box-shaped cavity (the beam of paper Sect. 2.4, Fig. 1),
//! import of Gmsh `.msh` (format 2.2 and 4.1, ASCII) and Abaqus `.inp` (`C3D8`/`C3D8R`), and the
//! boundary surface (bilinear quads) the solids expose.
//!
//! Node order of an element: $(\xi,\eta,\zeta)$ = (−,−,−), (+,−,−), (+,+,−), (−,+,−), (−,−,+),
//! (+,−,+), (+,+,+), (−,+,+) — the Gmsh/Abaqus convention.

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

/// A mesh of 8-node hexahedra in the reference configuration [m].
#[derive(Debug, Clone, Default)]
pub struct HexMesh {
    /// Node coordinates [m].
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

/// An axis-aligned box `[min, max]` [m].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    /// Lower corner [m].
    pub min: [f64; 3],
    /// Upper corner [m].
    pub max: [f64; 3],
}

impl Aabb {
    /// Volume [m³].
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
    /// Target element edge length in the walls and solid parts [m] (at least one element
    /// across every wall).
    pub wall_element_m: f64,
    /// Target element edge length across the cavity span (x and y) [m].
    pub core_element_m: f64,
    /// Target element edge length along z over the cavity [m].
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

    /// Total volume from the 2 × 2 × 2 Gauss rule [m³].
    pub fn volume(&self) -> f64 {
        super::svk::element_volumes(self).iter().sum()
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

/// Errors of mesh import.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// Malformed file content.
    #[error("line {line}: {message}")]
    Parse {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file has no hex8 elements.
    #[error("no hexahedral (8-node) elements found")]
    NoHexes,
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
            t.parse::<T>()
                .map_err(|_| perr(line, format!("cannot parse {t:?}")))
        })
        .collect()
}

/// Compacts a mesh given by node ids: keeps nodes used by elements, scales coordinates.
fn compact(
    nodes: &HashMap<i64, [f64; 3]>,
    elems: &[[i64; 8]],
    scale: f64,
) -> Result<HexMesh, MeshError> {
    if elems.is_empty() {
        return Err(MeshError::NoHexes);
    }
    let mut map: HashMap<i64, usize> = HashMap::new();
    let mut mesh = HexMesh::default();
    for el in elems {
        let mut e = [0; 8];
        for (a, id) in el.iter().enumerate() {
            let next = mesh.nodes.len();
            let idx = *map.entry(*id).or_insert(next);
            if idx == next {
                let p = nodes
                    .get(id)
                    .ok_or_else(|| perr(0, format!("element references unknown node {id}")))?;
                mesh.nodes.push([p[0] * scale, p[1] * scale, p[2] * scale]);
            }
            e[a] = idx;
        }
        mesh.elements.push(e);
    }
    Ok(mesh)
}

/// Reads a Gmsh ASCII mesh (format 2.2 or 4.1); keeps hex8 elements (type 5). Coordinates are
/// multiplied by `scale` (e.g. 1e-3 for a mesh in mm).
pub fn read_gmsh(text: &str, scale: f64) -> Result<HexMesh, MeshError> {
    let lines: Vec<&str> = text.lines().collect();
    let mut version = 2.2;
    let mut nodes = HashMap::new();
    let mut elems = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        match lines[i].trim() {
            "$MeshFormat" => {
                version = nums::<f64>(lines.get(i + 1).copied().unwrap_or(""), i + 1)?
                    .first()
                    .copied()
                    .unwrap_or(2.2);
                i += 2;
            }
            "$Nodes" if version < 4.0 => {
                let n = nums::<usize>(lines.get(i + 1).copied().unwrap_or(""), i + 1)?
                    .first()
                    .copied()
                    .unwrap_or(0);
                for k in 0..n {
                    let l = i + 2 + k;
                    let v = nums::<f64>(
                        lines
                            .get(l)
                            .copied()
                            .ok_or_else(|| perr(l, "missing node"))?,
                        l,
                    )?;
                    if v.len() < 4 {
                        return Err(perr(l, "node line needs id x y z"));
                    }
                    nodes.insert(v[0] as i64, [v[1], v[2], v[3]]);
                }
                i += 2 + n;
            }
            "$Nodes" => {
                let h = nums::<usize>(lines.get(i + 1).copied().unwrap_or(""), i + 1)?;
                let blocks = h.first().copied().unwrap_or(0);
                let mut l = i + 2;
                for _ in 0..blocks {
                    let b = nums::<usize>(
                        lines
                            .get(l)
                            .copied()
                            .ok_or_else(|| perr(l, "missing block"))?,
                        l,
                    )?;
                    let n = *b.get(3).ok_or_else(|| perr(l, "bad node block header"))?;
                    let tags: Vec<i64> = (0..n)
                        .map(|k| {
                            nums::<i64>(lines.get(l + 1 + k).copied().unwrap_or(""), l + 1 + k)
                                .map(|v| v.first().copied().unwrap_or(-1))
                        })
                        .collect::<Result<_, _>>()?;
                    for (k, t) in tags.iter().enumerate() {
                        let ll = l + 1 + n + k;
                        let v = nums::<f64>(
                            lines
                                .get(ll)
                                .copied()
                                .ok_or_else(|| perr(ll, "missing coordinates"))?,
                            ll,
                        )?;
                        if v.len() < 3 {
                            return Err(perr(ll, "need x y z"));
                        }
                        nodes.insert(*t, [v[0], v[1], v[2]]);
                    }
                    l += 1 + 2 * n;
                }
                i = l;
            }
            "$Elements" if version < 4.0 => {
                let n = nums::<usize>(lines.get(i + 1).copied().unwrap_or(""), i + 1)?
                    .first()
                    .copied()
                    .unwrap_or(0);
                for k in 0..n {
                    let l = i + 2 + k;
                    let v = nums::<i64>(
                        lines
                            .get(l)
                            .copied()
                            .ok_or_else(|| perr(l, "missing element"))?,
                        l,
                    )?;
                    if v.len() >= 3 && v[1] == 5 {
                        let nt = v[2] as usize;
                        let c = v
                            .get(3 + nt..3 + nt + 8)
                            .ok_or_else(|| perr(l, "hex8 needs 8 nodes"))?;
                        elems.push(c.try_into().map_err(|_| perr(l, "hex8 needs 8 nodes"))?);
                    }
                }
                i += 2 + n;
            }
            "$Elements" => {
                let h = nums::<usize>(lines.get(i + 1).copied().unwrap_or(""), i + 1)?;
                let blocks = h.first().copied().unwrap_or(0);
                let mut l = i + 2;
                for _ in 0..blocks {
                    let b = nums::<i64>(
                        lines
                            .get(l)
                            .copied()
                            .ok_or_else(|| perr(l, "missing block"))?,
                        l,
                    )?;
                    if b.len() < 4 {
                        return Err(perr(l, "bad element block header"));
                    }
                    let (ty, n) = (b[2], b[3] as usize);
                    for k in 0..n {
                        let ll = l + 1 + k;
                        if ty == 5 {
                            let v = nums::<i64>(
                                lines
                                    .get(ll)
                                    .copied()
                                    .ok_or_else(|| perr(ll, "missing element"))?,
                                ll,
                            )?;
                            let c = v.get(1..9).ok_or_else(|| perr(ll, "hex8 needs 8 nodes"))?;
                            elems.push(c.try_into().map_err(|_| perr(ll, "hex8 needs 8 nodes"))?);
                        }
                    }
                    l += 1 + n;
                }
                i = l;
            }
            _ => i += 1,
        }
    }
    compact(&nodes, &elems, scale)
}

/// Reads the `*NODE` and `*ELEMENT, TYPE=C3D8`/`C3D8R`/`C3D8I` blocks of an Abaqus input file.
pub fn read_abaqus_inp(text: &str, scale: f64) -> Result<HexMesh, MeshError> {
    let mut nodes = HashMap::new();
    let mut elems = Vec::new();
    #[derive(PartialEq)]
    enum Mode {
        None,
        Node,
        Hex,
    }
    let mut mode = Mode::None;
    let mut pending: Vec<i64> = Vec::new();
    for (l, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.starts_with("**") || line.is_empty() {
            continue;
        }
        if line.starts_with('*') {
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
            pending.clear();
            continue;
        }
        match mode {
            Mode::Node => {
                let v = nums::<f64>(line, l)?;
                if v.len() < 4 {
                    return Err(perr(l, "node line needs id, x, y, z"));
                }
                nodes.insert(v[0] as i64, [v[1], v[2], v[3]]);
            }
            Mode::Hex => {
                pending.extend(nums::<i64>(line, l)?);
                if pending.len() >= 9 {
                    elems.push(pending[1..9].try_into().expect("8 nodes"));
                    pending.clear();
                }
            }
            Mode::None => {}
        }
    }
    compact(&nodes, &elems, scale)
}
