// One thread per pixel: the pixel's whole ray tree, depth first, from a private stack of
// pending rays. Depth first keeps at most one waiting sibling per level, plus the extra rays of
// one dispersive split, so PATH_STACK entries hold every tree up to max_depth = PATH_STACK - 5
// exactly; past that, a ray that finds the stack full is dropped and counted.

const PATH_STACK: u32 = 16u;

@group(0) @binding(4) var output: texture_storage_2d<rgba32float, write>;

var<private> stack: array<PendingRay, PATH_STACK>;

@compute @workgroup_size(8, 8)
fn cs_trace(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(u32(camera.width), u32(camera.height));
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    shadow_rays = 0u;
    cut_at_max_depth = 0u;
    var rays = 0u;
    var dropped = 0u;
    var radiance = vec3<f32>(0.0);
    stack[0] = primary_ray(id.xy);
    var top = 1u;
    while (top > 0u) {
        top -= 1u;
        let ray = stack[top];
        rays += 1u;
        let hit = traverse(ray.origin, ray.dir, FAR, false);
        radiance += shade(ray, hit);
        for (var i = 0u; i < child_count; i++) {
            if (top < PATH_STACK) {
                stack[top] = children[i];
                top += 1u;
            } else {
                dropped += 1u;
            }
        }
    }
    textureStore(output, vec2<i32>(id.xy), vec4<f32>(radiance, 1.0));
    atomicAdd(&counters[COUNT_RAYS], rays);
    atomicAdd(&counters[COUNT_SHADOW_RAYS], shadow_rays);
    if (cut_at_max_depth > 0u) {
        atomicAdd(&counters[COUNT_CUT_AT_MAX_DEPTH], cut_at_max_depth);
    }
    if (dropped > 0u) {
        atomicAdd(&counters[COUNT_DROPPED], dropped);
    }
}
