//! Stable-Rust mutation fuzzing of every reader, run in CI: the seed corpora in `fuzz/corpus/`
//! (shared with the cargo-fuzz targets, see docs/fuzzing.md) plus random byte flips,
//! truncations, splices and insertions of interesting tokens, for a fixed time per reader. A
//! panic fails the test and prints the input that caused it.
//!
//! Time per reader: `PDAMP_FUZZ_SECONDS` (default 2 s); seed: `PDAMP_FUZZ_SEED`.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::time::{Duration, Instant};

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

const TOKENS: &[&[u8]] = &[
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

fn mutate(rng: &mut Rng, seed: &[u8], corpus: &[Vec<u8>]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        match rng.below(7) {
            0 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
            1 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] = rng.next() as u8;
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
                // Overwrite 4 bytes with an extreme little-endian integer (binary headers).
                let i = rng.below(b.len() - 3);
                let v: u32 = [0, 1, u32::MAX, 0x7fff_ffff, 1 << 24][rng.below(5)];
                b[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            _ => b.push(rng.next() as u8),
        }
    }
    b
}

fn corpus(target: &str) -> Vec<Vec<u8>> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("corpus {}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.truncate(200);
    files.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

#[test]
fn readers_never_panic_on_mutated_input() {
    let secs: f64 = std::env::var("PDAMP_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.0);
    let seed: u64 = std::env::var("PDAMP_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x5eed_1234_abcd_0001);
    // Silence the default hook while we catch panics; report them ourselves.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut report = Vec::new();
    for (name, reader) in pdamp_io::fuzz::TARGETS {
        let seeds = corpus(name);
        assert!(!seeds.is_empty(), "no seeds for {name}");
        let mut rng = Rng(seed ^ name.len() as u64 * 0x9e37_79b9);
        let t0 = Instant::now();
        let mut runs = 0u64;
        let mut panics: Vec<Vec<u8>> = Vec::new();
        for s in &seeds {
            if catch_unwind(AssertUnwindSafe(|| reader(s))).is_err() {
                panics.push(s.clone());
            }
            runs += 1;
        }
        while t0.elapsed() < Duration::from_secs_f64(secs) && panics.len() < 3 {
            let base = &seeds[rng.below(seeds.len())];
            let input = mutate(&mut rng, base, &seeds);
            let t = Instant::now();
            if catch_unwind(AssertUnwindSafe(|| reader(&input))).is_err() {
                panics.push(input.clone());
            }
            assert!(
                t.elapsed() < Duration::from_secs(5),
                "{name}: one input took {:?}: {:?}",
                t.elapsed(),
                String::from_utf8_lossy(&input[..input.len().min(400)])
            );
            runs += 1;
        }
        eprintln!(
            "{name}: {runs} inputs in {:.1} s, {} panics",
            t0.elapsed().as_secs_f64(),
            panics.len()
        );
        for p in &panics {
            report.push(format!(
                "{name} panicked on {} bytes: {:?}",
                p.len(),
                String::from_utf8_lossy(&p[..p.len().min(400)])
            ));
        }
    }
    std::panic::set_hook(hook);
    assert!(report.is_empty(), "{}", report.join("\n"));
}
