//! The embedding example, run as a test: its own device, both stages and its own render
//! pass in one encoder, moving control points; the last frame against a snapshot, and the
//! comparison shown to fail on a frame where the points are elsewhere.

#[path = "../examples/embed.rs"]
#[allow(dead_code)]
mod embed;

use std::path::{Path, PathBuf};

use tessera_wgpu::image_out::load_png;
use tessera_wgpu::snapshot::{self, check_snapshot, compare, Tolerance};

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

#[test]
fn the_embedding_example_draws_its_snapshot_and_not_another_frame() {
    let last = embed::run(&assets(), embed::FRAMES).expect("the example runs cleanly");
    assert_eq!(last.dimensions(), embed::SIZE);
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots/embed.png");
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("snapshots");
    let c = check_snapshot(
        "embed",
        &last,
        &reference,
        &out,
        &Tolerance::DEFAULT,
        snapshot::bless_requested(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("embed: {}", c.summary());
    // The first frame has the torus's control points elsewhere: the same comparison
    // must tell it from the last.
    let first = embed::run(&assets(), 1).expect("one frame");
    let expected = load_png(&reference).expect("the snapshot");
    let other = compare(&expected, &first, &Tolerance::DEFAULT);
    assert!(
        !other.passed(),
        "a different frame passed: {}",
        other.summary()
    );
}

/// Whether every line of `snippet` (trimmed; blank lines and `// …` remarks aside)
/// appears in `source`, in order: the README's snippet compiles because the example does.
fn is_excerpt(snippet: &str, source: &str) -> Result<(), String> {
    let mut lines = source.lines().map(str::trim);
    for want in snippet.lines().map(str::trim) {
        if want.is_empty() || want.starts_with("// …") {
            continue;
        }
        if !lines.any(|have| have == want) {
            return Err(format!("not in the example (in this order): {want}"));
        }
    }
    Ok(())
}

#[test]
fn the_readme_snippet_is_taken_from_the_example() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("../../README.md")).expect("README");
    let example = std::fs::read_to_string(root.join("examples/embed.rs")).expect("example");
    let start = readme
        .find("<!-- embed-example")
        .expect("the snippet's marker");
    let block = &readme[start..];
    let open = block
        .find("```rust\n")
        .expect("a rust block after the marker")
        + 8;
    let snippet = &block[open..open + block[open..].find("```").expect("closed")];
    assert!(snippet.lines().count() > 10, "{snippet}");
    is_excerpt(snippet, &example).unwrap_or_else(|e| panic!("README: {e}"));
    // The check fails on a line the example does not have, and on lines out of order.
    assert!(is_excerpt("cc.prepare(&device, &mut encoder)?;", &example).is_err());
    let swapped =
        "cc.prepare(&device, &queue, &mut encoder)?;\nlet kernels = Kernels::new(&device);";
    assert!(is_excerpt(swapped, &example).is_err());
}
