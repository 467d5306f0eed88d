//! The command line: a thin layer over the library. Each subcommand lives in its own file.

use clap::{Parser, Subcommand};

pub mod dem;

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
    /// Inspect and convert DEMs.
    Dem(dem::DemArgs),
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Dem(a) => dem::run(a),
    }
}
