// Bicubic Bézier evaluation. Twin of `tessera_core::bezier::patch`.
// Reads `nets: texture_storage_2d<rgba32float, read>` (declared by the kernel; a
// read-only storage texture for the reason given in `map.wgsl`): per patch 12 texels, the 48 words of `GpuPatch::cp` in order (`tessera_core::gpu_types::NetTexture`).

struct Frame {
    pos: vec3f,
    du: vec3f,
    dv: vec3f,
    duv: vec3f,
}

struct Basis {
    b: vec4f,
    d: vec4f,
}

fn bernstein(t: f32) -> Basis {
    let s = 1.0 - t;
    let b = vec4f(s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t);
    let d = vec4f(
        -3.0 * s * s,
        3.0 * s * s - 6.0 * t * s,
        6.0 * t * s - 3.0 * t * t,
        3.0 * t * t,
    );
    return Basis(b, d);
}

fn net_texel(p: u32, k: u32) -> vec4f {
    let at = vec2u((p % NET_TEXTURE_PATCHES_PER_ROW) * 12u + k, p / NET_TEXTURE_PATCHES_PER_ROW);
    return textureLoad(nets, at);
}

// Row `row` of the net weighted by the basis `bu`: its four points, `x y z` each, are
// texels 3·row .. 3·row + 2. Written out, without arrays (an array indexed by a loop
// counter is a memory access per lane on a CPU device).
struct RowSums {
    q: vec3f,
    qu: vec3f,
}

fn row_sums(p: u32, row: u32, bu: Basis) -> RowSums {
    let x = net_texel(p, 3u * row);
    let y = net_texel(p, 3u * row + 1u);
    let z = net_texel(p, 3u * row + 2u);
    let c0 = x.xyz;
    let c1 = vec3f(x.w, y.xy);
    let c2 = vec3f(y.zw, z.x);
    let c3 = z.yzw;
    let q = c0 * bu.b.x + c1 * bu.b.y + c2 * bu.b.z + c3 * bu.b.w;
    let qu = c0 * bu.d.x + c1 * bu.d.y + c2 * bu.d.z + c3 * bu.d.w;
    return RowSums(q, qu);
}

fn eval_frame(p: u32, u: f32, v: f32) -> Frame {
    let bu = bernstein(u);
    let bv = bernstein(v);
    let r0 = row_sums(p, 0u, bu);
    let r1 = row_sums(p, 1u, bu);
    let r2 = row_sums(p, 2u, bu);
    let r3 = row_sums(p, 3u, bu);
    return Frame(
        r0.q * bv.b.x + r1.q * bv.b.y + r2.q * bv.b.z + r3.q * bv.b.w,
        r0.qu * bv.b.x + r1.qu * bv.b.y + r2.qu * bv.b.z + r3.qu * bv.b.w,
        r0.q * bv.d.x + r1.q * bv.d.y + r2.q * bv.d.z + r3.q * bv.d.w,
        r0.qu * bv.d.x + r1.qu * bv.d.y + r2.qu * bv.d.z + r3.qu * bv.d.w,
    );
}

// Unit normal; where a side collapses to a point (du or dv vanishes) the limit normal
// from the mixed derivative, never NaN.
fn frame_normal(f: Frame, u: f32, v: f32) -> vec3f {
    let scale = length(f.du) + length(f.dv) + length(f.duv);
    let tiny = scale * 1e-5;
    var du = f.du;
    var dv = f.dv;
    if length(du) <= tiny {
        du = select(-f.duv, f.duv, v < 0.5);
    }
    if length(dv) <= tiny {
        dv = select(-f.duv, f.duv, u < 0.5);
    }
    let n = cross(du, dv);
    let len = length(n);
    if len > 0.0 && len < 3.4e38 {
        return n / len;
    }
    return vec3f(0.0, 0.0, 1.0);
}
