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

@fragment
fn fs_scene(in: VertexOut, @builtin(front_facing) front: bool) -> GBuffer {
    let material = materials[mesh_materials[in.mesh]];
    var n = normalize(in.normal);
    // Face the eye, as the CPU flips normals to face the incoming ray.
    if (dot(n, camera.eye_world - in.position) < 0.0) {
        n = -n;
    }
    let color = surface_radiance(material, in.position, n, in.uv);
    var out: GBuffer;
    out.color = vec4<f32>(color, 1.0);
    out.position = vec4<f32>(in.position, 1.0);
    out.normal = vec4<f32>(n, 0.0);
    out.ids = vec2<u32>(in.mesh + 1u, in.triangle);
    return out;
}

// The geometry targets only (RasterSpec targets = Geometry): no lighting, colour black.
@fragment
fn fs_geometry(in: VertexOut) -> GBuffer {
    var n = normalize(in.normal);
    if (dot(n, camera.eye_world - in.position) < 0.0) {
        n = -n;
    }
    var out: GBuffer;
    out.color = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    out.position = vec4<f32>(in.position, 1.0);
    out.normal = vec4<f32>(n, 0.0);
    out.ids = vec2<u32>(in.mesh + 1u, in.triangle);
    return out;
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
