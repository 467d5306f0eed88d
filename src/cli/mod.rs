//! The command line: a thin layer over the library. Each subcommand lives in its own file.

pub mod eval;
pub mod tree;

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
    /// Validate, inspect and edit tree files.
    Tree(tree::TreeArgs),
    /// Print field values and gradients at points (CSV `x,y,z` from a file or stdin).
    Eval(eval::EvalArgs),
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Tree(a) => tree::run(a),
        Command::Eval(a) => eval::run(a),
    }
}
