// Wavefront form: the image is traced tile by tile; within a tile, all rays of one generation
// (path depth) wait in a queue in GPU memory, one dispatch extends them all (closest hit,
// shading, shadow rays) and appends what they spawn to the next generation's queue. Each
// contribution is added to its pixel's accumulator atomically (several rays of a pixel can be
// in one generation). The queues are the two halves of one buffer, used in turn.

struct Tile {
    origin: vec2<u32>,
    size: vec2<u32>,
    // Rays a queue may hold for this tile: queue_factor × its pixels.
    capacity: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

// Which generation a dispatch extends (a dynamic offset selects it).
struct Generation {
    index: u32,
};

@group(0) @binding(4) var output: texture_storage_2d<rgba32float, write>;

@group(2) @binding(0) var<storage, read_write> queues: array<PendingRay>;
// Rays in each generation's queue; slot g + 1 counts what generation g appended.
@group(2) @binding(1) var<storage, read_write> queue_counts: array<atomic<u32>, 66>;
// The tile's radiance, three float bit patterns per pixel, added to with compare-and-swap.
@group(2) @binding(2) var<storage, read_write> accumulator: array<atomic<u32>>;
@group(2) @binding(3) var<uniform> tile: Tile;
@group(2) @binding(4) var<uniform> generation: Generation;

// Each queue is half of the buffer (settings.queue_capacity rays, the largest tile's).
fn queue_start(g: u32) -> u32 {
    return (g % 2u) * settings.queue_capacity;
}

fn add_float(i: u32, v: f32) {
    if (v == 0.0) {
        return;
    }
    var old = atomicLoad(&accumulator[i]);
    loop {
        let result = atomicCompareExchangeWeak(&accumulator[i], old, bitcast<u32>(bitcast<f32>(old) + v));
        if (result.exchanged) {
            break;
        }
        old = result.old_value;
    }
}

// Generation 0: the primary ray of every pixel of the tile.
@compute @workgroup_size(64)
fn cs_generate(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = tile.size.x * tile.size.y;
    if (id.x >= n) {
        return;
    }
    if (id.x == 0u) {
        atomicStore(&queue_counts[0], n);
    }
    let local = vec2<u32>(id.x % tile.size.x, id.x / tile.size.x);
    var ray = primary_ray(tile.origin + local);
    ray.pixel = id.x;
    queues[queue_start(0u) + id.x] = ray;
}

@compute @workgroup_size(64)
fn cs_extend(@builtin(global_invocation_id) id: vec3<u32>) {
    let g = generation.index;
    let count = min(atomicLoad(&queue_counts[g]), tile.capacity);
    if (id.x >= count) {
        return;
    }
    shadow_rays = 0u;
    cut_at_max_depth = 0u;
    let ray = queues[queue_start(g) + id.x];
    let hit = traverse(ray.origin, ray.dir, FAR, false);
    let radiance = shade(ray, hit);
    add_float(3u * ray.pixel, radiance.x);
    add_float(3u * ray.pixel + 1u, radiance.y);
    add_float(3u * ray.pixel + 2u, radiance.z);
    var dropped = 0u;
    if (child_count > 0u) {
        let first = atomicAdd(&queue_counts[g + 1u], child_count);
        for (var i = 0u; i < child_count; i++) {
            if (first + i < tile.capacity) {
                queues[queue_start(g + 1u) + first + i] = children[i];
            } else {
                dropped += 1u;
            }
        }
    }
    atomicAdd(&counters[COUNT_RAYS], 1u);
    if (shadow_rays > 0u) {
        atomicAdd(&counters[COUNT_SHADOW_RAYS], shadow_rays);
    }
    if (cut_at_max_depth > 0u) {
        atomicAdd(&counters[COUNT_CUT_AT_MAX_DEPTH], cut_at_max_depth);
    }
    if (dropped > 0u) {
        atomicAdd(&counters[COUNT_DROPPED], dropped);
    }
}

// Writes the tile's accumulated radiance to the output image.
@compute @workgroup_size(64)
fn cs_resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = tile.size.x * tile.size.y;
    if (id.x >= n) {
        return;
    }
    let local = vec2<u32>(id.x % tile.size.x, id.x / tile.size.x);
    let radiance = vec3<f32>(
        bitcast<f32>(atomicLoad(&accumulator[3u * id.x])),
        bitcast<f32>(atomicLoad(&accumulator[3u * id.x + 1u])),
        bitcast<f32>(atomicLoad(&accumulator[3u * id.x + 2u])),
    );
    textureStore(output, vec2<i32>(tile.origin + local), vec4<f32>(radiance, 1.0));
}
