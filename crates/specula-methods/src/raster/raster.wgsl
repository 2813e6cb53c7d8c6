// The scene raster pass: the background, then every surface with depth. Non-specular surfaces
// are shaded (unlit; Lambert with the scene's lights, distance shadow maps and ambient);
// specular ones are left black for the technique to fill. Writes the G-buffer techniques reuse:
// world position (w = 1 on geometry), shading normal facing the eye, and mesh + triangle IDs.
// Prepended: camera.wgsl, scene.wgsl, cubemap.wgsl.

struct ShadowView {
    clip_from_world: mat4x4<f32>,
    origin: vec3<f32>,
    directional: u32,
    direction: vec3<f32>,
    // World size of one shadow-map texel at unit distance (point) or anywhere (directional).
    texel_size: f32,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(2) @binding(0) var<storage, read> shadow_views: array<ShadowView>;
@group(2) @binding(1) var shadow_maps: texture_2d_array<f32>;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) mesh: u32,
    @location(2) normal: vec3<f32>,
    @location(3) triangle: u32,
    @location(4) uv: vec2<f32>,
};

struct VertexOut {
    // Invariant: passes that redraw a surface over this depth (with LessEqual) must get
    // bit-identical depths.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) mesh: u32,
    @location(4) @interpolate(flat) triangle: u32,
};

struct GBuffer {
    @location(0) color: vec4<f32>,
    @location(1) position: vec4<f32>,
    @location(2) normal: vec4<f32>,
    @location(3) ids: vec2<u32>,
};

@vertex
fn vs_scene(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = camera.clip_from_world * vec4<f32>(v.position, 1.0);
    out.position = v.position;
    out.normal = v.normal;
    out.uv = v.uv;
    out.mesh = v.mesh;
    out.triangle = v.triangle;
    return out;
}

// The shadow metric of a point for a view: distance along the light direction (directional)
// or distance from the light (point, spot).
fn shadow_metric(view: ShadowView, p: vec3<f32>) -> f32 {
    if (view.directional == 1u) {
        return dot(p - view.origin, view.direction);
    }
    return distance(p, view.origin);
}

// 1 when the light reaches `p` (with shading normal `n`), 0 when something is in the way.
fn light_visibility(light: Light, p: vec3<f32>, n: vec3<f32>) -> f32 {
    var layer = light.shadow_layer;
    if (light.kind != LIGHT_DIRECTIONAL) {
        layer += cube_face(p - light.position);
    }
    let view = shadow_views[layer];
    let size = textureDimensions(shadow_maps);
    var texel_world = view.texel_size;
    if (view.directional == 0u) {
        texel_world *= distance(p, view.origin);
    }
    // Normal offset and a constant bias of a few texels keep surfaces from shadowing themselves.
    let to_light = light_sample(light, p).to_light;
    let n_light = select(-n, n, dot(n, to_light) >= 0.0);
    let p_offset = p + n_light * texel_world * 1.5;
    let uv = face_uv(view.clip_from_world, p_offset);
    if (any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0))) {
        return 1.0;
    }
    let texel_coord = vec2<i32>(uv * vec2<f32>(size));
    let stored = textureLoad(shadow_maps, texel_coord, i32(layer), 0).x;
    return select(0.0, 1.0, shadow_metric(view, p_offset) - 2.0 * texel_world <= stored);
}

@fragment
fn fs_scene(in: VertexOut, @builtin(front_facing) front: bool) -> GBuffer {
    let material = materials[mesh_materials[in.mesh]];
    var n = normalize(in.normal);
    // Face the eye, as the CPU flips normals to face the incoming ray.
    if (dot(n, camera.eye_world - in.position) < 0.0) {
        n = -n;
    }
    var color = vec3<f32>(0.0);
    if (material.kind == MATERIAL_UNLIT) {
        color = material_base(material, in.uv);
    } else if (material.kind == MATERIAL_DIFFUSE) {
        var irradiance = vec3<f32>(0.0);
        for (var i = 0u; i < scene_info.light_count; i++) {
            let s = light_sample(lights[i], in.position);
            let cos_theta = dot(n, s.to_light);
            if (cos_theta > 0.0) {
                irradiance += s.irradiance * cos_theta * light_visibility(lights[i], in.position, n);
            }
        }
        color = material_base(material, in.uv) * (irradiance / PI + scene_info.ambient);
    }
    var out: GBuffer;
    out.color = vec4<f32>(color, 1.0);
    out.position = vec4<f32>(in.position, 1.0);
    out.normal = vec4<f32>(n, 0.0);
    out.ids = vec2<u32>(in.mesh + 1u, in.triangle);
    return out;
}

struct BackgroundOut {
    @builtin(position) clip: vec4<f32>,
};

@vertex
fn vs_background(@builtin(vertex_index) i: u32) -> BackgroundOut {
    var out: BackgroundOut;
    out.clip = fullscreen_triangle(i);
    return out;
}

@fragment
fn fs_background(in: BackgroundOut) -> GBuffer {
    var out: GBuffer;
    out.color = vec4<f32>(background_radiance(camera_ray_direction(camera, in.clip.xy)), 1.0);
    out.position = vec4<f32>(0.0);
    out.normal = vec4<f32>(0.0);
    out.ids = vec2<u32>(0u, 0u);
    return out;
}

// Shadow-map pass: the metric of each surface point, nearest kept by the depth test.
struct ShadowOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) position: vec3<f32>,
};

@group(0) @binding(1) var<uniform> shadow_view: ShadowView;

@vertex
fn vs_shadow(v: VertexIn) -> ShadowOut {
    var out: ShadowOut;
    out.clip = shadow_view.clip_from_world * vec4<f32>(v.position, 1.0);
    out.position = v.position;
    return out;
}

@fragment
fn fs_shadow(in: ShadowOut) -> @location(0) vec4<f32> {
    return vec4<f32>(shadow_metric(shadow_view, in.position), 0.0, 0.0, 0.0);
}
