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
