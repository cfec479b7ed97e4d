//! How busy the mark kernel's lanes are: each coarse triangle whose root may split walks
//! its bisection tree, one node per loop iteration, and a CPU device runs 8 lanes in
//! step, each vector as long as its longest walk. From the CPU twin's walks at 1024
//! patches (32 teapots), for the bench's thresholds: the share of busy lanes with the
//! triangles in index order (which the root kernel's list follows closely), sorted by
//! their walks (the best any order can do), sorted by the points on their sides (known
//! from the edge decisions before the walk), and split into two classes at a cut.
//! (Running the mark kernel in the side-point order gained nothing on lavapipe: the
//! README's GPU results say why.)
//!
//! ```sh
//! cargo run --release -p tessera-bench --example walk_lanes
//! ```

use glam::Vec3;
use tessera_core::bezier::edge_tests::bit_count;
use tessera_core::bezier::lattice::TreeWalk;
use tessera_core::bezier::refine::splits;
use tessera_core::bezier::tessellate::{edge_decide, root_known_leaf, tri_context};
use tessera_core::bezier::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};

const LANES: usize = 8;

/// Busy lanes over lane steps, the walks taken `LANES` at a time in this order.
fn busy(walks: impl Iterator<Item = u32>) -> f64 {
    let walks: Vec<u32> = walks.collect();
    let work: u64 = walks.iter().map(|&w| w as u64).sum();
    let steps: u64 = walks
        .chunks(LANES)
        .map(|c| LANES as u64 * *c.iter().max().unwrap() as u64)
        .sum();
    work as f64 / steps as f64
}

fn main() {
    let teapot = BezierModel::load(std::path::Path::new("assets/teaset/teapot")).expect("teapot");
    let (lo, hi) = teapot.bounds();
    let diag = (hi - lo).length();
    let prep = PreparedBezier::new(&teapot.grid_of_copies(32, 1.2 * diag));
    let l = prep.layout;
    let cps: Vec<[Vec3; 16]> = (0..l.patches).map(|p| prep.control_points(p)).collect();
    println!("threshold | walking | index order | best order | by side points | two classes");
    for rel in [0.008f32, 0.004, 0.002, 0.001, 0.0005] {
        let params = AdaptiveParams {
            test: EdgeTest::Map4p,
            threshold: rel * diag,
            max_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
        };
        let bits: Vec<_> = (0..l.coarse_edges)
            .map(|e| edge_decide(&prep, &cps, &params, e).0)
            .collect();
        // (nodes walked, points on the sides) per triangle the mark kernel takes.
        let mut walks: Vec<(u32, u32)> = Vec::new();
        for t in 0..l.coarse_triangles {
            let ctx = tri_context(&prep, &cps, &bits, &params, t);
            if root_known_leaf(&ctx) {
                continue;
            }
            let mut w = TreeWalk::new(ctx.lattice.root());
            let mut nodes = 0;
            loop {
                nodes += 1;
                if splits(&ctx, w.t, w.level).0 {
                    w.down();
                } else if !w.advance() {
                    break;
                }
            }
            let side_points = ctx
                .sides
                .iter()
                .map(|&(e, _, _)| bit_count(&ctx.edge_bits[e as usize]))
                .sum();
            walks.push((nodes, side_points));
        }
        let mut best: Vec<u32> = walks.iter().map(|w| w.0).collect();
        best.sort_unstable_by(|a, b| b.cmp(a));
        let mut by_points = walks.clone();
        by_points.sort_by_key(|w| std::cmp::Reverse(w.1));
        let two_classes = (2..=12)
            .step_by(2)
            .map(|cut| {
                let heavy = walks.iter().filter(|w| w.1 >= cut);
                let light = walks.iter().filter(|w| w.1 < cut);
                (busy(heavy.chain(light).map(|w| w.0)), cut)
            })
            .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
        println!(
            "{:.4} | {} of {} | {:.2} | {:.2} | {:.2} | {:.2} (cut at {} points)",
            rel * diag,
            walks.len(),
            l.coarse_triangles,
            busy(walks.iter().map(|w| w.0)),
            busy(best.into_iter()),
            busy(by_points.iter().map(|w| w.0)),
            two_classes.0,
            two_classes.1
        );
    }
}
