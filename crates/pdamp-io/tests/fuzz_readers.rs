//! Stable-Rust mutation fuzzing of every reader, run in CI: the seed corpora in `fuzz/corpus/`
//! (shared with the cargo-fuzz targets, see docs/reliability.md) plus random byte flips,
//! truncations, splices and insertions of interesting tokens
//! ([`pdamp_io::fuzz::mutation_fuzz`]), for a fixed time per reader. A panic, or an input
//! taking more than 5 s, fails the test and prints the input.
//!
//! Time per reader: `PDAMP_FUZZ_SECONDS` (default 2 s); seed: `PDAMP_FUZZ_SEED`.

use pdamp_io::fuzz::{TARGETS, mutation_fuzz, read_corpus};
use std::path::PathBuf;

fn env_or<T: std::str::FromStr>(key: &str, default: T) -> T {
    std::env::var(key)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

#[test]
fn readers_never_panic_on_mutated_input() {
    let secs: f64 = env_or("PDAMP_FUZZ_SECONDS", 2.0);
    let seed: u64 = env_or("PDAMP_FUZZ_SEED", 0x5eed_1234_abcd_0001);
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut failures = Vec::new();
    for (name, reader) in TARGETS {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fuzz/corpus")
            .join(name);
        let seeds = read_corpus(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        assert!(!seeds.is_empty(), "no seeds for {name}");
        let rep = mutation_fuzz(reader, &seeds, secs, seed ^ name.len() as u64);
        eprintln!(
            "{name}: {} inputs, {} panics, slowest {:.3} s",
            rep.runs,
            rep.panics.len(),
            rep.slowest_s
        );
        for p in &rep.panics {
            failures.push(format!(
                "{name} panicked on {} bytes: {:?}",
                p.len(),
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
