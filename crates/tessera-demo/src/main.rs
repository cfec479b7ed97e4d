//! `tessera-demo`: an interactive window around tessera's stages.
//!
//! ```text
//! cargo run --release -p tessera-demo -- [INPUT]
//! ```
//!
//! `INPUT` is any file `tessera render` takes: a Newell teaset file (Bézier patches) or a
//! Catmull-Clark control mesh (OBJ with OpenSubdiv tags, glTF, GLB); without it the Utah
//! teapot opens. Other models come from the panel's menu of shipped assets or by dropping
//! a file on the window. The surface goes up to the GPU once; the stage's kernels write
//! the buffers that `tessera_wgpu::MeshRenderer` draws, and run again only when something
//! they depend on changes. Controls, the panel and the stats: `docs/demo.md`.
//!
//! # Scripted mode
//!
//! ```text
//! tessera-demo INPUT --frames N [--screenshot OUT.png] [--size WxH] [--script FILE]
//!                    [--stats-json OUT.json] [--no-panel]
//! ```
//!
//! runs N frames in a real window, saves the last one (with the panel unless
//! `--no-panel`) and exits 0. Animation time advances by 1/30 s per frame, and every
//! frame waits for the GPU, so a run gives the same frames and figures on any machine.
//! Any wgpu validation error, or a tessellation the stage refuses, exits 1 with the error
//! on stderr. With `--no-panel` the view is `tessera render`'s at the same size: the same
//! framing, renderer options, background and tessellation defaults.
//!
//! `--script FILE` replays one action per line at a frame number (`#` starts a comment):
//!
//! ```text
//! FRAME orbit YAW PITCH       degrees about the up axis, and up or down
//! FRAME zoom FACTOR           above 1 moves closer
//! FRAME pan RIGHT UP          in view heights
//! FRAME frame                 the home view (the key F)
//! FRAME up x|y|z              the model's up axis (framed again)
//! FRAME set KEY VALUE         method map2p|map4p|map8p|flat|uniform|adaptive,
//!                             threshold T (Bézier, model units), tolerance-px P
//!                             (Catmull-Clark, pixels of the view: the default, 1),
//!                             tolerance-rel R (Catmull-Clark, fraction of the
//!                             diagonal, instead of pixels), cull-backfaces on|off
//!                             (Catmull-Clark in pixels), max-depth D,
//!                             first-split search|midpoint, segments N,
//!                             wireframe on|off, patch-tint on|off, backend gpu|cpu
//! FRAME animate on|off|toggle the control points' animation
//! FRAME reset                 control points at rest, animation time 0
//! FRAME load FILE             opens FILE (a failure keeps the open model, as in the window)
//! FRAME screenshot OUT.png    saves that frame
//! ```
//!
//! Frames count from 0; a line that does not parse, or a setting the model does not take,
//! is `error: FILE:LINE: problem` and exit 1. `--stats-json` writes one object per frame:
//! `frame`, `triangles`, `vertices`, `patches`, `guaranteed_bound`, `gpu_ms` (timestamp
//! queries) or `wall_ms`, `frame_ms`, `growths`, `tessellated`.

mod app;
mod camera;
mod gpu;
mod panel;
mod scene;
mod script;
mod stats;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;

#[derive(Parser, Debug)]
#[command(
    name = "tessera-demo",
    version,
    about = "An interactive window around tessera's GPU tessellation stages"
)]
struct Args {
    /// A Newell teaset file or a Catmull-Clark control mesh (.obj, .gltf, .glb); default
    /// the Utah teapot (assets/teaset/teapot).
    input: Option<PathBuf>,
    /// Scripted mode: run this many frames, then exit.
    #[arg(long)]
    frames: Option<u32>,
    /// Scripted mode: save the last frame as a PNG.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Window size in pixels, WIDTHxHEIGHT (default 1280x800).
    #[arg(long, value_parser = tessera_wgpu::image_out::parse_size)]
    size: Option<(u32, u32)>,
    /// Scripted mode: actions at frame numbers (see docs/demo.md).
    #[arg(long)]
    script: Option<PathBuf>,
    /// Scripted mode: write every frame's stats as a JSON array.
    #[arg(long)]
    stats_json: Option<PathBuf>,
    /// Hide the panel (the view is then `tessera render`'s).
    #[arg(long)]
    no_panel: bool,
    /// The model's up axis (the teapot is z-up; the teacup and teaspoon y-up).
    #[arg(long, value_enum, default_value = "z")]
    up: camera::Axis,
    /// Catmull-Clark: cut the mesh along its non-manifold edges (as `tessera
    /// --split-non-manifold`).
    #[arg(long)]
    split_non_manifold: bool,
}

fn main() -> ExitCode {
    quiet_vulkan_layer();
    let args = Args::parse();
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> Result<(), String> {
    let scripted = match args.frames {
        None => {
            if args.screenshot.is_some() || args.script.is_some() || args.stats_json.is_some() {
                return Err(
                    "--screenshot, --script and --stats-json are for scripted mode: add --frames N"
                        .into(),
                );
            }
            None
        }
        Some(0) => return Err("--frames must be at least 1".into()),
        Some(frames) => {
            if let Some(p) = &args.screenshot {
                script::check_png(p)?;
            }
            let script = match &args.script {
                Some(p) => script::Script::load(p, frames)?,
                None => script::Script::default(),
            };
            Some(app::Scripted {
                frames,
                screenshot: args.screenshot,
                script,
                stats_json: args.stats_json,
            })
        }
    };
    let input = args
        .input
        .unwrap_or_else(|| app::assets_dir().join("teaset/teapot"));
    // Before any window: a bad file is the CLI's one line and exit 1.
    let model = scene::Model::load(&input, args.split_non_manifold).map_err(|e| e.to_string())?;
    for w in &model.warnings {
        eprintln!("warning: {w}");
    }
    let options = app::Options {
        size: args.size.unwrap_or((1280, 800)),
        up: args.up,
        split_non_manifold: args.split_non_manifold,
        panel: !args.no_panel,
        scripted,
    };
    app::run(options, model)
}

/// Without a desktop login (no `XDG_RUNTIME_DIR`, as under `xvfb-run`), Mesa's
/// device-select Vulkan layer probes for a Wayland display and prints an error line per
/// probe; it only reorders adapters, which one window does not need. As the CLI does;
/// set before any thread starts.
fn quiet_vulkan_layer() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && std::env::var_os("NODEVICE_SELECT").is_none()
    {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}
