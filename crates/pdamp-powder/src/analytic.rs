//! First-order analytical models of paper Sect. 4 (eq. 17–26): frictional work dissipated in a
//! rectangular box (width b, length l) filled with equal spheres of radius R, all in sliding
//! contact, under pure shear (angle φ) and pure bending (corner rotation φ). Wall normal forces
//! $F_{N,x}$, $F_{N,y}$ are shared by the contacts of a row (eq. 17): $F_{N,y,i} = F_{N,y}/N_x$,
//! $F_{N,x,i} = F_{N,x}/N_y$ with $N_x = b/(2R)$, $N_y = l/(2R)$.
//! Both large-N limits are independent of R — the paper's argument for the weak particle-size
//! dependence of the damping (Sect. 3.2).
//!
//! The functions live in `pdamp_structure::formulas` (where they also form the approach-3
//! damper model `PowderFrictionDamper`, docs/structure.md) and are re-exported here; their
//! tests are there (`friction_work_is_independent_of_particle_size`).

pub use pdamp_structure::formulas::{
    bending_work, bending_work_discrete, shear_work, shear_work_discrete,
};
