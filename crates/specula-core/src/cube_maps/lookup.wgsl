// Per-reflector environment cube maps (envmap's `CubeMaps`): six faces per reflector in one 2D
// array, each drawn from the reflector's centre with its own view (see cubemap.wgsl).
// The including shader declares, at the bindings `CubeMaps::layout_entries` gives:
//   var env_faces: texture_2d_array<f32>;
//   var<storage, read> env_views: array<EnvView>;
//   var<storage, read> reflectors: array<Reflector>;
//   var<storage, read> mesh_reflector: array<i32>;   // each mesh's reflector index, or -1
// Prepended before it: cubemap.wgsl.

struct EnvView {
    clip_from_world: mat4x4<f32>,
};

struct Reflector {
    center: vec3<f32>,
    radius: f32,
    first_layer: u32,
    // How rays leave a solid refractor: 0 = they do not (one interface), 1 = through the
    // bounding sphere, 2 = through a face parallel to the entry face (a thin slab).
    exit_model: u32,
    pad0: u32,
    pad1: u32,
};

fn env_texel(layer: u32, x: i32, y: i32, size: i32) -> vec3<f32> {
    return textureLoad(env_faces, vec2<i32>(clamp(x, 0, size - 1), clamp(y, 0, size - 1)), i32(layer), 0).xyz;
}

// Radiance the cube map of `r` holds in direction `d` (as seen from the reflector's centre).
fn env_lookup(r: Reflector, d: vec3<f32>) -> vec3<f32> {
    let layer = r.first_layer + cube_face(d);
    let uv = face_uv(env_views[layer].clip_from_world, r.center + d);
    let size = i32(textureDimensions(env_faces).x);
    let x = uv.x * f32(size) - 0.5;
    let y = uv.y * f32(size) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xi = i32(x0);
    let yi = i32(y0);
    let top = mix(env_texel(layer, xi, yi, size), env_texel(layer, xi + 1, yi, size), fx);
    let bottom = mix(env_texel(layer, xi, yi + 1, size), env_texel(layer, xi + 1, yi + 1, size), fx);
    return mix(top, bottom, fy);
}
