//! (to be written)
use crate::math::Vec3;
use serde::{Deserialize, Serialize};
use super::WallContact;
/// placeholder
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TriMesh {}
/// placeholder
#[derive(Debug)]
pub struct MeshError;
impl TriMesh { /// placeholder
 pub fn sphere_contacts(&self, _x: &Vec3, _r: f64, _m: f64, _out: &mut Vec<WallContact>) {}
 /// placeholder
 pub fn bounding_box(&self) -> Option<(Vec3, Vec3)> { None } }
