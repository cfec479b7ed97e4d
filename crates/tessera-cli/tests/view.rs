//! `tessellate` with a view: a tolerance in pixels that `--measure` confirms, culling,
//! an empty file for a view that sees nothing, and clear errors for what views do not
//! take yet.

use std::path::{Path, PathBuf};
use std::process::Command;

fn tessera() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tessera"))
}

fn asset(rel: &str) -> String {
    let p: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(rel);
    p.to_str().unwrap().to_string()
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tessera-cli-view-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Close to one side of the torus and looking past it: part of it out of view.
const CLOSE_VIEW: [&str; 6] = [
    "--eye",
    "2.2,0,0.6",
    "--target",
    "1.5,1.5,0",
    "--tolerance-px",
    "1",
];

fn stats_of(args: &[&str], name: &str) -> serde_json::Value {
    stats_and_summary(args, name).0
}

/// The stats `args` write to `name`, and the summary line on stdout.
fn stats_and_summary(args: &[&str], name: &str) -> (serde_json::Value, String) {
    let stats = tmp(name);
    let out = tessera()
        .args(args)
        .arg("--stats")
        .arg(&stats)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        serde_json::from_str(&std::fs::read_to_string(stats).unwrap()).unwrap(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

#[test]
fn a_pixel_tolerance_holds_when_measured_and_culling_drops_what_is_out_of_view() {
    let torus = asset("opensubdiv/catmark_torus.obj");
    let framed = stats_of(
        &[
            "tessellate",
            &torus,
            "--tolerance-px",
            "1",
            "--size",
            "320x240",
            "--measure",
            "--measure-samples",
            "32",
        ],
        "framed.json",
    );
    let px = framed["max_error_px"].as_f64().unwrap();
    assert!(px <= 1.0 && px > 0.05, "{px}");
    assert_eq!(framed["tolerance_px"], 1.0);
    assert_eq!(framed["unmet"], 0);
    assert_eq!(framed["culled_patches"], 0);
    // Twice the pixels: fewer triangles.
    let coarse = stats_of(
        &[
            "tessellate",
            &torus,
            "--tolerance-px",
            "2",
            "--size",
            "320x240",
        ],
        "coarse.json",
    );
    assert!(coarse["triangles"].as_u64() < framed["triangles"].as_u64());
    // Close to one side and looking past it: part of the torus is culled, and kept with
    // --no-cull.
    let mut close = vec!["tessellate", &torus, "--size", "320x240"];
    close.extend(CLOSE_VIEW);
    let culled = stats_of(&close, "close.json");
    let mut kept_args = close.clone();
    kept_args.push("--no-cull");
    let kept = stats_of(&kept_args, "kept.json");
    assert!(culled["culled_patches"].as_u64().unwrap() > 0, "{culled}");
    assert!(culled["triangles"].as_u64() < kept["triangles"].as_u64());
    assert_eq!(kept["culled_patches"], 0);
    // Spot, framed: the patches facing away go too, with the frustum's or alone.
    let spot = asset("catmull_clark/spot_control_mesh.obj");
    let framed = [
        "tessellate",
        &spot,
        "--size",
        "320x240",
        "--tolerance-px",
        "1",
    ];
    let whole = stats_of(&framed, "spot.json");
    let mut backs_args = framed.to_vec();
    backs_args.push("--cull-backfaces");
    let backs = stats_of(&backs_args, "backs.json");
    assert!(backs["culled_patches"].as_u64() > whole["culled_patches"].as_u64());
    assert!(backs["triangles"].as_u64() < whole["triangles"].as_u64());
    backs_args.push("--no-cull");
    let backs_only = stats_of(&backs_args, "backs_only.json");
    assert!(
        backs_only["culled_patches"].as_u64().unwrap() > 0,
        "{backs_only}"
    );
    assert!(backs_only["triangles"].as_u64() < whole["triangles"].as_u64());
    // The car small on screen: faces taken whole, fewer triangles, the pixels still hold.
    let car = asset("opensubdiv/catmark_car.obj");
    let small = [
        "tessellate",
        &car,
        "--size",
        "160x120",
        "--tolerance-px",
        "1",
        "--measure",
        "--measure-samples",
        "32",
    ];
    let patches = stats_of(&small, "car.json");
    let mut faces_args = small.to_vec();
    faces_args.push("--face-leaves");
    let faces = stats_of(&faces_args, "car_faces.json");
    assert!(
        faces["triangles"].as_u64().unwrap() < patches["triangles"].as_u64().unwrap() * 3 / 4,
        "{faces} against {patches}"
    );
    let px = faces["max_error_px"].as_f64().unwrap();
    assert!(px <= 1.0, "{px}");
    assert_eq!(faces["unmet"], 0);
    // The GPU stage takes the same faces whole.
    let mut gpu_args = faces_args.clone();
    gpu_args.extend(["--backend", "gpu"]);
    let gpu = stats_of(&gpu_args, "car_faces_gpu.json");
    assert_eq!(
        gpu["triangles"], faces["triangles"],
        "{gpu} against {faces}"
    );
    assert_eq!(gpu["culled_patches"], faces["culled_patches"]);
    assert!(gpu["max_error_px"].as_f64().unwrap() <= 1.0, "{gpu}");
}

#[test]
fn a_view_that_sees_nothing_writes_an_empty_mesh() {
    let torus = asset("opensubdiv/catmark_torus.obj");
    let obj = tmp("nothing.obj");
    let stats = stats_of(
        &[
            "tessellate",
            &torus,
            "--eye",
            "-10,0,0",
            "--target",
            "-20,0,0",
            "--tolerance-px",
            "1",
            "-o",
            obj.to_str().unwrap(),
        ],
        "nothing.json",
    );
    assert_eq!(stats["triangles"], 0);
    assert_eq!(stats["culled_patches"], stats["patches"]);
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(!text.lines().any(|l| l.starts_with("f ")), "{text}");
}

#[test]
fn views_refuse_what_they_do_not_take_yet_with_one_line() {
    let torus = asset("opensubdiv/catmark_torus.obj");
    let teapot = asset("teaset/teapot");
    for (args, says) in [
        (
            vec![
                "tessellate",
                &torus,
                "--backend",
                "gpu",
                "--max-triangles",
                "100",
            ],
            "--tolerance-px",
        ),
        (
            vec![
                "tessellate",
                &torus,
                "--tolerance-px",
                "1",
                "--method",
                "uniform",
            ],
            "--method adaptive",
        ),
        (
            vec![
                "tessellate",
                &teapot,
                "--eye",
                "9,-12,5",
                "--target",
                "0,0,1",
            ],
            "give --tolerance-px",
        ),
        (
            vec![
                "tessellate",
                &teapot,
                "--tolerance-px",
                "1",
                "--max-triangles",
                "1000",
            ],
            "Catmull-Clark",
        ),
        (
            vec![
                "tessellate",
                &teapot,
                "--tolerance-px",
                "1",
                "--face-leaves",
            ],
            "Catmull-Clark",
        ),
        (vec!["tessellate", &torus, "--tolerance-px=-1"], "positive"),
        (
            vec!["tessellate", &torus, "--eye", "-1,2", "--target", "0,0,0"],
            "X,Y,Z",
        ),
        (
            vec!["tessellate", &torus, "--eye", "1,1,1", "--target", "1,1,1"],
            "distinct",
        ),
    ] {
        let out = tessera().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn render_draws_what_the_view_tessellated_on_either_backend() {
    let torus = asset("opensubdiv/catmark_torus.obj");
    let png = tmp("close.png");
    let png_path = png.to_str().unwrap();
    let mut close = vec![
        "render",
        &torus,
        "-o",
        png_path,
        "--backend",
        "cpu",
        "--size",
        "160x120",
    ];
    close.extend(CLOSE_VIEW);
    let out = tessera().args(&close).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // The tessellate command with the same view gives the triangles render reports.
    let mut twin = vec!["tessellate", &torus, "--size", "160x120"];
    twin.extend(CLOSE_VIEW);
    let stats = stats_of(&twin, "render_twin.json");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains(&format!(" {} triangles", stats["triangles"])),
        "{said} against {stats}"
    );
    // The GPU stage tessellates the same view into the same triangles.
    let mut on_gpu = close.clone();
    on_gpu[5] = "gpu";
    let gpu = tessera().args(&on_gpu).output().unwrap();
    assert!(
        gpu.status.success(),
        "{}",
        String::from_utf8_lossy(&gpu.stderr)
    );
    let said = String::from_utf8_lossy(&gpu.stdout);
    assert!(
        said.contains(&format!(" {} triangles", stats["triangles"])),
        "{said} against {stats}"
    );
    let mut gpu_twin = twin.clone();
    gpu_twin.extend(["--backend", "gpu"]);
    let gpu_stats = stats_of(&gpu_twin, "render_gpu_twin.json");
    for key in ["triangles", "culled_patches", "achieved_tolerance_px"] {
        assert_eq!(gpu_stats[key], stats[key], "{key}");
    }
    assert!(stats["culled_patches"].as_u64().unwrap() > 0);
}

#[test]
fn max_triangles_coarsens_the_pixels_and_reports_what_it_achieved() {
    let torus = asset("opensubdiv/catmark_torus.obj");
    let free = stats_of(
        &["tessellate", &torus, "--tolerance-px", "0.25"],
        "free.json",
    );
    let cap = free["triangles"].as_u64().unwrap() / 2;
    let capped = stats_of(
        &[
            "tessellate",
            &torus,
            "--tolerance-px",
            "0.25",
            "--max-triangles",
            &cap.to_string(),
            "--measure",
        ],
        "capped.json",
    );
    assert!(capped["triangles"].as_u64().unwrap() <= cap, "{capped}");
    let achieved = capped["achieved_tolerance_px"].as_f64().unwrap();
    assert!(achieved > 0.25, "{capped}");
    assert!(
        capped["max_error_px"].as_f64().unwrap() <= achieved,
        "{capped}"
    );
    assert_eq!(free["achieved_tolerance_px"], 0.25);
    // The GPU stage stops at the same step.
    let on_gpu = stats_of(
        &[
            "tessellate",
            &torus,
            "--tolerance-px",
            "0.25",
            "--max-triangles",
            &cap.to_string(),
            "--backend",
            "gpu",
        ],
        "capped_gpu.json",
    );
    for key in ["triangles", "achieved_tolerance_px"] {
        assert_eq!(on_gpu[key], capped[key], "{key}");
    }
}

#[test]
fn a_bezier_view_scales_the_threshold_on_either_backend() {
    // The teapot from close by: the threshold in pixels of that view, each patch's scaled
    // from its control points. Both backends give the same triangles, coarser pixels give
    // fewer, and the stats carry the pixels and the measured pixel error.
    let teapot = asset("teaset/teapot");
    let view = [
        "--eye", "4,-6,3", "--target", "0,0,1.5", "--size", "320x240",
    ];
    let run = |px: &str, backend: &str, name: &str| {
        let mut args = vec![
            "tessellate",
            &teapot,
            "--tolerance-px",
            px,
            "--backend",
            backend,
            "--measure",
        ];
        args.extend(view);
        stats_of(&args, name)
    };
    let cpu = run("1", "cpu", "bezier_cpu.json");
    let gpu = run("1", "gpu", "bezier_gpu.json");
    assert_eq!(cpu["triangles"], gpu["triangles"]);
    assert_eq!(cpu["tolerance_px"], 1.0);
    assert!(cpu["max_error_px"].as_f64().is_some(), "{cpu}");
    let coarse = run("4", "cpu", "bezier_coarse.json");
    assert!(
        coarse["triangles"].as_u64() < cpu["triangles"].as_u64(),
        "{coarse} against {cpu}"
    );
    // Closer, by the spout: the patches out of view are culled alike on both backends,
    // and kept with --no-cull.
    let close = |backend: &str, keep: bool, name: &str| {
        let mut args = vec![
            "tessellate",
            &teapot,
            "--tolerance-px",
            "1",
            "--backend",
            backend,
            "--eye",
            "4.3,-3.7,2.4",
            "--target",
            "2.7,0,1.6",
            "--fov",
            "30",
            "--size",
            "640x480",
        ];
        if keep {
            args.push("--no-cull");
        }
        stats_of(&args, name)
    };
    let (cpu, gpu) = (
        close("cpu", false, "bezier_close_cpu.json"),
        close("gpu", false, "bezier_close_gpu.json"),
    );
    assert!(cpu["culled_patches"].as_u64().unwrap() > 0, "{cpu}");
    assert_eq!(cpu["culled_patches"], gpu["culled_patches"]);
    assert_eq!(cpu["triangles"], gpu["triangles"]);
    assert_eq!(cpu["evaluations"], gpu["evaluations"]);
    let kept = close("cpu", true, "bezier_close_kept.json");
    assert_eq!(kept["culled_patches"], 0, "{kept}");
    assert!(kept["triangles"].as_u64() > cpu["triangles"].as_u64());
    // From above the far side, back faces culled too.
    let mut above = vec![
        "tessellate",
        &teapot,
        "--tolerance-px",
        "1",
        "--eye",
        "5.1,-7.4,7.3",
        "--target",
        "0.2,0,1.6",
        "--size",
        "640x480",
    ];
    let front = stats_of(&above, "bezier_above.json");
    above.push("--cull-backfaces");
    let backs = stats_of(&above, "bezier_above_backs.json");
    assert!(
        backs["culled_patches"].as_u64() > front["culled_patches"].as_u64(),
        "{front} then {backs}"
    );
    assert!(backs["triangles"].as_u64() < front["triangles"].as_u64());
}

#[test]
fn a_walk_the_device_cuts_short_coarsens_to_the_cpu_backends_mesh_at_the_pixels_reached() {
    // From inside the cube at 0.25 px, the cells at the near plane split deep near the
    // corners: lavapipe's loop limit cuts those walks short, and the GPU backend coarsens
    // the pixels until they fit, saying why. The CPU backend keeps the pixels asked for,
    // and at the pixels reached gives the GPU's mesh.
    let cube = asset("opensubdiv/catmark_cube.obj");
    let view = |px: &str, backend: &str| {
        vec![
            "tessellate".to_string(),
            cube.clone(),
            "--eye".into(),
            "0.2,0.1,0".into(),
            "--target".into(),
            "0.5,0.3,0.3".into(),
            "--first-split".into(),
            "midpoint".into(),
            "--max-depth".into(),
            "8".into(),
            "--tolerance-px".into(),
            px.into(),
            "--backend".into(),
            backend.into(),
        ]
    };
    let run = |px: &str, backend: &str, name: &str| {
        let args = view(px, backend);
        stats_and_summary(&args.iter().map(String::as_str).collect::<Vec<_>>(), name)
    };
    let (gpu, summary) = run("0.25", "gpu", "walk_gpu.json");
    let reached = gpu["achieved_tolerance_px"].as_f64().unwrap();
    eprintln!("reached {reached} px on the GPU backend");
    assert!(reached >= 0.25, "{gpu}");
    assert_eq!(summary.contains("loop limit"), reached > 0.25, "{summary}");
    let (asked, _) = run("0.25", "cpu", "walk_cpu.json");
    assert_eq!(asked["achieved_tolerance_px"], 0.25);
    let (at_reached, _) = run(&format!("{reached}"), "cpu", "walk_cpu_reached.json");
    for key in ["triangles", "culled_patches", "unmet"] {
        assert_eq!(at_reached[key], gpu[key], "{key}");
    }
}
