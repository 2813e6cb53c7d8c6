// Cube-map helpers. specula stores the six faces of a cube map (or of a point light's shadow
// map) as layers of a 2D array, in the order +X, -X, +Y, -Y, +Z, -Z, each rendered with its own
// view-projection matrix; a direction is looked up by choosing the face of its major axis and
// projecting it with that face's matrix, so lookups match exactly how the faces were rendered.

// Face (0..5, in the order +X, -X, +Y, -Y, +Z, -Z) that direction `d` falls on.
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1u, 0u, d.x > 0.0);
    }
    if (a.y >= a.z) {
        return select(3u, 2u, d.y > 0.0);
    }
    return select(5u, 4u, d.z > 0.0);
}

// Texture coordinate ((0, 0) = top-left) of world point `p` in a face rendered with
// `clip_from_world`.
fn face_uv(clip_from_world: mat4x4<f32>, p: vec3<f32>) -> vec2<f32> {
    let clip = clip_from_world * vec4<f32>(p, 1.0);
    let ndc = clip.xy / clip.w;
    return vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
}
