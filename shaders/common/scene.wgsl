// The scene as uploaded by specula_methods::gpu_scene (host mirrors: GpuMaterial, GpuLight,
// GpuTextureInfo, GpuSceneInfo). Sampling here reproduces the CPU reference exactly: bilinear,
// repeat wrapping, uv (0, 0) at the image's top-left corner.

const MATERIAL_UNLIT: u32 = 0u;
const MATERIAL_DIFFUSE: u32 = 1u;
const MATERIAL_MIRROR: u32 = 2u;
const MATERIAL_DIELECTRIC: u32 = 3u;
const FLAG_FRESNEL: u32 = 1u;
const FLAG_THIN: u32 = 2u;
const LIGHT_POINT: u32 = 0u;
const LIGHT_DIRECTIONAL: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;
const PI: f32 = 3.14159265358979;

struct Material {
    color: vec3<f32>,
    kind: u32,
    ior: vec3<f32>,
    texture: i32,
    flags: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

struct TextureInfo {
    offset: u32,
    width: u32,
    height: u32,
    pad: u32,
};

struct Light {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    cos_inner: f32,
    intensity: vec3<f32>,
    cos_outer: f32,
    shadow_layer: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

struct SceneInfo {
    ambient: vec3<f32>,
    light_count: u32,
    background: vec3<f32>,
    background_texture: i32,
    background_intensity: f32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

// What a light delivers at a point (as the CPU's `Light::sample`).
struct LightSample {
    to_light: vec3<f32>,
    distance: f32,
    irradiance: vec3<f32>,
};

fn light_sample(light: Light, p: vec3<f32>) -> LightSample {
    var s: LightSample;
    if (light.kind == LIGHT_DIRECTIONAL) {
        s.to_light = -light.direction;
        s.distance = 3.0e38;
        s.irradiance = light.intensity;
        return s;
    }
    let offset = light.position - p;
    s.distance = length(offset);
    s.to_light = offset / s.distance;
    var falloff = 1.0;
    if (light.kind == LIGHT_SPOT) {
        let cos_angle = dot(-s.to_light, light.direction);
        let t = clamp((cos_angle - light.cos_outer) / max(light.cos_inner - light.cos_outer, 1e-6), 0.0, 1.0);
        falloff = t * t;
    }
    s.irradiance = light.intensity * falloff / (s.distance * s.distance);
    return s;
}

// Equirectangular texture coordinate of a unit world direction (docs/conventions.md).
fn equirect_uv(d: vec3<f32>) -> vec2<f32> {
    let u = 0.5 + atan2(d.x, -d.z) / (2.0 * PI);
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return vec2<f32>(u, v);
}

// One vertex of the uploaded scene as a vertex shader reads it (host: GpuVertex, laid out by
// raster::vertex_layout).
struct SceneVertex {
    @location(0) position: vec3<f32>,
    @location(1) mesh: u32,
    @location(2) normal: vec3<f32>,
    @location(3) triangle: u32,
    @location(4) uv: vec2<f32>,
};

// Bind group 1 of every technique: the uploaded scene (see GpuScene::bind_group_layout).
@group(1) @binding(0) var<uniform> scene_info: SceneInfo;
@group(1) @binding(1) var<storage, read> materials: array<Material>;
@group(1) @binding(2) var<storage, read> mesh_materials: array<u32>;
@group(1) @binding(3) var<storage, read> texture_infos: array<TextureInfo>;
@group(1) @binding(4) var<storage, read> texels: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read> lights: array<Light>;

fn texel(info: TextureInfo, x: i32, y: i32) -> vec3<f32> {
    let w = i32(info.width);
    let h = i32(info.height);
    let xi = ((x % w) + w) % w;
    let yi = ((y % h) + h) % h;
    return texels[info.offset + u32(yi * w + xi)].xyz;
}

// Bilinear with repeat wrapping, as specula_scene::Texture::sample.
fn sample_texture(index: i32, uv: vec2<f32>) -> vec3<f32> {
    let info = texture_infos[index];
    let x = uv.x * f32(info.width) - 0.5;
    let y = uv.y * f32(info.height) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xi = i32(x0);
    let yi = i32(y0);
    let top = mix(texel(info, xi, yi), texel(info, xi + 1, yi), fx);
    let bottom = mix(texel(info, xi, yi + 1), texel(info, xi + 1, yi + 1), fx);
    return mix(top, bottom, fy);
}

fn background_radiance(direction: vec3<f32>) -> vec3<f32> {
    if (scene_info.background_texture < 0) {
        return scene_info.background;
    }
    return sample_texture(scene_info.background_texture, equirect_uv(direction)) * scene_info.background_intensity;
}

// Base colour × texture of a material at a texture coordinate.
fn material_base(material: Material, uv: vec2<f32>) -> vec3<f32> {
    if (material.texture < 0) {
        return material.color;
    }
    return material.color * sample_texture(material.texture, uv);
}
