//! Output plumbing shared by every writer: atomic files, memory budgets, progress bars.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Default memory budget for grids and images, in bytes (CLI flag `--max-memory`).
pub const DEFAULT_MEMORY_BUDGET: u64 = 8 << 30;

/// Errors from [`write_atomic`] and [`check_budget`].
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// Writing failed; the destination was left as it was.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The destination.
        path: PathBuf,
        /// What went wrong.
        source: io::Error,
    },
    /// A request would take more memory than allowed.
    #[error("{what} would need {} but the memory budget is {} (raise it with --max-memory)", human_bytes(*.need), human_bytes(*.budget))]
    OverBudget {
        /// What was asked for.
        what: String,
        /// Bytes it would take.
        need: u64,
        /// Bytes allowed.
        budget: u64,
    },
}

/// Writes a file atomically: the bytes go to a temporary file beside `path`, which is then
/// renamed over it, so a failed run never leaves a truncated file.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), IoError> {
    let err = |source| IoError::Write {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| err(io::Error::other("not a file name")))?;
    let tmp = dir.join(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut file = io::BufWriter::new(std::fs::File::create(&tmp)?);
        write(&mut file)?;
        file.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(err)
}

/// Writes `bytes` to `path` atomically.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// Refuses a request of `need` bytes over `budget`, before anything is allocated.
pub fn check_budget(what: impl Into<String>, need: u64, budget: u64) -> Result<(), IoError> {
    if need > budget {
        return Err(IoError::OverBudget {
            what: what.into(),
            need,
            budget,
        });
    }
    Ok(())
}

/// `1536` → `"1.5 KiB"`.
pub fn human_bytes(b: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// A progress bar over `len` steps that draws only on a terminal and never with `quiet`.
pub fn progress(len: u64, message: &str, quiet: bool) -> ProgressBar {
    let target = if quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(len), target);
    bar.set_style(
        ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} {elapsed_precise}")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_message(message.to_string());
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_keeps_old_file_on_failure() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        write_bytes_atomic(&path, b"first").unwrap();
        let r = write_atomic(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"first");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temp file left"
        );
    }

    #[test]
    fn budget_is_enforced_before_allocation() {
        let e = check_budget("a 4096³ grid", 1 << 40, DEFAULT_MEMORY_BUDGET).unwrap_err();
        assert!(e.to_string().contains("1.0 TiB"), "{e}");
        assert!(check_budget("small", 10, 100).is_ok());
    }
}
