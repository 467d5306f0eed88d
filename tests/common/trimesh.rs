//! What Python's `trimesh` (the loader behind many DCC and engine pipelines) makes of an
//! exported mesh: a Blender-style import check. `.ci/run` installs it with pip.

use std::path::Path;
use std::process::Command;

use super::optional::{REQUIRE_TRIMESH, unavailable};

/// Loads a mesh file with trimesh and prints, as JSON, each geometry's visual (kind,
/// material type, UV count), vertex and face counts, and the scene's bounds (node
/// transforms applied).
const SCRIPT: &str = r#"
import json, sys
import trimesh
scene = trimesh.load(sys.argv[1], force="scene")
out = {"bounds": scene.bounds.tolist(), "geometries": []}
for name, g in scene.geometry.items():
    v = g.visual
    uv = getattr(v, "uv", None)
    mat = getattr(v, "material", None)
    out["geometries"].append({
        "name": name,
        "kind": v.kind,
        "material": type(mat).__name__ if mat is not None else None,
        "uvs": 0 if uv is None else len(uv),
        "vertices": len(g.vertices),
        "faces": len(g.faces),
    })
print(json.dumps(out))
"#;

/// Runs Python with `args`; `None` (after a notice, or a failure where
/// [`REQUIRE_TRIMESH`] is set) when Python or trimesh is missing.
fn python(args: &[&std::ffi::OsStr]) -> Option<std::process::Output> {
    let out = match Command::new("python3").args(args).output() {
        Ok(o) => o,
        Err(e) => {
            unavailable(
                REQUIRE_TRIMESH,
                &format!("trimesh: python3 cannot run ({e})"),
            );
            return None;
        }
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && stderr.contains("No module named 'trimesh'") {
        unavailable(
            REQUIRE_TRIMESH,
            "trimesh is not installed (pip install trimesh)",
        );
        return None;
    }
    Some(out)
}

/// trimesh's version; `None` when Python or trimesh is missing (see [`python`]).
pub fn trimesh_version() -> Option<String> {
    let out = python(&[
        "-c".as_ref(),
        "import trimesh; print(trimesh.__version__)".as_ref(),
    ])?;
    assert!(out.status.success(), "{out:?}");
    Some(String::from_utf8_lossy(&out.stdout).trim().to_owned())
}

/// What trimesh loads from `file` (see [`SCRIPT`]); `None` when Python or trimesh is
/// missing. Panics when trimesh fails on the file.
pub fn trimesh_import(file: &Path) -> Option<serde_json::Value> {
    let out = python(&["-c".as_ref(), SCRIPT.as_ref(), file.as_os_str()])?;
    assert!(
        out.status.success(),
        "trimesh cannot load {}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_slice(&out.stdout).expect("the script prints JSON"))
}
