//! (to be written)
use crate::math::Vec3;
use serde::{Deserialize, Serialize};
use super::WallContact;
/// placeholder
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CylinderInside {}
impl CylinderInside { /// placeholder
 pub fn bounding_box(&self) -> (Vec3, Vec3) { (Vec3::zeros(), Vec3::zeros()) }
 /// placeholder
 pub fn sphere_contacts(&self, _x: &Vec3, _r: f64, _m: f64, _out: &mut Vec<WallContact>) {} }
/// placeholder
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CylinderOutside {}
impl CylinderOutside { /// placeholder
 pub fn sphere_contacts(&self, _x: &Vec3, _r: f64, _m: f64, _out: &mut Vec<WallContact>) {}
 /// placeholder
 pub fn bounding_box(&self) -> (Vec3, Vec3) { (Vec3::zeros(), Vec3::zeros()) } }
