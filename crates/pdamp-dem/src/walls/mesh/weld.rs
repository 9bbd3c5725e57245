//! Welding the vertices of a triangle soup (STL) into an indexed mesh.

use crate::math::Vec3;
use std::collections::HashMap;

/// Welds vertices closer than `tol` (exactly equal ones always); returns the welded list and
/// the old → new index map.
pub(super) fn weld(vertices: &[Vec3], tol: f64) -> (Vec<Vec3>, Vec<u32>) {
    let cell = if tol > 0.0 { tol * 2.0 } else { 1.0 };
    let key = |p: &Vec3| -> [i64; 3] {
        [
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        ]
    };
    let mut map: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    let mut out: Vec<Vec3> = Vec::new();
    let mut remap = Vec::with_capacity(vertices.len());
    for p in vertices {
        let k = key(p);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = map.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for &j in list {
                            let q = &out[j as usize];
                            if q == p || (q - p).norm() <= tol {
                                found = Some(j);
                                break 'search;
                            }
                        }
                    }
                }
            }
        }
        let id = match found {
            Some(j) => j,
            None => {
                out.push(*p);
                map.entry(k).or_default().push(out.len() as u32 - 1);
                out.len() as u32 - 1
            }
        };
        remap.push(id);
    }
    (out, remap)
}
