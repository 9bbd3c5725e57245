use super::*;
use crate::math::Rotation;
use crate::walls::BoxInside;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const TOL: f64 = 1e-12;

fn contacts(m: &TriMesh, x: &Vec3, r: f64, margin: f64) -> Vec<WallContact> {
    let mut out = Vec::new();
    m.sphere_contacts(x, r, margin, &mut out);
    out
}

/// Kind of a feature id: 0 face, 1 edge, 2 vertex.
fn kind(m: &TriMesh, f: u32) -> u8 {
    let (nf, ne) = (m.num_triangles() as u32, m.num_edges() as u32);
    if f < nf {
        0
    } else if f < nf + ne {
        1
    } else {
        2
    }
}

/// Triangle soup of the box (as an STL would store it: vertices repeated per triangle).
fn box_soup(c: Vec3, h: Vec3) -> Vec<[Vec3; 3]> {
    let m = TriMesh::box_inside(c, h);
    m.faces()
        .iter()
        .map(|f| f.map(|i| m.vertices()[i as usize]))
        .collect()
}

#[test]
fn walls_mesh_welding_cube_topology() {
    let soup = box_soup(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.5, 0.25, 1.0));
    assert_eq!(soup.len(), 12);
    let m = TriMesh::from_triangles(soup.clone()).unwrap();
    assert_eq!(m.num_vertices(), 8);
    assert_eq!(m.num_edges(), 18);
    assert_eq!(m.num_triangles(), 12);
    // Every edge of a closed mesh has exactly two triangles.
    for e in 0..m.num_edges() {
        assert_eq!(m.d.edge_tri_start[e + 1] - m.d.edge_tri_start[e], 2);
    }
    // Near-duplicates within 1e-9 of the diagonal are welded too (1e-12 relative jitter).
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let jittered: Vec<[Vec3; 3]> = soup
        .iter()
        .map(|t| {
            t.map(|p| {
                p + Vec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                ) * 1e-12
            })
        })
        .collect();
    let m2 = TriMesh::from_triangles(jittered).unwrap();
    assert_eq!(
        (m2.num_vertices(), m2.num_edges(), m2.num_triangles()),
        (8, 18, 12)
    );
    // Inward normals of box_inside: the -z face triangles point +z.
    let bottom: Vec<usize> = (0..12)
        .filter(|&t| {
            m.faces()[t]
                .iter()
                .all(|&i| m.vertices()[i as usize].z < 3.0)
        })
        .collect();
    assert_eq!(bottom.len(), 2);
    for t in bottom {
        assert!((m.triangle_normal(t) - Vec3::z()).norm() < TOL);
    }
    let (lo, hi) = m.bounding_box().unwrap();
    assert!((lo - Vec3::new(0.5, 1.75, 2.0)).norm() < TOL);
    assert!((hi - Vec3::new(1.5, 2.25, 4.0)).norm() < TOL);
}

#[test]
fn walls_mesh_errors() {
    let a = Vec3::zeros();
    let b = Vec3::x();
    let c = Vec3::y();
    let err = TriMesh::from_triangles(vec![[a, b, c], [a, b, b * 2.0]]).unwrap_err();
    assert_eq!(err, MeshError::Degenerate { triangle: 1 });
    assert!(err.to_string().contains("triangle 1"), "{err}");
    // Collapsed by welding.
    let err = TriMesh::from_triangles(vec![[a, b, c], [a, b, b * (1.0 + 1e-13)]]).unwrap_err();
    assert_eq!(err, MeshError::Degenerate { triangle: 1 });
    assert_eq!(
        TriMesh::from_triangles(vec![]).unwrap_err(),
        MeshError::Empty
    );
    let err = TriMesh::from_indexed(vec![a, b, c], vec![[0, 1, 3]]).unwrap_err();
    assert!(matches!(
        err,
        MeshError::IndexOutOfRange {
            triangle: 0,
            index: 3,
            ..
        }
    ));
    let err = TriMesh::from_triangles(vec![[a, b, Vec3::new(f64::NAN, 0.0, 0.0)]]).unwrap_err();
    assert_eq!(err, MeshError::NonFinite { vertex: 2 });
    let m = TriMesh::from_triangles(vec![[a, b, c]]).unwrap();
    assert_eq!(m.transformed(0.0, a).unwrap_err(), MeshError::BadScale(0.0));
}

/// Matches two contact sets by (overlap, normal) within `TOL`.
fn assert_same_contacts(a: &[WallContact], b: &[WallContact], ctx: &str) {
    assert_eq!(a.len(), b.len(), "{ctx}: {a:?} vs {b:?}");
    let mut used = vec![false; b.len()];
    for ca in a {
        let j = (0..b.len()).find(|&j| {
            !used[j]
                && (ca.overlap_m - b[j].overlap_m).abs() < TOL
                && (ca.normal - b[j].normal).norm() < TOL
        });
        match j {
            Some(j) => used[j] = true,
            None => panic!("{ctx}: contact {ca:?} not matched in {b:?}"),
        }
    }
}

#[test]
fn walls_mesh_box_matches_box_inside() {
    let c = Vec3::new(0.1, -0.2, 0.3);
    let h = Vec3::new(0.05, 0.03, 0.04);
    let mesh = TriMesh::box_inside(c, h);
    let boxw = BoxInside::new(c, h);
    let mut rng = ChaCha8Rng::seed_from_u64(20240611);
    let mut n_multi = 0;
    let mut n_edge_feature = 0;
    for i in 0..10_000 {
        let r = rng.random_range(0.002..0.02);
        let margin = if i % 2 == 0 { 0.0 } else { 0.3 * r };
        let mut rel = Vec3::zeros();
        for k in 0..3 {
            // Mix: uniform inside, and close to a wall (concave edges and corners).
            rel[k] = match rng.random_range(0..3) {
                0 => rng.random_range(-0.999..0.999) * h[k],
                1 => h[k] - rng.random_range(0.0001..1.3) * r,
                _ => -h[k] + rng.random_range(0.0001..1.3) * r,
            };
            rel[k] = rel[k].clamp(-0.9999 * h[k], 0.9999 * h[k]);
        }
        match i % 5 {
            // On face diagonals: rel_y / h_y = ± rel_x / h_x etc.
            1 => rel.y = h.y * rel.x / h.x,
            2 => rel.z = -h.z * rel.y / h.y,
            3 => {
                let s = rel.x / h.x;
                rel = Vec3::new(s * h.x, s * h.y, s * h.z);
            }
            _ => {}
        }
        let x = c + rel;
        let a = contacts(&mesh, &x, r, margin);
        let mut b = Vec::new();
        boxw.sphere_contacts(&x, r, margin, &mut b);
        assert_same_contacts(&a, &b, &format!("sample {i} x={x:?} r={r}"));
        n_multi += (a.len() >= 2) as usize;
        n_edge_feature += a.iter().filter(|k| kind(&mesh, k.feature) != 0).count();
        for k in &a {
            assert_eq!(k.curvature_radius_m, f64::INFINITY);
        }
    }
    // The sample really probed concave edges/corners and diagonal edges.
    assert!(n_multi > 1000, "{n_multi}");
    assert!(n_edge_feature > 100, "{n_edge_feature}");
}

/// A 2 × 2 square grid (8 triangles) in the plane z = 0 with an interior vertex at (1, 1),
/// rotated and shifted; returns the mesh and the rigid transform.
fn flat_grid() -> (TriMesh, Rotation, Vec3) {
    let rot = Rotation::from_euler_angles(0.3, -0.7, 1.1);
    let shift = Vec3::new(0.2, -0.1, 0.05);
    let mut verts = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            verts.push(rot * Vec3::new(i as f64, j as f64, 0.0) + shift);
        }
    }
    let mut faces = Vec::new();
    for j in 0..2u32 {
        for i in 0..2u32 {
            let v0 = j * 3 + i;
            let (v1, v2, v3) = (v0 + 1, v0 + 4, v0 + 3);
            // Alternate the diagonal direction.
            if (i + j) % 2 == 0 {
                faces.push([v0, v1, v2]);
                faces.push([v0, v2, v3]);
            } else {
                faces.push([v0, v1, v3]);
                faces.push([v1, v2, v3]);
            }
        }
    }
    (TriMesh::from_indexed(verts, faces).unwrap(), rot, shift)
}

#[test]
fn walls_mesh_coplanar_sliding_is_constant() {
    let (m, rot, shift) = flat_grid();
    let n = rot * Vec3::z();
    let r = 0.3;
    let height = 0.21;
    let mut kinds_seen = [0usize; 3];
    // Paths in the local plane: along an edge line through the interior vertex, across
    // diagonals and vertical edges, and along the diagonal through the interior vertex.
    let paths = [
        (Vec3::new(0.2, 1.0, 0.0), Vec3::new(1.8, 1.0, 0.0)),
        (Vec3::new(0.1, 0.7, 0.0), Vec3::new(1.9, 0.7, 0.0)),
        (Vec3::new(0.1, 0.1, 0.0), Vec3::new(1.9, 1.9, 0.0)),
        (Vec3::new(1.0, 0.05, 0.0), Vec3::new(1.0, 1.95, 0.0)),
        (Vec3::new(0.3, 1.9, 0.0), Vec3::new(1.9, 0.3, 0.0)),
    ];
    for (p0, p1) in paths {
        let steps = 400; // step 1/400 of the path: hits the vertex (1,1) and edges exactly
        for s in 0..=steps {
            let local = p0 + (p1 - p0) * (s as f64 / steps as f64) + Vec3::z() * height;
            let x = rot * local + shift;
            let cs = contacts(&m, &x, r, 0.0);
            assert_eq!(cs.len(), 1, "local {local:?}: {cs:?}");
            let k = cs[0];
            assert!((k.overlap_m - (r - height)).abs() < TOL, "{local:?}: {k:?}");
            assert!((k.normal - n).norm() < TOL, "{local:?}: {k:?}");
            assert!((k.point - (x - n * height)).norm() < TOL);
            kinds_seen[kind(&m, k.feature) as usize] += 1;
        }
    }
    // Faces, shared edges and the interior vertex were all crossed.
    assert!(kinds_seen.iter().all(|&c| c > 0), "{kinds_seen:?}");
    // Beside the mesh boundary (open edge, same plane): edge contact towards the outside.
    let x = rot * Vec3::new(2.1, 1.3, 0.0) + shift;
    let cs = contacts(&m, &x, r, 0.0);
    assert_eq!(cs.len(), 1);
    assert!((cs[0].overlap_m - (r - 0.1)).abs() < TOL);
    assert!((cs[0].normal - rot * Vec3::x()).norm() < TOL);
    assert_eq!(kind(&m, cs[0].feature), 1);
    // Behind the one-sided surface by less than r: face contact pushing to the front.
    let x = rot * Vec3::new(0.6, 0.3, -0.1) + shift;
    let cs = contacts(&m, &x, r, 0.0);
    assert_eq!(cs.len(), 1);
    assert!((cs[0].overlap_m - (r + 0.1)).abs() < TOL);
    assert!((cs[0].normal - n).norm() < TOL);
    // Behind by less than r exactly under the interior vertex and a shared edge: still the
    // plane contact (continuous with the face contacts around).
    for local in [
        Vec3::new(1.0, 1.0, -0.1),
        Vec3::new(1.0, 0.6, -0.1),
        Vec3::new(0.5, 0.5, -0.1),
    ] {
        let x = rot * local + shift;
        let cs = contacts(&m, &x, r, 0.0);
        assert_eq!(cs.len(), 1, "{local:?}: {cs:?}");
        assert!((cs[0].overlap_m - (r + 0.1)).abs() < TOL);
        assert!((cs[0].normal - n).norm() < TOL);
    }
    // Further behind than r: nothing.
    let x = rot * Vec3::new(0.6, 0.3, -0.31) + shift;
    assert!(contacts(&m, &x, r, 0.0).is_empty());
}

/// Closest point of the solid axis-aligned box `c ± h` to an outside point.
fn box_closest(c: &Vec3, h: &Vec3, x: &Vec3) -> Vec3 {
    let mut q = *x;
    for k in 0..3 {
        q[k] = q[k].clamp(c[k] - h[k], c[k] + h[k]);
    }
    q
}

#[test]
fn walls_mesh_convex_edge_switches_continuously() {
    let c = Vec3::new(0.0, 0.0, 0.0);
    let h = Vec3::new(0.5, 0.5, 0.5);
    let mut solid = TriMesh::box_inside(c, h);
    solid.flip_normals(); // outward normals: a solid obstacle, particles outside
    let r = 0.1;
    // Path over the top edge x = 0.5, z = 0.5 at y = 0.2: horizontal at height 0.05 above the
    // top face, beyond the edge it leaves the top face: overlap r - dist to the edge.
    let mut prev: Option<f64> = None;
    let mut seq = Vec::new();
    let steps = 2000;
    for s in 0..=steps {
        let u = -0.3 + 0.45 * s as f64 / steps as f64;
        let x = Vec3::new(0.5 + u, 0.13, 0.55);
        let cs = contacts(&solid, &x, r, 0.0);
        let q = box_closest(&c, &h, &x);
        let d = (x - q).norm();
        if d >= r {
            assert!(cs.is_empty());
            continue;
        }
        assert_eq!(cs.len(), 1, "x {x:?}: {cs:?}");
        let k = cs[0];
        assert!((k.overlap_m - (r - d)).abs() < TOL);
        assert!((k.normal - (x - q) / d).norm() < TOL);
        assert!((k.point - q).norm() < TOL);
        if let Some(p) = prev {
            assert!((k.overlap_m - p).abs() < 1e-3, "jump at {x:?}");
        }
        prev = Some(k.overlap_m);
        let kd = kind(&solid, k.feature);
        if seq.last() != Some(&kd) {
            seq.push(kd);
        }
    }
    assert_eq!(seq, vec![0, 1]);
    // Around the edge at constant distance 0.06: face → edge → face, constant overlap.
    let mut seq = Vec::new();
    for s in 0..=steps {
        let phi = -0.4 + (std::f64::consts::FRAC_PI_2 + 0.8) * s as f64 / steps as f64;
        let x = if phi < 0.0 {
            Vec3::new(0.56, 0.2, 0.5 + 0.3 * phi)
        } else if phi > std::f64::consts::FRAC_PI_2 {
            Vec3::new(0.5 - 0.3 * (phi - std::f64::consts::FRAC_PI_2), 0.2, 0.56)
        } else {
            Vec3::new(0.5 + 0.06 * phi.cos(), 0.2, 0.5 + 0.06 * phi.sin())
        };
        let cs = contacts(&solid, &x, r, 0.0);
        assert_eq!(cs.len(), 1, "x {x:?}: {cs:?}");
        assert!((cs[0].overlap_m - 0.04).abs() < TOL, "{x:?}: {cs:?}");
        let q = box_closest(&c, &h, &x);
        assert!((cs[0].normal - (x - q).normalize()).norm() < TOL);
        let kd = kind(&solid, cs[0].feature);
        if seq.last() != Some(&kd) {
            seq.push(kd);
        }
    }
    assert_eq!(seq, vec![0, 1, 0]);
}

#[test]
fn walls_mesh_solid_box_random_outside_points() {
    // Outside a convex solid every point has exactly one locally closest feature: the mesh
    // contact equals the analytic closest point (faces, edges and corners).
    let c = Vec3::new(0.3, 0.1, -0.2);
    let h = Vec3::new(0.2, 0.1, 0.15);
    let mut solid = TriMesh::box_inside(c, h);
    solid.flip_normals();
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    let mut kinds_seen = [0usize; 3];
    let mut tested = 0;
    while tested < 5000 {
        let r = rng.random_range(0.01..0.05);
        let x = c + Vec3::new(
            rng.random_range(-1.0..1.0) * (h.x + r),
            rng.random_range(-1.0..1.0) * (h.y + r),
            rng.random_range(-1.0..1.0) * (h.z + r),
        );
        let q = box_closest(&c, &h, &x);
        let d = (x - q).norm();
        if d == 0.0 {
            continue; // inside the solid
        }
        tested += 1;
        let cs = contacts(&solid, &x, r, 0.0);
        if d >= r {
            assert!(cs.is_empty(), "{x:?}: {cs:?}");
            continue;
        }
        assert_eq!(cs.len(), 1, "{x:?}: {cs:?}");
        assert!((cs[0].overlap_m - (r - d)).abs() < TOL);
        assert!((cs[0].normal - (x - q) / d).norm() < TOL);
        kinds_seen[kind(&solid, cs[0].feature) as usize] += 1;
    }
    assert!(kinds_seen.iter().all(|&k| k > 10), "{kinds_seen:?}");
}

#[test]
fn walls_mesh_fine_plane_single_contact_and_grid() {
    // A finely tessellated, tilted plane (triangles much smaller than the sphere): still exactly
    // one contact with the plane overlap, also where the grid must be searched widely.
    let rot = Rotation::from_euler_angles(-0.2, 0.4, 0.9);
    let nq = 40;
    let a = 0.01;
    let mut verts = Vec::new();
    for j in 0..=nq {
        for i in 0..=nq {
            verts.push(rot * Vec3::new(i as f64 * a, j as f64 * a, 0.0));
        }
    }
    let mut faces = Vec::new();
    let id = |i: u32, j: u32| j * (nq + 1) + i;
    for j in 0..nq {
        for i in 0..nq {
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let m = TriMesh::from_indexed(verts, faces).unwrap();
    assert_eq!(m.num_triangles(), 2 * 40 * 40);
    let n = rot * Vec3::z();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..2000 {
        let r = rng.random_range(0.005..0.05);
        let hgt = rng.random_range(-0.9..0.999) * r;
        let lx = rng.random_range(r..0.4 - r);
        let ly = rng.random_range(r..0.4 - r);
        let x = rot * Vec3::new(lx, ly, hgt);
        let cs = contacts(&m, &x, r, 0.0);
        assert_eq!(cs.len(), 1, "{x:?}: {cs:?}");
        assert!((cs[0].overlap_m - (r - hgt)).abs() < TOL);
        assert!((cs[0].normal - n).norm() < TOL);
    }
    // Far away: nothing, and no panic outside the grid.
    assert!(contacts(&m, &Vec3::new(10.0, -5.0, 3.0), 0.1, 0.0).is_empty());
}

#[test]
fn walls_mesh_parallel_queries_agree() {
    use rayon::prelude::*;
    let (m, rot, shift) = flat_grid();
    let xs: Vec<Vec3> = (0..2000)
        .map(|i| {
            let t = i as f64 / 2000.0;
            rot * Vec3::new(0.1 + 1.8 * t, 1.9 - 1.7 * t, 0.1 + 0.1 * t) + shift
        })
        .collect();
    let serial: Vec<Vec<WallContact>> = xs.iter().map(|x| contacts(&m, x, 0.3, 0.0)).collect();
    let parallel: Vec<Vec<WallContact>> = xs
        .par_iter()
        .map(|x| {
            let mut out = Vec::with_capacity(8);
            m.sphere_contacts(x, 0.3, 0.0, &mut out);
            out
        })
        .collect();
    assert_eq!(serial, parallel);
}

#[test]
fn walls_mesh_transform_and_flip() {
    let m = TriMesh::box_inside(Vec3::zeros(), Vec3::new(1.0, 1.0, 1.0));
    let t = m.transformed(0.5, Vec3::new(1.0, 0.0, 0.0)).unwrap();
    let (lo, hi) = t.bounding_box().unwrap();
    assert!((lo - Vec3::new(0.5, -0.5, -0.5)).norm() < TOL);
    assert!((hi - Vec3::new(1.5, 0.5, 0.5)).norm() < TOL);
    let mut f = t.clone();
    f.flip_normals();
    for i in 0..12 {
        assert!((f.triangle_normal(i) + t.triangle_normal(i)).norm() < TOL);
    }
    assert_eq!(f.num_edges(), t.num_edges());
    // Inside the flipped (solid) box near the top, the contact pushes upwards/out, only with
    // penetration < r (one-sided).
    let cs = contacts(&f, &Vec3::new(1.0, 0.1, 0.45), 0.1, 0.0);
    assert_eq!(cs.len(), 1);
    assert!((cs[0].overlap_m - 0.15).abs() < TOL);
    assert!((cs[0].normal - Vec3::z()).norm() < TOL);
}

/// Winding number and closedness: a container box (inward normals) has w = −1 inside and 0
/// outside, the same box as an obstacle (outward normals) +1 inside; a box with a face missing
/// is open and has no inside; the enclosed volume is ∓ the box volume.
#[test]
fn winding_number_and_closedness() {
    let c = Vec3::new(0.1, -0.2, 0.3);
    let h = Vec3::new(0.5, 0.25, 1.0);
    let container = TriMesh::box_inside(c, h);
    assert!(container.is_closed());
    let vol = 8.0 * h.x * h.y * h.z;
    assert!((container.enclosed_volume_m3() + vol).abs() < 1e-12);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..200 {
        let u = Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - Vec3::repeat(1.0);
        let x = c + (h * 1.5).component_mul(&u);
        let inside = (0..3).all(|k| (x[k] - c[k]).abs() < h[k]);
        let w = container.winding_number(&x);
        let expect = if inside { -1.0 } else { 0.0 };
        assert!((w - expect).abs() < 1e-9, "{x:?}: w = {w}");
        assert_eq!(container.in_particle_region(&x), inside);
    }
    let mut obstacle = container.clone();
    obstacle.flip_normals();
    assert!(obstacle.is_closed());
    assert!((obstacle.enclosed_volume_m3() - vol).abs() < 1e-12);
    assert!((obstacle.winding_number(&c) - 1.0).abs() < 1e-12);
    assert!(!obstacle.in_particle_region(&c));
    assert!(obstacle.in_particle_region(&(c + h * 1.01)));
    let open = TriMesh::from_indexed(
        container.vertices().to_vec(),
        container.faces()[..10].to_vec(),
    )
    .unwrap();
    assert!(!open.is_closed());
    assert!(open.in_particle_region(&c));
}

/// A closed box with one reversed facet (the severe defect of the reliability audit: it created
/// ≈ 200 J from 5e-4 J) and a box with a repeated facet are refused, naming the triangles.
#[test]
fn reversed_or_repeated_facet_is_refused() {
    let good = TriMesh::box_inside(Vec3::zeros(), Vec3::repeat(0.02));
    let mut faces = good.faces().to_vec();
    faces[5].swap(1, 2);
    match TriMesh::from_indexed(good.vertices().to_vec(), faces) {
        Err(MeshError::InconsistentOrientation {
            triangle,
            neighbour,
        }) => {
            assert!(triangle == 5 || neighbour == 5, "{triangle} {neighbour}");
        }
        other => panic!("reversed facet accepted: {other:?}"),
    }
    let mut faces = good.faces().to_vec();
    faces.push([faces[3][1], faces[3][2], faces[3][0]]);
    assert_eq!(
        TriMesh::from_indexed(good.vertices().to_vec(), faces).unwrap_err(),
        MeshError::DuplicateFacet {
            triangle: 3,
            duplicate: 12
        }
    );
    // An open but consistent mesh (a box without its lid) stays valid.
    assert!(TriMesh::from_indexed(good.vertices().to_vec(), good.faces()[..10].to_vec()).is_ok());
}
