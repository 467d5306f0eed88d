//! Atomic writes: the bytes go to a temporary file beside the destination, which is then
//! renamed over it, so a failed or interrupted run never leaves a truncated file.
//!
//! The temporary file is `.NAME.tmpPID` and its writer holds an exclusive lock on it. A
//! run killed mid-write leaves it behind, unlocked; the next write to the same
//! destination removes such leftovers (unlocked, and older than [`STALE_AFTER`]).

use std::fs::File;
use std::io::{self, Write};
use std::path::Path;
use std::time::{Duration, SystemTime};

use super::IoError;

/// A temporary file this old whose writer is gone is a leftover.
pub(crate) const STALE_AFTER: Duration = Duration::from_secs(10);

/// Writes a file atomically (see the module documentation). A file it replaces keeps its
/// permissions (a mode-600 tree stays private).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), IoError> {
    write_atomic_as(path, None, write)
}

/// Writes `bytes` to `path` atomically with the permissions of the file `like` (a backup
/// takes its original's), or of the file it replaces when `like` cannot be read.
pub fn write_bytes_atomic_like(path: &Path, bytes: &[u8], like: &Path) -> Result<(), IoError> {
    let perms = std::fs::metadata(like).ok().map(|m| m.permissions());
    write_atomic_as(path, perms, |w| w.write_all(bytes))
}

/// [`write_atomic`] with the new file's permissions `perms`, or the replaced file's.
fn write_atomic_as(
    path: &Path,
    perms: Option<std::fs::Permissions>,
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
        .ok_or_else(|| err(io::Error::other("not a file name")))?
        .to_string_lossy();
    // Renaming over a device, a FIFO or a folder would replace it with a file.
    let existing = std::fs::metadata(path).ok();
    if let Some(meta) = existing.as_ref().filter(|m| !m.is_file()) {
        return Err(IoError::NotReplaceable {
            path: path.to_path_buf(),
            kind: super::file_kind(&meta.file_type()),
        });
    }
    let perms = perms.or_else(|| existing.map(|m| m.permissions()));
    let prefix = format!(".{name}.tmp");
    remove_leftovers(dir, &prefix);
    let tmp = dir.join(format!("{prefix}{}", std::process::id()));
    let result = (|| {
        let file = File::create(&tmp)?;
        file.try_lock().map_err(io::Error::other)?;
        // Before any byte is written: a private file's content is never readable by others.
        if let Some(p) = perms {
            file.set_permissions(p)?;
        }
        let mut out = io::BufWriter::new(file);
        write(&mut out)?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
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

/// Removes the temporary files `PREFIX<pid>` in `dir` that no writer holds any more.
/// Best effort: a leftover that cannot be examined is left alone.
fn remove_leftovers(dir: &Path, prefix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let now = SystemTime::now();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(|n| n.strip_prefix(prefix)) else {
            continue;
        };
        if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
            continue;
        }
        let path = entry.path();
        let stale = File::open(&path).is_ok_and(|f| {
            let old = f
                .metadata()
                .and_then(|m| m.modified())
                .is_ok_and(|t| now.duration_since(t).is_ok_and(|age| age >= STALE_AFTER));
            old && f.try_lock().is_ok()
        });
        if stale {
            let _ = std::fs::remove_file(&path);
        }
    }
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

    #[cfg(unix)]
    #[test]
    fn only_regular_files_are_replaced() {
        let dir = tempfile::tempdir().unwrap();
        // A link to a character device: the rename would replace the device itself.
        let full = dir.path().join("full.png");
        std::os::unix::fs::symlink("/dev/null", &full).unwrap();
        let e = write_bytes_atomic(Path::new("/dev/null"), b"png").unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
        let e = write_bytes_atomic(&full, b"png").unwrap_err();
        assert!(matches!(e, IoError::NotReplaceable { .. }), "{e}");
        assert!(std::fs::symlink_metadata(&full).unwrap().is_symlink());
        let folder = dir.path().join("out.glb");
        std::fs::create_dir(&folder).unwrap();
        let e = write_bytes_atomic(&folder, b"glb").unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        assert!(folder.is_dir());
        let file = dir.path().join("file.png");
        write_bytes_atomic(&file, b"a").unwrap();
        write_bytes_atomic(&file, b"b").unwrap();
        assert_eq!(std::fs::read(&file).unwrap(), b"b");
    }

    #[cfg(unix)]
    #[test]
    fn replaced_files_and_backups_keep_their_mode() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let tree = dir.path().join("t.ron");
        write_bytes_atomic(&tree, b"one").unwrap();
        std::fs::set_permissions(&tree, std::fs::Permissions::from_mode(0o600)).unwrap();
        write_bytes_atomic(&tree, b"two").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&tree), 0o600);
        let bak = dir.path().join("t.ron.bak");
        write_bytes_atomic_like(&bak, b"two", &tree).unwrap();
        assert_eq!(mode(&bak), 0o600);
    }

    #[test]
    fn leftovers_of_killed_writers_are_removed_by_the_next_write() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mesh.glb");
        let old = SystemTime::now() - 2 * STALE_AFTER;
        let leftover = |name: &str| {
            let p = dir.path().join(name);
            let f = File::create(&p).unwrap();
            f.set_modified(old).unwrap();
            (p, f)
        };
        // A killed writer's file, a live writer's (locked), a fresh one, another name's.
        let (dead, _) = leftover(".mesh.glb.tmp4242");
        let (live, live_file) = leftover(".mesh.glb.tmp4343");
        live_file.try_lock().unwrap();
        let fresh = dir.path().join(".mesh.glb.tmp4444");
        File::create(&fresh).unwrap();
        let (other, _) = leftover(".other.glb.tmp4545");
        write_bytes_atomic(&path, b"mesh").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"mesh");
        assert!(!dead.exists(), "the killed writer's leftover is removed");
        assert!(live.exists() && fresh.exists() && other.exists());
    }
}
