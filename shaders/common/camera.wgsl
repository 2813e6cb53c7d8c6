// The camera as every technique receives it (host struct: specula_gpu::shaders::CameraUniform).
// Directions and positions are in world space; pixel (0, 0) is the top-left pixel.

struct Camera {
    clip_from_world: mat4x4<f32>,
    eye_world: vec3<f32>,
    tan_half_fov_y: f32,
    right_world: vec3<f32>,
    aspect: f32,
    up_world: vec3<f32>,
    width: f32,
    forward_world: vec3<f32>,
    height: f32,
};

// Unit world-space direction of the ray through image point `pixel` (in pixels from the
// top-left corner), the same ray as the CPU reference's `Camera::ray_direction`.
fn camera_ray_direction(camera: Camera, pixel: vec2<f32>) -> vec3<f32> {
    let ndc_x = (2.0 * pixel.x / camera.width - 1.0) * camera.tan_half_fov_y * camera.aspect;
    let ndc_y = (1.0 - 2.0 * pixel.y / camera.height) * camera.tan_half_fov_y;
    return normalize(camera.forward_world + ndc_x * camera.right_world + ndc_y * camera.up_world);
}

// Clip position of vertex `i` (0, 1, 2) of one triangle that covers the whole screen, at the
// far plane.
fn fullscreen_triangle(i: u32) -> vec4<f32> {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    return vec4<f32>(xy, 1.0, 1.0);
}

// The vertex stage of full-screen passes (draw 3 vertices): `clip.xy` in the fragment stage is
// the pixel centre.
struct FullscreenOut {
    @builtin(position) clip: vec4<f32>,
};

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> FullscreenOut {
    var out: FullscreenOut;
    out.clip = fullscreen_triangle(i);
    return out;
}
