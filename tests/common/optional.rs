//! Checks that need a tool a machine may lack: the GPU comparisons need an adapter, the
//! glTF export tests need Node and the Khronos validator, the import checks Python and
//! trimesh, the heightmap export tests GDAL's `gdalinfo`, the tiles' array job Slurm
//! (`slurm-wlm` and `munge`, run as root). Locally a missing tool prints a
//! notice and the check is skipped; where the tool's `KARSTIC_REQUIRE_*` variable is set
//! (to anything but empty or `0`; `.ci/run` sets them all) its absence fails the test.

/// Makes a missing GPU adapter a test failure.
pub const REQUIRE_GPU: &str = "KARSTIC_REQUIRE_GPU";

/// Makes a missing Node or Khronos glTF validator a test failure.
pub const REQUIRE_GLTF_VALIDATOR: &str = "KARSTIC_REQUIRE_GLTF_VALIDATOR";

/// Makes a missing Python or trimesh (the import checks of the exports) a test failure.
pub const REQUIRE_TRIMESH: &str = "KARSTIC_REQUIRE_TRIMESH";

/// Makes a missing `gdalinfo` (GDAL's command-line tools) a test failure.
pub const REQUIRE_GDAL: &str = "KARSTIC_REQUIRE_GDAL";

/// Makes a missing Slurm (`slurmctld`, `slurmd`, `sbatch`, `munged`, or not running as
/// root) a test failure.
pub const REQUIRE_SLURM: &str = "KARSTIC_REQUIRE_SLURM";

/// Whether the environment variable `var` requires its tool: set, not empty, not `0`.
fn required(var: &str) -> bool {
    std::env::var_os(var).is_some_and(|v| !v.is_empty() && v != "0")
}

/// Reports that a check cannot run for `reason`: panics when `var` requires the tool,
/// prints a notice otherwise (the caller then skips the check).
#[track_caller]
pub fn unavailable(var: &str, reason: &str) {
    assert!(
        !required(var),
        "{reason} ({var} is set: the check may not be skipped)"
    );
    eprintln!("NOTICE: {reason}; skipping the check (set {var}=1 to make this a failure)");
}
