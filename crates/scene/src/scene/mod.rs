//! Tree files: the RON format users edit, its loading and validation, and splicing values
//! into it. Compiling a scene into a field tree, and editing a file (each edit is checked
//! by compiling), come above the landform generators the compiler runs.

pub mod heightfield;
pub mod landform;
pub mod load;
pub mod spec;
pub mod splice;
pub mod validate;
pub mod volume;

pub use heightfield::{AmplifySpec, DemCache, HeightfieldSpec};
pub use load::{SceneError, SceneFile, load, parse_scene};
pub use spec::{FORMAT_VERSION, NodeSpec, Scene};
pub use volume::VolumeFile;
