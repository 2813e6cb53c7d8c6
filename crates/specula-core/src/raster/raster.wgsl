// The scene raster pass: the background, then every surface with depth. Non-specular surfaces
// are shaded (unlit; Lambert with the scene's lights, distance shadow maps and ambient);
// specular ones are left black for the technique to fill. Writes the G-buffer techniques reuse:
// world position (w = 1 on geometry), shading normal facing the eye, and mesh + triangle IDs.
// Prepended: camera.wgsl, scene.wgsl, cubemap.wgsl, lighting.wgsl.

@group(0) @binding(0) var<uniform> camera: Camera;

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
fn vs_scene(v: SceneVertex) -> VertexOut {
    var out: VertexOut;
    out.clip = camera.clip_from_world * vec4<f32>(v.position, 1.0);
    out.position = v.position;
    out.normal = v.normal;
    out.uv = v.uv;
    out.mesh = v.mesh;
    out.triangle = v.triangle;
    return out;
}

// The shading normal facing the side rays come from: the eye's, or with `from_behind` the far
// side (a view looking back along the rays, pvrr's zooming view: rays reach the surface from
// the mirror beyond it), as the CPU flips normals to face the incoming ray.
fn facing_normal(normal: vec3<f32>, position: vec3<f32>, from_behind: bool) -> vec3<f32> {
    let n = normalize(normal);
    let toward_eye = dot(n, camera.eye_world - position) >= 0.0;
    return select(-n, n, toward_eye != from_behind);
}

fn g_buffer(in: VertexOut, from_behind: bool, shaded: bool) -> GBuffer {
    let n = facing_normal(in.normal, in.position, from_behind);
    var color = vec3<f32>(0.0);
    if (shaded) {
        color = surface_radiance(materials[mesh_materials[in.mesh]], in.position, n, in.uv);
    }
    var out: GBuffer;
    out.color = vec4<f32>(color, 1.0);
    out.position = vec4<f32>(in.position, 1.0);
    out.normal = vec4<f32>(n, 0.0);
    out.ids = vec2<u32>(in.mesh + 1u, in.triangle);
    return out;
}

@fragment
fn fs_scene(in: VertexOut) -> GBuffer {
    return g_buffer(in, false, true);
}

// The geometry targets only (RasterSpec targets = Geometry): no lighting, colour black.
@fragment
fn fs_geometry(in: VertexOut) -> GBuffer {
    return g_buffer(in, false, false);
}

// As fs_scene and fs_geometry, lit from the far side (the reversed depth test's pass).
@fragment
fn fs_scene_from_behind(in: VertexOut) -> GBuffer {
    return g_buffer(in, true, true);
}

@fragment
fn fs_geometry_from_behind(in: VertexOut) -> GBuffer {
    return g_buffer(in, true, false);
}

@fragment
fn fs_background(in: FullscreenOut) -> GBuffer {
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
fn vs_shadow(v: SceneVertex) -> ShadowOut {
    var out: ShadowOut;
    out.clip = shadow_view.clip_from_world * vec4<f32>(v.position, 1.0);
    out.position = v.position;
    return out;
}

@fragment
fn fs_shadow(in: ShadowOut) -> @location(0) vec4<f32> {
    return vec4<f32>(shadow_metric(shadow_view, in.position), 0.0, 0.0, 0.0);
}
