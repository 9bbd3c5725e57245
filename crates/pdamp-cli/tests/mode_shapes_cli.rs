//! `pdamp structure modes` draws the mode shapes of a beam (`mode_shapes.png/.svg`) and says on
//! stderr why there is no picture for a structure without node coordinates.

use std::path::{Path, PathBuf};
use std::process::Command;

fn pdamp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdamp"))
}

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-cli-modes-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn modes(example: &str, out: &Path) -> std::process::Output {
    let o = pdamp()
        .args(["structure", "modes"])
        .arg(examples().join(example))
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

/// The cantilever (4 modes, f1 = 8.355 Hz): the picture exists with its axis titles and one
/// legend entry per mode with its frequency; the manifest lists it. The single-mode ch5 beam
/// has no coordinates: no picture, a note on stderr.
#[test]
fn beam_mode_shapes_are_drawn() {
    let out = scratch("cantilever");
    modes("structure_cantilever_small.toml", &out);
    assert!(out.join("mode_shapes.png").is_file());
    let svg = std::fs::read_to_string(out.join("mode_shapes.svg")).unwrap();
    for label in [
        "position along the beam x (m)",
        "deflection u_y, normalised (-)",
        "mode 1: 8.355 Hz",
        "mode 4: ",
    ] {
        assert!(svg.contains(label), "mode_shapes.svg lacks {label:?}");
    }
    let manifest = std::fs::read_to_string(out.join("manifest.json")).unwrap();
    assert!(manifest.contains("mode_shapes.svg"), "{manifest}");
    let _ = std::fs::remove_dir_all(&out);

    let out = scratch("single");
    let o = modes("structure_ch5_beam.toml", &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("note: no mode_shapes.png"), "{err}");
    assert!(!out.join("mode_shapes.png").exists());
    assert!(out.join("modes.csv").is_file());
    let _ = std::fs::remove_dir_all(&out);
}
