//! CI mutation fuzzing of the Gmsh and Abaqus mesh readers and the `pdamp powder run`
//! checkpoint decoder (seed corpora in `fuzz/corpus/{gmsh,abaqus,powder_checkpoint}/`, engine
//! [`pdamp_io::fuzz::mutation_fuzz`]); `PDAMP_FUZZ_SECONDS` sets the time per reader (default
//! 2 s). Longer: `PDAMP_FUZZ_SECONDS=60 cargo test --release -p pdamp-powder --test fuzz_readers`.

use std::path::PathBuf;

fn corpus() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus")
}

#[test]
fn powder_readers_never_panic_on_mutated_input() {
    let failures = pdamp_io::fuzz::fuzz_all(
        &pdamp_powder::fuzz::TARGETS,
        &corpus(),
        pdamp_io::fuzz::seconds_from_env(),
        0x9d3a_0031,
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The seeds themselves read: the meshes as one or two valid hexes, the checkpoints as the
/// phase they hold.
#[test]
fn seeds_are_valid_inputs() {
    for name in ["hex2_v22.msh", "hex1_v41.msh"] {
        let text = std::fs::read_to_string(corpus().join("gmsh").join(name)).unwrap();
        let m = pdamp_powder::fe::read_gmsh(&text, 1e-3).unwrap();
        m.validate().unwrap();
    }
    let text = std::fs::read_to_string(corpus().join("abaqus/hex2.inp")).unwrap();
    assert_eq!(
        pdamp_powder::fe::read_abaqus_inp(&text, 1e-3)
            .unwrap()
            .elements
            .len(),
        2
    );
    for (name, phase) in [
        ("preparing.bin", "preparing"),
        ("running.bin", "running"),
        ("finished.bin", "finished"),
    ] {
        let bytes = std::fs::read(corpus().join("powder_checkpoint").join(name)).unwrap();
        assert_eq!(
            pdamp_powder::cantilever::inspect_checkpoint(&bytes)
                .unwrap()
                .0,
            phase
        );
    }
}

/// Writes the checkpoint seeds from the tiny cantilever (`tests/data/tiny_cantilever.toml`):
/// `cargo test -p pdamp-powder --test fuzz_readers -- --ignored write_checkpoint_seeds`.
#[test]
#[ignore]
fn write_checkpoint_seeds() {
    use pdamp_powder::cantilever::{self, CantileverScenario, RunOptions};
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/tiny_cantilever.toml"
    ))
    .unwrap();
    let sc = CantileverScenario::from_toml(&text).unwrap();
    let dir = std::env::temp_dir().join(format!("pdamp-powder-seeds-{}", std::process::id()));
    let seeds = corpus().join("powder_checkpoint");
    std::fs::create_dir_all(&seeds).unwrap();
    let ck = dir.join("checkpoint.bin");
    // the coupled run right after the preparation (its first checkpoint), then finished
    let opts = RunOptions::new(1e6, false);
    let mut copied = false;
    cantilever::run_in_dir(&sc, &dir, opts.clone(), &mut |stage, _| {
        if stage == "coupled run" && !copied {
            std::fs::copy(&ck, seeds.join("running.bin")).unwrap();
            copied = true;
        }
    })
    .unwrap();
    std::fs::copy(&ck, seeds.join("finished.bin")).unwrap();
    // a preparation stopped at once
    let _ = std::fs::remove_dir_all(&dir);
    let cancel = pdamp_dem::time_loop::CancelToken::new();
    cancel.cancel();
    let e = cantilever::run_in_dir(&sc, &dir, opts.cancelled_by(&cancel), &mut |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(e.starts_with(pdamp_io::checkpoint::INTERRUPTED), "{e}");
    std::fs::copy(&ck, seeds.join("preparing.bin")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}
