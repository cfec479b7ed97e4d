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
    quiet_headless_vulkan();
    let args = cli::Cli::parse();
    match tessellate::run(args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Without a desktop login (no `XDG_RUNTIME_DIR`), Mesa's device-select Vulkan layer probes for
/// a Wayland display and libwayland prints an error line per probe; the layer only
/// reorders adapters, which a headless run does not need. Set before any thread starts.
fn quiet_headless_vulkan() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && std::env::var_os("NODEVICE_SELECT").is_none()
    {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}
