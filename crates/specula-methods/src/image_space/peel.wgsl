// image-space, `layers` > 1: one depth-peeled layer of the solid refractors' surfaces (both
// facings) as seen from the eye: the nearest surface behind the previous layer's.
// Prepended: camera.wgsl, scene.wgsl.

struct Peel {
    // 1: keep only surfaces behind the previous layer's (every layer but the first).
    behind_previous: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

@group(0) @binding(0) var<uniform> camera: Camera;
// The previous layer's position: xyz world, w the view depth (0 where it holds no surface).
@group(0) @binding(1) var previous: texture_2d<f32>;
@group(0) @binding(2) var<uniform> peel: Peel;

struct PeelVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
};

struct PeelTexel {
    // xyz world position, w view depth.
    @location(0) position: vec4<f32>,
    // xyz the stored (outward) normal.
    @location(1) normal: vec4<f32>,
};

@vertex
fn vs_peel(v: SceneVertex) -> PeelVertex {
    var out: PeelVertex;
    out.clip = camera.clip_from_world * vec4<f32>(v.position, 1.0);
    out.position = v.position;
    out.normal = v.normal;
    return out;
}

@fragment
fn fs_peel(in: PeelVertex) -> PeelTexel {
    let z = dot(in.position - camera.eye_world, camera.forward_world);
    if (peel.behind_previous == 1u) {
        let before = textureLoad(previous, vec2<i32>(in.clip.xy), 0).w;
        // Nothing in the previous layer here: nothing lies further either. The margin keeps
        // the previous layer's own surface out (its depth interpolated the same way).
        if (before == 0.0 || z <= before * (1.0 + 1e-5) + 1e-6) {
            discard;
        }
    }
    var out: PeelTexel;
    out.position = vec4<f32>(in.position, z);
    out.normal = vec4<f32>(normalize(in.normal), 0.0);
    return out;
}
