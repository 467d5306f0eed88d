//! The command line: a thin layer over the library. Each subcommand lives in its own file.

pub mod build;
pub mod curves;
pub mod dem;
pub mod eval;
pub mod sample;
pub mod tree;

use clap::{Parser, Subcommand};

pub mod render;
pub mod run;

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
    /// The main job: mesh a tree's region and render a preview, timing every stage.
    Run(run::RunArgs),
    /// Build a mesh (.glb, .gltf, .obj, .ply) from a tree with bound-pruned Marching Cubes.
    Build(build::BuildArgs),
    /// Inspect and convert DEMs.
    Dem(dem::DemArgs),
    /// Validate, inspect and edit tree files.
    Tree(tree::TreeArgs),
    /// Print field values and gradients at points (CSV `x,y,z` from a file or stdin).
    Eval(eval::EvalArgs),
    /// Sample a tree's field on a grid as a float32 .npy with a JSON sidecar.
    Sample(sample::SampleArgs),
    /// Render a PNG preview of a tree by tracing its implicit surface.
    Render(render::RenderArgs),
    /// Feature Curves: run the voxel pipeline on a `FeatureVolume` file.
    Curves(curves::CurvesArgs),
}

/// Loads and compiles a tree file.
pub fn load_tree(path: &std::path::Path) -> anyhow::Result<crate::field::Tree> {
    let compiled = crate::scene::load(path)?.compile()?;
    for n in &compiled.notices {
        eprintln!("notice: {n}");
    }
    Ok(compiled.tree)
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Run(a) => run::run(a),
        Command::Build(a) => build::run(a),
        Command::Dem(a) => dem::run(a),
        Command::Tree(a) => tree::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Sample(a) => sample::run(a),
        Command::Render(args) => render::run(args),
        Command::Curves(a) => curves::run(a),
    }
}
