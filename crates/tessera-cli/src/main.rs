//! `tessera`: tessellate Bézier and Catmull-Clark surfaces from the command line.
//!
//! Every failure prints one line (`error: FILE:LINE: problem`) and exits non-zero; no
//! output file is left behind.

mod catmull_clark;
mod cli;
mod gpu;
mod render;
mod tessellate;

use clap::Parser;

fn main() -> std::process::ExitCode {
    let args = cli::Cli::parse();
    match tessellate::run(args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
