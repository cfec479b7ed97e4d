//! The `tessera` binary: outputs, stats, and bad input (one line, non-zero exit, no
//! output file, no panic).

use std::path::{Path, PathBuf};
use std::process::Command;

fn tessera() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tessera"))
}

/// Runs the command and asserts it succeeded, showing its stderr if not.
fn run_ok(cmd: &mut Command) -> std::process::Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn teapot() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/teaset/teapot")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tessera-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn writes_obj_ply_and_stats() {
    let (obj, ply, stats) = (tmp("t.obj"), tmp("t.ply"), tmp("s.json"));
    for out in [&obj, &ply] {
        run_ok(
            tessera()
                .args([
                    "tessellate",
                    teapot().to_str().unwrap(),
                    "--method",
                    "map4p",
                    "--measure",
                    "--stats",
                ])
                .arg(&stats)
                .arg("-o")
                .arg(out),
        );
    }
    let json = stats_with_spec_keys(&stats, &[]);
    let tris = json["triangles"].as_u64().unwrap();
    let ply_text = std::fs::read_to_string(&ply).unwrap();
    assert!(ply_text.contains(&format!("element face {tris}")));
    assert!(ply_text.contains("property float nx") && ply_text.contains("property uint face"));
    let obj_text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(
        obj_text.lines().filter(|l| l.starts_with("f ")).count() as u64,
        tris
    );
    assert!(
        obj_text.lines().any(|l| l.starts_with("vt "))
            && obj_text.lines().any(|l| l.starts_with("vn "))
    );
}

#[test]
fn target_triangles_lands_within_two_percent() {
    let stats = tmp("target.json");
    for method in ["map4p", "flat"] {
        run_ok(
            tessera()
                .args([
                    "tessellate",
                    teapot().to_str().unwrap(),
                    "--method",
                    method,
                    "--target-triangles",
                    "6000",
                    "--stats",
                ])
                .arg(&stats),
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        let n = json["triangles"].as_f64().unwrap();
        assert!((n - 6000.0).abs() <= 120.0, "{method}: {n}");
    }
}

/// The `--stats` JSON, checked for the keys the CLI reference promises (with `--measure`) and `extra`.
fn stats_with_spec_keys(stats: &Path, extra: &[&str]) -> serde_json::Value {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(stats).unwrap()).unwrap();
    let spec = [
        "triangles",
        "vertices",
        "vertex_face",
        "vertex_uv",
        "patches",
        "evaluations",
        "upload_bytes",
        "timings_ms",
        "max_error",
        "mean_error",
        "bbox_diag",
    ];
    for key in spec.iter().chain(extra) {
        assert!(json.get(key).is_some(), "stats lack {key}: {json}");
    }
    json
}

/// Without any Vulkan driver the render fails in one line that says how to get one, and
/// writes nothing.
#[test]
fn no_adapter_says_how_to_get_one() {
    let png = tmp("no_adapter.png");
    let _ = std::fs::remove_file(&png);
    let out = tessera()
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env_remove("WGPU_BACKEND")
        .args(["render", teapot().to_str().unwrap(), "-o"])
        .arg(&png)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no GPU adapter"), "{stderr}");
    assert!(
        stderr.contains("apt-get install mesa-vulkan-drivers"),
        "{stderr}"
    );
    assert!(!png.exists());
}

/// `--tolerance-rel` and the stats' `bbox_diag` speak of one box, the control points':
/// on the pyramid it is 6.0 long across, where the limit surface's is much smaller.
#[test]
fn relative_tolerance_and_stats_use_the_control_points_box() {
    let input =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/opensubdiv/catmark_pyramid.obj");
    let stats = tmp("pyramid.json");
    run_ok(
        tessera()
            .arg("tessellate")
            .arg(&input)
            .args(["--tolerance-rel", "1e-3", "--measure", "--stats"])
            .arg(&stats),
    );
    let json = stats_with_spec_keys(&stats, &["surface_bbox_diag", "tolerance"]);
    let f = |k: &str| json[k].as_f64().unwrap();
    assert!((f("bbox_diag") - 6.0).abs() < 1e-9, "{json}");
    assert!(f("surface_bbox_diag") < 0.5 * f("bbox_diag"), "{json}");
    assert!((f("tolerance") - 6e-3).abs() < 1e-12, "{json}");
    assert!(
        (f("max_error_rel") - f("max_error") / f("bbox_diag")).abs() < 1e-12,
        "{json}"
    );
    assert!(f("max_error") <= f("tolerance"), "{json}");
}

fn expect_failure(content: &[u8], expect: &str) {
    expect_failure_as("bad_input", content, expect);
}

/// Writes `content` to a file called `name` and checks that tessellating it fails
/// cleanly: one line naming the file and `expect`, non-zero exit, no output, no panic.
fn expect_failure_as(name: &str, content: &[u8], expect: &str) {
    let input = tmp(name);
    std::fs::write(&input, content).unwrap();
    let out = tmp("bad.obj");
    let _ = std::fs::remove_file(&out);
    let r = tessera()
        .arg("tessellate")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success(), "accepted bad input {expect}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains(input.to_str().unwrap()) && stderr.contains(expect),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));
    assert!(!out.exists(), "left an output file behind");
}

#[test]
fn bad_input_is_one_line_naming_file_line_and_problem() {
    let good = std::fs::read_to_string(teapot()).unwrap();
    expect_failure(b"", ":1: unexpected end of file");
    expect_failure(b"\x00\xff\xfe binary", "not a text file");
    let truncated: String = good.lines().take(40).map(|l| format!("{l}\n")).collect();
    expect_failure(truncated.as_bytes(), ":34: vertex count 306 does not match");
    expect_failure(
        good.replacen("1,2,3,4,", "1,2,3,999,", 1).as_bytes(),
        ":2: index 4 is 999",
    );
    expect_failure(
        format!("4000000000\n{good}").as_bytes(),
        ":1: patch count 4000000000 exceeds",
    );
    // A count whose `+ 2` would wrap around to a small number.
    expect_failure(
        format!("{}\n{good}", u64::MAX).as_bytes(),
        ":1: patch count 18446744073709551615 exceeds",
    );
    expect_failure(
        good.replacen("1.4,0.0,2.4", "1.4,1e38,2.4", 1).as_bytes(),
        "coordinate 2 is 1e38: beyond",
    );
    expect_failure(
        good.replacen("1.4,0.0,2.4", "1.4,NaN,2.4", 1).as_bytes(),
        "not finite",
    );
    expect_failure(
        good.replacen("1.4,0.0,2.4", "1.4,inf,2.4", 1).as_bytes(),
        "not finite",
    );
    expect_failure(
        good.replacen("1.4,0.0,2.4", "1.4,zero,2.4", 1).as_bytes(),
        "is not a number",
    );
}

/// Parameters that cannot work, or would be silently ignored: exit status 1, one line
/// saying what is wrong, no panic, no output file. The CPU backend, so that the checks
/// are shown to come before any device is needed.
#[test]
fn bad_parameters_fail_cleanly() {
    let teapot = teapot();
    let cube = asset("opensubdiv/catmark_cube.obj");
    let spot = asset("catmull_clark/spot_control_mesh.obj");
    let cases: &[(&Path, &[&str], &str)] = &[
        (
            &teapot,
            &["--threshold=-1"],
            "threshold must be a positive number",
        ),
        (&teapot, &["--max-depth", "40"], "max depth 40 is beyond"),
        (
            &teapot,
            &["--segments", "5"],
            "--segments is for --method uniform",
        ),
        (
            &teapot,
            &["--method", "uniform", "--threshold", "0.1"],
            "--threshold and --max-depth are for the adaptive methods",
        ),
        (
            &teapot,
            &["--method", "uniform", "--segments", "5000"],
            "segments must be in 1..=1024",
        ),
        (
            &teapot,
            &["--measure", "--measure-samples", "100000000"],
            "must be in 32..=1024",
        ),
        (
            &teapot,
            &["--measure", "--measure-samples", "16"],
            "must be in 32..=1024",
        ),
        (&teapot, &["--measure-samples", "40"], "add --measure"),
        (
            &teapot,
            &["--first-split", "midpoint"],
            "--split-non-manifold and --no-creases are Catmull-Clark options",
        ),
        (
            &teapot,
            &["--split-non-manifold"],
            "--split-non-manifold and --no-creases are Catmull-Clark options",
        ),
        (
            &teapot,
            &["--no-creases"],
            "--split-non-manifold and --no-creases are Catmull-Clark options",
        ),
        (
            &cube,
            &["--method", "uniform", "--first-split", "midpoint"],
            "--first-split and --leaf-bound are for --method adaptive",
        ),
        (
            &cube,
            &["--method", "uniform", "--leaf-bound", "triangles"],
            "--first-split and --leaf-bound are for --method adaptive",
        ),
        (
            &cube,
            &["--tolerance-rel", "1e-300"],
            "finer than single-precision output can hold",
        ),
        (
            &cube,
            &["--tolerance-rel", "0"],
            "tolerance must be a positive number",
        ),
        (
            &spot,
            &["--method", "uniform", "--segments", "4096"],
            "more than the 134217728 allowed",
        ),
        (
            &spot,
            &["--measure", "--measure-samples", "1024"],
            "more than the 67108864 allowed",
        ),
        (Path::new("/nonexistent/teapot"), &[], "/nonexistent/teapot"),
    ];
    // The own-triangles leaf bound is a CPU option: refused on the GPU before any
    // device is opened.
    let out = tmp("bad_leaf_bound.ply");
    let _ = std::fs::remove_file(&out);
    let r = tessera()
        .arg("tessellate")
        .arg(&cube)
        .args(["--leaf-bound", "triangles", "--backend", "gpu", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("--leaf-bound triangles runs on the CPU only") && !out.exists(),
        "{stderr}"
    );
    let out = tmp("bad_param.ply");
    for (input, args, expect) in cases {
        let _ = std::fs::remove_file(&out);
        let r = tessera()
            .arg("tessellate")
            .arg(input)
            .args(*args)
            .args(["--backend", "cpu", "-o"])
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.contains(expect),
            "{args:?}: expected {expect:?} in {stderr}"
        );
        assert!(!stderr.contains("panicked") && !out.exists(), "{args:?}");
    }
}

/// The mesh and the stats are written together: a stats file that cannot be written
/// leaves no mesh either (and no temporary file).
#[test]
fn a_failed_stats_write_leaves_no_mesh() {
    let dir = tmp("stats_fail");
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = dir.join("m.obj");
    let r = tessera()
        .arg("tessellate")
        .arg(teapot())
        .args(["--backend", "cpu", "-o"])
        .arg(&mesh)
        .arg("--stats")
        .arg(dir.join("missing/s.json"))
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr).contains("missing/s.json"));
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "left files behind"
    );
}

/// `-o OUT.glb` writes binary glTF, which reads back as a triangle control mesh with one
/// face per output triangle (the glTF reader, through the CLI).
#[test]
fn glb_output_reads_back_as_a_control_mesh() {
    // The cube's limit surface: closed and manifold once the GLB's vertices are welded
    // (the teapot is not: its lid rests on the body's rim).
    let (glb, stats) = (tmp("cube.glb"), tmp("glb.json"));
    run_ok(
        tessera()
            .arg("tessellate")
            .arg(asset("opensubdiv/catmark_cube.obj"))
            .args(["--backend", "cpu", "--tolerance-rel", "0.01", "-o"])
            .arg(&glb)
            .arg("--stats")
            .arg(&stats),
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let info = run_ok(tessera().arg("info").arg(&glb));
    let info = String::from_utf8_lossy(&info.stdout);
    let faces = format!(
        "{} faces (sizes 3:{})",
        json["triangles"], json["triangles"]
    );
    assert!(info.contains(&faces), "{info}");
    // And it tessellates as a Catmull-Clark mesh.
    run_ok(tessera().arg("tessellate").arg(&glb).args([
        "--backend",
        "cpu",
        "--tolerance-rel",
        "0.01",
    ]));
}

#[test]
fn gpu_and_cpu_backends_write_the_same_mesh() {
    let (gpu, cpu, stats) = (tmp("gpu.ply"), tmp("cpu.ply"), tmp("gpu.json"));
    for (backend, out) in [("gpu", &gpu), ("cpu", &cpu)] {
        run_ok(
            tessera()
                .args([
                    "tessellate",
                    teapot().to_str().unwrap(),
                    "--method",
                    "map4p",
                ])
                .args(["--threshold", "0.02", "--backend", backend, "--stats"])
                .arg(&stats)
                .arg("-o")
                .arg(out),
        );
        if backend == "gpu" {
            let s: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
            assert_eq!(s["backend"], "gpu");
            assert!(s["adapter"].is_string());
            assert!(s["timings_ms"]["tessellate"].as_f64().unwrap() > 0.0);
            assert!(s["timings_ms"]["gpu"]["pipelines_and_upload"]
                .as_f64()
                .is_some());
        }
    }
    let (gpu, cpu) = (
        std::fs::read_to_string(&gpu).unwrap(),
        std::fs::read_to_string(&cpu).unwrap(),
    );
    same_ply_mesh(&gpu, &cpu).unwrap();
    // The comparison fails on a planted difference: the last face turned around, the
    // first vertex moved by 6e-4, about 7e-5 of the model (7× the tolerance).
    let edit = |index: usize, change: &dyn Fn(&str) -> String| {
        let lines: Vec<String> = cpu
            .lines()
            .enumerate()
            .map(|(i, l)| if i == index { change(l) } else { l.to_string() })
            .collect();
        lines.join("\n") + "\n"
    };
    let turned = edit(cpu.lines().count() - 1, &|l| {
        let k: Vec<&str> = l.split(' ').collect();
        format!("{} {} {} {}", k[0], k[3], k[2], k[1])
    });
    let e = same_ply_mesh(&gpu, &turned).unwrap_err();
    assert!(e.starts_with("face"), "{e}");
    let first_vertex = cpu.lines().position(|l| l == "end_header").unwrap() + 1;
    let moved = edit(first_vertex, &|l| {
        let mut f: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
        f[0] += 6e-4; // the teapot's diagonal is about 8.2
        f.iter().map(f64::to_string).collect::<Vec<_>>().join(" ")
    });
    let e = same_ply_mesh(&gpu, &moved).unwrap_err();
    assert!(e.starts_with("vertex 0"), "{e}");
}

/// Whether two ASCII PLY files (`x y z nx ny nz u v face` vertices) hold the same mesh,
/// as the GPU and CPU backends must write it: the same header and faces, positions within
/// 1e-5 of the model's diagonal, normals within 1e-3, the same (face, u, v). Not byte for
/// byte: a GPU may fuse a multiply and an add where the CPU rounds twice.
fn same_ply_mesh(actual: &str, expected: &str) -> Result<(), String> {
    /// Header lines, vertex rows, face lines.
    fn split(s: &str) -> (Vec<&str>, Vec<Vec<f64>>, Vec<&str>) {
        let lines: Vec<&str> = s.lines().collect();
        let end = lines
            .iter()
            .position(|&l| l == "end_header")
            .expect("a PLY header");
        let vertices: usize = lines
            .iter()
            .find_map(|l| l.strip_prefix("element vertex "))
            .expect("a vertex count")
            .parse()
            .unwrap();
        let body = &lines[end + 1..];
        let rows: Vec<Vec<f64>> = body[..vertices]
            .iter()
            .map(|l| l.split(' ').map(|x| x.parse().unwrap()).collect())
            .collect();
        (lines[..=end].to_vec(), rows, body[vertices..].to_vec())
    }
    let (a_header, a_rows, a_faces) = split(actual);
    let (e_header, e_rows, e_faces) = split(expected);
    if a_header != e_header {
        return Err(format!("headers differ: {a_header:?} and {e_header:?}"));
    }
    if let Some(k) =
        (0..a_faces.len().max(e_faces.len())).find(|&k| a_faces.get(k) != e_faces.get(k))
    {
        return Err(format!(
            "face {k} differs: {:?} and {:?}",
            a_faces.get(k),
            e_faces.get(k)
        ));
    }
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for r in &e_rows {
        for c in 0..3 {
            lo[c] = lo[c].min(r[c]);
            hi[c] = hi[c].max(r[c]);
        }
    }
    let diag = (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt();
    let dist = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    for (k, (a, e)) in a_rows.iter().zip(&e_rows).enumerate() {
        let (dp, dn) = (dist(&a[0..3], &e[0..3]), dist(&a[3..6], &e[3..6]));
        if dp > 1e-5 * diag || dn > 1e-3 || a[6..] != e[6..] {
            return Err(format!(
                "vertex {k} differs: {a:?} and {e:?} (diagonal {diag})"
            ));
        }
    }
    Ok(())
}

#[test]
fn render_writes_a_png_of_the_requested_size() {
    let png = tmp("teapot.png");
    let out = run_ok(
        tessera()
            .env_remove("XDG_RUNTIME_DIR")
            .env_remove("NODEVICE_SELECT")
            .args([
                "render",
                teapot().to_str().unwrap(),
                "--size",
                "96x64",
                "--wireframe",
                "-o",
            ])
            .arg(&png),
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // IHDR: width and height, big-endian, at bytes 16..24.
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert_eq!((w, h), (96, 64));
    // A headless render says one line, without the driver's noise.
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 1);
}

#[test]
fn render_rejects_bad_arguments_without_writing() {
    for (size, out) in [("96x0", "a.png"), ("axb", "b.png"), ("64x64", "c.ply")] {
        let path = tmp(out);
        let st = tessera()
            .args(["render", teapot().to_str().unwrap(), "--size", size, "-o"])
            .arg(&path)
            .output()
            .unwrap();
        assert!(!st.status.success(), "{size} {out} accepted");
        let err = String::from_utf8_lossy(&st.stderr);
        assert!(!err.contains("panicked"), "{err}");
        assert!(!path.exists(), "{out} written despite the error");
    }
}

fn asset(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(rel)
}

#[test]
fn catmull_clark_adaptive_and_uniform_write_ply_and_stats() {
    let (ply, stats) = (tmp("cc.ply"), tmp("cc.json"));
    run_ok(
        tessera()
            .args(["tessellate"])
            .arg(asset("catmull_clark/blub_control_mesh.obj"))
            .args([
                "--tolerance-rel",
                "0.003",
                "--measure",
                "--backend",
                "cpu",
                "-o",
            ])
            .arg(&ply)
            .arg("--stats")
            .arg(&stats),
    );
    let json = stats_with_spec_keys(&stats, &["guaranteed_error"]);
    let tol = json["tolerance"].as_f64().unwrap();
    assert!(json["max_error"].as_f64().unwrap() <= tol);
    assert!(json["guaranteed_error"].as_f64().unwrap() <= tol);
    assert_eq!(json["unmet"], 0);
    let text = std::fs::read_to_string(&ply).unwrap();
    assert!(text.contains(&format!("element face {}", json["triangles"])));
    assert!(text.contains("property float nx") && text.contains("property uint face"));
    assert_eq!(json["first_split"], "search");
    // Each vertex names its control face; a point on an edge between faces is one
    // vertex per face, at one position.
    let faces = json["faces"].as_u64().unwrap();
    let (vertices, positions) = (
        json["vertices"].as_u64().unwrap(),
        json["positions"].as_u64().unwrap(),
    );
    assert!(positions < vertices && faces > 1, "{json}");
    assert!(json["vertex_face"]
        .as_str()
        .unwrap()
        .contains("control face"));
    assert!(json["vertex_uv"].as_str().unwrap().contains("Bfr"));
    let end = text.lines().position(|l| l == "end_header").unwrap();
    let face_ids: Vec<u64> = text
        .lines()
        .skip(end + 1)
        .take(vertices as usize)
        .map(|l| l.rsplit(' ').next().unwrap().parse().unwrap())
        .collect();
    assert!(face_ids.iter().all(|&f| f < faces));

    // --first-split midpoint: the paper's subdivision, one quadtree per patch (L leaves
    // over P patches test L + (L - P) / 3 cells, each with a bound or the split proof),
    // more triangles, still within ε.
    let (search_tris, search_bounds) = (json["triangles"].clone(), json["flatness_bounds"].clone());
    run_ok(
        tessera()
            .args(["tessellate"])
            .arg(asset("catmull_clark/blub_control_mesh.obj"))
            .args(["--tolerance-rel", "0.003", "--backend", "cpu"])
            .args(["--first-split", "midpoint", "--stats"])
            .arg(&stats),
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["first_split"], "midpoint");
    let (leaves, patches) = (
        json["leaves"].as_u64().unwrap(),
        json["patches"].as_u64().unwrap(),
    );
    let (bounds, proofs) = (
        json["flatness_bounds"].as_u64().unwrap(),
        json["split_proofs"].as_u64().unwrap(),
    );
    assert_eq!(bounds + proofs, leaves + (leaves - patches) / 3);
    assert!(
        proofs > 0,
        "blub has vertices: some cells split on the proof"
    );
    assert!(json["triangles"].as_u64() > search_tris.as_u64());
    assert!(json["flatness_bounds"].as_u64() < search_bounds.as_u64());
    assert!(json["guaranteed_error"].as_f64().unwrap() <= tol);

    // --level L is the 2^L grid per patch: 2·4^L triangles per patch.
    run_ok(
        tessera()
            .args(["tessellate"])
            .arg(asset("opensubdiv/catmark_cube.obj"))
            .args(["--method", "uniform", "--level", "2", "--stats"])
            .arg(&stats),
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["triangles"], 24 * 2 * 16);
    // Unsupported tags are warned about on stderr, never silently ignored.
    let st = run_ok(
        tessera()
            .args(["tessellate"])
            .arg(asset("opensubdiv/catmark_square_hedit0.obj")),
    );
    assert!(
        String::from_utf8_lossy(&st.stderr).contains("warning:")
            && String::from_utf8_lossy(&st.stderr).contains("edit")
    );
}

fn expect_cc_failure(content: &[u8], expect: &str) {
    expect_failure_as("bad_mesh.obj", content, expect);
}

#[test]
fn bad_control_meshes_fail_with_one_line() {
    let sq = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    expect_cc_failure(b"", "empty file");
    expect_cc_failure(b"\x7fELF\x02\x01\x01\x00\x00", "not a text file");
    expect_cc_failure(
        format!("{sq}f 1 2 3 7\n").as_bytes(),
        ":5: vertex index 7 out of range",
    );
    expect_cc_failure(format!("{sq}f 1 0 3\n").as_bytes(), ":5: vertex index 0");
    expect_cc_failure(
        b"v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        ":1: coordinate \"nan\" is not finite",
    );
    expect_cc_failure(format!("{sq}f 1 2\n").as_bytes(), ":5: face has 2 vertices");
    expect_cc_failure(
        format!("{sq}v 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 5\nf 1 2 6\n").as_bytes(),
        ":9: non-manifold edge 1-2: used by more than two faces (--split-non-manifold cuts the mesh there)",
    );
    let pole = std::fs::read(asset("opensubdiv/catmark_pole360.obj")).unwrap();
    expect_cc_failure(&pole, "valence 360; at most 64");
}

#[test]
fn catmull_clark_on_the_gpu_writes_what_the_cpu_writes_and_renders() {
    // The same triangles and vertices from both backends, the GPU's guarantee reported
    // and kept (measured error at or under the tolerance), and a PNG from `render`.
    let mut counts = Vec::new();
    for backend in ["gpu", "cpu"] {
        let stats = tmp(&format!("cc_{backend}.json"));
        let ply = tmp(&format!("cc_{backend}.ply"));
        run_ok(
            tessera()
                .args(["tessellate"])
                .arg(asset("opensubdiv/catmark_pyramid.obj"))
                .args([
                    "--method",
                    "adaptive",
                    "--tolerance-rel",
                    "2e-3",
                    "--max-depth",
                    "6",
                ])
                .args(["--backend", backend, "--measure", "--stats"])
                .arg(&stats)
                .arg("-o")
                .arg(&ply),
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(json["backend"], backend);
        let tol = json["tolerance"].as_f64().unwrap();
        assert!(
            json["max_error"].as_f64().unwrap() <= tol,
            "{backend}: {json}"
        );
        assert!(json["guaranteed_error"].as_f64().unwrap() <= tol * (1.0 + 1e-6));
        assert_eq!(json["unmet"], 0);
        if backend == "gpu" {
            assert!(json["timings_ms"]["gpu"]["tessellate"].as_f64().unwrap() > 0.0);
        }
        counts.push((
            json["triangles"].clone(),
            json["vertices"].clone(),
            json["leaves"].clone(),
        ));
    }
    assert_eq!(counts[0], counts[1], "gpu and cpu differ");
    // The uniform peer runs on the GPU too: the same grid, the same measured error.
    let mut uniform = Vec::new();
    for backend in ["gpu", "cpu"] {
        let stats = tmp(&format!("cc_uniform_{backend}.json"));
        run_ok(
            tessera()
                .args(["tessellate"])
                .arg(asset("opensubdiv/catmark_pyramid.obj"))
                .args(["--method", "uniform", "--segments", "3", "--measure"])
                .args(["--backend", backend, "--stats"])
                .arg(&stats),
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(json["backend"], backend);
        assert_eq!(json["triangles"], 16 * 2 * 9);
        uniform.push(json);
    }
    assert_eq!(uniform[0]["vertices"], uniform[1]["vertices"]);
    let (g, c) = (
        uniform[0]["max_error"].as_f64().unwrap(),
        uniform[1]["max_error"].as_f64().unwrap(),
    );
    assert!(
        (g - c).abs() <= 1e-3 * c,
        "uniform max error gpu {g} cpu {c}"
    );
    let png = tmp("cc.png");
    run_ok(
        tessera()
            .args(["render"])
            .arg(asset("opensubdiv/catmark_pyramid.obj"))
            .args(["--size", "64x48", "--tolerance-rel", "3e-3", "-o"])
            .arg(&png),
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let png = tmp("cc_uniform.png");
    run_ok(
        tessera()
            .args(["render"])
            .arg(asset("opensubdiv/catmark_pyramid.obj"))
            .args([
                "--size",
                "64x48",
                "--method",
                "uniform",
                "--segments",
                "3",
                "-o",
            ])
            .arg(&png),
    );
    assert_eq!(&std::fs::read(&png).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
    // --segments without --method uniform, and options of the other kind of surface,
    // are refused.
    for (option, file, expect) in [
        (
            &["--segments", "3"][..],
            "opensubdiv/catmark_pyramid.obj",
            "--method uniform",
        ),
        (
            &["--threshold", "0.1"],
            "opensubdiv/catmark_pyramid.obj",
            "--tolerance-rel",
        ),
        (
            &[
                "--method",
                "uniform",
                "--segments",
                "3",
                "--first-split",
                "search",
            ],
            "opensubdiv/catmark_pyramid.obj",
            "not a tolerance or --first-split",
        ),
        (
            &["--first-split", "midpoint"],
            "teaset/teapot",
            "--split-non-manifold, --no-creases and --backend are Catmull-Clark options",
        ),
        (
            &["--split-non-manifold"],
            "teaset/teapot",
            "--split-non-manifold, --no-creases and --backend are Catmull-Clark options",
        ),
    ] {
        let out = tessera()
            .args(["render"])
            .arg(asset(file))
            .args(option)
            .arg("-o")
            .arg(tmp("never.png"))
            .output()
            .unwrap();
        assert!(!out.status.success());
        assert!(String::from_utf8_lossy(&out.stderr).contains(expect));
    }
    assert!(!tmp("never.png").exists());
}

#[test]
fn split_non_manifold_tessellates_each_sheet() {
    // OpenSubdiv's fan (three sheets on a chain of edges) is refused as it is, and cut
    // into sheets with the flag, on both backends alike.
    let fan = asset("opensubdiv/catmark_fan.obj");
    let mut counts = Vec::new();
    for backend in ["cpu", "gpu"] {
        let ply = tmp(&format!("fan_{backend}.ply"));
        let out = run_ok(
            tessera()
                .arg("tessellate")
                .arg(&fan)
                .args([
                    "--split-non-manifold",
                    "--tolerance-rel",
                    "3e-3",
                    "--measure",
                ])
                .args(["--backend", backend, "-o"])
                .arg(&ply),
        );
        assert!(ply.exists());
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        let triangles: String = stdout
            .split(" triangles")
            .next()
            .and_then(|s| s.rsplit(' ').next())
            .unwrap()
            .to_string();
        let triangles: usize = triangles.parse().unwrap_or_else(|_| panic!("{stdout}"));
        assert!(triangles > 0);
        counts.push(triangles);
    }
    assert_eq!(counts[0], counts[1], "cpu and gpu triangle counts");
    let r = tessera()
        .arg("tessellate")
        .arg(&fan)
        .arg("-o")
        .arg(tmp("fan_refused.ply"))
        .output()
        .unwrap();
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("--split-non-manifold"));
}
