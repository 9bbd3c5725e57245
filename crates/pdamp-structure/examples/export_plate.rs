//! Writes the stiffness and mass matrices of a cantilever steel plate as a user's FE program
//! would export them (Matrix Market, symmetric, with an ANSYS-style node/dof map): the
//! user-style structure of `examples/design_plate.toml`.
//!
//! ```text
//! cargo run --release -p pdamp-structure --example export_plate -- examples/plate
//! ```
//!
//! The plate ([`Plate::EXAMPLE`]): 250 × 250 × 3 mm, E = 210 GPa, ν = 0.3, ρ = 7850 kg/m³,
//! clamped along x = 0, 12 × 12 ACM Kirchhoff elements ([`pdamp_structure::fe::plate`]); nodes numbered from 1,
//! row by row along x (node = 13 j + i + 1 at x = i·a/12, y = j·b/12). The crate's tests check
//! these files against a fresh export and the frequencies against Leissa.

use pdamp_structure::fe::plate::Plate;
use pdamp_structure::matrix_market::{format_dof_map, format_symmetric};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .ok_or("usage: export_plate OUT_DIR")?,
    );
    std::fs::create_dir_all(&dir)?;
    let a = Plate::EXAMPLE.assemble()?;
    std::fs::write(dir.join("K.mtx"), format_symmetric(&a.stiffness, 0.0))?;
    std::fs::write(dir.join("M.mtx"), format_symmetric(&a.mass, 0.0))?;
    let rows: Vec<(i64, _)> = a.dofs.iter().map(|&(n, d)| (n as i64 + 1, d)).collect();
    std::fs::write(dir.join("dofs.txt"), format_dof_map(&rows))?;
    println!(
        "{} dofs written to {} (K.mtx, M.mtx, dofs.txt)",
        a.dofs.len(),
        dir.display()
    );
    Ok(())
}
