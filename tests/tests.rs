//! The integration tests: one binary (linking wgpu and naga once), a module per area.

// Shared helpers.
mod common;
mod curves_util;
mod doc_util;
mod gltf_validator;
mod mesh_fields;

// Suites.
mod cli_inputs;
mod curves_cli;
mod curves_field;
mod curves_mesh;
mod curves_scenes;
mod dem_cli;
mod dem_corpus;
mod dem_formats;
mod dem_fuzz;
mod dem_implicit;
mod dem_mesh;
mod dem_readers;
mod doc_commands;
mod doc_pictures;
mod docs;
mod elevation_trees;
mod erosion;
mod heightmap;
mod main_job;
mod masks;
mod meld;
mod mesh_cli;
mod mesh_export;
mod mesh_extract;
mod optional_checks;
mod previews;
mod primitives;
mod render_cli;
mod render_gpu;
mod render_trace;
mod render_trees;
mod tape_conformance;
mod tape_header;
mod tiles;
mod tin;
mod tree_core;
mod tree_files;
mod trees_build;
