//! `cargo xtask test` and `cargo xtask bench`: the project's two entry points for
//! developers and CI. Only the standard library: it must build fast on a fresh machine.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("test") => test(&args[1..]),
        Some("bench") => bench(&args[1..]),
        _ => {
            eprintln!("usage: cargo xtask test [-- <cargo test args>]\n       cargo xtask bench [--quick]");
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
    apt(&[
        "install",
        "-y",
        "-q",
        "--no-install-recommends",
        "mesa-vulkan-drivers",
        "libvulkan1",
    ])?;
    if !vulkan_driver_present() {
        return Err("mesa-vulkan-drivers installed but no Vulkan ICD manifest appeared".into());
    }
    Ok(())
}

fn test(extra: &[String]) -> Result<(), String> {
    ensure_vulkan()?;
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
    let mut t = cargo();
    t.args(["test", "--workspace", "--locked"]);
    if !extra.is_empty() {
        t.args(extra.iter().skip_while(|a| *a == "--"));
    }
    run(&mut t)
}

fn bench(extra: &[String]) -> Result<(), String> {
    let out = root().join("bench");
    run(cargo()
        .args(["run", "--release", "--locked", "-p", "tessera-bench", "--"])
        .arg("--out")
        .arg(&out)
        .args(extra))?;
    // Paste the tables into the README between their markers.
    let readme_path = root().join("README.md");
    let mut readme =
        std::fs::read_to_string(&readme_path).map_err(|e| format!("README.md: {e}"))?;
    for entry in std::fs::read_dir(&out)
        .map_err(|e| format!("{}: {e}", out.display()))?
        .flatten()
    {
        let path = entry.path();
        if path.extension().is_none_or(|e| e != "md") {
            continue;
        }
        let name = path
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let table =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let (start, end) = (
            format!("<!-- bench:{name}:start -->"),
            format!("<!-- bench:{name}:end -->"),
        );
        if let (Some(a), Some(b)) = (readme.find(&start), readme.find(&end)) {
            readme = format!(
                "{}{start}\n{}\n{}",
                &readme[..a],
                table.trim_end(),
                &readme[b..]
            );
        }
    }
    std::fs::write(&readme_path, readme).map_err(|e| format!("README.md: {e}"))?;
    eprintln!("xtask: results in {} and README.md", out.display());
    Ok(())
}
