// image-space: two-interface refraction of nearby geometry (Wyman 2005), the final pass.
// A full-screen pass over the scene G-buffer: every refractor pixel is refracted twice with
// the back-face textures and shown with what the nearby-geometry (NG) texture holds where the
// refracted ray meets it; everything else keeps the raster's colour.
// Prepended: optics.wgsl, camera.wgsl, scene.wgsl, cubemap.wgsl, specular_pixel.wgsl,
// envmap's lookup.wgsl.

const MODE_KAY_GREENBERG: u32 = 0u;
const MODE_RAY_PLANE: u32 = 1u;
const MODE_ITERATIVE: u32 = 2u;

// Counter slots (mod.rs `COUNTERS` has their names, in this order).
const COUNT_LEFT_FRUSTUM: u32 = 0u;
const COUNT_NOTHING_NEARBY: u32 = 1u;
const COUNT_EXIT_OFF_BACK_FACES: u32 = 2u;
const COUNT_TIR_FOLLOWED: u32 = 3u;
const COUNT_INTERNAL_NOT_RESOLVED: u32 = 4u;
const COUNT_REENTRIES: u32 = 5u;
const COUNT_TIR_NOT_FOLLOWED: u32 = 6u;

const FALLBACK_BACKGROUND: u32 = 1u;

struct Settings {
    mode: u32,
    seeds: u32,
    iterations: u32,
    plane_count: u32,
    // 0: each material's own index of refraction.
    index_override: f32,
    // The iterative mode accepts a nearby-geometry hit when its depth and the ray's differ by
    // less than this fraction of the depth (0: any hit, as the paper).
    depth_tolerance: f32,
    // Steps of the march that follows an internally reflected ray.
    inside_steps: u32,
    // Depth-matching steps refining P̃2 against the back-face texture (0: the paper's P̃2).
    exit_iterations: u32,
    // The scene's bounding sphere: where rays leave the scene.
    scene_center: vec3<f32>,
    scene_radius: f32,
    // The scene's bounding box, the proxy of parallax-corrected cube-map lookups.
    scene_min: vec3<f32>,
    // 1: cube-map lookups are corrected for parallax against the scene's box.
    parallax: u32,
    scene_max: vec3<f32>,
    // Pairs of interfaces a path may cross (the `layers` parameter; 1 = the paper's two).
    layers: u32,
    // Depth-peeled surface layers bound (0 with layers = 1).
    peeled: u32,
    // The largest solid refractor's bounding-sphere diameter: how far marches between
    // refractors look.
    refractor_extent: f32,
    // View depth of the far plane: what the NG z-buffer holds where nothing was drawn.
    far_depth: f32,
    // 1: the iterative mode's bracketed search (0: the paper's iteration from the best seed).
    bracket: u32,
    // 1: ray-plane's planes are discs (0: the paper's infinite planes).
    discs: u32,
    // 1: Fresnel's split at the exit, the reflected part followed inside (0: the paper's
    // refraction of all of it).
    internal_reflection: u32,
    // 1: the first surface's Fresnel reflection is added (0: the refracted colour alone).
    reflection: u32,
    // What a ray that finds no nearby geometry sees: 0 the cube map, 1 the background.
    fallback: u32,
    // 1: dispersive materials refract once per channel (0: one path at the green index).
    dispersion: u32,
    pad1: u32,
    pad2: u32,
    pad3: u32,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var g_color: texture_2d<f32>;
@group(0) @binding(2) var g_position: texture_2d<f32>;
@group(0) @binding(3) var g_normal: texture_2d<f32>;
@group(0) @binding(4) var g_ids: texture_2d<u32>;
// First pass: the refractors' back faces (world position, normal facing the eye, IDs).
@group(0) @binding(5) var back_position: texture_2d<f32>;
@group(0) @binding(6) var back_normal: texture_2d<f32>;
@group(0) @binding(7) var back_ids: texture_2d<u32>;
// Second pass: the nearby (non-specular) geometry seen from the eye (colour, world position,
// IDs; ids.x = 0 where nothing is).
@group(0) @binding(8) var ng_color: texture_2d<f32>;
@group(0) @binding(9) var ng_position: texture_2d<f32>;
@group(0) @binding(10) var ng_ids: texture_2d<u32>;
// The scene vertices (10 words per GpuVertex), d_N per vertex (-1: none found), and each
// mesh's first vertex.
@group(0) @binding(11) var<storage, read> vertex_data: array<f32>;
@group(0) @binding(12) var<storage, read> normal_distance: array<f32>;
@group(0) @binding(13) var<storage, read> mesh_first_vertex: array<u32>;
@group(0) @binding(14) var<uniform> settings: Settings;
// The ray-plane mode's planes (mod.rs `GpuPlane`).
struct Plane {
    // Zero: the plane faces the eye through `center`.
    normal: vec3<f32>,
    offset: f32,
    center: vec3<f32>,
    // A disc: hits farther than this from `center` miss.
    radius: f32,
};
@group(0) @binding(15) var<storage, read> planes: array<Plane>;
@group(0) @binding(16) var<storage, read_write> counters: array<atomic<u32>, 7>;
@group(0) @binding(17) var env_faces: texture_2d_array<f32>;
@group(0) @binding(18) var<storage, read> env_views: array<EnvView>;
@group(0) @binding(19) var<storage, read> reflectors: array<Reflector>;
@group(0) @binding(20) var<storage, read> mesh_reflector: array<i32>;
// With layers > 1: the solid refractors' surfaces peeled from the eye (peel.wgsl): position
// (w = view depth, 0 where none) and normal per layer.
@group(0) @binding(21) var layer_position: texture_2d_array<f32>;
@group(0) @binding(22) var layer_normal: texture_2d_array<f32>;

fn count(slot: u32) {
    atomicAdd(&counters[slot], 1u);
}

// Where world point `p` lands on the screen: xy in [0, 1) (top-left origin) when visible, z the
// clip w (<= 0 behind the eye).
fn project(p: vec3<f32>) -> vec3<f32> {
    let clip = camera.clip_from_world * vec4<f32>(p, 1.0);
    if (clip.w <= 1e-6) {
        return vec3<f32>(-1.0, -1.0, clip.w);
    }
    let ndc = clip.xy / clip.w;
    return vec3<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5, clip.w);
}

fn on_screen(q: vec3<f32>) -> bool {
    return q.z > 0.0 && q.x >= 0.0 && q.x < 1.0 && q.y >= 0.0 && q.y < 1.0;
}

// The texel of a texture of size `size` under screen point `q`.
fn texel_at(q: vec3<f32>, size: vec2<u32>) -> vec2<i32> {
    let last = vec2<i32>(size) - 1;
    return clamp(vec2<i32>(q.xy * vec2<f32>(size)), vec2<i32>(0), last);
}

fn view_depth(p: vec3<f32>) -> f32 {
    return dot(p - camera.eye_world, camera.forward_world);
}

// Distance along the ray p + t·d (p inside) to where it leaves the scene's bounding sphere.
fn scene_exit(p: vec3<f32>, d: vec3<f32>) -> f32 {
    let oc = p - settings.scene_center;
    let b = dot(oc, d);
    let c = dot(oc, oc) - settings.scene_radius * settings.scene_radius;
    return max(-b + sqrt(max(b * b - c, 0.0)), 0.0);
}

// Envmap's cube map for a ray p + t·d. Beyond the paper: with `parallax`, the direction looked
// up is the one from the map's centre to where the ray leaves the scene's bounding box (exact
// for the walls of a room that is the scene's box), instead of d itself (exact only for an
// environment at infinity).
fn env_along(r: Reflector, p: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    if (settings.parallax == 0u) {
        return env_lookup(r, d);
    }
    let inverse = 1.0 / d;
    let t_far = max((settings.scene_min - p) * inverse, (settings.scene_max - p) * inverse);
    let t = min(t_far.x, min(t_far.y, t_far.z));
    let towards = p + d * max(t, 0.0) - r.center;
    if (dot(towards, towards) < 1e-12) {
        return env_lookup(r, d);
    }
    return env_lookup(r, normalize(towards));
}

// ---- Nearby geometry (§4) -------------------------------------------------------------------

struct NearbyHit {
    // 0: found (colour valid); 1: left the NG texture's frustum; 2: nothing nearby.
    status: u32,
    color: vec3<f32>,
};

// The NG texel under world point `p`, accepted when `accept_any` or when its depth agrees with
// p's within `depth_tolerance`.
fn ng_sample(p: vec3<f32>, accept_any: bool) -> NearbyHit {
    let q = project(p);
    if (!on_screen(q)) {
        return NearbyHit(1u, vec3<f32>(0.0));
    }
    let texel = texel_at(q, textureDimensions(ng_ids));
    if (textureLoad(ng_ids, texel, 0).x == 0u) {
        return NearbyHit(2u, vec3<f32>(0.0));
    }
    if (!accept_any && settings.depth_tolerance > 0.0) {
        let z_ng = view_depth(textureLoad(ng_position, texel, 0).xyz);
        if (abs(z_ng - view_depth(p)) > settings.depth_tolerance * z_ng) {
            return NearbyHit(2u, vec3<f32>(0.0));
        }
    }
    return NearbyHit(0u, textureLoad(ng_color, texel, 0).xyz);
}

// §4.1: the NG texture straight behind the exit point (rays assumed parallel to the view).
fn kay_greenberg(p: vec3<f32>) -> NearbyHit {
    return ng_sample(p, true);
}

// §4.2: the nearest of the CPU's planes along the ray, projected into the NG texture. Beyond
// the paper (`discs`): a plane catches only hits within its disc.
fn ray_plane(p: vec3<f32>, d: vec3<f32>) -> NearbyHit {
    var t_best = 3.4e38;
    for (var i = 0u; i < settings.plane_count; i++) {
        let plane = planes[i];
        var normal = plane.normal;
        var offset = plane.offset;
        if (dot(normal, normal) == 0.0) {
            normal = normalize(camera.eye_world - plane.center);
            offset = dot(normal, plane.center);
        }
        let denom = dot(normal, d);
        if (abs(denom) > 1e-6) {
            let t = (offset - dot(normal, p)) / denom;
            let x = p + d * t;
            let on_disc = settings.discs == 0u || distance(x, plane.center) <= plane.radius;
            if (t > 1e-5 && t < t_best && on_disc) {
                t_best = t;
            }
        }
    }
    if (t_best == 3.4e38) {
        return NearbyHit(2u, vec3<f32>(0.0));
    }
    return ng_sample(p + d * t_best, true);
}

// The ray point at `t` against the NG texture under it: x = -1 off the screen, 0 where no
// geometry is (y then against the far plane's depth, what the paper's cleared z-buffer holds),
// 1 where geometry is; y = z(ray point) − z(NG) (negative while the ray is in front of what the
// eye sees).
fn ng_depth_gap(p: vec3<f32>, d: vec3<f32>, t: f32) -> vec2<f32> {
    let x = p + d * t;
    let q = project(x);
    if (!on_screen(q)) {
        return vec2<f32>(-1.0, 0.0);
    }
    let texel = texel_at(q, textureDimensions(ng_ids));
    if (textureLoad(ng_ids, texel, 0).x == 0u) {
        return vec2<f32>(0.0, view_depth(x) - settings.far_depth);
    }
    return vec2<f32>(1.0, view_depth(x) - view_depth(textureLoad(ng_position, texel, 0).xyz));
}

// §4.3's seeds along the ray p + t·d: spaced evenly on the screen between p and where the ray
// leaves the scene, the segment cut where the clip w falls to a tenth of p's (in front of the
// eye).
struct SeedSpan {
    t_end: f32,
    w0: f32,
    w1: f32,
};

fn seed_span(p: vec3<f32>, d: vec3<f32>) -> SeedSpan {
    var t_end = scene_exit(p, d);
    let w0 = max(project(p).z, 1e-6);
    var w1 = project(p + d * t_end).z;
    if (w1 < 0.1 * w0) {
        let w_min = 0.1 * w0;
        t_end = t_end * (w0 - w_min) / (w0 - w1);
        w1 = w_min;
    }
    return SeedSpan(t_end, w0, w1);
}

// The ray parameter of seed `i` of `seeds`: its projection lies at fraction (i + ½) / seeds of
// the screen segment.
fn seed_t(span: SeedSpan, i: u32, seeds: u32) -> f32 {
    let s = (f32(i) + 0.5) / f32(seeds);
    return span.t_end * s * span.w0 / ((1.0 - s) * span.w1 + s * span.w0);
}

// §4.3 as published (`bracket` off, G–J): the seed whose depth best agrees with the NG z-buffer
// under it (empty texels hold the far plane's depth) starts `iterations` steps of
// t ← t − (z(p + t·d) − z_NG) / (d · forward) (Figure 7); the texel the last step lands on is
// taken. The iteration stops where its point leaves the screen (nothing to read there) or where
// d is perpendicular to the view direction (the step's denominator is zero).
fn iterative_as_published(p: vec3<f32>, d: vec3<f32>) -> NearbyHit {
    let span = seed_span(p, d);
    let seeds = max(settings.seeds, 1u);
    var t = -1.0;
    var best_error = 3.4e38;
    for (var i = 0u; i < seeds; i++) {
        let seed = seed_t(span, i, seeds);
        let gap = ng_depth_gap(p, d, seed);
        if (gap.x >= 0.0 && abs(gap.y) < best_error) {
            best_error = abs(gap.y);
            t = seed;
        }
    }
    if (t < 0.0) {
        return NearbyHit(1u, vec3<f32>(0.0));
    }
    let rate = dot(d, camera.forward_world);
    for (var k = 0u; k < settings.iterations; k++) {
        let gap = ng_depth_gap(p, d, t);
        if (abs(rate) < 1e-3 || gap.x < 0.0) {
            break;
        }
        t -= gap.y / rate;
    }
    return ng_sample(p + d * t, false);
}

// §4.3 with the bracketed search (`bracket`, beyond the paper): seeds over empty texels are
// skipped; where two consecutive seeds bracket the NG surface (the ray passes from in front of
// it to behind it), the iteration is a secant search in that bracket, which cannot run off;
// the point with the best depth agreement met anywhere is kept; and a ray in front of the NG
// surface at every seed finds nothing nearby.
fn iterative(p: vec3<f32>, d: vec3<f32>) -> NearbyHit {
    let span = seed_span(p, d);
    var best_t = -1.0;
    var best_error = 3.4e38;
    var any_on_screen = false;
    var bracket_found = false;
    var before_t = 0.0;
    var before_gap = 0.0;
    var after_t = 0.0;
    var after_gap = 0.0;
    var previous_t = -1.0;
    var previous_gap = 0.0;
    var any_behind = false;
    let seeds = max(settings.seeds, 1u);
    for (var i = 0u; i < seeds; i++) {
        let t = seed_t(span, i, seeds);
        let gap = ng_depth_gap(p, d, t);
        if (gap.x < 0.0) {
            previous_t = -1.0;
            continue;
        }
        any_on_screen = true;
        if (gap.x == 0.0) {
            previous_t = -1.0;
            continue;
        }
        if (abs(gap.y) < best_error) {
            best_error = abs(gap.y);
            best_t = t;
        }
        any_behind = any_behind || gap.y >= 0.0;
        if (!bracket_found && previous_t >= 0.0 && previous_gap < 0.0 && gap.y >= 0.0) {
            bracket_found = true;
            before_t = previous_t;
            before_gap = previous_gap;
            after_t = t;
            after_gap = gap.y;
        }
        previous_t = t;
        previous_gap = gap.y;
    }
    if (best_t < 0.0) {
        return NearbyHit(select(1u, 2u, any_on_screen), vec3<f32>(0.0));
    }
    // A ray that stays in front of everything the NG texture holds, at every seed, passes over
    // the nearby geometry (beside an object's silhouette): nothing nearby.
    if (!any_behind) {
        return NearbyHit(2u, vec3<f32>(0.0));
    }
    if (bracket_found) {
        for (var k = 0u; k < settings.iterations; k++) {
            let t = before_t + (after_t - before_t) * before_gap / (before_gap - after_gap);
            let gap = ng_depth_gap(p, d, t);
            if (gap.x <= 0.0) {
                break;
            }
            if (abs(gap.y) < best_error) {
                best_error = abs(gap.y);
                best_t = t;
            }
            if (gap.y < 0.0) {
                before_t = t;
                before_gap = gap.y;
            } else {
                after_t = t;
                after_gap = gap.y;
            }
        }
    } else {
        let rate = dot(d, camera.forward_world);
        var t = best_t;
        for (var k = 0u; k < settings.iterations; k++) {
            if (abs(rate) < 1e-3) {
                break;
            }
            let t_next = t - ng_depth_gap(p, d, t).y / rate;
            if (t_next <= 0.0) {
                break;
            }
            let gap = ng_depth_gap(p, d, t_next);
            if (gap.x <= 0.0) {
                break;
            }
            t = t_next;
            if (abs(gap.y) < best_error) {
                best_error = abs(gap.y);
                best_t = t;
            }
        }
    }
    return ng_sample(p + d * best_t, false);
}

// Radiance arriving along the ray p + t·d that has left the refractor: the nearby geometry by
// the chosen mode, else `nothing_nearby`, counted.
fn nearby(r: Reflector, p: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    var hit: NearbyHit;
    switch settings.mode {
        case MODE_KAY_GREENBERG: {
            hit = kay_greenberg(p);
        }
        case MODE_RAY_PLANE: {
            hit = ray_plane(p, d);
        }
        default: {
            if (settings.bracket == 1u) {
                hit = iterative(p, d);
            } else {
                hit = iterative_as_published(p, d);
            }
        }
    }
    if (hit.status == 0u) {
        return hit.color;
    }
    count(select(COUNT_NOTHING_NEARBY, COUNT_LEFT_FRUSTUM, hit.status == 1u));
    return nothing_nearby(r, p, d);
}

// What a ray p + t·d that finds no nearby geometry sees: envmap's cube map of the refractor
// (beyond the paper: it holds the nearby objects too), or with `fallback` the paper's
// background environment map along d. The zero vector (the paper's refract under total
// internal reflection) selects no texel in any defined way: a one-colour background is that
// colour whichever texel is read; anything else gives no light.
fn nothing_nearby(r: Reflector, p: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let background = settings.fallback == FALLBACK_BACKGROUND;
    if (dot(d, d) == 0.0) {
        if (background && scene_info.background_texture < 0) {
            return scene_info.background;
        }
        return vec3<f32>(0.0);
    }
    if (background) {
        return background_radiance(d);
    }
    return env_along(r, p, d);
}

// ---- The refractor's surfaces (§3) ------------------------------------------------------------

// d_N at the G-buffer's surface point: the per-vertex distances of its triangle, interpolated.
fn interpolated_normal_distance(mesh: u32, triangle: u32, p: vec3<f32>) -> f32 {
    let first = mesh_first_vertex[mesh] + 3u * triangle;
    var corners: array<vec3<f32>, 3>;
    var distances: vec3<f32>;
    for (var k = 0u; k < 3u; k++) {
        let w = 10u * (first + k);
        corners[k] = vec3<f32>(vertex_data[w], vertex_data[w + 1u], vertex_data[w + 2u]);
        distances[k] = normal_distance[first + k];
    }
    if (min(distances.x, min(distances.y, distances.z)) < 0.0) {
        return -1.0;
    }
    let e1 = corners[1] - corners[0];
    let e2 = corners[2] - corners[0];
    let ep = p - corners[0];
    let d11 = dot(e1, e1);
    let d12 = dot(e1, e2);
    let d22 = dot(e2, e2);
    let denom = d11 * d22 - d12 * d12;
    if (denom <= 0.0) {
        return distances.x;
    }
    let b1 = clamp((d22 * dot(ep, e1) - d12 * dot(ep, e2)) / denom, 0.0, 1.0);
    let b2 = clamp((d11 * dot(ep, e2) - d12 * dot(ep, e1)) / denom, 0.0, 1.0 - b1);
    return distances.x * (1.0 - b1 - b2) + distances.y * b1 + distances.z * b2;
}

struct Surface {
    found: bool,
    position: vec3<f32>,
    // Oriented along the ray that meets it (leaving the refractor).
    normal: vec3<f32>,
    // The stored (outward) normal faced the ray: the ray enters there. Known for peeled
    // layers only (false elsewhere).
    entering: bool,
};

// The refractor's back face under screen point `q`, its normal turned along `d`.
fn back_face(q: vec3<f32>, d: vec3<f32>) -> Surface {
    if (!on_screen(q)) {
        return Surface(false, vec3<f32>(0.0), vec3<f32>(0.0), false);
    }
    let texel = texel_at(q, textureDimensions(back_ids));
    if (textureLoad(back_ids, texel, 0).x == 0u) {
        return Surface(false, vec3<f32>(0.0), vec3<f32>(0.0), false);
    }
    var n = textureLoad(back_normal, texel, 0).xyz;
    if (dot(n, d) < 0.0) {
        n = -n;
    }
    return Surface(true, textureLoad(back_position, texel, 0).xyz, n, false);
}

// Whether world point `x` lies inside a solid refractor: with peeled layers, an odd number of
// them lie in front of it along the eye ray; else, for refractor `mesh`, it lies between the
// front face (the G-buffer) and the back face (the first pass) under it.
fn inside(mesh: u32, x: vec3<f32>) -> bool {
    if (settings.peeled == 0u) {
        return inside_refractor(mesh, x);
    }
    let q = project(x);
    if (!on_screen(q)) {
        return false;
    }
    let texel = texel_at(q, textureDimensions(layer_position));
    let z = view_depth(x);
    var crossings = 0u;
    for (var k = 0u; k < settings.peeled; k++) {
        let w = textureLoad(layer_position, texel, k, 0).w;
        if (w == 0.0 || w >= z) {
            break;
        }
        crossings++;
    }
    return crossings % 2u == 1u;
}

// The refractor's surface that a march crossed near `x`: the surface nearest in depth under
// it, of the peeled layers or else of the front and back faces; its normal turned along `d`.
fn crossed_surface(mesh: u32, x: vec3<f32>, d: vec3<f32>) -> Surface {
    let q = project(x);
    if (!on_screen(q)) {
        return Surface(false, vec3<f32>(0.0), vec3<f32>(0.0), false);
    }
    let z = view_depth(x);
    if (settings.peeled > 0u) {
        let texel = texel_at(q, textureDimensions(layer_position));
        var best = -1;
        var best_gap = 3.4e38;
        for (var k = 0u; k < settings.peeled; k++) {
            let w = textureLoad(layer_position, texel, k, 0).w;
            if (w == 0.0) {
                break;
            }
            if (abs(w - z) < best_gap) {
                best_gap = abs(w - z);
                best = i32(k);
            }
        }
        if (best < 0) {
            return Surface(false, vec3<f32>(0.0), vec3<f32>(0.0), false);
        }
        var n = textureLoad(layer_normal, texel, best, 0).xyz;
        let entering = dot(n, d) < 0.0;
        if (entering) {
            n = -n;
        }
        return Surface(true, textureLoad(layer_position, texel, best, 0).xyz, n, entering);
    }
    // The nearer of the two layers in depth is the one crossed.
    let g_texel = texel_at(q, textureDimensions(g_ids));
    let back = back_face(q, d);
    var use_front = !back.found;
    if (back.found && textureLoad(g_ids, g_texel, 0).x == mesh + 1u) {
        let z_front = view_depth(textureLoad(g_position, g_texel, 0).xyz);
        use_front = abs(z - z_front) < abs(z - view_depth(back.position));
    }
    if (use_front) {
        if (textureLoad(g_ids, g_texel, 0).x != mesh + 1u) {
            return Surface(false, vec3<f32>(0.0), vec3<f32>(0.0), false);
        }
        var n = textureLoad(g_normal, g_texel, 0).xyz;
        if (dot(n, d) < 0.0) {
            n = -n;
        }
        return Surface(true, textureLoad(g_position, g_texel, 0).xyz, n, false);
    }
    return back;
}

// Beyond the paper: marches the ray p + t·d (t up to `length`) in screen space until it
// crosses the refractor's surface into the state `to_inside`, refines the crossing by
// bisection and returns that surface. `leave_first`: the march must first be seen in the other
// state (a ray leaving the surface it starts on). Used to follow light reflected inside (§6's
// total internal reflection) and, with peeled layers, light entering the refractor again.
fn march(mesh: u32, p: vec3<f32>, d: vec3<f32>, length: f32, to_inside: bool, leave_first: bool) -> Surface {
    let steps = max(settings.inside_steps, 1u);
    var before_t = 0.0;
    var after_t = -1.0;
    var left = !leave_first;
    for (var i = 1u; i <= steps; i++) {
        let t = length * f32(i) / f32(steps);
        let state = inside(mesh, p + d * t);
        if (state != to_inside) {
            left = true;
        } else if (left) {
            after_t = t;
            break;
        }
        before_t = t;
    }
    if (after_t < 0.0) {
        return Surface(false, vec3<f32>(0.0), vec3<f32>(0.0), false);
    }
    for (var k = 0u; k < 6u; k++) {
        let mid = 0.5 * (before_t + after_t);
        if (inside(mesh, p + d * mid) == to_inside) {
            after_t = mid;
        } else {
            before_t = mid;
        }
    }
    return crossed_surface(mesh, p + d * after_t, d);
}

// Whether world point `x` lies between the refractor's front and back faces under it.
fn inside_refractor(mesh: u32, x: vec3<f32>) -> bool {
    let q = project(x);
    if (!on_screen(q)) {
        return false;
    }
    let g_texel = texel_at(q, textureDimensions(g_ids));
    if (textureLoad(g_ids, g_texel, 0).x != mesh + 1u) {
        return false;
    }
    let b_texel = texel_at(q, textureDimensions(back_ids));
    if (textureLoad(back_ids, b_texel, 0).x == 0u) {
        return false;
    }
    let z = view_depth(x);
    let z_front = view_depth(textureLoad(g_position, g_texel, 0).xyz);
    let z_back = view_depth(textureLoad(back_position, b_texel, 0).xyz);
    return z >= z_front && z <= z_back;
}

// Light that has left the refractor at `p` along `d`. With layers > 1, beyond the paper (§6's
// two-interface limit): where it enters a solid refractor again (another part of it, behind)
// it is refracted in there and out where it leaves, up to layers − 1 more pairs of
// interfaces, each found by marching the peeled layers; the light these interfaces reflect
// takes the cube map along its reflected direction. What goes on to the nearby geometry is
// returned, for the caller to look up.
// The light that goes on to the nearby geometry: from `p` along `d`, carrying `weight` of what
// it meets there, plus `color` already gathered on the way (from the cube map).
struct Onward {
    p: vec3<f32>,
    weight: f32,
    d: vec3<f32>,
    color: vec3<f32>,
};

fn onward(r: Reflector, mesh: u32, p_start: vec3<f32>, d_start: vec3<f32>, ior: f32) -> Onward {
    var p = p_start;
    var d = d_start;
    var weight = 1.0;
    var color = vec3<f32>(0.0);
    for (var k = 1u; k < settings.layers; k++) {
        let entry = march(mesh, p, d, settings.refractor_extent, true, true);
        // A crossing into the refractor must be through a surface facing the ray (its stored
        // normal against it) some way from where the ray left: else it is the surface just
        // left, seen through the textures' texels.
        if (!entry.found || !entry.entering || distance(entry.position, p) < 0.1 * r.radius) {
            break;
        }
        count(COUNT_REENTRIES);
        // entry.normal points along d, into the refractor. The light each extra interface
        // reflects takes the cube map along its reflected direction.
        let fresnel_in = fresnel_dielectric(dot(d, entry.normal), 1.0 / ior);
        color += weight * fresnel_in * env_along(r, entry.position, reflect(d, -entry.normal));
        weight *= 1.0 - fresnel_in;
        let t_in = refract(d, -entry.normal, 1.0 / ior);
        let exit = march(mesh, entry.position, t_in, settings.refractor_extent, false, false);
        var out_normal = -exit.normal;
        var fresnel_out = 0.0;
        if (exit.found) {
            fresnel_out = fresnel_dielectric(dot(t_in, exit.normal), ior);
            color += weight * fresnel_out * env_along(r, exit.position, reflect(t_in, out_normal));
        }
        if (!exit.found || fresnel_out >= 1.0) {
            count(COUNT_INTERNAL_NOT_RESOLVED);
            if (!exit.found) {
                color += weight * env_along(r, entry.position, t_in);
            }
            return Onward(p, 0.0, d, color);
        }
        weight *= 1.0 - fresnel_out;
        p = exit.position;
        d = refract(t_in, out_normal, ior);
    }
    return Onward(p, weight, d, color);
}

// Radiance of a ray inside the refractor, travelling `d`, that meets the surface `exit`:
// refracted out (Fresnel-weighted) to the nearby geometry; beyond the paper
// (`internal_reflection`), the part reflected inside (all of it under total internal
// reflection) followed once more to where it leaves. Both end in the nearby geometry through
// one loop (one copy of the lookup in the compiled shader). Without `internal_reflection`, as
// the paper's step F: all the light is refracted out, and under total internal reflection the
// paper's refract (Cg's, as WGSL's) gives the zero vector, which goes on as it is.
fn leave(r: Reflector, mesh: u32, exit: Surface, d: vec3<f32>, ior: f32) -> vec3<f32> {
    let exact_fresnel = fresnel_dielectric(dot(d, exit.normal), ior);
    let total = exact_fresnel >= 1.0;
    var fresnel = exact_fresnel;
    if (settings.internal_reflection == 0u) {
        fresnel = 0.0;
    }
    var color = vec3<f32>(0.0);
    var rays: array<Onward, 2>;
    rays[0] = Onward(exit.position, 0.0, d, vec3<f32>(0.0));
    rays[1] = rays[0];
    if (total && settings.internal_reflection == 0u) {
        count(COUNT_TIR_NOT_FOLLOWED);
        rays[0] = Onward(exit.position, 1.0, vec3<f32>(0.0), vec3<f32>(0.0));
    } else if (fresnel < 1.0) {
        let out = onward(r, mesh, exit.position, refract(d, -exit.normal, ior), ior);
        color += (1.0 - fresnel) * out.color;
        rays[0] = Onward(out.p, (1.0 - fresnel) * out.weight, out.d, vec3<f32>(0.0));
    } else {
        count(COUNT_TIR_FOLLOWED);
    }
    if (fresnel > 0.004) {
        let inner = reflect(d, -exit.normal);
        let next = march(mesh, exit.position, inner, 2.0 * r.radius, false, false);
        var fresnel_next = 1.0;
        if (next.found) {
            fresnel_next = fresnel_dielectric(dot(inner, next.normal), ior);
        }
        if (fresnel_next >= 1.0) {
            // Not resolved, or trapped again: the cube map along the last direction.
            count(COUNT_INTERNAL_NOT_RESOLVED);
            var at = exit.position;
            var towards = inner;
            if (next.found) {
                at = next.position;
                towards = reflect(inner, -next.normal);
            }
            color += fresnel * env_along(r, at, towards);
        } else {
            rays[1] = Onward(
                next.position,
                fresnel * (1.0 - fresnel_next),
                refract(inner, -next.normal, ior),
                vec3<f32>(0.0),
            );
        }
    }
    for (var k = 0u; k < 2u; k++) {
        if (rays[k].weight > 0.0) {
            color += rays[k].weight * nearby(r, rays[k].p, rays[k].d);
        }
    }
    return color;
}

// §3 A–F with §4's lookups: the radiance refracted through the solid at P1 for index `ior`.
fn refracted(r: Reflector, mesh: u32, pixel_q: vec3<f32>, p1: vec3<f32>, v: vec3<f32>, n1: vec3<f32>, d_n: f32, ior: f32) -> vec3<f32> {
    // A. T1.
    let t1 = refract(v, n1, 1.0 / ior);
    let theta_i = acos(clamp(-dot(v, n1), 0.0, 1.0));
    let theta_t = acos(clamp(-dot(t1, n1), 0.0, 1.0));
    // θt/θi → 1/n at normal incidence (Snell's law for small angles).
    var ratio = 1.0 / ior;
    if (theta_i > 1e-3) {
        ratio = theta_t / theta_i;
    }
    // B. d_V: from the front face to the back face under this pixel.
    let back_here = back_face(pixel_q, t1);
    var d_v = d_n;
    if (back_here.found && dot(back_here.position - p1, v) > 0.0) {
        d_v = length(back_here.position - p1);
    }
    var d_normal = d_n;
    if (d_normal < 0.0) {
        d_normal = d_v;
    }
    // C, D. d̃ and P̃2.
    let d_tilde = ratio * d_v + (1.0 - ratio) * d_normal;
    var p2 = p1 + t1 * d_tilde;
    // Beyond the paper: the back face's depth under P̃2 moves P̃2 along T1 to that depth, as
    // §4.3 iterates against the NG depth.
    let rate = dot(t1, camera.forward_world);
    if (abs(rate) > 0.05) {
        let z1 = view_depth(p1);
        for (var k = 0u; k < settings.exit_iterations; k++) {
            let b = back_face(project(p2), t1);
            if (!b.found) {
                break;
            }
            let t = (view_depth(b.position) - z1) / rate;
            if (t <= 0.0 || t > 4.0 * max(d_v, d_normal)) {
                break;
            }
            p2 = p1 + t1 * t;
        }
    }
    // E. N2 from the back-face texture where P̃2 projects.
    var exit = back_face(project(p2), t1);
    if (!exit.found) {
        count(COUNT_EXIT_OFF_BACK_FACES);
        exit = back_here;
        if (!exit.found) {
            // No back face at all (an open surface): leave as through a parallel face.
            exit = Surface(true, p2, -n1, false);
        }
    }
    // F (and §4): refract out and look up what the ray meets.
    return leave(r, mesh, Surface(true, p2, exit.normal, false), t1, ior);
}

@fragment
fn fs_shade(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.clip.xy);
    let s = specular_pixel(pixel);
    if (s.reflector < 0) {
        return s.base;
    }
    let r = reflectors[s.reflector];
    let mesh = s.mesh;
    let material = s.material;
    let p = s.p;
    let n = s.n;
    let v = s.v;
    let cos_i = -dot(v, n);
    let reflected = env_along(r, p, reflect(v, n));
    if (material.kind == MATERIAL_MIRROR) {
        var f = material.color;
        if ((material.flags & FLAG_FRESNEL) != 0u) {
            f = fresnel_schlick(material.color, cos_i);
        }
        return vec4<f32>(f * reflected, 1.0);
    }
    var ior = material.ior;
    if (settings.index_override > 0.0) {
        ior = vec3<f32>(settings.index_override);
    }
    let pixel_q = vec3<f32>(in.clip.xy / vec2<f32>(camera.width, camera.height), 1.0);
    var color = vec3<f32>(0.0);
    if ((material.flags & FLAG_THIN) != 0u) {
        // A thin sheet: the ray goes straight on, to the nearby geometry behind it.
        let straight = nearby(r, p, v);
        for (var c = 0u; c < 3u; c++) {
            let rs = thin_sheet_reflectance(cos_i, ior[c]);
            color[c] = rs * reflected[c] + (1.0 - rs) * straight[c];
        }
        return vec4<f32>(color, 1.0);
    }
    let d_n = interpolated_normal_distance(mesh, s.triangle, p);
    if (settings.dispersion == 0u) {
        ior = vec3<f32>(ior.y);
    }
    // Dispersion: one refracted path per colour channel; one for all three otherwise. (One
    // call site: the compiled shader holds one copy of the path.)
    var paths = 3u;
    if (ior.x == ior.y && ior.y == ior.z) {
        paths = 1u;
    }
    for (var c = 0u; c < paths; c++) {
        var rf = fresnel_dielectric(cos_i, 1.0 / ior[c]);
        if (settings.reflection == 0u) {
            rf = 0.0;
        }
        let through = rf * reflected + (1.0 - rf) * refracted(r, mesh, pixel_q, p, v, n, d_n, ior[c]);
        if (paths == 1u) {
            color = through;
        } else {
            color[c] = through[c];
        }
    }
    return vec4<f32>(color, 1.0);
}
