//! The Khronos glTF validator (`tests/gltf_validate.mjs` on Node), shared by the tests that
//! write glTF. `.ci/run` installs the package into `.node/`.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs the Khronos validator on `file`; `None` when Node or the package is missing.
pub fn khronos_validate(file: &Path) -> Option<(bool, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut paths = vec![root.join(".node/node_modules")];
    if let Ok(out) = Command::new("npm").args(["root", "-g"]).output() {
        paths.push(PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()));
    }
    let out = Command::new("node")
        .arg(root.join("tests/gltf_validate.mjs"))
        .arg(file)
        .env("NODE_PATH", std::env::join_paths(paths).unwrap())
        .output();
    let out = match out {
        Ok(o) => o,
        Err(_) => {
            println!("notice: node not found; skipping the Khronos glTF validator");
            return None;
        }
    };
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(3) {
        println!(
            "notice: {}; skipping the Khronos glTF validator",
            text.trim()
        );
        return None;
    }
    Some((out.status.success(), text))
}

/// Asserts that the validator (when available) reports no error and no warning on `file`.
pub fn assert_valid(file: &Path) {
    if let Some((ok, report)) = khronos_validate(file) {
        assert!(ok, "{report}");
        assert!(
            report.contains("\"numErrors\": 0") && report.contains("\"numWarnings\": 0"),
            "{}: {report}",
            file.display()
        );
    }
}
