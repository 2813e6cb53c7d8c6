// What a distance-map texel says about its surface: the material map holds (rgb, code), the
// geometry map (octahedral normal, mesh index + 1, distance). Codes follow the paper's sign coding of the index of
// refraction: 0 = diffuse (rgb = the radiance the surface sends towards the reference point),
// negative = reflector (rgb = F0; -1 with Schlick's Fresnel, -2 with exactly F0), positive =
// refractor (rgb = F0 per channel, from which the per-channel indices follow; the code is the
// green index, plus THIN_OFFSET for a thin-walled sheet). Distance -1 marks a texel that sees
// nothing. Needs scene.wgsl before it.

const CODE_DIFFUSE: f32 = 0.0;
const CODE_MIRROR_SCHLICK: f32 = -1.0;
const CODE_MIRROR_CONSTANT: f32 = -2.0;
// Added to a thin sheet's index: beyond any real index, so a code > THIN_OFFSET means a sheet.
const THIN_OFFSET: f32 = 100.0;

// Reflectance at normal incidence of an interface from air to a medium of index `n` and
// extinction coefficient `k` (the paper's F0; k = 0 for dielectrics).
fn fresnel_f0(n: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let k2 = k * k;
    return ((n - 1.0) * (n - 1.0) + k2) / ((n + 1.0) * (n + 1.0) + k2);
}

// The index of a dielectric (k = 0) from its F0: the inverse of fresnel_f0.
fn ior_from_f0(f0: vec3<f32>) -> vec3<f32> {
    let s = sqrt(clamp(f0, vec3<f32>(0.0), vec3<f32>(0.999)));
    return (1.0 + s) / (1.0 - s);
}

// (rgb, code) of a mirror or dielectric material.
fn specular_code(material: Material) -> vec4<f32> {
    if (material.kind == MATERIAL_MIRROR) {
        let code = select(CODE_MIRROR_CONSTANT, CODE_MIRROR_SCHLICK, (material.flags & FLAG_FRESNEL) != 0u);
        return vec4<f32>(material.color, code);
    }
    var code = material.ior.y;
    if ((material.flags & FLAG_THIN) != 0u) {
        code += THIN_OFFSET;
    }
    return vec4<f32>(fresnel_f0(material.ior, vec3<f32>(0.0)), code);
}

fn is_specular(material: Material) -> bool {
    return material.kind == MATERIAL_MIRROR || material.kind == MATERIAL_DIELECTRIC;
}

// Octahedral encoding of a unit normal in two numbers (so that the geometry map has room for
// the mesh index).
fn octahedral_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z < 0.0) {
        return (1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    }
    return p;
}

fn octahedral_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}
