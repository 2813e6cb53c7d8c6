// c3rc: envmap's shading (shade.wgsl), with each mirror pixel's reflection of the nearby
// objects (splatted by the C3RCs on the CPU) in place of the cube-map lookup where it found
// something nearer than the far field; the far field stays the cube maps', drawn without the
// nearby objects.

// One vec4 per pixel, row by row: radiance along the reflected ray and, in alpha, where it came
// from: > 0, the distance along the pixel's reflected ray to the nearby surface (depth-tested
// against the far field); < 0, a colour taken as it is (traced, per-vertex, or splatted colour);
// 0, nothing found (the far field shows).
@group(0) @binding(9) var<storage, read> near_reflection: array<vec4<f32>>;
// The far field's world positions, face by face as `env_faces` (w = 0 where nothing was drawn).
@group(0) @binding(10) var far_positions: texture_2d_array<f32>;

// Steps of the search along the reflected ray for a far surface in front of the nearby one.
const FAR_STEPS: u32 = 16u;

// The far-field surface on the segment from `p` to `p + d·t`, if any (a linear search in the
// far field's positions, as distance maps search theirs): the first step at which the ray
// passes behind a far surface seen from the reflector's centre, next to that surface. Its
// colour (the face texel's) with alpha 1; alpha 0: none.
fn far_field_in_front(r: Reflector, p: vec3<f32>, d: vec3<f32>, t: f32) -> vec4<f32> {
    let size = i32(textureDimensions(far_positions).x);
    let step = t / f32(FAR_STEPS);
    for (var i = 1u; i < FAR_STEPS; i++) {
        let x = p + d * (step * f32(i));
        let from_center = x - r.center;
        let layer = r.first_layer + cube_face(from_center);
        let uv = face_uv(env_views[layer].clip_from_world, x);
        let texel = clamp(vec2<i32>(uv * f32(size)), vec2<i32>(0), vec2<i32>(size - 1));
        let far = textureLoad(far_positions, texel, i32(layer), 0);
        if (far.w > 0.5 && length(far.xyz - r.center) < length(from_center)
            && length(far.xyz - x) < 2.0 * step) {
            return vec4<f32>(env_texel(layer, texel.x, texel.y, size), 1.0);
        }
    }
    return vec4<f32>(0.0);
}

@fragment
fn fs_shade(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.clip.xy);
    let width = textureDimensions(g_color).x;
    var near = near_reflection[u32(pixel.y) * width + u32(pixel.x)];
    if (near.a < 0.0) {
        near.a = 1.0;
    } else if (near.a > 0.0) {
        let mesh = textureLoad(g_ids, pixel, 0).x - 1u;
        let r = reflectors[mesh_reflector[mesh]];
        let p = textureLoad(g_position, pixel, 0).xyz;
        let n = textureLoad(g_normal, pixel, 0).xyz;
        let d = reflect(normalize(p - camera.eye_world), n);
        let far = far_field_in_front(r, p, d, near.a);
        near = select(vec4<f32>(near.rgb, 1.0), far, far.a > 0.0);
    }
    return shade(pixel, near);
}
