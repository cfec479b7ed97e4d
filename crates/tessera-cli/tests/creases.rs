//! The tools on creased meshes: tessellated with their creases on the CPU, smooth with
//! `--no-creases`, refused by the GPU backend with one line that names both ways out.

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
fn the_gpu_backend_refuses_a_creased_mesh_in_one_line_and_writes_nothing() {
    let car = asset("opensubdiv/catmark_cube_creases1.obj");
    let ply = tmp("refused.ply");
    let out = tessera()
        .args([
            "tessellate",
            car.to_str().unwrap(),
            "--backend",
            "gpu",
            "-o",
        ])
        .arg(&ply)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.starts_with("warning:"))
        .collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].contains("--backend cpu") && lines[0].contains("--no-creases"),
        "{stderr}"
    );
    assert!(!ply.exists());
    // Smooth, the GPU takes it (where an adapter exists; lavapipe in the tests).
    let out = tessera()
        .args([
            "tessellate",
            car.to_str().unwrap(),
            "--backend",
            "gpu",
            "--no-creases",
            "-o",
        ])
        .arg(&ply)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(ply.exists());
}

#[test]
fn render_draws_a_creased_mesh_tessellated_on_the_cpu() {
    let png = tmp("creased.png");
    let out = tessera()
        .args([
            "render",
            asset("opensubdiv/catmark_cube_creases1.obj")
                .to_str()
                .unwrap(),
            "--size",
            "64x48",
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
    assert!(stdout.contains("(cpu)"), "{stdout}");
    assert!(png.exists());
    let refused = tmp("refused.png");
    let out = tessera()
        .args([
            "render",
            asset("opensubdiv/catmark_cube_creases1.obj")
                .to_str()
                .unwrap(),
            "--backend",
            "gpu",
            "-o",
        ])
        .arg(&refused)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--no-creases"));
    assert!(!refused.exists());
}
