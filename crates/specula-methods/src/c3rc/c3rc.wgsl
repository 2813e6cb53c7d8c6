// c3rc: envmap's shading (shade.wgsl), with each mirror pixel's reflection of the nearby
// objects (splatted by the C3RCs on the CPU) in place of the cube-map lookup where it found
// something; the far field stays the cube maps', drawn without the nearby objects.

@group(0) @binding(9) var near_reflection: texture_2d<f32>;

@fragment
fn fs_shade(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.clip.xy);
    return shade(pixel, textureLoad(near_reflection, pixel, 0));
}
