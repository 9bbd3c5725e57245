//! Entry points for fuzzing the readers: each takes arbitrary bytes and must return (an error
//! or a value) without panicking, hanging or allocating beyond the input's size. They are
//! shared by the cargo-fuzz targets in `fuzz/` and the stable-Rust mutation test
//! `tests/fuzz_readers.rs` that runs in CI.

use std::io::Cursor;

/// STL, binary or ASCII ([`crate::stl::read_stl_from`]).
pub fn stl(bytes: &[u8]) {
    if let Ok(mesh) = crate::stl::read_stl_from(Cursor::new(bytes)) {
        let _ = mesh.bounding_box();
    }
}

/// Numeric CSV (`fields.csv`, `energy.csv`, …): [`crate::csv::parse_csv_f64`].
pub fn csv(bytes: &[u8]) {
    let _ = crate::csv::parse_csv_f64(&String::from_utf8_lossy(bytes));
}

/// Restitution tables: [`crate::restitution::parse_restitution_table`].
pub fn restitution_table(bytes: &[u8]) {
    let _ = crate::restitution::parse_restitution_table(&String::from_utf8_lossy(bytes));
}

/// LAMMPS / LIGGGHTS data files ([`crate::bed_formats::read_lammps_data`]); a bed that reads
/// is written back ([`crate::bed_formats::write_lammps_data`]) and must read back identical (a
/// difference panics, so the harnesses report it).
pub fn lammps_data(bytes: &[u8]) {
    use crate::bed_formats::{read_lammps_data, write_lammps_data};
    let text = String::from_utf8_lossy(bytes);
    if let Ok(bed) = read_lammps_data(&text, &[]) {
        let densities = vec![1000.0; bed.materials.len()];
        let out = write_lammps_data(&bed, &densities, ([-1.0; 3], [1.0; 3]));
        let again = read_lammps_data(&out, &bed.materials);
        assert_eq!(
            again.as_ref(),
            Ok(&bed),
            "LAMMPS data round trip changed the bed"
        );
    }
}

/// Bed CSV ([`crate::bed_formats::read_bed_csv`]); a bed that reads is written back
/// ([`crate::bed_formats::write_bed_csv`]) and must read back identical (a difference panics).
pub fn bed_csv(bytes: &[u8]) {
    use crate::bed_formats::{read_bed_csv, write_bed_csv};
    let text = String::from_utf8_lossy(bytes);
    if let Ok(bed) = read_bed_csv(&text, "default") {
        let again = read_bed_csv(&write_bed_csv(&bed), "default");
        assert_eq!(
            again.as_ref(),
            Ok(&bed),
            "bed CSV round trip changed the bed"
        );
    }
}

/// Native bed files of `pdamp settle` ([`crate::bed::decode_bed`]), also with a valid
/// trailing digest so that mutated payloads reach the decoder.
pub fn bed_native(bytes: &[u8]) {
    let _ = crate::bed::decode_bed(bytes);
    if bytes.len() > 24 {
        let mut b = bytes[..bytes.len() - 16].to_vec();
        let sum = crate::checkpoint::digest(&b);
        b.extend_from_slice(sum.as_bytes());
        let _ = crate::bed::decode_bed(&b);
    }
}

/// A named fuzz entry point.
pub type Target = (&'static str, fn(&[u8]));

/// All readers of this crate by name (for the harnesses; the scenario and run-checkpoint
/// readers are `pdamp_scenario::fuzz::TARGETS`).
pub const TARGETS: [Target; 6] = [
    ("stl", stl),
    ("csv", csv),
    ("restitution_table", restitution_table),
    ("lammps_data", lammps_data),
    ("bed_csv", bed_csv),
    ("bed_native", bed_native),
];

/// Deterministic xorshift64* generator for the mutation fuzzer.
#[derive(Debug, Clone)]
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in `0..n` (0 for n = 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next_u64() % n as u64) as usize
        }
    }
}

/// Tokens the mutator inserts: extreme numbers, separators, TOML/STL/CSV keywords.
pub const TOKENS: &[&[u8]] = &[
    b"NaN",
    b"inf",
    b"-inf",
    b"1e308",
    b"-1e-320",
    b"0",
    b"-1",
    b"4294967295",
    b"18446744073709551616",
    b",",
    b"\n",
    b"\r\n",
    b"\"",
    b"[",
    b"]",
    b"{",
    b"}",
    b"=",
    b"%",
    b"%%MatrixMarket matrix coordinate real symmetric\n",
    b"[[particles]]",
    b"solid",
    b"endsolid",
    b"facet normal",
    b"vertex",
    b"\xff\xfe",
    b"count = 99999999999",
    b"radius_m = 0",
    b"law = \"gonthier-table\"",
];

/// One to four random edits of `seed`: bit flips, byte changes, truncation, token insertion,
/// deletion, splicing with another corpus entry, extreme little-endian integers.
pub fn mutate(rng: &mut Rng, seed: &[u8], corpus: &[Vec<u8>]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        match rng.below(7) {
            0 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
            1 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] = rng.next_u64() as u8;
            }
            2 => {
                let n = rng.below(b.len() + 1);
                b.truncate(n);
            }
            3 => {
                let t = TOKENS[rng.below(TOKENS.len())];
                let i = rng.below(b.len() + 1);
                b.splice(i..i, t.iter().copied());
            }
            4 if !b.is_empty() => {
                let i = rng.below(b.len());
                let n = rng.below((b.len() - i).min(64) + 1);
                b.drain(i..i + n);
            }
            5 if !corpus.is_empty() => {
                let other = &corpus[rng.below(corpus.len())];
                let i = rng.below(b.len() + 1);
                let j = rng.below(other.len() + 1);
                b.truncate(i);
                b.extend_from_slice(&other[j..]);
            }
            _ if b.len() >= 4 => {
                let i = rng.below(b.len() - 3);
                let v: u32 = [0, 1, u32::MAX, 0x7fff_ffff, 1 << 24][rng.below(5)];
                b[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            _ => b.push(rng.next_u64() as u8),
        }
    }
    b
}

/// Outcome of [`mutation_fuzz`].
#[derive(Debug, Clone, Default)]
pub struct FuzzReport {
    /// Inputs tried (seeds included).
    pub runs: u64,
    /// Inputs that panicked (at most 3 are kept).
    pub panics: Vec<Vec<u8>>,
    /// Slowest single input, s.
    pub slowest_s: f64,
}

/// Runs `reader` on every seed, then on mutations of them for `seconds` (stops after 3
/// panics). Panics are caught (install a silent panic hook to keep the output clean).
pub fn mutation_fuzz(reader: fn(&[u8]), seeds: &[Vec<u8>], seconds: f64, seed: u64) -> FuzzReport {
    use std::panic::{AssertUnwindSafe, catch_unwind};
    let mut rng = Rng(seed | 1);
    let mut rep = FuzzReport::default();
    let run = |input: &[u8], rep: &mut FuzzReport| {
        let t = std::time::Instant::now();
        if catch_unwind(AssertUnwindSafe(|| reader(input))).is_err() {
            rep.panics.push(input.to_vec());
        }
        rep.slowest_s = rep.slowest_s.max(t.elapsed().as_secs_f64());
        rep.runs += 1;
    };
    for s in seeds {
        run(s, &mut rep);
    }
    let t0 = std::time::Instant::now();
    while !seeds.is_empty() && t0.elapsed().as_secs_f64() < seconds && rep.panics.len() < 3 {
        let base = &seeds[rng.below(seeds.len())];
        let input = mutate(&mut rng, base, seeds);
        run(&input, &mut rep);
    }
    rep
}

/// Reads up to 200 files of a corpus directory (sorted by name).
pub fn read_corpus(dir: &std::path::Path) -> std::io::Result<Vec<Vec<u8>>> {
    let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files.truncate(200);
    files.iter().map(std::fs::read).collect()
}

/// Runs [`mutation_fuzz`] on every `(name, reader)` with the seeds of `corpus_root/name`, for
/// `seconds` each, printing one line per reader; returns the failures (panics with their
/// inputs, inputs slower than 5 s, missing corpora). Panics are silenced while it runs.
pub fn fuzz_all(
    targets: &[Target],
    corpus_root: &std::path::Path,
    seconds: f64,
    seed: u64,
) -> Vec<String> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut failures = Vec::new();
    for &(name, reader) in targets {
        let seeds = match read_corpus(&corpus_root.join(name)) {
            Ok(s) if !s.is_empty() => s,
            _ => {
                failures.push(format!(
                    "{name}: no seeds in {}",
                    corpus_root.join(name).display()
                ));
                continue;
            }
        };
        let rep = mutation_fuzz(reader, &seeds, seconds, seed ^ name.len() as u64);
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
    failures
}

/// `PDAMP_FUZZ_SECONDS` (default 2 s per reader) for the CI fuzz tests.
pub fn seconds_from_env() -> f64 {
    std::env::var("PDAMP_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.0)
}
