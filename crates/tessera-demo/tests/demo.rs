//! The demo window in scripted mode, in a real X server (`xvfb-run`) on whatever Vulkan
//! adapter wgpu finds (lavapipe in CI): what a user sees, and the figures it reports.
//!
//! - the teapot is drawn, and without the panel it is `tessera render`'s image of the
//!   same view and size (within the snapshot tolerance), which an orbited view is not;
//! - an animated Catmull-Clark model moves, and its triangle count with it;
//! - a finer tolerance gives more triangles;
//! - a bad file exits 1 with the CLI's one line, a bad script line with `FILE:LINE:`;
//! - no run reports a wgpu validation error (scripted mode exits 1 on any).
//!
//! Runs go one at a time (they share the CPU, and `xvfb-run -a` picks a display number
//! that two runs started together can both pick).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;

use tessera_core::bezier::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};
use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::image::{Rgba, RgbaImage};
use tessera_wgpu::image_out::{load_png, render_view_to_rgba, save_png, BACKGROUND};
use tessera_wgpu::snapshot::{compare, delta_e, Tolerance};
use tessera_wgpu::{Kernels, RenderOptions, View};

const BIN: &str = env!("CARGO_BIN_EXE_tessera-demo");
const SIZE: (u32, u32) = (320, 240);

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(name)
}

/// A fresh folder for one test's files.
fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("tessera-demo")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("test folder");
    d
}

fn xvfb_run() -> PathBuf {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join("xvfb-run"))
            .find(|p| p.is_file())
    });
    found.unwrap_or_else(|| {
        panic!(
            "xvfb-run is missing, so the demo window cannot be tested: run `cargo xtask test`, \
             which installs Xvfb (or `apt-get install xvfb xauth`)"
        )
    })
}

/// Runs the demo in a fresh X server with `args`.
fn demo(args: &[&str]) -> Output {
    demo_with_env(args, &[])
}

fn demo_with_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let started = std::time::Instant::now();
    let out = Command::new(xvfb_run())
        .args(["-a", "-s", "-screen 0 1280x1024x24", BIN])
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("xvfb-run starts");
    eprintln!(
        "tessera-demo {}: {:?} in {:.1} s",
        args.join(" "),
        out.status.code(),
        started.elapsed().as_secs_f64()
    );
    out
}

/// Runs the demo and requires it to succeed without a word on stderr about errors.
fn demo_ok(args: &[&str]) -> Output {
    let out = demo(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "tessera-demo {args:?} failed ({:?}):\n{stderr}",
        out.status
    );
    for line in stderr.lines() {
        let l = line.to_ascii_lowercase();
        assert!(
            !(l.contains("error") || l.contains("validation") || l.contains("panic")),
            "tessera-demo {args:?}: {line}"
        );
    }
    out
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn size_arg() -> String {
    format!("{}x{}", SIZE.0, SIZE.1)
}

fn stats(path: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(path).expect("stats written");
    let v: serde_json::Value = serde_json::from_str(&text).expect("stats are JSON");
    v.as_array().expect("an array").clone()
}

fn u(row: &serde_json::Value, key: &str) -> u64 {
    row[key]
        .as_u64()
        .unwrap_or_else(|| panic!("{key} in {row}"))
}

/// Fraction of pixels clearly not the background.
fn coverage(img: &RgbaImage) -> f64 {
    let [r, g, b] = BACKGROUND;
    let bg = Rgba([r, g, b, 255]);
    img.pixels().filter(|p| delta_e(**p, bg) > 10.0).count() as f64 / img.pixels().len() as f64
}

/// Fraction of pixels dark enough to be text.
fn dark(img: &RgbaImage) -> f64 {
    let n = img
        .pixels()
        .filter(|p| (p[0] as u32 + p[1] as u32 + p[2] as u32) < 3 * 110)
        .count();
    n as f64 / img.pixels().len() as f64
}

/// The left and right halves of `img`.
fn halves(img: &RgbaImage) -> (RgbaImage, RgbaImage) {
    let (w, h) = img.dimensions();
    let half = |x0| RgbaImage::from_fn(w / 2, h, |x, y| *img.get_pixel(x0 + x, y));
    (half(0), half(w / 2))
}

/// `tessera render assets/teaset/teapot --size 320x240`, in process: the CLI's stage,
/// parameters, camera and renderer options (crates/tessera-cli/src/render.rs).
fn tessera_render_teapot() -> RgbaImage {
    let gpu = Gpu::new().expect("a wgpu adapter (`cargo xtask test` installs lavapipe)");
    let model = BezierModel::load(&asset("teaset/teapot")).expect("teapot");
    let (lo, hi) = model.bounds();
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.002 * (hi - lo).length(),
        max_depth: 6,
    };
    let kernels = Kernels::new(&gpu.device);
    let mut stage = BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &kernels,
        &PreparedBezier::new(&model),
        &params,
    )
    .expect("stage");
    stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let (w, h) = SIZE;
    let view = View::framing(lo.as_dvec3(), hi.as_dvec3(), (w, h));
    let image = render_view_to_rgba(&gpu, stage.output(), &view, w, h, &RenderOptions::default())
        .expect("render");
    gpu.check().expect("no wgpu errors");
    image
}

#[test]
fn the_teapot_is_drawn_and_without_the_panel_matches_tessera_render() {
    let d = dir("teapot");
    let (panel, home, orbited) = (
        d.join("panel.png"),
        d.join("home.png"),
        d.join("orbited.png"),
    );
    demo_ok(&[
        s(&asset("teaset/teapot")),
        "--frames",
        "3",
        "--size",
        "480x300",
        "--screenshot",
        s(&panel),
    ]);
    let with_panel = load_png(&panel).expect("screenshot");
    assert_eq!(with_panel.dimensions(), (480, 300));
    // The panel's text on the left, the teapot on the right.
    let (left, right) = halves(&with_panel);
    let text = dark(&left);
    assert!(text > 0.01, "the panel has {text:.4} dark pixels");
    let c = coverage(&right);
    assert!(c > 0.1, "the teapot covers {c:.3} of the right half");

    let script = d.join("orbit.txt");
    std::fs::write(
        &script,
        "# the home view first, then turned\n2 screenshot HOME\n3 orbit 40 10\n",
    )
    .expect("script");
    let text = std::fs::read_to_string(&script).expect("script");
    std::fs::write(&script, text.replace("HOME", s(&home))).expect("script");
    demo_ok(&[
        s(&asset("teaset/teapot")),
        "--frames",
        "5",
        "--size",
        &size_arg(),
        "--no-panel",
        "--script",
        s(&script),
        "--screenshot",
        s(&orbited),
    ]);
    let demo_home = load_png(&home).expect("home view");
    let demo_orbited = load_png(&orbited).expect("orbited view");
    let bare = coverage(&demo_home);
    assert!(
        (0.1..0.9).contains(&bare),
        "the teapot covers {bare:.3} of the frame"
    );

    let reference = tessera_render_teapot();
    let _ = save_png(&reference, &d.join("tessera_render.png"));
    let same = compare(&reference, &demo_home, &Tolerance::DEFAULT);
    eprintln!("demo against tessera render: {}", same.summary());
    assert!(
        same.passed(),
        "the demo's view is not tessera render's: {}",
        same.summary()
    );
    let other = compare(&reference, &demo_orbited, &Tolerance::DEFAULT);
    eprintln!("orbited against tessera render: {}", other.summary());
    assert!(
        !other.passed(),
        "an orbited view passed: {}",
        other.summary()
    );
}

#[test]
fn an_animated_catmull_clark_model_moves_and_its_triangles_change() {
    let d = dir("animated");
    let (a, b, json) = (d.join("a.png"), d.join("b.png"), d.join("stats.json"));
    let script = d.join("animate.txt");
    std::fs::write(
        &script,
        format!(
            "0 animate on\n0 set tolerance-rel 3e-3\n2 screenshot {}\n17 screenshot {}\n",
            s(&a),
            s(&b)
        ),
    )
    .expect("script");
    demo_ok(&[
        s(&asset("opensubdiv/catmark_torus.obj")),
        "--frames",
        "18",
        "--size",
        &size_arg(),
        "--no-panel",
        "--script",
        s(&script),
        "--stats-json",
        s(&json),
    ]);
    let (a, b) = (load_png(&a).expect("a"), load_png(&b).expect("b"));
    let c = compare(&a, &b, &Tolerance::DEFAULT);
    eprintln!("frame 2 against frame 17: {}", c.summary());
    assert!(
        !c.passed(),
        "the animated model did not move: {}",
        c.summary()
    );

    let rows = stats(&json);
    assert_eq!(rows.len(), 18);
    // Every frame of the animation tessellates the moved points.
    assert!(rows.iter().all(|r| r["tessellated"] == true), "{rows:?}");
    let triangles: Vec<u64> = rows.iter().map(|r| u(r, "triangles")).collect();
    eprintln!("triangles per frame: {triangles:?}");
    assert!(triangles.iter().all(|&t| t > 0), "{triangles:?}");
    let (min, max) = (
        triangles.iter().min().copied().unwrap_or(0),
        triangles.iter().max().copied().unwrap_or(0),
    );
    assert!(max > min, "the triangle count never changed: {triangles:?}");
    for r in &rows {
        assert!(
            r["guaranteed_bound"].as_f64().is_some_and(|b| b > 0.0),
            "{r}"
        );
        assert!(
            r["gpu_ms"]
                .as_f64()
                .or(r["wall_ms"].as_f64())
                .is_some_and(|t| t > 0.0),
            "{r}"
        );
    }
}

#[test]
fn a_finer_tolerance_gives_more_triangles_and_a_still_scene_does_not_tessellate() {
    let d = dir("tolerance");
    let (json, script) = (d.join("stats.json"), d.join("tolerance.txt"));
    std::fs::write(
        &script,
        "0 set tolerance-rel 3e-3\n\
         4 set tolerance-rel 3e-4   # finer: more triangles\n",
    )
    .expect("script");
    demo_ok(&[
        s(&asset("opensubdiv/catmark_torus.obj")),
        "--frames",
        "12",
        "--size",
        &size_arg(),
        "--script",
        s(&script),
        "--stats-json",
        s(&json),
    ]);
    let rows = stats(&json);
    assert_eq!(rows.len(), 12);
    let coarse = &rows[3];
    let fine = &rows[11];
    eprintln!(
        "3e-3: {} triangles (bound {}); 3e-4: {} triangles (bound {}); growths {}",
        coarse["triangles"],
        coarse["guaranteed_bound"],
        fine["triangles"],
        fine["guaranteed_bound"],
        fine["growths"]
    );
    assert!(
        u(fine, "triangles") > u(coarse, "triangles"),
        "finer tolerance, not more triangles: {coarse} then {fine}"
    );
    let bound = |r: &serde_json::Value| r["guaranteed_bound"].as_f64().unwrap_or(f64::NAN);
    assert!(bound(fine) < bound(coarse), "{coarse} then {fine}");
    // The change tessellates, then once more after each growth its overflow asked for,
    // until the run fits; frames with nothing changed draw the same buffers.
    assert_eq!(rows[0]["tessellated"], true);
    for r in &rows[1..4] {
        assert_eq!(r["tessellated"], false, "a still frame tessellated: {r}");
    }
    assert_eq!(rows[4]["tessellated"], true);
    let reruns = rows[5..]
        .iter()
        .filter(|r| r["tessellated"] == true)
        .count() as u64;
    let grown = u(fine, "growths") - u(coarse, "growths");
    assert_eq!(reruns, grown, "one rerun per growth: {rows:?}");
    let last_run = rows
        .iter()
        .rposition(|r| r["tessellated"] == true)
        .unwrap_or(0);
    assert!(last_run < 11, "still growing at the last frame: {rows:?}");
    for r in &rows[last_run..] {
        assert_eq!(u(r, "triangles"), u(fine, "triangles"), "{r}");
    }
}

#[test]
fn in_pixels_by_default_moving_the_camera_tessellates_again_and_culls() {
    // A Catmull-Clark model opens with a tolerance of one pixel of the view drawn: a
    // still view does not tessellate again, zooming in does (more triangles, and patches
    // off screen culled), and a tolerance in model units no longer follows the view.
    let rows = scripted_stats(
        "pixels",
        "opensubdiv/catmark_torus.obj",
        16,
        "5 zoom 3\n\
         12 set tolerance-rel 3e-3\n\
         14 zoom 0.5\n",
    );
    assert_eq!(rows.len(), 16);
    for r in &rows[..12] {
        assert_eq!(r["tolerance_px"].as_f64(), Some(1.0), "{r}");
    }
    let (home, close) = (&rows[4], &rows[11]);
    eprintln!(
        "home: {home}
close: {close}"
    );
    assert_eq!(u(home, "culled_patches"), 0, "the home view frames it all");
    assert!(u(close, "culled_patches") > 0, "{close}");
    assert!(
        u(close, "triangles") > u(home, "triangles"),
        "{home} then {close}"
    );
    assert_eq!(rows[5]["tessellated"], true, "the zoom tessellates again");
    for r in &rows[1..5] {
        assert_eq!(r["tessellated"], false, "a still frame tessellated: {r}");
    }
    // In model units the mesh stays as the camera moves.
    assert!(rows[12]["tolerance_px"].is_null(), "{}", rows[12]);
    assert_eq!(rows[14]["tessellated"], false, "{}", rows[14]);
    assert_eq!(u(&rows[15], "triangles"), u(&rows[14], "triangles"));
}

#[test]
fn a_bad_file_or_script_line_exits_1_with_one_line() {
    let d = dir("bad");
    let bad = d.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 1 2 9\n").expect("bad file");
    // What the CLI prints for it: its loader's error, after `error: `.
    let want = match tessera_core::io::load_control_mesh(&bad).and_then(|mut control| {
        tessera_core::catmull_clark::patch_mesh(&mut control, false).map(|_| ())
    }) {
        Err(e) => format!("error: {e}"),
        Ok(()) => panic!("the bad file loads"),
    };
    for args in [vec![s(&bad)], vec![s(&bad), "--frames", "2", "--no-panel"]] {
        let out = demo(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end(), want, "{args:?}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
    let missing = d.join("missing.obj");
    let out = demo(&[s(&missing), "--frames", "1"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with(&format!("error: {}: ", missing.display()))
            && stderr.lines().count() == 1,
        "{stderr}"
    );

    let script = d.join("bad_script.txt");
    std::fs::write(&script, "# fine\n1 orbit 10 0\n2 spin 3\n").expect("script");
    let out = demo(&[
        s(&asset("teaset/teapot")),
        "--frames",
        "4",
        "--script",
        s(&script),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with(&format!(
            "error: {}:3: unknown action \"spin\"",
            script.display()
        )) && stderr.lines().count() == 1,
        "{stderr}"
    );
    // A setting the model does not take is the script's error too, found when it runs.
    std::fs::write(&script, "1 set tolerance-rel 1e-3\n").expect("script");
    let out = demo(&[
        s(&asset("teaset/teapot")),
        "--frames",
        "3",
        "--no-panel",
        "--script",
        s(&script),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with(&format!(
            "error: {}:1: tolerance-rel is a Catmull-Clark setting",
            script.display()
        )),
        "{stderr}"
    );
}

#[test]
fn a_file_that_fails_to_load_in_the_window_keeps_the_open_model() {
    let d = dir("keep");
    let bad = d.join("bad.obj");
    std::fs::write(&bad, "this is not an obj file\n").expect("bad file");
    let (script, json, shot) = (d.join("load.txt"), d.join("stats.json"), d.join("kept.png"));
    std::fs::write(
        &script,
        format!(
            "1 load {}\n3 load {}\n",
            s(&bad),
            s(&asset("opensubdiv/catmark_cube.obj"))
        ),
    )
    .expect("script");
    let out = demo(&[
        s(&asset("teaset/teapot")),
        "--frames",
        "5",
        "--size",
        &size_arg(),
        "--script",
        s(&script),
        "--stats-json",
        s(&json),
        "--screenshot",
        s(&shot),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // The failure is reported (the panel shows it; stderr says so once) and not fatal.
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("load failed") && stderr.contains(s(&bad)),
        "{stderr}"
    );
    let rows = stats(&json);
    let patches: Vec<u64> = rows.iter().map(|r| u(r, "patches")).collect();
    // The teapot's 32 patches until the cube (24) opens.
    assert_eq!(patches, [32, 32, 32, 24, 24], "{rows:?}");
    assert!(u(&rows[2], "triangles") > 0);
}

#[cfg(target_os = "linux")]
#[test]
fn no_adapter_exits_1_with_one_line() {
    // No Metal on Linux: wgpu has no backend, so no adapter can draw to the window.
    let out = demo_with_env(&["--frames", "2"], &[("WGPU_BACKEND", "metal")]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with("error: no GPU adapter (") && stderr.contains("install a Vulkan driver"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

#[test]
fn culling_back_faces_drops_the_patches_facing_away() {
    // Spot in pixels: turning back-face culling on culls more patches with fewer
    // triangles, and off again gives the first mesh back.
    let rows = scripted_stats(
        "backfaces",
        "catmull_clark/spot_control_mesh.obj",
        6,
        "2 set cull-backfaces on\n\
         4 set cull-backfaces off\n",
    );
    let (front, culled, back) = (&rows[1], &rows[3], &rows[5]);
    eprintln!("{front}\n{culled}\n{back}");
    assert!(
        u(culled, "culled_patches") > u(front, "culled_patches"),
        "{front} then {culled}"
    );
    assert!(u(culled, "triangles") < u(front, "triangles"));
    assert_eq!(u(back, "triangles"), u(front, "triangles"));
    assert_eq!(u(back, "culled_patches"), u(front, "culled_patches"));
}

/// The demo on asset `model` for `frames` frames without the panel, running `script`:
/// the stats of each frame.
fn scripted_stats(name: &str, model: &str, frames: u32, script: &str) -> Vec<serde_json::Value> {
    let d = dir(name);
    let (json, path) = (d.join("stats.json"), d.join("script.txt"));
    std::fs::write(&path, script).expect("script");
    demo_ok(&[
        s(&asset(model)),
        "--frames",
        &frames.to_string(),
        "--size",
        &size_arg(),
        "--no-panel",
        "--script",
        s(&path),
        "--stats-json",
        s(&json),
    ]);
    stats(&json)
}
