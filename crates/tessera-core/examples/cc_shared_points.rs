//! What choosing each patch's first split by the points it adds (rather than by its
//! leaves) would save: the adaptive tessellation's triangles are `2V − 2χ` whatever the
//! triangulation (V the vertex count), so only the marked points count. Every first
//! split of [`first_splits`] is marked for every patch (the same trees as the CPU
//! reference: `flatness_bound` on the same grid), then each patch in turn takes the
//! trial that adds the fewest points not already marked by the others, until nothing
//! changes (coordinate descent from the reference's choice, fewest leaves).
//!
//! `cargo run --release -p tessera-core --example cc_shared_points -- assets/catmull_clark/spot_control_mesh.obj 3e-3`
//!
//! Arguments: the mesh and a tolerance relative to the control mesh's diagonal.
use std::collections::HashMap;
use std::path::Path;
use tessera_core::catmull_clark::adaptive::{first_splits, flatness_bound, CcParams, FirstSplit};
use tessera_core::catmull_clark::keys::point_key;
use tessera_core::catmull_clark::{PatchMesh, SurfaceModel, MAX_DEPTH, TREE_DEPTH};
use tessera_core::io::load_control_mesh;

/// Marks cell `[i, i + w] × [j, j + h]` (in units of `1 / grid`) of patch `p` as the
/// reference does; pushes the leaves.
fn mark(
    model: &SurfaceModel,
    p: usize,
    c: [u32; 4],
    left: u32,
    params: &CcParams,
    out: &mut Vec<[u32; 4]>,
) {
    let [i, j, w, h] = c;
    let t = |x: u32| x as f64 / params.grid() as f64;
    let bound = flatness_bound(model, p, [t(i), t(i + w), t(j), t(j + h)]);
    if bound <= params.tolerance || left == 0 {
        out.push(c);
        return;
    }
    let (w, h) = (w / 2, h / 2);
    for (di, dj) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
        mark(
            model,
            p,
            [i + di * w, j + dj * h, w, h],
            left - 1,
            params,
            out,
        );
    }
}

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
    };
    let grid = params.grid();
    let splits: Vec<(u32, u32)> = first_splits().collect();
    // Per patch, per trial: (leaf count, sorted keys of the leaves' corners).
    let mut trials: Vec<Vec<(usize, Vec<u64>)>> = Vec::new();
    for p in model.mesh.surface_patches() {
        let per = splits
            .iter()
            .map(|&(ku, kv)| {
                let (w, h) = (grid / ku, grid / kv);
                let mut leaves = Vec::new();
                for c in 0..ku * kv {
                    let cell = [(c % ku) * w, (c / ku) * h, w, h];
                    mark(&model, p, cell, MAX_DEPTH, &params, &mut leaves);
                }
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
