//! The `karstic` command: a thin layer over the library, one file per subcommand in
//! [`cli`]. The rules (budgets, fallbacks, validation) live in the library; the binary
//! parses flags, calls it and prints what it reports.

mod cli;

use clap::Parser;

fn main() -> std::process::ExitCode {
    // Mesa's window-system probes print "XDG_RUNTIME_DIR is invalid or not set" twice
    // when wgpu lists adapters on a headless machine. karstic opens no window: point it
    // at the temporary folder when it is unset.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: no other thread exists yet; nothing reads the environment concurrently.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
