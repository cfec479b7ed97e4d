//! Mutated input files through the `tessera` binary: every run either succeeds with both
//! outputs, or fails with one line naming the input and leaves no file behind (no output,
//! no temporary); never a panic or a hang.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use tessera_tests::fuzz::{inputs, mutant_seed, mutate, Rng, DEFAULT_SEED};

/// Mutants per input file (five files: Newell, two OBJ, glTF, GLB).
const PER_INPUT: usize = 6;

/// Runs `cmd`, killing it after `limit`: (exit code, stderr), or `None` on a timeout.
fn run_with_limit(cmd: &mut Command, limit: Duration) -> Option<(Option<i32>, String)> {
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("tessera starts");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("wait").is_some() {
            let out = child.wait_with_output().expect("output");
            return Some((
                out.status.code(),
                String::from_utf8_lossy(&out.stderr).into_owned(),
            ));
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// `error: FILE: problem` or `error: FILE:LINE: problem`.
fn names_file(error: &str, file: &Path) -> bool {
    let Some(rest) = error.strip_prefix(&format!("error: {}:", file.display())) else {
        return false;
    };
    let problem = match rest.strip_prefix(' ') {
        Some(problem) => Some(problem),
        None => rest
            .trim_start_matches(|c: char| c.is_ascii_digit())
            .strip_prefix(": ")
            .filter(|_| rest.starts_with(|c: char| c.is_ascii_digit())),
    };
    problem.is_some_and(|p| !p.is_empty())
}

fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn mutated_inputs_fail_cleanly_or_write_both_outputs() {
    let root = std::env::temp_dir().join(format!("tessera-cli-fuzz-{}", std::process::id()));
    let (mut succeeded, mut failed) = (0, 0);
    for (k, input) in inputs().into_iter().flat_map(|(_, i)| i).enumerate() {
        for i in 0..PER_INPUT {
            let seed = mutant_seed(DEFAULT_SEED, k as u64, i as u64);
            let mutant = mutate(&mut Rng::new(seed), &input.seed);
            let dir = root.join(format!("{}-{i}", input.name));
            std::fs::create_dir_all(&dir).unwrap();
            let file_name = format!("mutant.{}", input.ext);
            let file = dir.join(&file_name);
            std::fs::write(&file, &mutant.bytes).unwrap();
            let what = format!(
                "{} mutant {i} (seed {seed:#x}: {})",
                input.name,
                mutant.ops.join(", ")
            );
            let (code, stderr) = run_with_limit(
                Command::new(env!("CARGO_BIN_EXE_tessera"))
                    .arg("tessellate")
                    .arg(&file)
                    .args(["-o", "OUT.obj", "--stats", "OUT.json", "--backend", "cpu"])
                    .current_dir(&dir),
                Duration::from_secs(120),
            )
            .unwrap_or_else(|| panic!("{what}: still running after 120 s"));
            assert!(
                code != Some(101) && !stderr.contains("panicked"),
                "{what}: panicked: {stderr}"
            );
            let names = names_in(&dir);
            if code == Some(0) {
                succeeded += 1;
                assert_eq!(
                    names,
                    ["OUT.json", "OUT.obj", file_name.as_str()],
                    "{what}: succeeded"
                );
            } else {
                failed += 1;
                // Warnings may come first (tags ignored, ...); the error is one line.
                let (errors, others): (Vec<&str>, Vec<&str>) =
                    stderr.lines().partition(|l| l.starts_with("error"));
                let error = errors.first().copied().unwrap_or_default();
                assert!(
                    errors.len() == 1
                        && names_file(error, &file)
                        && others
                            .iter()
                            .all(|l| l.starts_with("warning: ") || l.starts_with("note: ")),
                    "{what}: exit {code:?}, not one error line naming the file: {stderr}"
                );
                assert_eq!(names, [file_name.as_str()], "{what}: {error}: left files");
            }
        }
    }
    eprintln!("{succeeded} mutants tessellated, {failed} refused");
    // The mutants exercise both ends: some still tessellate, most are refused.
    assert!(
        succeeded > 0 && failed > 0,
        "{succeeded} succeeded, {failed} failed"
    );
    let _ = std::fs::remove_dir_all(&root);
}
