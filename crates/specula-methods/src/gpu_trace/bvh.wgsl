// Ray queries over the CPU's binary SAH BVH as uploaded (specula_trace::bvh::BvhNode, and the
// triangles in the BVH's leaf order), with the watertight ray-triangle test of Woop, Benthin
// and Wald (JCGT 2013) as specula_trace::accel implements it: the same hits, up to the
// rounding of single-precision arithmetic (the CPU decides a ray exactly on an edge in double
// precision; WGSL has no double, so such a ray counts as on the triangle here).
//
// Needs shade.wgsl (its `settings` hold the triangle count).
//
// Traversal: ordered (near child first), with an explicit stack of the far children and their
// entry distances. The builder caps the tree's depth at 60 levels, so a 64-entry stack never
// overflows.

struct BvhNode {
    min: vec3<f32>,
    // Interior: the first of the two children. Leaf: the first triangle.
    first: u32,
    max: vec3<f32>,
    // 0 for an interior node, else the leaf's triangle count.
    count: u32,
};

// One triangle in leaf order: its corners (world space) and the index of its first vertex in
// the scene's vertex buffer (GpuVertex, three per triangle), where normals, texture coordinates
// and the mesh index are.
struct Triangle {
    p0: vec3<f32>,
    vertex: u32,
    p1: vec3<f32>,
    pad0: u32,
    p2: vec3<f32>,
    pad1: u32,
};

@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> triangles: array<Triangle>;

const BVH_STACK: u32 = 64u;
// 1 + 2 gamma(3) (Ize 2013): widens a box's far distance so rounding never misses a box.
const ROBUST_WIDENING: f32 = 1.0000003576;
const NO_HIT: u32 = 0xffffffffu;
const FAR: f32 = 3.0e38;

struct Hit {
    t: f32,
    b1: f32,
    b2: f32,
    // Leaf-order triangle index, NO_HIT for a miss.
    triangle: u32,
};

// Per-ray constants of the slab and watertight tests.
struct RayData {
    origin: vec3<f32>,
    inv_dir: vec3<f32>,
    kx: u32,
    ky: u32,
    kz: u32,
    shear: vec3<f32>,
};

fn ray_data(origin: vec3<f32>, dir: vec3<f32>) -> RayData {
    var r: RayData;
    r.origin = origin;
    let a = abs(dir);
    var kz = 2u;
    if (a.x > a.y) {
        if (a.x > a.z) {
            kz = 0u;
        }
    } else if (a.y > a.z) {
        kz = 1u;
    }
    r.kz = kz;
    r.kx = (kz + 1u) % 3u;
    r.ky = (kz + 2u) % 3u;
    // Zero components become a tiny signed value, as on the CPU, so the slab test sees no inf.
    let tiny = vec3<f32>(1e-30);
    let negative_bits = (bitcast<vec3<u32>>(dir) & vec3<u32>(0x80000000u)) != vec3<u32>(0u);
    let safe = select(dir, select(tiny, -tiny, negative_bits), abs(dir) < tiny);
    r.inv_dir = vec3<f32>(1.0) / safe;
    r.shear = vec3<f32>(dir[r.kx] / dir[kz], dir[r.ky] / dir[kz], 1.0 / dir[kz]);
    return r;
}

// Entry distance of the ray into box [lo, hi] before t_max, or -1 when it misses.
fn box_entry(r: RayData, lo: vec3<f32>, hi: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (lo - r.origin) * r.inv_dir;
    let t1 = (hi - r.origin) * r.inv_dir;
    // Choose planes by the direction's sign (not min/max), so empty inverted boxes stay missed.
    let negative = r.inv_dir < vec3<f32>(0.0);
    let near = select(t0, t1, negative);
    let far = select(t1, t0, negative);
    let t_near = max(max(max(near.x, near.y), near.z), 0.0);
    let t_far = min(min(min(far.x, far.y), far.z), t_max) * ROBUST_WIDENING;
    return select(-1.0, t_near, t_near <= t_far);
}

fn permute(a: vec3<f32>, r: RayData) -> vec3<f32> {
    return vec3<f32>(a[r.kx], a[r.ky], a[r.kz]);
}

// The watertight test: (t, b1, b2) in `hit` when 0 < t < t_max.
fn hit_triangle(r: RayData, tri: Triangle, t_max: f32, hit: ptr<function, Hit>) -> bool {
    let a = permute(tri.p0 - r.origin, r);
    let b = permute(tri.p1 - r.origin, r);
    let c = permute(tri.p2 - r.origin, r);
    let ax = a.x - r.shear.x * a.z;
    let ay = a.y - r.shear.y * a.z;
    let bx = b.x - r.shear.x * b.z;
    let by = b.y - r.shear.y * b.z;
    let cx = c.x - r.shear.x * c.z;
    let cy = c.y - r.shear.y * c.z;
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return false;
    }
    let det = u + v + w;
    if (det == 0.0) {
        return false;
    }
    let az = r.shear.z * a.z;
    let bz = r.shear.z * b.z;
    let cz = r.shear.z * c.z;
    let t_scaled = u * az + v * bz + w * cz;
    if (det > 0.0) {
        if (t_scaled <= 0.0 || t_scaled >= t_max * det) {
            return false;
        }
    } else if (t_scaled >= 0.0 || t_scaled <= t_max * det) {
        return false;
    }
    let inv_det = 1.0 / det;
    (*hit).t = t_scaled * inv_det;
    (*hit).b1 = v * inv_det;
    (*hit).b2 = w * inv_det;
    return true;
}

// Closest hit with 0 < t < t_max (`any_hit`: stop at the first, for shadow rays).
fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_max_in: f32, any_hit: bool) -> Hit {
    var best: Hit;
    best.triangle = NO_HIT;
    best.t = t_max_in;
    // An empty scene still binds one placeholder triangle: the count says there is none.
    if (settings.triangle_count == 0u) {
        return best;
    }
    let r = ray_data(origin, dir);
    var stack_node: array<u32, BVH_STACK>;
    var stack_t: array<f32, BVH_STACK>;
    var top = 0u;
    let root = nodes[0];
    if (box_entry(r, root.min, root.max, best.t) < 0.0) {
        return best;
    }
    var current = 0u;
    loop {
        let node = nodes[current];
        if (node.count > 0u) {
            for (var i = node.first; i < node.first + node.count; i++) {
                var candidate: Hit;
                if (hit_triangle(r, triangles[i], best.t, &candidate)) {
                    candidate.triangle = i;
                    best = candidate;
                    if (any_hit) {
                        return best;
                    }
                }
            }
        } else {
            let left = nodes[node.first];
            let right = nodes[node.first + 1u];
            let t_left = box_entry(r, left.min, left.max, best.t);
            let t_right = box_entry(r, right.min, right.max, best.t);
            if (t_left >= 0.0 && t_right >= 0.0) {
                // Both: descend into the nearer, keep the farther for later.
                var near = node.first;
                var far = node.first + 1u;
                var t_far = t_right;
                if (t_right < t_left) {
                    near = node.first + 1u;
                    far = node.first;
                    t_far = t_left;
                }
                stack_node[top] = far;
                stack_t[top] = t_far;
                top += 1u;
                current = near;
                continue;
            }
            if (t_left >= 0.0) {
                current = node.first;
                continue;
            }
            if (t_right >= 0.0) {
                current = node.first + 1u;
                continue;
            }
        }
        // Pop the nearest pending node that can still hold a closer hit.
        var found = false;
        loop {
            if (top == 0u) {
                break;
            }
            top -= 1u;
            if (stack_t[top] <= best.t) {
                current = stack_node[top];
                found = true;
                break;
            }
        }
        if (!found) {
            break;
        }
    }
    return best;
}
