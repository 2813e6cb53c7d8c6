// pvrr, 2nd pass: draws a mirror or lens over the scene raster with per-vertex texture coordinates
// into the reflection map (1st pass), so each vertex shows exactly its ray-traced hit point.
// Prepended: optics.wgsl, camera.wgsl.

struct MirrorMaterial {
    f0: vec3<f32>,
    fresnel: u32,
    // 1: stripe the pixels of unresolved vertices magenta (the markers overlay).
    stripes: u32,
    // 1: blend in the unresolved vertices' ray-traced radiance (not zooming=map); 0: they show
    // the map where their texture coordinates put them, as the paper's algorithm does.
    blend_traced: u32,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var reflection_map: texture_2d<f32>;
@group(0) @binding(2) var<uniform> mirror: MirrorMaterial;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) weight: f32,
    @location(4) unresolved: f32,
    @location(5) traced: vec3<f32>,
};

struct VertexOut {
    // The same expression as the scene raster's, invariant, so LessEqual against its depth
    // passes exactly on the mirror's own pixels.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) weight: f32,
    @location(4) unresolved: f32,
    @location(5) traced: vec3<f32>,
};

@vertex
fn vs_mirror(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = camera.clip_from_world * vec4<f32>(v.position, 1.0);
    out.position = v.position;
    out.normal = v.normal;
    out.uv = v.uv;
    out.weight = v.weight;
    out.unresolved = v.unresolved;
    out.traced = v.traced;
    return out;
}

fn map_texel(x: i32, y: i32, size: vec2<i32>) -> vec3<f32> {
    return textureLoad(reflection_map, clamp(vec2<i32>(x, y), vec2<i32>(0), size - 1), 0).xyz;
}

// Bilinear lookup, clamped at the map's edges.
fn sample_map(uv: vec2<f32>) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(reflection_map));
    let p = uv * vec2<f32>(size) - 0.5;
    let p0 = floor(p);
    let f = p - p0;
    let i = vec2<i32>(p0);
    let top = mix(map_texel(i.x, i.y, size), map_texel(i.x + 1, i.y, size), f.x);
    let bottom = mix(map_texel(i.x, i.y + 1, size), map_texel(i.x + 1, i.y + 1, size), f.x);
    return mix(top, bottom, f.y);
}

@fragment
fn fs_mirror(in: VertexOut) -> @location(0) vec4<f32> {
    let d = normalize(in.position - camera.eye_world);
    var n = normalize(in.normal);
    if (dot(n, d) > 0.0) {
        n = -n;
    }
    var f = mirror.f0;
    if (mirror.fresnel != 0u) {
        f = fresnel_schlick(mirror.f0, -dot(d, n));
    }
    // Where a vertex's hit is one the map cannot show (zooming region), its ray-traced
    // radiance is blended in (not zooming=map), by the interpolated share of such vertices; the
    // markers overlay stripes those pixels magenta.
    if (in.unresolved > 0.0 && mirror.stripes != 0u) {
        let stripe = (i32(floor((in.clip.x + in.clip.y) / 6.0)) & 1) == 0;
        if (stripe) {
            return vec4<f32>(1.0, 0.0, 1.0, 1.0);
        }
    }
    var traced_share = 0.0;
    if (mirror.blend_traced != 0u) {
        traced_share = clamp(in.unresolved, 0.0, 1.0);
    }
    let seen = mix(sample_map(in.uv), in.traced, traced_share);
    return vec4<f32>(in.weight * f * seen, 1.0);
}
