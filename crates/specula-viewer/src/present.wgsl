// Draws the viewer's images onto the window: the left image alone, or the left image left of a
// vertical split and the right image right of it. Images are linear radiance (Rgba32Float, read
// with textureLoad at the nearest texel, so a reduced-resolution frame is upscaled blockwise),
// clamped to [0, 1] like the PNG writer, and sRGB-encoded here when the surface format is not.

struct Params {
    size: vec2<f32>,
    split: f32,
    // 0: left only, 1: split.
    mode: u32,
    encode_srgb: u32,
    // Where the viewport begins on the window (the panel is left of it), pixels.
    offset_x: f32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var left_image: texture_2d<f32>;
@group(0) @binding(1) var right_image: texture_2d<f32>;
@group(0) @binding(2) var<uniform> params: Params;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn texel(image: texture_2d<f32>, uv: vec2<f32>) -> vec3<f32> {
    let dims = vec2<f32>(textureDimensions(image));
    let p = clamp(vec2<i32>(uv * dims), vec2<i32>(0), vec2<i32>(dims) - 1);
    return textureLoad(image, p, 0).rgb;
}

fn srgb(c: vec3<f32>) -> vec3<f32> {
    let low = c * 12.92;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    // The fragment's position is the window's; the images fill the viewport.
    let local = position.xy - vec2<f32>(params.offset_x, 0.0);
    let uv = local / params.size;
    let cut = params.split * params.size.x;
    var color: vec3<f32>;
    if params.mode == 1u && local.x >= cut {
        color = texel(right_image, uv);
    } else {
        color = texel(left_image, uv);
    }
    if params.mode == 1u && abs(local.x - cut) < 1.0 {
        color = vec3<f32>(1.0);
    }
    color = clamp(color, vec3<f32>(0.0), vec3<f32>(1.0));
    if params.encode_srgb == 1u {
        color = srgb(color);
    }
    return vec4<f32>(color, 1.0);
}
