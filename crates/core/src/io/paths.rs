//! Which files a run reads and writes: outputs must not overwrite inputs or each other.

use std::path::{Path, PathBuf};

use super::IoError;

/// Refuses a run whose `outputs` would overwrite one of its `inputs` (the same file by
/// another name counts: `./a.ron`, `a.ron`, a symbolic or hard link to it) or whose
/// outputs would overwrite each other, before anything is written.
pub fn check_outputs(
    inputs: &[impl AsRef<Path>],
    outputs: &[impl AsRef<Path>],
) -> Result<(), IoError> {
    for (k, out) in outputs.iter().map(AsRef::as_ref).enumerate() {
        if let Some(input) = inputs.iter().map(AsRef::as_ref).find(|i| same_file(i, out)) {
            return Err(IoError::OutputIsInput {
                output: out.to_path_buf(),
                input: input.to_path_buf(),
            });
        }
        if let Some(other) = outputs[..k]
            .iter()
            .map(AsRef::as_ref)
            .find(|o| same_file(o, out))
        {
            return Err(IoError::OutputsCollide {
                first: other.to_path_buf(),
                second: out.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Refuses a stem of output files that is not a plain file name: empty, `.`, `..`, or
/// with a path separator (`../../x` would write outside the output folder).
pub fn check_file_name(stem: &str) -> Result<(), String> {
    let bad = stem.is_empty()
        || stem == "."
        || stem == ".."
        || stem.contains(['/', '\\', '\0'])
        || Path::new(stem).is_absolute();
    match bad {
        true => Err(format!(
            "{stem:?} is not a file name (no folders, `.` or `..`; the output folder says where)"
        )),
        false => Ok(()),
    }
}

/// True when `a` and `b` name the same file, existing or not.
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        use std::os::unix::fs::MetadataExt;
        return (ma.dev(), ma.ino()) == (mb.dev(), mb.ino());
    }
    resolved(a) == resolved(b)
}

/// `path` with its links and `.`/`..` resolved as far as it exists.
fn resolved(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    let parent = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (parent.canonicalize(), path.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_may_not_be_inputs_or_each_other() {
        let dir = tempfile::tempdir().unwrap();
        let tree = dir.path().join("t.ron");
        std::fs::write(&tree, "x").unwrap();
        let dotted = dir.path().join(".").join("t.ron");
        let e = check_outputs(&[&tree], &[&dotted]).unwrap_err();
        assert!(matches!(e, IoError::OutputIsInput { .. }), "{e}");
        assert!(e.to_string().contains("t.ron"), "{e}");
        #[cfg(unix)]
        {
            let link = dir.path().join("link.ron");
            std::os::unix::fs::symlink(&tree, &link).unwrap();
            assert!(check_outputs(&[&tree], &[&link]).is_err());
            let hard = dir.path().join("hard.ron");
            std::fs::hard_link(&tree, &hard).unwrap();
            assert!(check_outputs(&[&tree], &[&hard]).is_err());
        }
        let npy = dir.path().join("s.json");
        let e = check_outputs(&[&tree], &[&npy, &dir.path().join("s.json")]).unwrap_err();
        assert!(matches!(e, IoError::OutputsCollide { .. }), "{e}");
        for bad in ["../../evil", "a/b", "..", "", "/abs", "a\\b"] {
            assert!(check_file_name(bad).is_err(), "{bad:?}");
        }
        assert!(check_file_name("jacksboro_full").is_ok());
        let png = dir.path().join("t.png");
        assert!(check_outputs(&[&tree], &[&png, &dir.path().join("c.png")]).is_ok());
    }
}
