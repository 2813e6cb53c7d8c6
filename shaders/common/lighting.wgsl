// Direct lighting of non-specular surfaces, as the CPU reference shades them: unlit base colour,
// or Lambert with the scene's lights, their distance shadow maps (raster::RasterPass renders
// them; bind group 2) and ambient. Specular surfaces get black: the techniques fill them.
// Needs scene.wgsl and cubemap.wgsl before it.

struct ShadowView {
    clip_from_world: mat4x4<f32>,
    origin: vec3<f32>,
    directional: u32,
    direction: vec3<f32>,
    // World size of one shadow-map texel at unit distance (point) or anywhere (directional).
    texel_size: f32,
};

@group(2) @binding(0) var<storage, read> shadow_views: array<ShadowView>;
@group(2) @binding(1) var shadow_maps: texture_2d_array<f32>;

// The shadow metric of a point for a view: distance along the light direction (directional)
// or distance from the light (point, spot).
fn shadow_metric(view: ShadowView, p: vec3<f32>) -> f32 {
    if (view.directional == 1u) {
        return dot(p - view.origin, view.direction);
    }
    return distance(p, view.origin);
}

// 1 when the light reaches `p` (with shading normal `n`), 0 when something is in the way.
fn light_visibility(light: Light, p: vec3<f32>, n: vec3<f32>) -> f32 {
    var layer = light.shadow_layer;
    if (light.kind != LIGHT_DIRECTIONAL) {
        layer += cube_face(p - light.position);
    }
    let view = shadow_views[layer];
    let size = textureDimensions(shadow_maps);
    var texel_world = view.texel_size;
    if (view.directional == 0u) {
        texel_world *= distance(p, view.origin);
    }
    // Normal offset and a constant bias of a few texels keep surfaces from shadowing themselves.
    let to_light = light_sample(light, p).to_light;
    let n_light = select(-n, n, dot(n, to_light) >= 0.0);
    let p_offset = p + n_light * texel_world * 1.5;
    let uv = face_uv(view.clip_from_world, p_offset);
    if (any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0))) {
        return 1.0;
    }
    let texel_coord = vec2<i32>(uv * vec2<f32>(size));
    let stored = textureLoad(shadow_maps, texel_coord, i32(layer), 0).x;
    return select(0.0, 1.0, shadow_metric(view, p_offset) - 2.0 * texel_world <= stored);
}

// Radiance leaving a surface point `p` with normal `n` (facing the viewer) and texture
// coordinate `uv`.
fn surface_radiance(material: Material, p: vec3<f32>, n: vec3<f32>, uv: vec2<f32>) -> vec3<f32> {
    if (material.kind == MATERIAL_UNLIT) {
        return material_base(material, uv);
    }
    if (material.kind != MATERIAL_DIFFUSE) {
        return vec3<f32>(0.0);
    }
    var irradiance = vec3<f32>(0.0);
    for (var i = 0u; i < scene_info.light_count; i++) {
        let s = light_sample(lights[i], p);
        let cos_theta = dot(n, s.to_light);
        if (cos_theta > 0.0) {
            irradiance += s.irradiance * cos_theta * light_visibility(lights[i], p, n);
        }
    }
    return material_base(material, uv) * (irradiance / PI + scene_info.ambient);
}
