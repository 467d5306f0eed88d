//! A folder laid out like a checkout for the doc commands: `trees/` copied (commands edit
//! tree files), `../shared` linked to the real one (the DEMs), and `karstic` first on the
//! `PATH` as the binary under test. Commands run in it with bash, and what they write stays
//! in the temporary folder.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::{copy_dir, root};

/// A temporary checkout; removed when dropped.
pub struct Sandbox {
    _dir: tempfile::TempDir,
    repo: PathBuf,
    path: std::ffi::OsString,
}

/// What a command did: its exit status and its stdout and stderr interleaved as a
/// terminal shows them.
pub struct Ran {
    /// Whether it exited with status 0.
    pub ok: bool,
    /// stdout and stderr, in the order they were written.
    pub output: String,
}

impl Sandbox {
    /// A fresh sandbox.
    pub fn new() -> Self {
        let dir = tempfile::tempdir().expect("temporary folder");
        let repo = dir.path().join("repo");
        copy_dir(&root().join("trees"), &repo.join("trees"));
        let shared = root().join("../shared");
        assert!(
            shared.is_dir(),
            "{} is missing: the docs' DEM commands read ../shared/data/dem/ beside the checkout",
            shared.display()
        );
        std::os::unix::fs::symlink(&shared, dir.path().join("shared")).expect("link ../shared");
        let bin = dir.path().join("bin");
        std::fs::create_dir(&bin).expect("bin/");
        std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_karstic"), bin.join("karstic"))
            .expect("link karstic");
        let mut paths = vec![bin];
        paths.extend(std::env::split_paths(
            &std::env::var_os("PATH").unwrap_or_default(),
        ));
        let path = std::env::join_paths(paths).expect("PATH");
        Sandbox {
            _dir: dir,
            repo,
            path,
        }
    }

    /// The checkout's root: where commands run.
    pub fn repo(&self) -> &Path {
        &self.repo
    }

    /// Runs `script` with `bash -o pipefail` in the checkout's root.
    pub fn run(&self, script: &str) -> Ran {
        let out = Command::new("bash")
            .args(["-o", "pipefail", "-c"])
            .arg(format!("{{\n{script}\n}} 2>&1"))
            .current_dir(&self.repo)
            .env("PATH", &self.path)
            .output()
            .expect("bash runs");
        Ran {
            ok: out.status.success(),
            output: String::from_utf8_lossy(&out.stdout).into_owned(),
        }
    }
}
