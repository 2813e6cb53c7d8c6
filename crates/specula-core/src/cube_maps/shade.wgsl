// The shading of envmap (and of the techniques that refine it): the specular pixels of the
// G-buffer from per-reflector environment cube maps (six faces in a 2D array; see
// cubemap.wgsl). Prepended: optics.wgsl, camera.wgsl, scene.wgsl, cubemap.wgsl,
// specular_pixel.wgsl, lookup.wgsl.

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var g_color: texture_2d<f32>;
@group(0) @binding(2) var g_position: texture_2d<f32>;
@group(0) @binding(3) var g_normal: texture_2d<f32>;
@group(0) @binding(4) var g_ids: texture_2d<u32>;
@group(0) @binding(5) var env_faces: texture_2d_array<f32>;
@group(0) @binding(6) var<storage, read> env_views: array<EnvView>;
@group(0) @binding(7) var<storage, read> reflectors: array<Reflector>;
// Reflector index of each mesh, or -1.
@group(0) @binding(8) var<storage, read> mesh_reflector: array<i32>;

// Far intersection of the ray p + t·d (p inside) with the reflector's bounding sphere.
fn exit_point(r: Reflector, p: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let oc = p - r.center;
    let b = dot(oc, d);
    let c = dot(oc, oc) - r.radius * r.radius;
    let t = -b + sqrt(max(b * b - c, 0.0));
    return p + d * t;
}

// Transmitted radiance of one colour channel through a solid dielectric of index `ior`.
fn transmitted(r: Reflector, p: vec3<f32>, d: vec3<f32>, n: vec3<f32>, ior: f32, channel: u32) -> f32 {
    let t_in = refract(d, n, 1.0 / ior);
    if (r.exit_model == 0u) {
        // Single interface: the environment seen along the refracted ray.
        return env_lookup(r, t_in)[channel];
    }
    // Naive second interface: the bounding sphere's normal where the ray leaves it, or the
    // entry face's own normal (a slab of parallel faces).
    var n_out = -n;
    if (r.exit_model == 1u) {
        n_out = normalize(exit_point(r, p, t_in) - r.center);
    }
    let cos_exit = dot(t_in, n_out);
    let r_exit = fresnel_dielectric(cos_exit, ior);
    var t_out = refract(t_in, -n_out, ior);
    if (dot(t_out, t_out) == 0.0) {
        t_out = reflect(t_in, -n_out);
    }
    return env_lookup(r, t_out)[channel] * (1.0 - r_exit);
}

// The colour of `pixel`: the G-buffer's, or for a specular pixel its reflection (and
// refraction) looked up in the cube maps. A mirror pixel whose `near.a` is positive reflects
// `near.rgb` instead (radiance a technique found along the reflected ray by other means).
fn shade(pixel: vec2<i32>, near: vec4<f32>) -> vec4<f32> {
    let s = specular_pixel(pixel);
    if (s.reflector < 0) {
        return s.base;
    }
    let r = reflectors[s.reflector];
    let material = s.material;
    let p = s.p;
    let n = s.n;
    let d = s.v;
    let cos_i = -dot(d, n);
    var reflected = env_lookup(r, reflect(d, n));
    if (material.kind == MATERIAL_MIRROR && near.a > 0.0) {
        reflected = near.rgb;
    }
    var color = vec3<f32>(0.0);
    if (material.kind == MATERIAL_MIRROR) {
        var f = material.color;
        if ((material.flags & FLAG_FRESNEL) != 0u) {
            f = fresnel_schlick(material.color, cos_i);
        }
        color = f * reflected;
    } else if ((material.flags & FLAG_THIN) != 0u) {
        let straight = env_lookup(r, d);
        for (var c = 0u; c < 3u; c++) {
            let rs = thin_sheet_reflectance(cos_i, material.ior[c]);
            color[c] = rs * reflected[c] + (1.0 - rs) * straight[c];
        }
    } else {
        for (var c = 0u; c < 3u; c++) {
            let rf = fresnel_dielectric(cos_i, 1.0 / material.ior[c]);
            color[c] = rf * reflected[c] + (1.0 - rf) * transmitted(r, p, d, n, material.ior[c], c);
        }
    }
    return vec4<f32>(color, 1.0);
}
