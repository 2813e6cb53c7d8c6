// Vertex tracing's composition on the raster (Ullmann et al. 2001, §3: the refined triangles
// "are rendered with Gouraud shading"). Each leaf face of a refined reflector triangle is drawn
// with its corners' traced colours; a fragment is kept only where the ID buffer shows the face's
// own triangle, so the faces take exactly the pixels the CPU composition gives them. Alpha 1
// marks a pixel composed here; faces the GPU cannot shade as the CPU does (deferred textures, a
// corner behind the eye, no screen area) write alpha 0, and the CPU shades those pixels.

struct ComposeSettings {
    // 1: corners weighted by 1/depth (perspective-correct Gouraud); 0: linear on the screen.
    perspective_correct: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> settings: ComposeSettings;
// (mesh + 1, triangle) of each pixel's first surface: the frame's ID buffer.
@group(0) @binding(2) var id_buffer: texture_2d<u32>;

struct FaceVertex {
    @location(0) p_world: vec3<f32>,
    @location(1) color: vec3<f32>,
    @location(2) triangle_id: vec2<u32>,
    @location(3) cpu_shaded: u32,
};

struct FaceFragment {
    @builtin(position) clip: vec4<f32>,
    @location(0) color_perspective: vec3<f32>,
    @location(1) @interpolate(linear) color_linear: vec3<f32>,
    @location(2) @interpolate(flat) triangle_id: vec2<u32>,
    @location(3) @interpolate(flat) cpu_shaded: u32,
};

@vertex
fn vs_face(v: FaceVertex) -> FaceFragment {
    var out: FaceFragment;
    out.clip = camera.clip_from_world * vec4<f32>(v.p_world, 1.0);
    out.color_perspective = v.color;
    out.color_linear = v.color;
    out.triangle_id = v.triangle_id;
    out.cpu_shaded = v.cpu_shaded;
    return out;
}

@fragment
fn fs_face(f: FaceFragment) -> @location(0) vec4<f32> {
    let owner = textureLoad(id_buffer, vec2<i32>(f.clip.xy), 0).xy;
    if any(owner != f.triangle_id) {
        discard;
    }
    if f.cpu_shaded != 0u {
        return vec4<f32>(0.0);
    }
    let color = select(f.color_linear, f.color_perspective, settings.perspective_correct != 0u);
    return vec4<f32>(color, 1.0);
}
