// Lit rendering of a tessellation stage's output (`render::MeshRenderer`).
//
// Vertex layout: `MeshBuffers::VERTEX_LAYOUT` (position, normal, the face's uv, face id).
// Entry points: `vs_main` + `fs_shaded` for the surface, `vs_wire` + `fs_wire` for the
// wireframe overlay, which the renderer draws with a `PolygonMode::Line` pipeline over
// the same indexed triangles. Colours are computed in linear space; `flags.y` asks for
// the sRGB encoding when the target format does not do it.
//
// Self-contained on purpose: no `#include`.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // xyz: eye position; w: fraction of the eye distance wire vertices move toward the eye.
    eye: vec4<f32>,
    // xyz: direction toward the key light (world); w: its intensity.
    key: vec4<f32>,
    // xyz: direction toward the fill light (world); w: its intensity.
    fill: vec4<f32>,
    // xyz: world up (hemispheric ambient); w: ambient intensity.
    up: vec4<f32>,
    // rgb: linear base colour; a: specular strength (0 = none).
    base: vec4<f32>,
    // rgb: linear colour of back faces; a: unused.
    back: vec4<f32>,
    // rgba: linear wire colour and its opacity.
    wire: vec4<f32>,
    // x: tint by face id; y: encode sRGB in the shader.
    flags: vec4<u32>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) face: u32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) face: u32,
};

// `v` drawn at `at` (its own position, or one moved toward the eye).
fn vertex_at(v: VertexIn, at: vec3<f32>) -> VertexOut {
    var o: VertexOut;
    o.clip = u.view_proj * vec4<f32>(at, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.uv = v.uv;
    o.face = v.face;
    return o;
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    return vertex_at(v, v.position);
}

// The wireframe's vertices move toward the eye by a small fraction of their distance, so
// the lines win the depth test against the surface they lie on at any scale, while
// surfaces clearly in front still hide them.
@vertex
fn vs_wire(v: VertexIn) -> VertexOut {
    return vertex_at(v, mix(v.position, u.eye.xyz, u.eye.w));
}

fn hash_u32(x0: u32) -> u32 {
    var x = x0;
    x = x ^ (x >> 16u);
    x = x * 0x7feb352du;
    x = x ^ (x >> 15u);
    x = x * 0x846ca68bu;
    x = x ^ (x >> 16u);
    return x;
}

// A soft, fully saturated hue for face `id` (golden-ratio steps around the hue circle).
fn face_hue(id: u32) -> vec3<f32> {
    let h = fract(f32(id) * 0.618034 + f32(hash_u32(id) & 255u) / 2048.0);
    let k = vec3<f32>(0.0, 2.0 / 3.0, 1.0 / 3.0);
    return clamp(abs(fract(h + k) * 6.0 - 3.0) - 1.0, vec3<f32>(0.0), vec3<f32>(1.0));
}

fn encode_srgb(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

fn finish(c: vec3<f32>, a: f32) -> vec4<f32> {
    var rgb = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    if u.flags.y != 0u {
        rgb = encode_srgb(rgb);
    }
    return vec4<f32>(rgb, a);
}

@fragment
fn fs_shaded(i: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let view = normalize(u.eye.xyz - i.world);
    var n = i.normal;
    let len = length(n);
    // Degenerate normals (collapsed patch corners) face the viewer.
    n = select(view, n / len, len > 1e-20);
    // Two-sided: the side facing the viewer is lit (open models show their insides).
    n = select(-n, n, dot(n, view) >= 0.0);

    // The side the normals point away from (counter-clockwise triangles face their
    // normals) has its own colour, so holes and flipped patches show.
    var albedo = select(u.back.rgb, u.base.rgb, front);
    if u.flags.x != 0u {
        albedo = mix(albedo, face_hue(i.face) * 0.8 + 0.1, 0.35);
    }
    let key_l = normalize(u.key.xyz);
    let fill_l = normalize(u.fill.xyz);
    let diffuse = u.key.w * max(dot(n, key_l), 0.0) + u.fill.w * max(dot(n, fill_l), 0.0);
    // Hemispheric ambient: a little more from above than from below.
    let ambient = u.up.w * mix(0.55, 1.0, 0.5 + 0.5 * dot(n, normalize(u.up.xyz)));
    let h = normalize(key_l + view);
    let spec = u.base.a * u.key.w * pow(max(dot(n, h), 0.0), 48.0) * step(0.0, dot(n, key_l));
    return finish(albedo * (diffuse + ambient) + vec3<f32>(spec), 1.0);
}

@fragment
fn fs_wire(i: VertexOut) -> @location(0) vec4<f32> {
    return finish(u.wire.rgb, u.wire.a);
}
