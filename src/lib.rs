//! karstic: terrain modelling with implicit construction trees.
//!
//! A DEM becomes an implicit primitive, Feature Curves become an S-field primitive, and
//! both combine with skeletal primitives through blend, carve and warp nodes. The compiled
//! [`field`] tree is the single thing the mesher and the tracers consume.
//!
//! This crate gathers the workspace's layers under one name; each is a crate of its own,
//! which a library user can take alone (ARCHITECTURE.md): `karstic-core` (the field, the
//! value types, I/O), `karstic-dem`, `karstic-mesh`, `karstic-volume` (Feature Curves and
//! the voxel pipeline), `karstic-elevation`, `karstic-geology`, `karstic-render` (the
//! tracers, wgpu), `karstic-scene` (tree files and what runs them) and `karstic-editor`.

pub use karstic_core::{cache, field, io, rng, value};
pub use karstic_dem::dem;
pub use karstic_editor::editor;
pub use karstic_elevation::elevation;
pub use karstic_geology::geology;
pub use karstic_mesh::mesh;
pub use karstic_render::{render, tape};
pub use karstic_scene::{
    analysis, compile, erosion, heightmap, job, landform, picture, procedural, scene, tiles,
};
pub use karstic_volume::{curves, voxel};
