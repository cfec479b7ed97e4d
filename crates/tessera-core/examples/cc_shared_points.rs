//! What choosing each patch's first split by the points it adds (rather than by its
//! leaves) would save: the adaptive tessellation's triangles are `2V − 2χ` whatever the
//! triangulation (V the vertex count), so only the marked points count. Every first
//! split of [`first_splits`] is marked for every patch (`split_leaves`: the CPU
//! reference's own marking), then each patch in turn takes the trial that adds the
//! fewest points not already marked by the others, until nothing changes (coordinate
//! descent from the reference's choice, fewest leaves).
//!
//! `cargo run --release -p tessera-core --example cc_shared_points -- assets/catmull_clark/spot_control_mesh.obj 3e-3`
//!
//! Arguments: the mesh and a tolerance relative to the control mesh's diagonal.
use std::collections::HashMap;
use std::path::Path;
use tessera_core::catmull_clark::adaptive::{first_splits, split_leaves, CcParams, FirstSplit};
use tessera_core::catmull_clark::keys::point_key;
use tessera_core::catmull_clark::{PatchMesh, SurfaceModel, MAX_DEPTH, TREE_DEPTH};
use tessera_core::io::load_control_mesh;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("a mesh");
    let rel: f64 = args
        .next()
        .expect("a relative tolerance")
        .parse()
        .expect("a number");
    let control = load_control_mesh(Path::new(&path)).expect("a valid mesh");
    let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid"), TREE_DEPTH);
    let params = CcParams {
        tolerance: rel * control.bbox_diag(),
        max_depth: MAX_DEPTH,
        first_split: FirstSplit::Search,
        leaf_bound: Default::default(),
    };
    let grid = params.grid();
    let splits: Vec<(u32, u32)> = first_splits().collect();
    // Per patch, per trial: (leaf count, sorted keys of the leaves' corners).
    let mut trials: Vec<Vec<(usize, Vec<u64>)>> = Vec::new();
    for p in model.mesh.surface_patches() {
        let per = splits
            .iter()
            .map(|&split| {
                let leaves = split_leaves(&model, &params, p, split);
                let mut keys: Vec<u64> = leaves
                    .iter()
                    .flat_map(|&[i, j, w, h]| [(i, j), (i + w, j), (i + w, j + h), (i, j + h)])
                    .map(|(a, b)| point_key(&model.mesh, p, a, b, grid))
                    .collect();
                keys.sort_unstable();
                keys.dedup();
                (leaves.len(), keys)
            })
            .collect();
        trials.push(per);
    }
    // The reference's choice: fewest leaves, ties to the earlier trial.
    let mut pick: Vec<usize> = trials
        .iter()
        .map(|t| (0..t.len()).min_by_key(|&k| (t[k].0, k)).unwrap())
        .collect();
    let mut uses: HashMap<u64, u32> = HashMap::new();
    for (t, &k) in trials.iter().zip(&pick) {
        for &key in &t[k].1 {
            *uses.entry(key).or_default() += 1;
        }
    }
    println!("fewest leaves: {} vertices", uses.len());
    for round in 1.. {
        let mut changed = 0;
        for (p, t) in trials.iter().enumerate() {
            for key in &t[pick[p]].1 {
                let n = uses.get_mut(key).unwrap();
                *n -= 1;
                if *n == 0 {
                    uses.remove(key);
                }
            }
            let added = |k: usize| t[k].1.iter().filter(|key| !uses.contains_key(key)).count();
            let best = (0..t.len()).min_by_key(|&k| (added(k), k)).unwrap();
            if added(best) < added(pick[p]) {
                pick[p] = best;
                changed += 1;
            }
            for &key in &t[pick[p]].1 {
                *uses.entry(key).or_default() += 1;
            }
        }
        println!(
            "round {round}: {} vertices ({changed} patches changed)",
            uses.len()
        );
        if changed == 0 {
            break;
        }
    }
}
