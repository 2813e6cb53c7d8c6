// Every specular pixel shaded from the cube maps alone (shade.wgsl): envmap, and the second
// level of two-level cube maps.

@fragment
fn fs_shade(in: FullscreenOut) -> @location(0) vec4<f32> {
    return shade(vec2<i32>(in.clip.xy), vec4<f32>(0.0));
}
