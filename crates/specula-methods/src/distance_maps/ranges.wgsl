// distance-maps, step 1b (min-max acceleration): the smallest and largest valid distance of
// each layer over its six faces, as float bits (positive floats order as their bits). The host
// clears each pair to (largest float, 0) first.

@group(0) @binding(0) var range_geometry: texture_2d_array<f32>;
@group(0) @binding(1) var<storage, read_write> ranges: array<atomic<u32>>;

var<workgroup> workgroup_min: atomic<u32>;
var<workgroup> workgroup_max: atomic<u32>;

// One invocation per texel of a face, z = the map (reflector × layer); loops over the six faces.
@compute @workgroup_size(8, 8, 1)
fn cs_range(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    if (local == 0u) {
        atomicStore(&workgroup_min, 0x7f7fffffu);
        atomicStore(&workgroup_max, 0u);
    }
    workgroupBarrier();
    let size = textureDimensions(range_geometry);
    if (id.x < size.x && id.y < size.y) {
        for (var face = 0u; face < 6u; face++) {
            let d = textureLoad(range_geometry, vec2<i32>(id.xy), i32(id.z * 6u + face), 0).w;
            if (d > 0.0) {
                atomicMin(&workgroup_min, bitcast<u32>(d));
                atomicMax(&workgroup_max, bitcast<u32>(d));
            }
        }
    }
    workgroupBarrier();
    if (local == 0u) {
        atomicMin(&ranges[2u * id.z], atomicLoad(&workgroup_min));
        atomicMax(&ranges[2u * id.z + 1u], atomicLoad(&workgroup_max));
    }
}
