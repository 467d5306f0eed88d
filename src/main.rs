use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = karstic::cli::Cli::parse();
    match karstic::cli::run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
