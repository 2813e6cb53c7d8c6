// The G-buffer pixel a specular shading pass starts from: the raster's colour, and for a pixel of
// a reflector (a mesh with a reflector index) its mesh, triangle, reflector, material, world
// position, normal and view direction. Needs camera.wgsl and scene.wgsl before it.
// The including shader declares, at bindings of its own:
//   var<uniform> camera: Camera;
//   var g_color: texture_2d<f32>;
//   var g_position: texture_2d<f32>;
//   var g_normal: texture_2d<f32>;
//   var g_ids: texture_2d<u32>;
//   var<storage, read> mesh_reflector: array<i32>;   // each mesh's reflector index, or -1

struct SpecularPixel {
    // The raster's colour: what the pixel shows where it is not a reflector's.
    base: vec4<f32>,
    // The reflector's index; -1 for the background or a mesh that is no reflector (the fields
    // below are then unset).
    reflector: i32,
    mesh: u32,
    triangle: u32,
    material: Material,
    // World position, normal (facing the eye) and the unit direction from the eye to `p`.
    p: vec3<f32>,
    n: vec3<f32>,
    v: vec3<f32>,
};

// The G-buffer's pixel `pixel`, as a specular shading pass reads it.
fn specular_pixel(pixel: vec2<i32>) -> SpecularPixel {
    var s: SpecularPixel;
    s.base = textureLoad(g_color, pixel, 0);
    s.reflector = -1;
    let ids = textureLoad(g_ids, pixel, 0).xy;
    if (ids.x == 0u) {
        return s;
    }
    s.mesh = ids.x - 1u;
    s.triangle = ids.y;
    s.reflector = mesh_reflector[s.mesh];
    if (s.reflector < 0) {
        return s;
    }
    s.material = materials[mesh_materials[s.mesh]];
    s.p = textureLoad(g_position, pixel, 0).xyz;
    s.n = textureLoad(g_normal, pixel, 0).xyz;
    s.v = normalize(s.p - camera.eye_world);
    return s;
}
