// The reference's shading (specula_trace::reference::Tracer::radiance), one hit at a time:
// what a hit emits towards the ray, and the rays it spawns with their weights. Whitted's
// recursion becomes a list of pending rays; whoever calls `shade` (one thread per pixel with
// its own stack, or the wavefront's queues) decides where they wait.
//
// Needs optics.wgsl, camera.wgsl, scene.wgsl and bvh.wgsl.

struct Settings {
    max_depth: u32,
    triangle_count: u32,
    // Wavefront only: rays one queue holds.
    queue_capacity: u32,
    pad: u32,
};

// A ray waiting to be traced, with everything its contribution needs.
struct PendingRay {
    origin: vec3<f32>,
    // Specular bounces so far on its path.
    depth: u32,
    dir: vec3<f32>,
    // The colour channel a dispersive interface split the path into, NO_CHANNEL before.
    channel: u32,
    // What its radiance is multiplied by before it adds to the pixel.
    weight: vec3<f32>,
    // The pixel it adds to (row-major index).
    pixel: u32,
};

const NO_CHANNEL: u32 = 3u;
// The most rays one hit spawns: a dispersive solid splits into three channels, each with a
// reflected and a transmitted ray.
const MAX_CHILDREN: u32 = 6u;

// Counter slots (host: COUNTER_NAMES in mod.rs).
const COUNT_RAYS: u32 = 0u;
const COUNT_SHADOW_RAYS: u32 = 1u;
const COUNT_CUT_AT_MAX_DEPTH: u32 = 2u;
const COUNT_DROPPED: u32 = 3u;

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(3) var<storage, read> vertex_data: array<f32>;
@group(0) @binding(5) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(6) var<uniform> settings: Settings;

// GpuVertex is 10 words: position (3), mesh, normal (3), triangle, uv (2).
const VERTEX_WORDS: u32 = 10u;

fn vertex_position(v: u32) -> vec3<f32> {
    let b = v * VERTEX_WORDS;
    return vec3<f32>(vertex_data[b], vertex_data[b + 1u], vertex_data[b + 2u]);
}

fn vertex_normal(v: u32) -> vec3<f32> {
    let b = v * VERTEX_WORDS + 4u;
    return vec3<f32>(vertex_data[b], vertex_data[b + 1u], vertex_data[b + 2u]);
}

fn vertex_uv(v: u32) -> vec2<f32> {
    let b = v * VERTEX_WORDS + 8u;
    return vec2<f32>(vertex_data[b], vertex_data[b + 1u]);
}

fn vertex_mesh(v: u32) -> u32 {
    return bitcast<u32>(vertex_data[v * VERTEX_WORDS + 3u]);
}

// As specula_trace::reference::SurfacePoint.
struct SurfacePoint {
    p: vec3<f32>,
    ng: vec3<f32>,
    ns: vec3<f32>,
    uv: vec2<f32>,
    backface: bool,
    material: u32,
};

fn surface_point(dir: vec3<f32>, hit: Hit) -> SurfacePoint {
    let v = triangles[hit.triangle].vertex;
    let b0 = 1.0 - hit.b1 - hit.b2;
    let p0 = vertex_position(v);
    let p1 = vertex_position(v + 1u);
    let p2 = vertex_position(v + 2u);
    var sp: SurfacePoint;
    sp.p = p0 * b0 + p1 * hit.b1 + p2 * hit.b2;
    var ng = normalize(cross(p1 - p0, p2 - p0));
    let n = vertex_normal(v) * b0 + vertex_normal(v + 1u) * hit.b1 + vertex_normal(v + 2u) * hit.b2;
    let length_n = length(n);
    var ns = ng;
    if (length_n > 0.0 && length_n < 3.0e38) {
        ns = n / length_n;
    }
    // Meshes whose stored normals disagree with the winding: trust the normals' side.
    if (dot(ns, ng) < 0.0) {
        ng = -ng;
    }
    sp.backface = dot(dir, ng) > 0.0;
    if (sp.backface) {
        ng = -ng;
        ns = -ns;
    }
    sp.ng = ng;
    sp.ns = ns;
    sp.uv = vertex_uv(v) * b0 + vertex_uv(v + 1u) * hit.b1 + vertex_uv(v + 2u) * hit.b2;
    sp.material = mesh_materials[vertex_mesh(v)];
    return sp;
}

// Origin of a ray leaving `p` in direction `dir`, pushed off the surface (as the CPU's
// `offset_origin`).
fn offset_origin(p: vec3<f32>, ng: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let a = abs(p);
    let eps = 2e-5 * (1.0 + max(max(a.x, a.y), a.z));
    if (dot(dir, ng) >= 0.0) {
        return p + ng * eps;
    }
    return p - ng * eps;
}

// What `shade` produced: radiance to add (already weighted) and the spawned rays.
var<private> children: array<PendingRay, MAX_CHILDREN>;
var<private> child_count: u32;
var<private> shadow_rays: u32;
var<private> cut_at_max_depth: u32;

fn spawn(parent: PendingRay, sp: SurfacePoint, dir: vec3<f32>, weight: vec3<f32>, channel: u32) {
    // A zero weight contributes nothing (the CPU traces it and multiplies by zero).
    if (all(weight == vec3<f32>(0.0))) {
        return;
    }
    var child: PendingRay;
    child.origin = offset_origin(sp.p, sp.ng, dir);
    child.dir = dir;
    child.depth = parent.depth + 1u;
    child.channel = channel;
    child.weight = weight;
    child.pixel = parent.pixel;
    children[child_count] = child;
    child_count += 1u;
}

// Both branches at a dielectric interface of index `ior` (as the CPU's `Tracer::dielectric`).
fn dielectric(ray: PendingRay, sp: SurfacePoint, ior: f32, thin: bool, weight: vec3<f32>, channel: u32) {
    let cos_i = clamp(-dot(ray.dir, sp.ns), 0.0, 1.0);
    let reflected = reflect(ray.dir, sp.ns);
    if (thin) {
        let r = thin_sheet_reflectance(cos_i, ior);
        spawn(ray, sp, reflected, weight * r, channel);
        spawn(ray, sp, ray.dir, weight * (1.0 - r), channel);
        return;
    }
    var eta = 1.0 / ior;
    if (sp.backface) {
        eta = ior;
    }
    let r = fresnel_dielectric(cos_i, eta);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if (k >= 0.0 && r < 1.0) {
        let transmitted = eta * ray.dir + (eta * cos_i - sqrt(k)) * sp.ns;
        spawn(ray, sp, normalize(transmitted), weight * (1.0 - r), channel);
        if (r > 0.0) {
            spawn(ray, sp, reflected, weight * r, channel);
        }
    } else {
        spawn(ray, sp, reflected, weight, channel);
    }
}

// Shades `ray`'s closest hit: returns the weighted radiance it emits; spawned rays are in
// `children[0..child_count]`.
fn shade(ray: PendingRay, hit: Hit) -> vec3<f32> {
    child_count = 0u;
    if (hit.triangle == NO_HIT) {
        return ray.weight * background_radiance(ray.dir);
    }
    let sp = surface_point(ray.dir, hit);
    let material = materials[sp.material];
    if (material.kind == MATERIAL_UNLIT) {
        return ray.weight * material_base(material, sp.uv);
    }
    if (material.kind == MATERIAL_DIFFUSE) {
        var irradiance = vec3<f32>(0.0);
        for (var i = 0u; i < scene_info.light_count; i++) {
            let s = light_sample(lights[i], sp.p);
            let cos_theta = dot(sp.ns, s.to_light);
            if (cos_theta <= 0.0 || all(s.irradiance == vec3<f32>(0.0))) {
                continue;
            }
            shadow_rays += 1u;
            let shadow = traverse(offset_origin(sp.p, sp.ng, s.to_light), s.to_light, s.distance, true);
            if (shadow.triangle == NO_HIT) {
                irradiance += s.irradiance * cos_theta;
            }
        }
        return ray.weight * material_base(material, sp.uv) * (irradiance / PI + scene_info.ambient);
    }
    if (ray.depth >= settings.max_depth) {
        cut_at_max_depth += 1u;
        return vec3<f32>(0.0);
    }
    if (material.kind == MATERIAL_MIRROR) {
        let cos_i = -dot(ray.dir, sp.ns);
        var f = material.color;
        if ((material.flags & FLAG_FRESNEL) != 0u) {
            f = fresnel_schlick(material.color, cos_i);
        }
        spawn(ray, sp, reflect(ray.dir, sp.ns), ray.weight * f, ray.channel);
        return vec3<f32>(0.0);
    }
    let thin = (material.flags & FLAG_THIN) != 0u;
    let ior = material.ior;
    let dispersive = ior.x != ior.y || ior.y != ior.z;
    if (ray.channel == NO_CHANNEL && dispersive) {
        // One path per colour channel from here on, each carrying only its channel's weight.
        for (var c = 0u; c < 3u; c++) {
            var mask = vec3<f32>(0.0);
            mask[c] = 1.0;
            dielectric(ray, sp, ior[c], thin, ray.weight * mask, c);
        }
    } else if (ray.channel == NO_CHANNEL) {
        dielectric(ray, sp, ior.x, thin, ray.weight, NO_CHANNEL);
    } else {
        dielectric(ray, sp, ior[ray.channel], thin, ray.weight, ray.channel);
    }
    return vec3<f32>(0.0);
}

fn primary_ray(pixel: vec2<u32>) -> PendingRay {
    var ray: PendingRay;
    ray.origin = camera.eye_world;
    ray.dir = camera_ray_direction(camera, vec2<f32>(pixel) + vec2<f32>(0.5));
    ray.depth = 0u;
    ray.channel = NO_CHANNEL;
    ray.weight = vec3<f32>(1.0);
    ray.pixel = pixel.y * u32(camera.width) + pixel.x;
    return ray;
}
