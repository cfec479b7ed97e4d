//! The tools on creased meshes: tessellated with their creases on either backend, the
//! same mesh on both, smooth with `--no-creases`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn tessera() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tessera"))
}

fn asset(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(rel)
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tessera-cli-creases-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn stats_of(args: &[&str], stats: &Path) -> serde_json::Value {
    let out = tessera()
        .args(args)
        .arg("--stats")
        .arg(stats)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(stats).unwrap()).unwrap()
}

#[test]
fn creases_are_tessellated_and_no_creases_smooths_them_with_a_warning() {
    let cube = asset("opensubdiv/catmark_cube_creases1.obj");
    let cube = cube.to_str().unwrap();
    let common = [
        "tessellate",
        cube,
        "--backend",
        "cpu",
        "--tolerance-rel",
        "1e-3",
        "--measure",
    ];
    let creased = stats_of(&common, &tmp("creased.json"));
    assert!(
        creased["warnings"].as_array().unwrap().is_empty(),
        "{creased}"
    );
    assert!(creased["max_error"].as_f64().unwrap() <= creased["tolerance"].as_f64().unwrap());
    let out = tessera()
        .args(common)
        .arg("--no-creases")
        .arg("--stats")
        .arg(tmp("smooth.json"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning:") && stderr.contains("--no-creases"),
        "{stderr}"
    );
    let smooth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp("smooth.json")).unwrap()).unwrap();
    // Different surfaces: the creased cube keeps its sharp edges, so it spends its
    // triangles differently.
    assert_ne!(creased["triangles"], smooth["triangles"]);
}

#[test]
fn the_gpu_backend_tessellates_a_creased_mesh_as_the_cpu_does() {
    let cube = asset("opensubdiv/catmark_cube_creases1.obj");
    let cube = cube.to_str().unwrap();
    let on = |backend: &str, extra: &[&str]| {
        let mut args = vec![
            "tessellate",
            cube,
            "--backend",
            backend,
            "--tolerance-rel",
            "1e-3",
        ];
        args.extend_from_slice(extra);
        stats_of(&args, &tmp(&format!("{backend}{}.json", extra.len())))
    };
    let (gpu, cpu) = (on("gpu", &[]), on("cpu", &[]));
    assert_eq!(gpu["backend"], "gpu", "{gpu}");
    assert_eq!(gpu["triangles"], cpu["triangles"], "{gpu} {cpu}");
    assert_eq!(gpu["vertices"], cpu["vertices"], "{gpu} {cpu}");
    // The creases were kept: the smooth surface spends its triangles differently.
    let smooth = on("gpu", &["--no-creases"]);
    assert_ne!(gpu["triangles"], smooth["triangles"], "{gpu} {smooth}");
}

#[test]
fn render_draws_a_creased_mesh_on_either_backend() {
    for backend in ["gpu", "cpu"] {
        let png = tmp(&format!("creased-{backend}.png"));
        let out = tessera()
            .args([
                "render",
                asset("opensubdiv/catmark_cube_creases1.obj")
                    .to_str()
                    .unwrap(),
                "--size",
                "64x48",
                "--backend",
                backend,
                "-o",
            ])
            .arg(&png)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(stdout.contains("(cpu)"), backend == "cpu", "{stdout}");
        assert!(png.exists());
    }
}
