// c3rc's forward phase on the GPU (`projection=gpu`): the points of every (camera, leaf) pair
// the CPU's backward phase found, projected with the camera (the cubic, every valid root) and
// splatted as on the CPU (phases.rs): nearest push-back depth first, then within a depth band
// the splat whose centre is nearest the pixel's; one-pixel holes filled (each step as the
// camera's switches and the host's dispatches say, as on the CPU). The per-vertex colour
// of small and self-seeing triangles is the CPU's, already in `near` (alpha -1, taken as it
// is by the shading pass): kept.
//
// Arithmetic is f32, in each camera's own frame: origin at its first vertex, scaled by its
// longest edge, so the cubic's coefficients stay near 1 for the points it can see.

struct Settings {
    eye: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    forward: vec4<f32>,
    // tan(fov_y / 2), aspect, splat_scale, max_splat
    lens: vec4<f32>,
    width: u32,
    height: u32,
    work_items: u32,
    // Work items per row of the 2D dispatch.
    row: u32,
};

struct Point {
    // Loaded pose; w: the point's cloud.
    p: vec4<f32>,
    // Normal; w: the cloud's splat radius (metres, scale 1).
    n: vec4<f32>,
    color: vec4<f32>,
};

struct Camera {
    // Vertices relative to v0 and scaled by `frame.w`; xyz of v0 in `frame`.
    v: array<vec4<f32>, 3>,
    d: array<vec4<f32>, 3>,
    // World v0 (xyz) and the scale: the longest base edge, metres (w).
    frame: vec4<f32>,
    // Plane bound in world space: n·x ≥ w.
    planes: array<vec4<f32>, 4>,
    // screen area (pixels²), obliquity, base area (world), fixed splat half-size in pixels
    // (0: each splat sized to its footprint)
    info: vec4<f32>,
    // mesh, splat every valid projection (it can project twice, and multiple projections are
    // wanted), one-sided points, resolve within a depth band (else the nearest depth alone)
    ids: vec4<u32>,
};

@group(0) @binding(0) var<uniform> settings: Settings;
@group(0) @binding(1) var<storage, read> points: array<Point>;
@group(0) @binding(2) var<storage, read> clouds: array<mat4x4<f32>>;
@group(0) @binding(3) var<storage, read> cameras: array<Camera>;
// (camera, first point, point count, stride) per visible leaf of each camera: every
// stride-th point is projected, its splat grown to stand for the others (level of detail).
@group(0) @binding(4) var<storage, read> work: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read_write> depth: array<atomic<u32>>;
// (squared distance to the splat's centre, quantised) << 24 | point index.
@group(0) @binding(6) var<storage, read_write> nearest: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> near: array<vec4<f32>>;
@group(0) @binding(8) var g_position: texture_2d<f32>;
@group(0) @binding(9) var g_ids: texture_2d<u32>;
// (points in leaves, points projected, valid projections, splats)
@group(0) @binding(10) var<storage, read_write> counts: array<atomic<u32>, 4>;
// 1 for each mesh that is a mirror c3rc draws.
@group(0) @binding(11) var<storage, read> mirror_meshes: array<u32>;

const EMPTY: u32 = 0xffffffffu;
const BARY_EPS: f32 = 1e-5;

fn cubic_roots(c: vec4<f32>) -> array<f32, 4> {
    // Returns up to three real roots in [0..2] and their count in [3].
    var out = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    let scale = max(max(abs(c.x), abs(c.y)), max(abs(c.z), abs(c.w)));
    if (scale == 0.0) {
        return out;
    }
    let k = c / scale;
    var n = 0u;
    if (abs(k.w) > 1e-6) {
        let a = k.z / k.w;
        let b = k.y / k.w;
        let cc = k.x / k.w;
        let p = b - a * a / 3.0;
        let q = 2.0 * a * a * a / 27.0 - a * b / 3.0 + cc;
        let shift = -a / 3.0;
        let disc = q * q / 4.0 + p * p * p / 27.0;
        if (disc > 0.0) {
            let s = sqrt(disc);
            let u = sign(-q / 2.0 + s) * pow(abs(-q / 2.0 + s), 1.0 / 3.0);
            let v = sign(-q / 2.0 - s) * pow(abs(-q / 2.0 - s), 1.0 / 3.0);
            out[0] = u + v + shift;
            n = 1u;
        } else if (p == 0.0) {
            out[0] = shift;
            n = 1u;
        } else {
            let r = sqrt(-p / 3.0);
            let phi = acos(clamp(-q / (2.0 * r * r * r), -1.0, 1.0));
            for (var i = 0u; i < 3u; i++) {
                out[i] = 2.0 * r * cos((phi + 6.283185307 * f32(i)) / 3.0) + shift;
            }
            n = 3u;
        }
    } else if (abs(k.z) > 1e-6) {
        let disc = k.y * k.y - 4.0 * k.z * k.x;
        if (disc >= 0.0) {
            let s = sqrt(disc);
            var qq = -0.5 * (k.y + select(-s, s, k.y >= 0.0));
            if (qq != 0.0) {
                out[0] = qq / k.z;
                out[1] = k.x / qq;
                n = 2u;
            }
        }
    } else if (abs(k.y) > 1e-6) {
        out[0] = -k.x / k.y;
        n = 1u;
    }
    for (var i = 0u; i < n; i++) {
        var x = out[i];
        for (var it = 0; it < 2; it++) {
            let f = ((k.w * x + k.z) * x + k.y) * x + k.x;
            let df = (3.0 * k.w * x + 2.0 * k.z) * x + k.y;
            if (df != 0.0) {
                x = x - f / df;
            }
        }
        out[i] = x;
    }
    out[3] = f32(n);
    return out;
}

fn det3(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return dot(a, cross(b, c));
}

// Pixel position (x, y) and view depth of a world point; z ≤ 0 behind the eye.
fn to_screen(p: vec3<f32>) -> vec3<f32> {
    let v = p - settings.eye.xyz;
    let z = dot(v, settings.forward.xyz);
    let x = dot(v, settings.right.xyz) / (z * settings.lens.x * settings.lens.y);
    let y = dot(v, settings.up.xyz) / (z * settings.lens.x);
    return vec3<f32>((x + 1.0) * 0.5 * f32(settings.width), (1.0 - y) * 0.5 * f32(settings.height), z);
}

struct Splat {
    x: f32,
    y: f32,
    radius: f32,
    depth: f32,
    band: f32,
    reach: f32,
    p_world: vec3<f32>,
};

// The valid projections of point `index` by camera `camera`, as splats; returns how many.
fn project(camera: Camera, index: u32, stride: u32, count_it: bool, splats: ptr<function, array<Splat, 3>>) -> u32 {
    let point = points[index];
    let cloud = u32(point.p.w);
    let m = clouds[cloud];
    let q_world = (m * vec4<f32>(point.p.xyz, 1.0)).xyz;
    let n_world = normalize((m * vec4<f32>(point.n.xyz, 0.0)).xyz);
    for (var i = 0; i < 4; i++) {
        let plane = camera.planes[i];
        if (dot(plane.xyz, q_world) < plane.w) {
            return 0u;
        }
    }
    let scale = camera.frame.w;
    let v0 = camera.frame.xyz;
    let q = (q_world - v0) / scale;
    let v = array<vec3<f32>, 3>(camera.v[0].xyz, camera.v[1].xyz, camera.v[2].xyz);
    let d = array<vec3<f32>, 3>(camera.d[0].xyz, camera.d[1].xyz, camera.d[2].xyz);
    let one_sided = camera.ids.z != 0u;
    if (one_sided && dot(n_world, v[0] - q) <= 0.0 && dot(n_world, v[1] - q) <= 0.0 && dot(n_world, v[2] - q) <= 0.0) {
        return 0u;
    }
    if (count_it) {
        atomicAdd(&counts[1], 1u);
    }
    let a1 = v[0] - q;
    let a2 = v[1] - q;
    let a3 = v[2] - q;
    let c = vec4<f32>(
        det3(a1, a2, a3),
        det3(d[0], a2, a3) + det3(a1, d[1], a3) + det3(a1, a2, d[2]),
        det3(d[0], d[1], a3) + det3(d[0], a2, d[2]) + det3(a1, d[1], d[2]),
        det3(d[0], d[1], d[2]),
    );
    let roots = cubic_roots(c);
    var count = 0u;
    let radius_world = point.n.w * settings.lens.z * sqrt(f32(stride));
    for (var r = 0u; r < u32(roots[3]); r++) {
        let lambda = max(roots[r], 0.0);
        if (roots[r] < -1e-4) {
            continue;
        }
        let w1 = v[0] + d[0] * lambda;
        let w2 = v[1] + d[1] * lambda;
        let w3 = v[2] + d[2] * lambda;
        let nn = cross(w2 - w1, w3 - w1);
        let len2 = dot(nn, nn);
        if (len2 <= 0.0) {
            continue;
        }
        let b1 = dot(cross(w2 - q, w3 - q), nn) / len2;
        let b2 = dot(cross(w3 - q, w1 - q), nn) / len2;
        let b3 = 1.0 - b1 - b2;
        if (min(b1, min(b2, b3)) < -BARY_EPS || max(b1, max(b2, b3)) > 1.0 + BARY_EPS) {
            continue;
        }
        if (count_it) {
            atomicAdd(&counts[2], 1u);
        }
        let base_local = v[0] * b1 + v[1] * b2 + v[2] * b3;
        if (one_sided && dot(n_world, base_local - q) <= 0.0) {
            continue;
        }
        let p_world = v0 + base_local * scale;
        let screen = to_screen(p_world);
        if (screen.z <= 1e-6) {
            continue;
        }
        // Cross-section of the sweeping triangle at λ against the base's screen area.
        let section = 0.5 * sqrt(len2) * scale * scale;
        let r_px = radius_world * sqrt(camera.info.x / max(section, 1e-30));
        let radius = select(clamp(r_px, 0.5, settings.lens.w), camera.info.w, camera.info.w > 0.0);
        let depth = length(q - base_local) * scale;
        let footprint = 2.0 * screen.z * settings.lens.x / f32(settings.height);
        (*splats)[count] = Splat(
            screen.x,
            screen.y,
            radius,
            depth,
            select(0.0, 2.0 * radius_world + 0.01 * depth, camera.ids.w != 0u),
            (radius + 1.5) * footprint * camera.info.y,
            p_world,
        );
        count++;
        if (camera.ids.y == 0u) {
            break;
        }
    }
    return count;
}

// The pixel index of the `i`-th pixel of the splat's square if it shows the splat's surface,
// else EMPTY; `d2` gets the squared distance to the centre.
fn splat_pixel(s: Splat, mesh: u32, i: i32, side: i32, d2: ptr<function, f32>) -> u32 {
    let x0 = i32(floor(s.x - s.radius));
    let y0 = i32(floor(s.y - s.radius));
    let px = x0 + i % side;
    let py = y0 + i / side;
    if (px < 0 || py < 0 || px >= i32(settings.width) || py >= i32(settings.height)) {
        return EMPTY;
    }
    let dx = f32(px) + 0.5 - s.x;
    let dy = f32(py) + 0.5 - s.y;
    if (abs(dx) > s.radius || abs(dy) > s.radius) {
        return EMPTY;
    }
    let pixel = vec2<i32>(px, py);
    if (textureLoad(g_ids, pixel, 0).x != mesh + 1u) {
        return EMPTY;
    }
    if (length(textureLoad(g_position, pixel, 0).xyz - s.p_world) > s.reach) {
        return EMPTY;
    }
    *d2 = dx * dx + dy * dy;
    return u32(py) * settings.width + u32(px);
}

fn work_item(group: vec3<u32>) -> u32 {
    return group.y * settings.row + group.x;
}

@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k < settings.width * settings.height) {
        atomicStore(&depth[k], EMPTY);
        atomicStore(&nearest[k], EMPTY);
    }
}

@compute @workgroup_size(64)
fn splat_depth(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let w = work_item(group);
    if (w >= settings.work_items) {
        return;
    }
    let item = work[w];
    let camera = cameras[item.x];
    if (lane == 0u) {
        atomicAdd(&counts[0], item.z);
    }
    for (var k = lane * item.w; k < item.z; k += 64u * item.w) {
        var splats: array<Splat, 3>;
        let n = project(camera, item.y + k, item.w, true, &splats);
        for (var s = 0u; s < n; s++) {
            atomicAdd(&counts[3], 1u);
            let splat = splats[s];
            let side = i32(ceil(splat.x + splat.radius)) - i32(floor(splat.x - splat.radius));
            for (var i = 0; i < side * side; i++) {
                var d2 = 0.0;
                let pixel = splat_pixel(splat, camera.ids.x, i, side, &d2);
                if (pixel != EMPTY) {
                    atomicMin(&depth[pixel], bitcast<u32>(splat.depth));
                }
            }
        }
    }
}

@compute @workgroup_size(64)
fn splat_nearest(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let w = work_item(group);
    if (w >= settings.work_items) {
        return;
    }
    let item = work[w];
    let camera = cameras[item.x];
    for (var k = lane * item.w; k < item.z; k += 64u * item.w) {
        var splats: array<Splat, 3>;
        let n = project(camera, item.y + k, item.w, false, &splats);
        for (var s = 0u; s < n; s++) {
            let splat = splats[s];
            let side = i32(ceil(splat.x + splat.radius)) - i32(floor(splat.x - splat.radius));
            for (var i = 0; i < side * side; i++) {
                var d2 = 0.0;
                let pixel = splat_pixel(splat, camera.ids.x, i, side, &d2);
                if (pixel != EMPTY
                    && splat.depth <= bitcast<f32>(atomicLoad(&depth[pixel])) + splat.band) {
                    let key = (min(u32(d2 * 64.0), 255u) << 24u) | (item.y + k);
                    atomicMin(&nearest[pixel], key);
                }
            }
        }
    }
}

// A splat's colour, taken as it is by the shading pass (alpha < 0; see c3rc.wgsl).
fn key_color(key: u32) -> vec4<f32> {
    return vec4<f32>(points[key & 0xffffffu].color.xyz, -1.0);
}

@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k >= settings.width * settings.height || near[k].w != 0.0) {
        return;
    }
    let key = atomicLoad(&nearest[k]);
    if (key != EMPTY) {
        near[k] = key_color(key);
    }
}

@compute @workgroup_size(64)
fn fill_holes(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k >= settings.width * settings.height || near[k].w != 0.0) {
        return;
    }
    let x = i32(k % settings.width);
    let y = i32(k / settings.width);
    let mesh1 = textureLoad(g_ids, vec2<i32>(x, y), 0).x;
    if (mesh1 == 0u || mirror_meshes[mesh1 - 1u] == 0u) {
        return;
    }
    var covered = 0;
    var best = EMPTY;
    var best_depth = EMPTY;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let nx = x + dx;
            let ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= i32(settings.width) || ny >= i32(settings.height)) {
                continue;
            }
            let n = u32(ny) * settings.width + u32(nx);
            let key = atomicLoad(&nearest[n]);
            if (key == EMPTY || textureLoad(g_ids, vec2<i32>(nx, ny), 0).x != mesh1) {
                continue;
            }
            covered++;
            let nd = atomicLoad(&depth[n]);
            if (nd < best_depth) {
                best_depth = nd;
                best = key;
            }
        }
    }
    if (covered >= 5 && best != EMPTY) {
        near[k] = key_color(best);
    }
}
