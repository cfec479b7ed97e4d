// Bicubic Bézier evaluation. Twin of `tessera_core::bezier::patch`.
// Reads `patches: array<GpuPatch>` (declared by the kernel).

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

fn control_point(p: u32, k: u32) -> vec3f {
    return vec3f(patches[p].cp[3u * k], patches[p].cp[3u * k + 1u], patches[p].cp[3u * k + 2u]);
}

fn eval_frame(p: u32, u: f32, v: f32) -> Frame {
    let bu = bernstein(u);
    let bv = bernstein(v);
    var f = Frame(vec3f(0.0), vec3f(0.0), vec3f(0.0), vec3f(0.0));
    for (var row = 0u; row < 4u; row++) {
        var q = vec3f(0.0);
        var qu = vec3f(0.0);
        for (var col = 0u; col < 4u; col++) {
            let c = control_point(p, 4u * row + col);
            q += c * bu.b[col];
            qu += c * bu.d[col];
        }
        f.pos += q * bv.b[row];
        f.du += qu * bv.b[row];
        f.dv += q * bv.d[row];
        f.duv += qu * bv.d[row];
    }
    return f;
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
