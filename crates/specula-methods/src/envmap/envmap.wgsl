// envmap: every specular pixel shaded from the cube maps alone (shade.wgsl).

@fragment
fn fs_shade(in: FullscreenOut) -> @location(0) vec4<f32> {
    return shade(vec2<i32>(in.clip.xy), vec4<f32>(0.0));
}
