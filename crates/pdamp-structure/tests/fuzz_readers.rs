//! CI mutation fuzzing of the Matrix Market and fields.csv readers (seed corpora in
//! `fuzz/corpus/`, engine [`pdamp_io::fuzz::mutation_fuzz`]); `PDAMP_FUZZ_SECONDS` sets the
//! time per reader (default 2 s).

use pdamp_io::fuzz::{mutation_fuzz, read_corpus};
use std::path::PathBuf;

#[test]
fn structural_readers_never_panic_on_mutated_input() {
    let secs: f64 = std::env::var("PDAMP_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.0);
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut failures = Vec::new();
    for (name, reader) in pdamp_structure::fuzz::TARGETS {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fuzz/corpus")
            .join(name);
        let seeds = read_corpus(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        assert!(!seeds.is_empty());
        let rep = mutation_fuzz(reader, &seeds, secs, 0xfeed_0000 + name.len() as u64);
        eprintln!(
            "{name}: {} inputs, {} panics, slowest {:.3} s",
            rep.runs,
            rep.panics.len(),
            rep.slowest_s
        );
        for p in &rep.panics {
            failures.push(format!(
                "{name} panicked on {:?}",
                String::from_utf8_lossy(&p[..p.len().min(400)])
            ));
        }
        if rep.slowest_s > 5.0 {
            failures.push(format!("{name}: one input took {:.1} s", rep.slowest_s));
        }
    }
    std::panic::set_hook(hook);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Regression of the first fuzz finding: a dof-map line holding only separators.
#[test]
fn dof_map_line_of_separators_is_skipped() {
    let m =
        pdamp_structure::matrix_market::parse_dof_map("1 10 ux\n,\n , ,\n2 11 uy\n", 2).unwrap();
    assert_eq!(m.rows.len(), 2);
}
