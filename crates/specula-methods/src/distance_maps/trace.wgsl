// distance-maps, steps 2 and 3: shades each reflector pixel of the G-buffer by tracing its
// secondary rays in the reflector's layered distance map (linear search per layer, secant
// search in each or in the nearest layer) and following the specular path to a diffuse surface.
// Prepended: optics.wgsl, camera.wgsl, scene.wgsl, cubemap.wgsl, specular_pixel.wgsl,
// codes.wgsl.

const OUTPUT_RADIANCE: u32 = 0u;
const OUTPUT_FIRST_HIT: u32 = 1u;
// First-hit output where the first secondary ray finds nothing.
const NO_HIT: f32 = -1.0e30;
const FAR: f32 = 3.0e38;

struct TraceSettings {
    // Layers per map.
    layers: u32,
    linear_steps: u32,
    secant_steps: u32,
    max_depth: u32,
    min_max: u32,
    // 1 when some dielectric has one index per channel: paths are then traced per channel.
    dispersive: u32,
    output: u32,
    // Texels per face side.
    resolution: f32,
    // 1: the search starts 2 / resolution of |x| along the ray; 0: at the paper's t.
    skip_start: u32,
    // 1: every layer's bracket is refined; 0: only the nearest overshoot's layer (the paper).
    refine_every_layer: u32,
    // 1: interpolation within one mesh and the cross-mesh bracket rule; 0: the paper's plain.
    per_mesh: u32,
    // 1: both branches at a dielectric; 0: the refracted one only (the paper).
    both_branches: u32,
    // 1: exact Fresnel terms at dielectrics; 0: Schlick's (the paper).
    exact_fresnel: u32,
    // 1: unresolved rays and cut branches take the map's estimate; 0: the background for a
    // missed ray, the path's weight for a cut one (the paper's Listing 17-5).
    estimate: u32,
    pad0: u32,
    pad1: u32,
};

// The paper's first linear-search parameter (Listing 17-1: t = 0.0001).
const PAPER_T_START: f32 = 0.0001;

// A reflector's map: its reference point, the index of its first layer (array layer of face f
// of layer j: (first_map + j) * 6 + f), and the distance beyond which the map holds nothing
// (its far plane: the whole scene lies within).
struct MapReflector {
    origin: vec3<f32>,
    first_map: u32,
    far: f32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

// Right, up and forward of a cube face, as the faces were rendered (raster::CUBE_FACES).
struct Face {
    right: vec4<f32>,
    up: vec4<f32>,
    forward: vec4<f32>,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> settings: TraceSettings;
@group(0) @binding(2) var g_color: texture_2d<f32>;
@group(0) @binding(3) var g_position: texture_2d<f32>;
@group(0) @binding(4) var g_normal: texture_2d<f32>;
@group(0) @binding(5) var g_ids: texture_2d<u32>;
@group(0) @binding(6) var map_material: texture_2d_array<f32>;
@group(0) @binding(7) var map_geometry: texture_2d_array<f32>;
@group(0) @binding(8) var<storage, read> reflectors: array<MapReflector>;
// Reflector index of each mesh, or -1.
@group(0) @binding(9) var<storage, read> mesh_reflector: array<i32>;
// (min, max) distance of each map as float bits; min > max for an empty one.
@group(0) @binding(10) var<storage, read> ranges: array<u32>;
@group(0) @binding(11) var<storage, read> faces: array<Face, 6>;
// Fallbacks taken this frame: rays the search did not resolve (found no surface where the
// map holds one), branches cut at max_depth,
// branches with no room on the stack (FALLBACK_*).
@group(0) @binding(12) var<storage, read_write> fallbacks: array<atomic<u32>, 3>;

// Where direction `d` falls in map `map`: array layer, the top-left texel of its bilinear
// footprint, and the weights within it.
struct Footprint {
    layer: i32,
    corner: vec2<i32>,
    weights: vec4<f32>,
    nearest: u32,
};

fn footprint(map: u32, d: vec3<f32>) -> Footprint {
    let face = cube_face(d);
    let f = faces[face];
    let z = dot(f.forward.xyz, d);
    let uv = vec2<f32>(0.5 + 0.5 * dot(f.right.xyz, d) / z, 0.5 - 0.5 * dot(f.up.xyz, d) / z);
    let texel = uv * settings.resolution - 0.5;
    let base = floor(texel);
    let w = texel - base;
    var fp: Footprint;
    fp.layer = i32(map * 6u + face);
    fp.corner = vec2<i32>(base);
    fp.weights = vec4<f32>((1.0 - w.x) * (1.0 - w.y), w.x * (1.0 - w.y), (1.0 - w.x) * w.y, w.x * w.y);
    fp.nearest = u32(select(0, 1, w.x >= 0.5)) + u32(select(0, 2, w.y >= 0.5));
    return fp;
}

// Texel `i` (0..3: top-left, top-right, bottom-left, bottom-right) of a footprint, clamped to
// the face (a lookup beside a face edge reuses the edge texels).
fn footprint_texel(fp: Footprint, i: u32) -> vec2<i32> {
    let size = i32(settings.resolution);
    let offset = vec2<i32>(i32(i & 1u), i32(i >> 1u));
    return clamp(fp.corner + offset, vec2<i32>(0), vec2<i32>(size - 1));
}

// Whether texel `geometry` enters the interpolation of a lookup whose nearest texel shows
// `nearest_mesh`: any visible texel (plain), or one of the same mesh (so that a silhouette does
// not blend two objects into a surface between them).
fn interpolated(geometry: vec4<f32>, nearest_mesh: f32) -> bool {
    return geometry.w > 0.0 && (settings.per_mesh == 0u || geometry.z == nearest_mesh);
}

// What the map stores in a direction: |l'|, bilinear over the footprint's texels `interpolated`
// admits, and the nearest texel's mesh (index + 1). Distance -1 where the nearest texel sees
// nothing.
struct Stored {
    distance: f32,
    mesh: f32,
};

fn map_distance(map: u32, d: vec3<f32>) -> Stored {
    let fp = footprint(map, d);
    let nearest = textureLoad(map_geometry, footprint_texel(fp, fp.nearest), fp.layer, 0);
    var stored: Stored;
    stored.distance = -1.0;
    stored.mesh = nearest.z;
    if (nearest.w <= 0.0) {
        return stored;
    }
    var sum = 0.0;
    var total = 0.0;
    for (var i = 0u; i < 4u; i++) {
        let texel = textureLoad(map_geometry, footprint_texel(fp, i), fp.layer, 0);
        if (interpolated(texel, nearest.z)) {
            sum += fp.weights[i] * texel.w;
            total += fp.weights[i];
        }
    }
    stored.distance = sum / total;
    return stored;
}

// The surface a map shows in direction `d`: material and code of the nearest texel; diffuse
// radiance and the normal interpolated over the footprint's texels `interpolated` admits.
struct MapSurface {
    rgb: vec3<f32>,
    code: f32,
    normal: vec3<f32>,
};

fn map_surface(map: u32, d: vec3<f32>) -> MapSurface {
    let fp = footprint(map, d);
    let nearest_xy = footprint_texel(fp, fp.nearest);
    let nearest = textureLoad(map_material, nearest_xy, fp.layer, 0);
    let nearest_mesh = textureLoad(map_geometry, nearest_xy, fp.layer, 0).z;
    var rgb = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var total = 0.0;
    for (var i = 0u; i < 4u; i++) {
        let xy = footprint_texel(fp, i);
        let material = textureLoad(map_material, xy, fp.layer, 0);
        let geometry = textureLoad(map_geometry, xy, fp.layer, 0);
        if (interpolated(geometry, nearest_mesh)) {
            rgb += fp.weights[i] * material.xyz;
            normal += fp.weights[i] * octahedral_decode(geometry.xy);
            total += fp.weights[i];
        }
    }
    var s: MapSurface;
    s.code = nearest.w;
    // Material constants (F0) are not interpolated.
    s.rgb = select(nearest.xyz, rgb / max(total, 1e-8), nearest.w == CODE_DIFFUSE);
    s.normal = normalize(normal);
    return s;
}

// The part [d0, d1] of the ray x + R d (|R| = 1, from d_start on) worth marching in layer `map`:
// up to where it leaves the map's far sphere; with min-max acceleration, only between the
// spheres of the layer's smallest and largest distance. d1 < d0 when there is none. The far end
// is a real sample behind everything, which closes the bracket of a hit on far geometry (the
// ray's end at infinity cannot be sampled).
fn marched_range(map: u32, far: f32, x: vec3<f32>, r: vec3<f32>, d_start: f32) -> vec2<f32> {
    var r_min = 0.0;
    var r_max = far;
    if (settings.min_max == 1u) {
        r_min = bitcast<f32>(ranges[2u * map]) * 0.9999;
        r_max = bitcast<f32>(ranges[2u * map + 1u]) * 1.0001;
    }
    if (r_min > r_max) {
        return vec2<f32>(1.0, 0.0);
    }
    let b = dot(x, r);
    let xx = dot(x, x);
    let disc_max = b * b - (xx - r_max * r_max);
    if (disc_max < 0.0) {
        return vec2<f32>(1.0, 0.0);
    }
    var d0 = max(d_start, -b - sqrt(disc_max));
    let d1 = -b + sqrt(disc_max);
    if (xx < r_min * r_min) {
        // Nothing is nearer than r_min: skip to where the ray leaves that sphere.
        d0 = max(d0, -b + sqrt(max(b * b - (xx - r_min * r_min), 0.0)));
    }
    return vec2<f32>(d0, d1);
}

// An undershooting (|l| < |l'|) and an overshooting ray parameter, consecutive along the
// search: the ray crosses the layer between them.
struct Bracket {
    found: bool,
    // Whether the secant search may refine it: with per-mesh interpolation, only where both
    // samples show the same mesh. Where they do not, the ray went from in front of one object
    // to behind another at a silhouette (it met the second one, or something hidden behind the
    // first): the map holds no surface between them to refine on, and the overshooting sample
    // is taken as the hit. The other way round is no hit. With plain interpolation every
    // bracket is refined, as the paper's.
    refinable: bool,
    dl: f32,
    llp: f32,
    dp: f32,
    ppp: f32,
};

// The paper's linear search, marching uniformly in texture space: the points r'(t) = s (1 - t)
// + e t between the projections s and e of the ray's start and end on the unit sphere map to ray
// parameters d = a t / (1 - t), a = |x| / |R|. The step count follows the texels the segment
// spans, at most `linear_steps`.
fn linear_search(map: u32, x: vec3<f32>, r: vec3<f32>, range: vec2<f32>) -> Bracket {
    let a = max(length(x), 1e-6);
    let t0 = range.x / (range.x + a);
    let t1 = range.y / (range.y + a);
    let texels = length(r - x / a) * (t1 - t0) * settings.resolution * 0.5;
    let steps = clamp(u32(ceil(texels)), 1u, settings.linear_steps);
    let dt = (t1 - t0) / f32(steps);
    var b: Bracket;
    var undershoot = false;
    var overshoot = false;
    var mesh = 0.0;
    for (var i = 0u; i <= steps; i++) {
        let t = t0 + dt * f32(i);
        let d = a * t / (1.0 - t);
        let p = x + r * d;
        let stored = map_distance(map, p);
        if (stored.distance > 0.0) {
            let ratio = length(p) / stored.distance;
            if (ratio < 1.0) {
                b.dl = d;
                b.llp = ratio;
                undershoot = true;
            } else {
                b.dp = d;
                b.ppp = ratio;
                overshoot = true;
            }
            if (undershoot && overshoot && settings.per_mesh == 0u) {
                // The paper's: the first consecutive undershooting and overshooting pair.
                b.found = true;
                b.refinable = true;
                return b;
            }
            if (undershoot && overshoot) {
                b.refinable = stored.mesh == mesh;
                // Between two meshes, a crossing needs the ray to pass the second one's distance
                // while stepping onto it: from in front of it (the undershooting point is nearer
                // than the second mesh here) to behind it. A ray that was already behind it went
                // round its silhouette; one that comes out from behind an object in front of
                // another met nothing. Either way, start over from here.
                let crossed = ratio >= 1.0 && length(x + r * b.dl) < stored.distance;
                if (b.refinable || crossed) {
                    b.found = true;
                    return b;
                }
                undershoot = ratio < 1.0;
                overshoot = ratio >= 1.0;
            }
            mesh = stored.mesh;
        } else {
            // Nothing visible: restart.
            undershoot = false;
            overshoot = false;
        }
    }
    return b;
}

struct Hit {
    found: bool,
    map: u32,
    d: f32,
};

// The secant search from a bracket: the ray parameter where it meets the layer, exact for a
// planar surface in one step. Without a refinable bracket (a silhouette between two meshes, or
// no secant steps), the overshooting sample.
fn secant_search(map: u32, x: vec3<f32>, r: vec3<f32>, bracket: Bracket) -> f32 {
    var dl = bracket.dl;
    var llp = bracket.llp;
    var dp = bracket.dp;
    var ppp = bracket.ppp;
    var d = dp;
    let steps = select(0u, settings.secant_steps, bracket.refinable);
    for (var i = 0u; i < steps; i++) {
        d = dl + (dp - dl) * (1.0 - llp) / (ppp - llp);
        let p = x + r * d;
        let stored = map_distance(map, p);
        if (stored.distance <= 0.0) {
            break;
        }
        let ratio = length(p) / stored.distance;
        if (ratio < 0.9999) {
            llp = ratio;
            dl = d;
        } else if (ratio > 1.0001) {
            ppp = ratio;
            dp = d;
        } else {
            break;
        }
    }
    return d;
}

// Hit(): the linear search in every layer of the reflector's map. The paper refines only the
// layer with the nearest overshooting sample; with `refine_every_layer` every layer's bracket
// is refined by the secant search and the nearest refined hit wins (where the marching steps
// are long, as on rays leaving near the reference point, the nearest overshooting sample can
// lie beyond another layer's hit).
fn trace_ray(reflector: MapReflector, x: vec3<f32>, r: vec3<f32>) -> Hit {
    // Skipping a texel's width (at the start point's distance) keeps the interpolated copy of
    // the surface the ray leaves from being taken for a hit; the paper starts at t = 0.0001.
    let a = length(x);
    let d_start = select(a * PAPER_T_START / (1.0 - PAPER_T_START), a * 2.0 / settings.resolution, settings.skip_start == 1u);
    var best: Hit;
    best.d = FAR;
    var nearest: Bracket;
    var nearest_map = 0u;
    var nearest_dp = FAR;
    for (var j = 0u; j < settings.layers; j++) {
        let map = reflector.first_map + j;
        let range = marched_range(map, reflector.far, x, r, d_start);
        if (range.y <= range.x) {
            continue;
        }
        let bracket = linear_search(map, x, r, range);
        if (!bracket.found) {
            continue;
        }
        if (settings.refine_every_layer == 0u) {
            if (bracket.dp < nearest_dp) {
                nearest_dp = bracket.dp;
                nearest = bracket;
                nearest_map = map;
            }
            continue;
        }
        let d = secant_search(map, x, r, bracket);
        if (d < best.d) {
            best.found = true;
            best.map = map;
            best.d = d;
        }
    }
    if (nearest_dp < FAR) {
        best.found = true;
        best.map = nearest_map;
        best.d = secant_search(nearest_map, x, r, nearest);
    }
    return best;
}

// A specular path's branch, waiting to be traced: leaving the point x (relative to the map's
// reference point) along `dir` with `weight`, after `depth` bounces.
struct Branch {
    x: vec3<f32>,
    dir: vec3<f32>,
    weight: vec3<f32>,
    depth: u32,
};

// Branches waiting per pixel. A dielectric splits a path in two; with the weight cut-off
// below, a glass object rarely needs more than four at once.
const STACK_SIZE: u32 = 8u;
// Branches carrying less than this share of the pixel's radiance are not traced (the
// reference traces them; at 0.4 % they are below an 8-bit step of a bright pixel).
const MIN_BRANCH_WEIGHT: f32 = 0.004;

// Where the counters of fallbacks are (counters[i], atomic).
const FALLBACK_MISSED: u32 = 0u;
const FALLBACK_DEPTH: u32 = 1u;
const FALLBACK_STACK: u32 = 2u;

var<private> stack: array<Branch, STACK_SIZE>;
var<private> stack_top: u32;

// The light leaving a specular surface splits into up to two branches: (direction, weight).
struct Split {
    count: u32,
    dir0: vec3<f32>,
    weight0: vec3<f32>,
    dir1: vec3<f32>,
    weight1: vec3<f32>,
};

// The branches of a path arriving along `dir` at a surface with `normal` and (rgb, code)
// `surface`: a mirror reflects (Schlick's Fresnel or exactly F0, as the reference); a
// dielectric reflects and refracts (all reflected under total internal reflection), a thin
// sheet reflects and passes straight through. The Fresnel terms at a dielectric are exact, or
// Schlick's with the incident angle on either side (the paper's Listing 17-5); with only the
// refracted branch (the paper's), the first branch is the refracted (or totally reflected) one.
fn split_at(dir: vec3<f32>, normal: vec3<f32>, surface: vec4<f32>, channel: u32) -> Split {
    var out: Split;
    let code = surface.w;
    let cos_v = abs(dot(normal, dir));
    if (code < 0.0) {
        out.count = 1u;
        out.dir0 = reflect(dir, normal);
        out.weight0 = select(surface.xyz, fresnel_schlick(surface.xyz, cos_v), code == CODE_MIRROR_SCHLICK);
        return out;
    }
    let iors = ior_from_f0(surface.xyz);
    let ior = select(iors[min(channel, 2u)], iors.y, channel == 3u);
    let branches = select(1u, 2u, settings.both_branches == 1u);
    let schlick = fresnel_schlick(surface.xyz, cos_v);
    if (code > THIN_OFFSET) {
        let sheet = select(2.0 * schlick / (1.0 + schlick), vec3<f32>(thin_sheet_reflectance(cos_v, ior)), settings.exact_fresnel == 1u);
        out.count = branches;
        out.dir0 = dir;
        out.weight0 = 1.0 - sheet;
        out.dir1 = reflect(dir, normal);
        out.weight1 = sheet;
        return out;
    }
    // The stored normal points out of the solid: a ray along it is leaving.
    var n_in = normal;
    var eta = 1.0 / ior;
    if (dot(dir, normal) > 0.0) {
        n_in = -normal;
        eta = ior;
    }
    let exact = fresnel_dielectric(cos_v, eta);
    let t = refract(dir, n_in, eta);
    let total = select(dot(t, t) == 0.0, exact >= 1.0, settings.exact_fresnel == 1u);
    let f = select(schlick, vec3<f32>(exact), settings.exact_fresnel == 1u);
    let r = reflect(dir, n_in);
    if (total) {
        out.count = 1u;
        out.dir0 = r;
        out.weight0 = vec3<f32>(1.0);
        return out;
    }
    out.count = branches;
    out.dir0 = t;
    out.weight0 = 1.0 - f;
    out.dir1 = r;
    out.weight1 = f;
    return out;
}

fn push(x: vec3<f32>, dir: vec3<f32>, weight: vec3<f32>, depth: u32) -> bool {
    // The cut-off belongs to the branching: the paper's single path is followed to its end.
    if (settings.both_branches == 1u && max(weight.x, max(weight.y, weight.z)) < MIN_BRANCH_WEIGHT) {
        return true;
    }
    if (stack_top == STACK_SIZE) {
        return false;
    }
    stack[stack_top] = Branch(x, dir, weight, depth);
    stack_top += 1u;
    return true;
}

// What a ray the search found nothing for meets. A ray that leaves the scene meets the
// background: where it leaves the map's far sphere, the map holds no diffuse surface.
// Otherwise the search missed a surface (a step over a thin object, a layer that lacks the
// surface): the best estimate the map has is the farthest diffuse surface it holds towards
// that exit point (an environment-map lookup there, off by parallax for near surfaces);
// `missed` says which.
struct Estimate {
    rgb: vec3<f32>,
    missed: bool,
};

fn estimate(reflector: MapReflector, x: vec3<f32>, r: vec3<f32>) -> Estimate {
    let b = dot(x, r);
    let exit = x + r * (-b + sqrt(max(b * b - (dot(x, x) - reflector.far * reflector.far), 0.0)));
    var out: Estimate;
    out.rgb = background_radiance(r);
    out.missed = false;
    for (var k = 0u; k < settings.layers; k++) {
        let map = reflector.first_map + settings.layers - 1u - k;
        if (map_distance(map, exit).distance > 0.0) {
            // Only a diffuse surface says the search missed something: mirror and glass
            // surfaces (the reflector's own, which surrounds its reference point) are what the
            // ray left.
            let s = map_surface(map, exit);
            if (s.code == CODE_DIFFUSE) {
                out.rgb = s.rgb;
                out.missed = true;
                return out;
            }
        }
    }
    return out;
}

// The first secondary ray's hit, for output=first-hit.
fn first_hit(reflector: MapReflector, p_world: vec3<f32>, v: vec3<f32>, n: vec3<f32>, first: vec4<f32>) -> vec3<f32> {
    let x = p_world - reflector.origin;
    let branches = split_at(v, n, first, 3u);
    let hit = trace_ray(reflector, x, branches.dir0);
    return select(vec3<f32>(NO_HIT), reflector.origin + x + branches.dir0 * hit.d, hit.found);
}

// The radiance a branch cut at `l` (at max_depth or over the stack) takes for what it would
// see along `dir`: the map's estimate, or (estimate = 0) 1, as the paper's Listing 17-5 returns
// its path's product of Fresnel factors, with no radiance, when the depth runs out.
fn cut_radiance(reflector: MapReflector, l: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    if (settings.estimate == 0u) {
        return vec3<f32>(1.0);
    }
    return estimate(reflector, l, dir).rgb;
}

// Radiance arriving at the eye along the specular paths that start at `p_world` (seen along
// unit `v`, normal `n` facing the eye, surface `first` as (rgb, code)). `channel` 0..2 traces
// one colour channel's index of refraction, 3 all channels with the green one. Every branch
// is followed (both at a dielectric, or the refracted one only) until it meets a diffuse
// surface, up to `max_depth` bounces; a ray the search cannot resolve takes the map's
// estimate (or the background), a branch at the depth limit and one with no room left
// `cut_radiance`; each counted.
fn trace_paths(reflector: MapReflector, p_world: vec3<f32>, v: vec3<f32>, n: vec3<f32>, first: vec4<f32>, channel: u32) -> vec3<f32> {
    var color = vec3<f32>(0.0);
    let x0 = p_world - reflector.origin;
    stack_top = 0u;
    let s0 = split_at(v, n, first, channel);
    push(x0, s0.dir0, s0.weight0, 0u);
    if (s0.count == 2u) {
        push(x0, s0.dir1, s0.weight1, 0u);
    }
    // Every branch pops once; the bound only guards the loop.
    for (var guard = 0u; guard < 64u && stack_top > 0u; guard++) {
        stack_top -= 1u;
        let b = stack[stack_top];
        let hit = trace_ray(reflector, b.x, b.dir);
        if (!hit.found) {
            let e = estimate(reflector, b.x, b.dir);
            if (e.missed) {
                atomicAdd(&fallbacks[FALLBACK_MISSED], 1u);
            }
            color += b.weight * select(background_radiance(b.dir), e.rgb, settings.estimate == 1u);
            continue;
        }
        let l = b.x + b.dir * hit.d;
        let s = map_surface(hit.map, l);
        if (s.code == CODE_DIFFUSE) {
            color += b.weight * s.rgb;
            continue;
        }
        let next = split_at(b.dir, s.normal, vec4<f32>(s.rgb, s.code), channel);
        if (b.depth + 1u >= settings.max_depth) {
            atomicAdd(&fallbacks[FALLBACK_DEPTH], 1u);
            if (settings.estimate == 0u) {
                // Listing 17-5 stops before the cut surface's Fresnel factor.
                color += b.weight;
                continue;
            }
            color += b.weight * next.weight0 * cut_radiance(reflector, l, next.dir0);
            if (next.count == 2u) {
                color += b.weight * next.weight1 * cut_radiance(reflector, l, next.dir1);
            }
            continue;
        }
        if (!push(l, next.dir0, b.weight * next.weight0, b.depth + 1u)) {
            atomicAdd(&fallbacks[FALLBACK_STACK], 1u);
            color += b.weight * next.weight0 * cut_radiance(reflector, l, next.dir0);
        }
        if (next.count == 2u && !push(l, next.dir1, b.weight * next.weight1, b.depth + 1u)) {
            atomicAdd(&fallbacks[FALLBACK_STACK], 1u);
            color += b.weight * next.weight1 * cut_radiance(reflector, l, next.dir1);
        }
    }
    return color;
}

@fragment
fn fs_shade(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.clip.xy);
    let s = specular_pixel(pixel);
    if (s.reflector < 0) {
        return s.base;
    }
    let reflector = reflectors[s.reflector];
    let material = s.material;
    let first = specular_code(material);
    let p = s.p;
    let n = s.n;
    let v = s.v;
    if (settings.output == OUTPUT_FIRST_HIT) {
        return vec4<f32>(first_hit(reflector, p, v, n, first), 1.0);
    }
    if (!(material.kind == MATERIAL_DIELECTRIC && settings.dispersive == 1u)) {
        return vec4<f32>(trace_paths(reflector, p, v, n, first, 3u), 1.0);
    }
    var color = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        color[c] = trace_paths(reflector, p, v, n, first, c)[c];
    }
    return vec4<f32>(color, 1.0);
}
