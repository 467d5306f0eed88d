//! Tree files: the RON format users edit, its validation, compilation and edits.

pub mod compile;
pub mod edit;
pub mod heightfield;
pub mod load;
pub mod spec;
pub mod splice;
pub mod validate;
pub mod volume;

pub use compile::{Compiled, compile_scene};
pub use heightfield::{DemCache, HeightfieldSpec};
pub use load::{SceneError, SceneFile, load, parse_scene};
pub use spec::{FORMAT_VERSION, NodeSpec, Scene};
pub use volume::VolumeFile;
