// distance-maps, step 1: one face of one layer of a layered distance map.
// Prepended: camera.wgsl, scene.wgsl, cubemap.wgsl, lighting.wgsl, codes.wgsl.

// Which surfaces a layer keeps (`LayerView::select`).
const KEEP_ALL: u32 = 0u;
const KEEP_SPECULAR_FACING: u32 = 1u;
const KEEP_SPECULAR_AWAY: u32 = 2u;
const KEEP_NON_SPECULAR: u32 = 3u;

struct LayerView {
    clip_from_world: mat4x4<f32>,
    // The reference point, world space.
    origin: vec3<f32>,
    select: u32,
    // 1 when this layer is peeled: only surfaces beyond the previous layer's distance count.
    peel: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

@group(0) @binding(0) var<uniform> view: LayerView;
// The previous layer's geometry for this face (one array layer), read when peeling.
@group(0) @binding(1) var previous_geometry: texture_2d_array<f32>;

struct LayerVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) mesh: u32,
};

struct LayerTexel {
    @location(0) material: vec4<f32>,
    @location(1) geometry: vec4<f32>,
};

@vertex
fn vs_layer(v: SceneVertex) -> LayerVertex {
    var out: LayerVertex;
    out.clip = view.clip_from_world * vec4<f32>(v.position, 1.0);
    out.position = v.position;
    out.normal = v.normal;
    out.uv = v.uv;
    out.mesh = v.mesh;
    return out;
}

@fragment
fn fs_layer(in: LayerVertex) -> LayerTexel {
    let material = materials[mesh_materials[in.mesh]];
    let specular = is_specular(material);
    // The stored normal: outward for closed meshes, which is what tells a ray that meets the
    // surface whether it enters or leaves.
    let n = normalize(in.normal);
    let to_origin = view.origin - in.position;
    let facing = dot(n, to_origin) > 0.0;
    switch view.select {
        case KEEP_SPECULAR_FACING: {
            if (!specular || !facing) {
                discard;
            }
        }
        case KEEP_SPECULAR_AWAY: {
            if (!specular || facing) {
                discard;
            }
        }
        case KEEP_NON_SPECULAR: {
            if (specular) {
                discard;
            }
        }
        default: {}
    }
    let distance = length(to_origin);
    if (view.peel == 1u) {
        let previous = textureLoad(previous_geometry, vec2<i32>(in.clip.xy), 0, 0).w;
        // Nothing in front means nothing behind; the margin keeps the previous layer's own
        // surface (same triangle, same texel: the same distance) out.
        if (previous < 0.0 || distance <= previous * (1.0 + 1e-5)) {
            discard;
        }
    }
    var out: LayerTexel;
    if (specular) {
        out.material = specular_code(material);
    } else {
        // Diffuse radiance does not depend on the direction it is seen from; shade with the
        // normal on the reference point's side, as the raster pass does for the eye.
        let n_seen = select(-n, n, facing);
        out.material = vec4<f32>(surface_radiance(material, in.position, n_seen, in.uv), CODE_DIFFUSE);
    }
    out.geometry = vec4<f32>(octahedral_encode(n), f32(in.mesh + 1u), distance);
    return out;
}
