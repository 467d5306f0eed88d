//! The command line: a thin layer over the library. Each subcommand lives in its own file.

pub mod build;
pub mod sample;

use clap::{Parser, Subcommand};

/// karstic: implicit terrain modelling — DEMs amplified with caves, arches and overhangs.
#[derive(Parser, Debug)]
#[command(name = "karstic", version, about)]
pub struct Cli {
    /// Subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// All subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Build a mesh (.glb, .gltf, .obj, .ply) from a tree with bound-pruned Marching Cubes.
    Build(build::BuildArgs),
    /// Sample a tree's field on a grid as a float32 .npy with a JSON sidecar.
    Sample(sample::SampleArgs),
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Build(a) => build::run(a),
        Command::Sample(a) => sample::run(a),
    }
}
