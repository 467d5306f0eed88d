//! The command line: a thin layer over the library. Each subcommand lives in its own file.

pub mod curves;

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
    /// Feature Curves: run the voxel pipeline on a `FeatureVolume` file.
    Curves(curves::CurvesArgs),
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Curves(a) => curves::run(a),
    }
}
