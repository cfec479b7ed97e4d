// The root cells of a round of the adaptive Catmull-Clark pipeline, per patch: in search
// round r, the cells of every first split (trial) of that round that could still beat
// or tie the patch's best so far (a split into ku·kv cells has at least ku·kv leaves);
// in the final round, the cells of the best split. `count` writes each patch's number of
// cells, the host scans them, `emit` writes the cells, `finish` starts the level loop.
// Twin: the first splits of `tessera_core::catmull_clark::adaptive::tessellate_with_splits`
// (`base_cells`), grouped into rounds by `gpu_types::cc_trial_round`.

#include "shared/cc_tess.wgsl"

@group(0) @binding(52) var<storage, read_write> cells_out: array<CcCell>;
@group(0) @binding(57) var<storage, read_write> root_offsets: array<u32>;

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let p = cc_invocation(gid, groups);
    if p >= cc_params.patch_count {
        return;
    }
    let tried = round_trials(p);
    var cells = 0u;
    for (var t = 0u; t < CC_TRIALS; t++) {
        if (tried[t / 32u] & (1u << (t % 32u))) != 0u {
            let s = cc_trial_split(t);
            cells += s.x * s.y;
        }
    }
    root_offsets[p] = cells;
}

@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let p = cc_invocation(gid, groups);
    if p >= cc_params.patch_count {
        return;
    }
    let tried = round_trials(p);
    var at = root_offsets[p];
    for (var t = 0u; t < CC_TRIALS; t++) {
        if (tried[t / 32u] & (1u << (t % 32u))) == 0u {
            continue;
        }
        let s = cc_trial_split(t);
        let w = cc_params.grid / s.x;
        let h = cc_params.grid / s.y;
        for (var c = 0u; c < s.x * s.y; c++) {
            if at < cc_params.cell_capacity {
                cells_out[at] = CcCell(p, t, (c % s.x) * w, (c / s.x) * h);
            }
            at += 1u;
        }
    }
}

@compute @workgroup_size(1)
fn finish() {
    let total = root_offsets[cc_params.patch_count];
    atomicMax(&cc_state.need_cells, total);
    if total > cc_params.cell_capacity {
        atomicOr(&cc_state.overflow, 1u);
    }
    cc_state.count = min(total, cc_params.cell_capacity);
    cc_write_args(0u, cc_state.count);
}
