//! The Khronos glTF validator (`tests/gltf_validate.mjs` on Node), shared by the tests that
//! write glTF. `.ci/run` installs the package into `.node/`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::{REQUIRE_GLTF_VALIDATOR, unavailable};

/// Runs `tests/gltf_validate.mjs` with `args`; `None` (after a notice, or a failure where
/// [`REQUIRE_GLTF_VALIDATOR`] is set) when Node or the package is missing.
fn run(args: &[&std::ffi::OsStr]) -> Option<Output> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut paths = vec![root.join(".node/node_modules")];
    if let Ok(out) = Command::new("npm").args(["root", "-g"]).output() {
        paths.push(PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()));
    }
    let out = Command::new("node")
        .arg(root.join("tests/gltf_validate.mjs"))
        .args(args)
        .env("NODE_PATH", std::env::join_paths(paths).unwrap())
        .output();
    let out = match out {
        Ok(o) => o,
        Err(e) => {
            unavailable(
                REQUIRE_GLTF_VALIDATOR,
                &format!("the Khronos glTF validator: node cannot run ({e})"),
            );
            return None;
        }
    };
    if out.status.code() == Some(3) {
        unavailable(
            REQUIRE_GLTF_VALIDATOR,
            &format!(
                "the Khronos glTF validator: {}",
                String::from_utf8_lossy(&out.stdout).trim()
            ),
        );
        return None;
    }
    Some(out)
}

/// The validator's version; `None` when Node or the package is missing (see [`run`]).
pub fn version() -> Option<String> {
    let out = run(&["--version".as_ref()])?;
    assert!(out.status.success(), "{out:?}");
    Some(String::from_utf8_lossy(&out.stdout).trim().to_owned())
}

/// Runs the Khronos validator on `file`: whether it found neither errors nor warnings,
/// and its report. `None` when Node or the package is missing (see [`run`]).
pub fn khronos_validate(file: &Path) -> Option<(bool, String)> {
    let out = run(&[file.as_os_str()])?;
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    Some((out.status.success(), text))
}

/// The one message a karstic mesh may carry: the validator's information (not a warning)
/// that no texture of the file reads TEXCOORD_0. The UVs are there for the user's own
/// textures, the texture masks (`karstic masks`) first of all.
const UNUSED_UVS: (&str, &str) = ("UNUSED_OBJECT", "/attributes/TEXCOORD_0");

/// Asserts that the validator (when available) reports nothing on `file`: no error, no
/// warning, and no information or hint but the unused-UVs note ([`UNUSED_UVS`]).
pub fn assert_valid(file: &Path) {
    let Some((ok, report)) = khronos_validate(file) else {
        return;
    };
    assert!(ok, "{report}");
    // The report is the JSON object the script prints (whatever Node adds on stderr).
    let json: serde_json::Value = report
        .find('{')
        .and_then(|at| {
            serde_json::Deserializer::from_str(&report[at..])
                .into_iter()
                .next()?
                .ok()
        })
        .unwrap_or_else(|| panic!("{}: the report is not JSON: {report}", file.display()));
    for count in ["numErrors", "numWarnings"] {
        assert_eq!(json[count], 0, "{}: {report}", file.display());
    }
    let messages = json["messages"].as_array().expect("a message list");
    for m in messages {
        let code = m["code"].as_str().unwrap_or_default();
        let pointer = m["pointer"].as_str().unwrap_or_default();
        assert!(
            code == UNUSED_UVS.0 && pointer.ends_with(UNUSED_UVS.1),
            "{}: {report}",
            file.display()
        );
    }
    let notes = json["numInfos"].as_u64().unwrap_or(u64::MAX)
        + json["numHints"].as_u64().unwrap_or(u64::MAX);
    assert_eq!(notes, messages.len() as u64, "{}: {report}", file.display());
}
