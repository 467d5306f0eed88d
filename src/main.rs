//! The `karstic` command: a thin layer over the library, one file per subcommand in
//! [`cli`]. The rules (budgets, fallbacks, validation) live in the library; the binary
//! parses flags, calls it and prints what it reports.

mod cli;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
