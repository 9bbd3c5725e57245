//! Atomic file writes: write to `<path>.tmp-<pid>-<n>` in the same directory, flush, fsync,
//! rename over `path` (and fsync the directory on Unix). Readers therefore see either the old or
//! the complete new file, never a truncated one, also if the process is killed mid-write.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Wraps `e` into an error of the same kind whose message names the operation and the path.
fn context(e: io::Error, what: &str, path: &Path) -> io::Error {
    io::Error::new(e.kind(), format!("{what} {}: {e}", path.display()))
}

/// Temporary file name next to `path`: `<path>.tmp-<pid>-<n>` (n distinguishes threads).
fn tmp_path(path: &Path) -> io::Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("not a file path: {}", path.display()),
        )
    })?;
    let mut tmp = name.to_os_string();
    tmp.push(format!(
        ".tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    Ok(path.with_file_name(tmp))
}

/// Writes `bytes` to `path` atomically. Errors name the path.
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Writes the output of `fill` (into a buffered writer) to `path` atomically. If `fill` or any
/// step fails, the temporary file is removed and `path` is left untouched. Errors keep their
/// [`io::ErrorKind`] and name the path.
pub fn write_atomic_with<F>(path: impl AsRef<Path>, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let path = path.as_ref();
    let tmp = tmp_path(path)?;
    let result = (|| {
        let file = File::create(&tmp).map_err(|e| context(e, "creating", &tmp))?;
        let mut w = BufWriter::with_capacity(1 << 16, file);
        fill(&mut w).map_err(|e| context(e, "writing", path))?;
        let file = w
            .into_inner()
            .map_err(|e| context(e.into_error(), "writing", path))?;
        file.sync_all().map_err(|e| context(e, "syncing", &tmp))?;
        drop(file);
        fs::rename(&tmp, path).map_err(|e| context(e, "renaming temporary file onto", path))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
        return result;
    }
    sync_parent_dir(path);
    Ok(())
}

/// Best-effort fsync of the directory holding `path` so the rename itself is durable.
fn sync_parent_dir(path: &Path) {
    #[cfg(unix)]
    {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = path;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("pdamp-io-atomic-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp-"))
            .collect()
    }

    #[test]
    fn writes_content_and_leaves_no_tmp() {
        let dir = test_dir("ok");
        let p = dir.join("a.txt");
        write_atomic(&p, b"hello").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"hello");
        write_atomic_with(&p, |w| {
            w.write_all(b"new ")?;
            write!(w, "{}", 42)
        })
        .unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "new 42");
        assert!(leftovers(&dir).is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failure_keeps_old_file_and_names_path() {
        let dir = test_dir("fail");
        let p = dir.join("b.txt");
        write_atomic(&p, b"old").unwrap();
        let e = write_atomic_with(&p, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(
            e.to_string().contains("b.txt") && e.to_string().contains("boom"),
            "{e}"
        );
        assert_eq!(fs::read(&p).unwrap(), b"old");
        assert!(leftovers(&dir).is_empty());
        // Missing directory: error names the path.
        let e = write_atomic(dir.join("missing/c.txt"), b"x").unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
        assert!(e.to_string().contains("c.txt"), "{e}");
        fs::remove_dir_all(&dir).unwrap();
    }
}
