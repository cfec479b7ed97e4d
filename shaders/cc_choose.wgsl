// After a search round: each patch keeps the split with the fewest leaves among those it
// had so far and those of this round (ties to the earlier trial, as the CPU reference
// trying them in order). After the last round the best is final: its largest leaf bound
// and its leaves over the tolerance go into the run's totals. `next_round` then
// advances the round.
// Twin: the trial loop of `tessera_core::catmull_clark::adaptive::tessellate_with_splits`.

#include "shared/cc_tess.wgsl"

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let p = cc_invocation(gid, groups);
    if p >= cc_params.patch_count || cc_state.round >= cc_params.search_rounds {
        return;
    }
    let tried = round_trials(p);
    var b = best_before(p);
    for (var t = 0u; t < CC_TRIALS; t++) {
        if cc_has_trial(tried, t) {
            // ku·kv + 3 · splits: exact for a trial run to the end, and for one dropped
            // a number that cannot win (see cc_split.wgsl).
            let s = cc_trial_split(t);
            let leaves = s.x * s.y + 3u * atomicLoad(&cc_state.trials[cc_trial_slot(0u, p, t)]);
            if leaves < b.x || (leaves == b.x && t < b.y) {
                b = vec2u(leaves, t);
            }
        }
    }
    best[p] = b;
    // Patches without a surface (holes) have no trial.
    if cc_state.round + 1u == cc_params.search_rounds && b.y < CC_TRIALS {
        atomicMax(&cc_state.max_bound_bits, atomicLoad(&cc_state.trials[cc_trial_slot(1u, p, b.y)]));
        atomicAdd(&cc_state.unmet, atomicLoad(&cc_state.trials[cc_trial_slot(2u, p, b.y)]));
    }
}

@compute @workgroup_size(1)
fn next_round() {
    cc_state.round += 1u;
}
