//! The two layered dampers of D Sect. 5.2.1 on the Ch. 5 beam with the analytical model
//! (approach 3) against the dissertation's numbers:
//!
//! - the design guideline (Eq. 5.15–5.18; `examples/couple_ch5_free_guideline.toml`): D Fig. 5.15
//!   — first cycle ζ = 0.035, then ζ ≈ 0.046, ζ ≈ 0.02 below 11 mm (here below 9 mm: the last
//!   layer rolls down to its X_opt = 10 mm), amplitude 10 mm at 4 s;
//! - the brute-force optimum (36, 36, 40) (`examples/couple_ch5_free_optimum.toml`): measured
//!   amplitude 3 mm after 4 s (the extraction notes' own formula run: 3.9 mm), ζ rising from 0.05
//!   to 0.11.

use std::path::Path;

/// (mean amplitude per cycle m, ζ, time s) of a free decay.
fn decay(example: &str) -> Vec<(f64, f64, f64)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let out = std::env::temp_dir().join(format!("pdamp-{example}-{}", std::process::id()));
    let options = pdamp_scenario::run::RunOptions::new(0.0, false);
    pdamp_structure::report::run_couple(&root.join(example), &out, options, &mut |_| {}).unwrap();
    let (header, rows) = pdamp_io::csv::read_csv_f64(out.join("damping.csv")).unwrap();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let (a, z, t) = (col("mean_amplitude_m"), col("damping_ratio"), col("time_s"));
    let _ = std::fs::remove_dir_all(&out);
    rows.iter().map(|r| (r[a], r[z], r[t])).collect()
}

/// The cycle amplitude at `t` (linear between the cycles around it), m.
fn amplitude_at(d: &[(f64, f64, f64)], t: f64) -> f64 {
    let k = d.iter().position(|c| c.2 >= t).unwrap();
    let (a0, _, t0) = d[k - 1];
    let (a1, _, t1) = d[k];
    a0 + (a1 - a0) * (t - t0) / (t1 - t0)
}

#[test]
fn guideline_and_optimum_of_d_sect_5_2_1() {
    let g = decay("couple_ch5_free_guideline.toml");
    let o = decay("couple_ch5_free_optimum.toml");
    let (xg, xo) = (amplitude_at(&g, 4.0), amplitude_at(&o, 4.0));
    let plateau: Vec<f64> = g
        .iter()
        .filter(|c| c.0 > 0.012 && c.0 < 0.040)
        .map(|c| c.1)
        .collect();
    let mean_plateau = plateau.iter().sum::<f64>() / plateau.len() as f64;
    let low = g
        .iter()
        .filter(|c| c.0 < 0.009)
        .map(|c| c.1)
        .fold(0.0, f64::max);
    let zmax_o = o.iter().map(|c| c.1).fold(0.0, f64::max);
    eprintln!(
        "guideline: first ζ {:.4} (D 0.035), plateau ζ {mean_plateau:.4} (D ≈ 0.046), below 9 mm ≤ {low:.4} \
         (D ≈ 0.02), amplitude at 4 s {:.2} mm (D 10 mm)",
        g[0].1,
        1e3 * xg
    );
    eprintln!(
        "optimum (36, 36, 40): first ζ {:.4} (D exp 0.05), largest ζ {zmax_o:.4} (D exp 0.11), \
         amplitude at 4 s {:.2} mm (D measured 3 mm; a formula run of the notes 3.9 mm)",
        o[0].1,
        1e3 * xo
    );
    // Guideline: D's design target and its measured decay.
    assert!((mean_plateau / 0.046 - 1.0).abs() < 0.15, "{mean_plateau}");
    assert!(g[0].1 > 0.030 && g[0].1 < 0.050, "{}", g[0].1);
    assert!(low < 0.025, "{low}");
    assert!((xg / 0.010 - 1.0).abs() < 0.15, "{xg}");
    // Optimum: ζ up to D's 0.11 and about a third of the guideline's amplitude at 4 s.
    assert!(zmax_o > 0.09 && zmax_o < 0.13, "{zmax_o}");
    assert!((o[0].1 / 0.05 - 1.0).abs() < 0.2, "{}", o[0].1);
    assert!(xo > 0.003 && xo < 0.0045, "{xo}");
    assert!(xo < 0.5 * xg);
}
