//! Fuzz entry points of the scenario readers (the harness is [`pdamp_io::fuzz`]): each takes
//! arbitrary bytes and must return without panicking, hanging or allocating beyond the input's
//! size.

use pdamp_io::fuzz::Target;

/// Scenario TOML: parsing, validation and the error location lookup. Worlds are not built
/// (that would place as many particles as the input asks for).
pub fn scenario(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let base = std::path::Path::new("/nonexistent-pdamp-fuzz");
    match crate::schema::Scenario::from_toml_in(&text, base) {
        Ok(s) => {
            if let Err(m) = s.validate() {
                let _ = crate::schema::locate_key(&text, m.key());
            } else {
                let _ = s.to_toml();
            }
        }
        Err(m) => {
            let _ = crate::schema::locate_key(&text, m.key());
        }
    }
}

/// Checkpoint files of `pdamp run` ([`crate::run::inspect_run_checkpoint`]).
pub fn checkpoint(bytes: &[u8]) {
    let _ = crate::run::inspect_run_checkpoint(bytes);
    // Again with a valid trailing digest, so that mutated payloads reach the decoder itself.
    if bytes.len() > 24 {
        let mut b = bytes[..bytes.len() - 16].to_vec();
        let sum = pdamp_io::checkpoint::digest(&b);
        b.extend_from_slice(sum.as_bytes());
        let _ = crate::run::inspect_run_checkpoint(&b);
    }
}

/// The readers of this crate by name (for the harnesses).
pub const TARGETS: [Target; 2] = [("scenario", scenario), ("checkpoint", checkpoint)];
