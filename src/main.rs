//! hexsim's command line: parse, dispatch (one file per command in `cli/`), exit codes — the work
//! is in the library.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = cli::Cli::parse();
    // Ctrl-C / SIGTERM stop the run at the next step; it then writes what it has, marked incomplete.
    let _ = ctrlc::set_handler(|| {
        hexsim::interrupt::INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed);
    });
    let result = cli.execute();
    match result {
        Ok(code) => code,
        // work cut short by Ctrl-C (terrain generation, set-up) ends as an interruption
        Err(_) if hexsim::interrupt::interrupted() => {
            eprintln!("{}", hexsim::interrupt::MESSAGE);
            ExitCode::from(130)
        }
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::from(2)
        }
    }
}
