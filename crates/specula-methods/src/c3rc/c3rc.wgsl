// c3rc: envmap's shading (shade.wgsl), with each mirror pixel's reflection of the nearby
// objects (splatted by the C3RCs on the CPU) in place of the cube-map lookup where it found
// something; the far field stays the cube maps', drawn without the nearby objects.

// One vec4 per pixel, row by row: radiance along the reflected ray, alpha 1 where found.
@group(0) @binding(9) var<storage, read> near_reflection: array<vec4<f32>>;

@fragment
fn fs_shade(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.clip.xy);
    let width = textureDimensions(g_color).x;
    return shade(pixel, near_reflection[u32(pixel.y) * width + u32(pixel.x)]);
}
