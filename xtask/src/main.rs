//! `cargo xtask render`, `cargo xtask test`, `cargo xtask bench` and `cargo xtask fuzz`:
//! the project's entry points for users, developers and CI. Only the standard library: it
//! must build fast on a fresh machine.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("render") => render(&args[1..]),
        Some("test") => test(&args[1..]),
        Some("bench") => bench(&args[1..]),
        Some("fuzz") => fuzz(&args[1..]),
        _ => {
            eprintln!("usage: cargo xtask render -- INPUT -o OUT.png [tessera render options]\n       cargo xtask test [-- <cargo test args>]\n       cargo xtask bench [--quick] [--only PART] | --assemble-only\n       cargo xtask fuzz N [--seed S]");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

fn run(cmd: &mut Command) -> Result<(), String> {
    eprintln!("xtask: running {cmd:?}");
    let status = cmd
        .current_dir(root())
        .status()
        .map_err(|e| format!("{cmd:?}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{cmd:?} failed with {status}"))
    }
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// Vulkan ICD manifests: a Vulkan driver (lavapipe or a GPU's) is installed when one exists.
fn vulkan_driver_present() -> bool {
    [
        "/usr/share/vulkan/icd.d",
        "/etc/vulkan/icd.d",
        "/usr/local/share/vulkan/icd.d",
    ]
    .iter()
    .filter_map(|d| std::fs::read_dir(d).ok())
    .flatten()
    .flatten()
    .any(|e| e.path().extension().is_some_and(|x| x == "json"))
}

/// Installs Mesa's lavapipe (CPU Vulkan) when no Vulkan driver is present, as the tests
/// render headless through wgpu on whatever Vulkan adapter exists.
fn ensure_vulkan() -> Result<(), String> {
    if vulkan_driver_present() {
        return Ok(());
    }
    eprintln!("xtask: no Vulkan driver found; installing Mesa's lavapipe (mesa-vulkan-drivers)");
    apt_install(&["mesa-vulkan-drivers", "libvulkan1"])?;
    if !vulkan_driver_present() {
        return Err("mesa-vulkan-drivers installed but no Vulkan ICD manifest appeared".into());
    }
    Ok(())
}

/// Debian packages by name, as root or through passwordless sudo.
fn apt_install(packages: &[&str]) -> Result<(), String> {
    let is_root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    let sudo: &[&str] = if is_root { &[] } else { &["sudo", "-n"] };
    let apt = |args: &[&str]| {
        let mut full: Vec<&str> = sudo.to_vec();
        full.push("apt-get");
        full.extend_from_slice(args);
        let mut c = Command::new(full[0]);
        c.args(&full[1..]).env("DEBIAN_FRONTEND", "noninteractive");
        run(&mut c)
    };
    apt(&["update", "-q"])?;
    let mut install = vec!["install", "-y", "-q", "--no-install-recommends"];
    install.extend_from_slice(packages);
    apt(&install)
}

/// The X server the demo's tests open their windows on (Xvfb, through `xvfb-run`), and
/// the X libraries winit loads at run time.
fn ensure_xvfb() -> Result<(), String> {
    let libs = [
        "libX11.so.6",
        "libX11-xcb.so.1",
        "libXcursor.so.1",
        "libXrandr.so.2",
        "libXi.so.6",
        "libxkbcommon-x11.so.0",
    ];
    let lib_present = |name: &str| {
        [
            "/usr/lib/x86_64-linux-gnu",
            "/usr/lib/aarch64-linux-gnu",
            "/usr/lib",
            "/lib",
        ]
        .iter()
        .any(|d| Path::new(d).join(name).exists())
    };
    let have_server = ["/usr/bin/Xvfb", "/usr/bin/xvfb-run", "/usr/bin/xauth"]
        .iter()
        .all(|p| Path::new(p).exists());
    if have_server && libs.iter().all(|l| lib_present(l)) {
        return Ok(());
    }
    eprintln!("xtask: installing Xvfb and the X libraries for the demo's tests");
    apt_install(&[
        "xvfb",
        "xauth",
        "libx11-6",
        "libx11-xcb1",
        "libxcursor1",
        "libxrandr2",
        "libxi6",
        "libxkbcommon-x11-0",
    ])
}

/// OpenSubdiv (Debian's `libosd-dev`), the reference the Catmull-Clark surface is tested
/// against, and g++ when missing, then its helper `tests/osd/osd_eval.cpp` built into
/// `target/osd-eval/osd_eval` (again whenever the source is newer). Returns its path.
fn ensure_osd_eval() -> Result<PathBuf, String> {
    const HEADER: &str = "/usr/include/opensubdiv/version.h";
    let have_gxx = Command::new("g++")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let mut missing = Vec::new();
    if !Path::new(HEADER).exists() {
        missing.push("libosd-dev");
    }
    if !have_gxx {
        missing.push("g++");
    }
    if !missing.is_empty() {
        let list = missing.join(" ");
        eprintln!("xtask: installing {list} for the tests against OpenSubdiv");
        apt_install(&missing).map_err(|e| {
            format!("the tests need OpenSubdiv and g++, and `apt-get install {list}` failed: {e}")
        })?;
        if !Path::new(HEADER).exists() {
            return Err(format!("libosd-dev installed but {HEADER} is missing"));
        }
    }
    let src = root().join("tests/osd/osd_eval.cpp");
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(|d| root().join(d))
        .unwrap_or_else(|| root().join("target"));
    let out = target.join("osd-eval/osd_eval");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    if matches!((modified(&src), modified(&out)), (Some(s), Some(o)) if o >= s) {
        return Ok(out);
    }
    let dir = out.parent().expect("a file in a folder");
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    // Built under a private name and renamed: a test running meanwhile never starts a
    // half-written binary.
    let tmp = out.with_file_name(format!("osd_eval.{}", std::process::id()));
    run(Command::new("g++")
        .args(["-O2", "-std=c++14"])
        .arg(&src)
        .arg("-o")
        .arg(&tmp)
        .arg("-losdCPU"))?;
    std::fs::rename(&tmp, &out).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(out)
}

/// The main job on a fresh machine: a Vulkan driver if there is none, then the CLI's
/// `tessera render` with the given arguments, in the caller's directory (paths are the
/// caller's), exiting as the CLI exits.
fn render(args: &[String]) -> Result<(), String> {
    ensure_vulkan()?;
    let manifest = root().join("Cargo.toml");
    let status = cargo()
        .args([
            "run",
            "--quiet",
            "--release",
            "--locked",
            "-p",
            "tessera-cli",
        ])
        .arg("--manifest-path")
        .arg(&manifest)
        .args(["--", "render"])
        .args(args.iter().skip_while(|a| *a == "--"))
        .status()
        .map_err(|e| format!("cargo run: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        // The CLI has said what went wrong, in one line.
        std::process::exit(status.code().unwrap_or(1))
    }
}

fn test(extra: &[String]) -> Result<(), String> {
    ensure_vulkan()?;
    ensure_xvfb()?;
    let osd_eval = ensure_osd_eval()?;
    run(cargo().args(["fmt", "--all", "--", "--check"]))?;
    run(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--locked",
        "--",
        "-D",
        "warnings",
    ]))?;
    // An embedding renderer turns the headless helpers off: the stage builds without them.
    run(cargo().args([
        "clippy",
        "-p",
        "tessera-wgpu",
        "--no-default-features",
        "--locked",
        "--",
        "-D",
        "warnings",
    ]))?;
    // The library crates' docs build without a warning (every public item documented).
    run(cargo()
        .args([
            "doc",
            "--no-deps",
            "--locked",
            "-p",
            "tessera-core",
            "-p",
            "tessera-wgpu",
        ])
        .env("RUSTDOCFLAGS", "-D warnings"))?;
    let mut t = cargo();
    t.args(["test", "--workspace", "--locked"])
        .env("TESSERA_OSD_EVAL", &osd_eval);
    if !extra.is_empty() {
        t.args(extra.iter().skip_while(|a| *a == "--"));
    }
    run(&mut t)
}

/// The tables of `bench/RESULTS.md`, in this order: file stem, heading, what it measures.
/// Any other `bench/*.md` follows under its file name.
const TABLES: &[(&str, &str, &str)] = &[
    (
        "bezier_gpu",
        "Bézier: the GPU stage against the CPU reference",
        "Map4p at five thresholds on 1, 32 and 1024 patches (copies of the teapot side by \
         side); the stage and the CPU reference timed in turns.",
    ),
    (
        "bezier_cpu",
        "Bézier: adaptive against uniform at equal measured error (CPU)",
        "The teapot and the teacup, every edge test at two depths, against the fewest \
         uniform triangles with a measured max error at or under each row's.",
    ),
    (
        "catmull_clark_cpu",
        "Catmull-Clark: adaptive against uniform at equal measured error (CPU)",
        "Per model and tolerance ε (a fraction of the bounding-box diagonal): the adaptive \
         mesh, its guaranteed bound and measured error (32×32 exact samples per patch), \
         then the smallest uniform grid n × n per patch whose measured max error is at or \
         under the adaptive one and the ratio of triangle counts (`ratio at ε`: against \
         the grid at or under ε itself); then the paper's midpoint subdivision and the \
         own-triangles leaf bound at the same ε, each against uniform the same way.",
    ),
    (
        "catmull_clark_creased",
        "Catmull-Clark with creases: every shipped creased shape (CPU)",
        "Every shipped OpenSubdiv shape with crease or corner tags, with its creases: the \
         measured max error (32×32 exact samples per patch) beside ε, the triangles against \
         the smallest uniform grid at or under the same measured error (`uniform n = 1`, two \
         triangles per patch, is the floor of both), the triangles of the same shape \
         without creases at the same ε, and the largest distance from OpenSubdiv's own \
         limit surface (Bfr at its deepest level; Far's limit masks on `catmark_chaikin1`, \
         where Bfr departs from Far) at random `(face, u, v)`. Car, bishop and rook at \
         three tolerances.",
    ),
    (
        "catmull_clark_gpu",
        "Catmull-Clark: the GPU stages against the CPU and uniform peers",
        "Per model, tolerance and first split: the adaptive stage on the GPU, the CPU \
         reference, and the uniform tessellation (CPU and GPU) at the smallest grid whose \
         measured max error is at or under the GPU output's; then where the GPU time \
         goes, the script's fixed cost with one leaf per patch, and the scaling from 3e-3 \
         to the first tolerance with 10× the triangles.",
    ),
    (
        "catmull_clark_view",
        "Catmull-Clark in a view: a tolerance in pixels",
        "Close-ups of the car and of Spot, on the CPU reference and the GPU stage: the \
         tolerance in pixels against the same view culled at the world tolerance that \
         guarantees the same pixel error everywhere in view; the car's stage as the camera \
         moves; a scene of 64 cars.",
    ),
];

/// `cargo xtask bench [ARGS]` runs the bench (ARGS go to `tessera-bench`: `--quick`,
/// `--only gpu|cpu|cc|creased|ccgpu|view`, ...), which writes `bench/NAME.{json,md}`, then assembles
/// `bench/RESULTS.md`; `cargo xtask bench --assemble-only` only assembles it.
fn bench(extra: &[String]) -> Result<(), String> {
    let out = root().join("bench");
    let assemble_only = extra.iter().any(|a| a == "--assemble-only");
    if !assemble_only {
        // The creased table compares with OpenSubdiv through the tests' helper.
        let osd_eval = ensure_osd_eval()?;
        run(cargo()
            .args(["run", "--release", "--locked", "-p", "tessera-bench", "--"])
            .arg("--out")
            .arg(&out)
            .args(extra)
            .env("TESSERA_OSD_EVAL", &osd_eval))?;
    }
    let command = std::iter::once("cargo xtask bench")
        .chain(extra.iter().map(String::as_str))
        .collect::<Vec<_>>()
        .join(" ");
    let results = assemble_results(&out, &command)?;
    eprintln!("xtask: results in {}", results.display());
    Ok(())
}

/// Writes `dir/RESULTS.md`: a header (this host, the command, each table's date and
/// adapter), then every `dir/*.md` table as the bench wrote it, in the order of
/// [`TABLES`]. A run with `--only` rewrites some tables; the others stay as their last
/// run left them, under that run's date. `*_subset.md` (partial runs, not committed) and
/// the tables of other devices (subfolders, linked from the header) are left out.
fn assemble_results(dir: &Path, command: &str) -> Result<PathBuf, String> {
    let read = |p: &Path| std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()));
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .filter_map(|p| Some(p.file_stem()?.to_string_lossy().into_owned()))
        .filter(|s| s != "RESULTS" && s != "README" && !s.ends_with("_subset"))
        .collect();
    let rank = |s: &str| TABLES.iter().position(|t| t.0 == s).unwrap_or(TABLES.len());
    stems.sort_by(|a, b| (rank(a), a).cmp(&(rank(b), b)));

    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut md = format!(
        "# Bench results\n\n\
         Written by `cargo xtask bench`, which runs the bench and then assembles this file from \
         the tables it wrote in `bench/` (`cargo xtask bench --assemble-only` assembles it \
         alone). Do not edit it by hand. A run with `--only` rewrites some of the tables; \
         each table below keeps the date of the run that last measured it. CPU times are one \
         thread of the host.\n\n\
         This file: `{command}` on {}, host {cpu}, {cores} cores ({} {}).\n\n\
         | table | measured | adapter |\n|---|---|---|\n",
        today(),
        std::env::consts::OS,
        std::env::consts::ARCH,
    );
    for stem in &stems {
        let title = TABLES
            .iter()
            .find(|t| t.0 == *stem)
            .map_or(stem.as_str(), |t| t.1);
        let adapter = read(&dir.join(format!("{stem}.json")))
            .ok()
            .and_then(|j| json_string(&j, "adapter").or_else(|| json_string(&j, "device")))
            .unwrap_or_else(|| "CPU only".into());
        md += &format!(
            "| [{title}](#{}) | {} | {adapter} |\n",
            anchor(title),
            measured(dir, stem)
        );
    }
    let mut others: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.join("README.md").is_file())
        .collect();
    others.sort();
    if !others.is_empty() {
        md += "\nOther devices (not rewritten by `cargo xtask bench`):\n\n";
        for d in &others {
            let name = d.file_name().unwrap_or_default().to_string_lossy();
            let readme = d.join("README.md");
            let heading = read(&readme)?
                .lines()
                .next()
                .unwrap_or_default()
                .trim_start_matches('#')
                .trim()
                .to_string();
            md += &format!("- [`{name}/`]({name}/README.md): {heading}\n");
        }
    }
    for stem in &stems {
        let (title, about) = TABLES
            .iter()
            .find(|t| t.0 == *stem)
            .map_or((stem.as_str(), ""), |t| (t.1, t.2));
        let path = dir.join(format!("{stem}.md"));
        md += &format!(
            "\n## {title}\n\n`bench/{stem}.md`, measured {}. {about}\n\n{}\n",
            measured(dir, stem),
            read(&path)?.trim()
        );
    }
    let results = dir.join("RESULTS.md");
    std::fs::write(&results, md).map_err(|e| format!("{}: {e}", results.display()))?;
    Ok(results)
}

/// The first string value of `"key"` in a JSON text (enough for the bench's flat files).
fn json_string(json: &str, key: &str) -> Option<String> {
    let rest = &json[json.find(&format!("\"{key}\""))? + key.len() + 2..];
    let rest = &rest[rest.find('"')? + 1..];
    Some(rest[..rest.find('"')?].to_string())
}

/// GitHub's anchor for a heading: lower case, spaces to dashes, punctuation dropped.
fn anchor(title: &str) -> String {
    title
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// When table `stem` was measured: when its numbers (`stem.json`, else the table itself)
/// were last written, so that a change of wording in the table keeps the run's date.
fn measured(dir: &Path, stem: &str) -> String {
    let json = dir.join(format!("{stem}.json"));
    written(&if json.is_file() {
        json
    } else {
        dir.join(format!("{stem}.md"))
    })
}

/// When a file was last written: its last commit's date if it is committed unchanged,
/// else its modification date.
fn written(path: &Path) -> String {
    let out = |c: &mut Command| {
        c.current_dir(root())
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let unchanged = out(Command::new("git")
        .args(["status", "--porcelain", "--"])
        .arg(path))
    .is_some_and(|s| s.is_empty());
    let committed = out(Command::new("git")
        .args(["log", "-1", "--format=%cs", "--"])
        .arg(path))
    .filter(|d| !d.is_empty());
    match committed {
        Some(date) if unchanged => date,
        _ => out(Command::new("date").args(["-u", "+%F", "-r"]).arg(path))
            .unwrap_or_else(|| "(date unknown)".into()),
    }
}

/// Today's date, UTC.
fn today() -> String {
    Command::new("date")
        .args(["-u", "+%F"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default()
}

/// The loaders' mutation fuzz with `N` mutants per loader (and a seed), optimized: the
/// same test as in `cargo xtask test`, which runs 1000.
fn fuzz(args: &[String]) -> Result<(), String> {
    let usage = || "usage: cargo xtask fuzz N [--seed S]".to_string();
    let mutants: u64 = args
        .first()
        .and_then(|n| n.parse().ok())
        .ok_or_else(usage)?;
    let mut t = cargo();
    t.args([
        "test",
        "--release",
        "--locked",
        "-p",
        "tessera-tests",
        "--test",
        "loader_fuzz",
        "--",
        "--nocapture",
    ])
    .env("TESSERA_FUZZ_MUTANTS", mutants.to_string());
    match &args[1..] {
        [] => {}
        [flag, seed] if flag == "--seed" => {
            t.env("TESSERA_FUZZ_SEED", seed);
        }
        _ => return Err(usage()),
    }
    run(&mut t)
}
