//! # pdamp-io — files in and out of pdamp
//!
//! The file formats of pdamp: meshes (STL), results (CSV, JSON), ParaView output (VTK XML),
//! checkpoints and bed files (native, CSV, LAMMPS data), restitution tables, provenance, and
//! the output directory that holds them. Every output file is written atomically (write to a
//! temporary file, then rename). The DEM scenario schema and the run driver are
//! `pdamp-scenario`.

#![forbid(unsafe_code)]
pub mod atomic;
pub mod bed;
pub mod bed_formats;
pub mod checkpoint;
pub mod csv;
pub mod fuzz;
pub mod output_dir;
pub mod provenance;
pub mod restitution;
pub mod stl;
pub mod vtk;
