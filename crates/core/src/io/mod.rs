//! Plumbing shared by every reader and writer: atomic files, memory budgets and the byte
//! sizes that set them, progress bars.

mod atomic;
mod hash;
mod paths;
mod png;
mod size;

pub use atomic::{write_atomic, write_bytes_atomic, write_bytes_atomic_like};
pub use hash::{content_hash, files_hash};
pub use paths::{check_file_name, check_outputs};
pub use png::write_rgba_png;
pub use size::parse_byte_size;

/// An error and its sources, one line: `outer: cause: root cause`.
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut next = e.source();
    while let Some(s) = next {
        text.push_str(&format!(": {s}"));
        next = s.source();
    }
    text
}

use std::io::{self, Read};
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Default memory budget for grids and images, in bytes (CLI flag `--max-memory`, read
/// with [`parse_byte_size`]).
pub const DEFAULT_MEMORY_BUDGET: u64 = 8 << 30;

/// Errors of reading and writing files and of memory budgets.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// Writing failed; the destination was left as it was.
    #[error("cannot write {path}")]
    Write {
        /// The destination.
        path: PathBuf,
        /// What went wrong.
        #[source]
        source: io::Error,
    },
    /// Reading failed.
    #[error("cannot read {path}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        #[source]
        source: io::Error,
    },
    /// An input is a directory, a FIFO, a device…: reading it could block or never end.
    #[error("{path} is not a regular file ({kind}); refusing to read it")]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What it is instead.
        kind: &'static str,
    },
    /// An output names something that is not a regular file (a device, a FIFO, a
    /// folder): writing would replace it.
    #[error("{path} is {kind}, not a regular file; refusing to replace it")]
    NotReplaceable {
        /// The output.
        path: PathBuf,
        /// What it is instead.
        kind: &'static str,
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
    /// An output would overwrite an input of the same run.
    #[error("the output {output} is the input {input}; refusing to overwrite it")]
    OutputIsInput {
        /// The output.
        output: PathBuf,
        /// The input it names.
        input: PathBuf,
    },
    /// Memory the budget allowed could not be had from the system.
    #[error("cannot allocate {} for {what}: the system refused it (lower --max-memory, or free memory)", human_bytes(*.need))]
    Alloc {
        /// What the memory was for.
        what: String,
        /// Bytes asked for.
        need: u64,
    },
    /// An image could not be encoded.
    #[error("cannot encode the image {path}")]
    Encode {
        /// The destination.
        path: PathBuf,
        /// What went wrong.
        #[source]
        source: image::ImageError,
    },
    /// Two outputs of one run would be the same file.
    #[error("the outputs {first} and {second} are the same file; give each its own name")]
    OutputsCollide {
        /// The first output.
        first: PathBuf,
        /// The one that would overwrite it.
        second: PathBuf,
    },
}

/// A vector of `len` copies of `value`, its memory asked of the system first: a refusal
/// (a budget raised past the machine's memory) is an error naming `what`, not an abort.
pub fn try_filled<T: Clone>(len: usize, value: T, what: &str) -> Result<Vec<T>, IoError> {
    let mut v = try_with_capacity(len, what)?;
    v.resize(len, value);
    Ok(v)
}

/// An empty vector with room for `len` elements, asked of the system first (see
/// [`try_filled`]).
pub fn try_with_capacity<T>(len: usize, what: &str) -> Result<Vec<T>, IoError> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| IoError::Alloc {
        what: what.to_string(),
        need: (len as u64).saturating_mul(std::mem::size_of::<T>() as u64),
    })?;
    Ok(v)
}

/// Reads the regular file `path` (symbolic links followed), refusing anything else (a
/// FIFO would block, `/dev/zero` never ends) and a file larger than `budget` bytes,
/// before reading it.
pub fn read_regular(path: &Path, budget: u64) -> Result<Vec<u8>, IoError> {
    let (file, len) = open_regular(path, budget)?;
    let mut bytes = Vec::with_capacity(len as usize);
    // A file that grows while it is read stops one byte past the budget.
    file.take(budget.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|source| IoError::Read {
            path: path.to_path_buf(),
            source,
        })?;
    check_budget(
        format!("reading {}", path.display()),
        bytes.len() as u64,
        budget,
    )?;
    Ok(bytes)
}

/// Opens the regular file `path` as [`read_regular`] would read it (same refusals),
/// for a reader that looks at its header first: the file and its length.
pub fn open_regular(path: &Path, budget: u64) -> Result<(std::fs::File, u64), IoError> {
    let read_err = |source| IoError::Read {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(read_err)?;
    if !meta.is_file() {
        return Err(IoError::NotAFile {
            path: path.to_path_buf(),
            kind: file_kind(&meta.file_type()),
        });
    }
    check_budget(format!("reading {}", path.display()), meta.len(), budget)?;
    let file = std::fs::File::open(path).map_err(read_err)?;
    Ok((file, meta.len()))
}

/// What a file that is not a regular file is, for messages.
pub(crate) fn file_kind(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
}

/// Requests from this size on are asked of the system too ([`check_budget`]).
const ASK_FROM: u64 = 256 << 20;

/// Refuses a request of `need` bytes over `budget`, or one the system refuses, before
/// anything is allocated. A budget raised past the machine (`--max-memory 1T`) let an
/// allocation the system cannot make abort the process; a large request is now asked of
/// the system first (reserved, never touched, and given back at once: no page is used),
/// and a refusal is an error here.
pub fn check_budget(what: impl Into<String>, need: u64, budget: u64) -> Result<(), IoError> {
    if need > budget {
        return Err(IoError::OverBudget {
            what: what.into(),
            need,
            budget,
        });
    }
    if need >= ASK_FROM {
        let len = usize::try_from(need).unwrap_or(usize::MAX);
        try_with_capacity::<u8>(len, &what.into())?;
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

/// A spinner saying `message` while work of unknown length runs (compiling a tree: DEMs
/// read, landforms generated, Feature Volumes built), drawn like [`progress`] bars: on a
/// terminal's standard error, not when piped or `quiet`.
pub fn spinner(message: &str, quiet: bool) -> ProgressBar {
    let target = if quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(None, target);
    bar.set_style(
        ProgressStyle::with_template("{msg:>12} {spinner} {elapsed_precise}")
            .expect("static template"),
    );
    bar.set_message(message.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
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
    fn budget_is_enforced_before_allocation() {
        let e = check_budget("a 4096³ grid", 1 << 40, DEFAULT_MEMORY_BUDGET).unwrap_err();
        assert!(e.to_string().contains("1.0 TiB"), "{e}");
        assert!(check_budget("small", 10, 100).is_ok());
    }

    #[cfg(unix)]
    #[test]
    fn only_regular_files_within_the_budget_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let zero = dir.path().join("zero.tif");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        let e = read_regular(&zero, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
        let fifo = dir.path().join("fifo.asc");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.is_ok_and(|s| s.success()), "mkfifo");
        let e = read_regular(&fifo, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("FIFO"), "{e}");
        let e = read_regular(dir.path(), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        let file = dir.path().join("f.bin");
        std::fs::write(&file, [7u8; 100]).unwrap();
        assert_eq!(read_regular(&file, 100).unwrap(), [7u8; 100]);
        let e = read_regular(&file, 99).unwrap_err();
        assert!(matches!(e, IoError::OverBudget { need: 100, .. }), "{e}");
    }
}
