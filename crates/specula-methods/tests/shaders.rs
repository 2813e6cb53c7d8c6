//! Every technique shader validates with naga, and every host struct that mirrors a WGSL one
//! has the same size and member offsets as naga computes for it.

use std::mem::{offset_of, size_of};

use specula_core::cube_maps::{self, GpuReflector};
use specula_core::gpu_scene::{GpuLight, GpuMaterial, GpuSceneInfo, GpuTextureInfo};
use specula_core::raster::{self, ShadowView};
use specula_methods::c3rc::{
    self,
    gpu::{GpuCamera, GpuPoint, GpuSettings as ProjectionSettings},
};
use specula_methods::distance_maps::{
    self, GpuFace, GpuLayerView, GpuMapReflector, GpuTraceSettings,
};
use specula_methods::image_space::{self, GpuPlane, GpuSettings};
use specula_methods::pvrr::{self, GpuMirrorMaterial};
use specula_methods::vertex_tracing::compose::ComposeSettings;

fn parse(name: &str, source: &str) -> naga::Module {
    specula_gpu::util::validate_wgsl(name, source).unwrap_or_else(|e| panic!("{e}"))
}

/// Asserts that WGSL struct `name` has `size` bytes and, member by member (padding members
/// included), the host offsets given in declaration order.
fn assert_layout(module: &naga::Module, name: &str, size: usize, host: &[usize]) {
    let (members, span) = module
        .types
        .iter()
        .find_map(|(_, ty)| match (&ty.name, &ty.inner) {
            (Some(n), naga::TypeInner::Struct { members, span }) if n == name => {
                Some((members.clone(), *span))
            }
            _ => None,
        })
        .unwrap_or_else(|| panic!("no WGSL struct {name}"));
    assert_eq!(
        span as usize, size,
        "{name}: WGSL size {span} vs host {size}"
    );
    // Host padding arrays cover several WGSL padding scalars: compare the leading members.
    for (member, &offset) in members.iter().zip(host) {
        assert_eq!(
            member.offset as usize,
            offset,
            "{name}.{}",
            member.name.as_deref().unwrap_or("?")
        );
    }
}

#[test]
fn technique_shaders_validate() {
    parse("raster.wgsl", &raster::shader_source());
    parse("cube-map shading", &cube_maps::shader_source());
    parse("c3rc.wgsl", &c3rc::shader_source());
    parse("c3rc/project.wgsl", &c3rc::gpu::shader_source());
    parse("image_space.wgsl", &image_space::shader_source());
    parse("image_space/peel.wgsl", &image_space::peel::shader_source());
    parse("pvrr.wgsl", &pvrr::shader_source());
    parse(
        "distance_maps/layers.wgsl",
        &distance_maps::layers_shader_source(),
    );
    parse(
        "distance_maps/ranges.wgsl",
        &distance_maps::ranges_shader_source(),
    );
    parse(
        "distance_maps/trace.wgsl",
        &distance_maps::trace_shader_source(),
    );
    parse(
        "gpu_trace/megakernel.wgsl",
        &specula_methods::gpu_trace::megakernel_source(),
    );
    parse(
        "gpu_trace/wavefront.wgsl",
        &specula_methods::gpu_trace::wavefront_source(),
    );
    parse(
        "vertex_tracing/compose.wgsl",
        &specula_methods::vertex_tracing::compose::shader_source(),
    );
}

#[test]
fn host_structs_match_wgsl_layouts() {
    let module = parse(
        "vertex_tracing/compose.wgsl",
        &specula_methods::vertex_tracing::compose::shader_source(),
    );
    assert_layout(
        &module,
        "ComposeSettings",
        size_of::<ComposeSettings>(),
        &[offset_of!(ComposeSettings, perspective_correct)],
    );
    let module = parse("raster.wgsl", &raster::shader_source());
    assert_layout(
        &module,
        "Material",
        size_of::<GpuMaterial>(),
        &[
            offset_of!(GpuMaterial, color),
            offset_of!(GpuMaterial, kind),
            offset_of!(GpuMaterial, ior),
            offset_of!(GpuMaterial, texture),
            offset_of!(GpuMaterial, flags),
            offset_of!(GpuMaterial, pad),
        ],
    );
    assert_layout(
        &module,
        "TextureInfo",
        size_of::<GpuTextureInfo>(),
        &[
            offset_of!(GpuTextureInfo, offset),
            offset_of!(GpuTextureInfo, width),
            offset_of!(GpuTextureInfo, height),
            offset_of!(GpuTextureInfo, pad),
        ],
    );
    assert_layout(
        &module,
        "Light",
        size_of::<GpuLight>(),
        &[
            offset_of!(GpuLight, position),
            offset_of!(GpuLight, kind),
            offset_of!(GpuLight, direction),
            offset_of!(GpuLight, cos_inner),
            offset_of!(GpuLight, intensity),
            offset_of!(GpuLight, cos_outer),
            offset_of!(GpuLight, shadow_layer),
            offset_of!(GpuLight, pad),
        ],
    );
    assert_layout(
        &module,
        "SceneInfo",
        size_of::<GpuSceneInfo>(),
        &[
            offset_of!(GpuSceneInfo, ambient),
            offset_of!(GpuSceneInfo, light_count),
            offset_of!(GpuSceneInfo, background),
            offset_of!(GpuSceneInfo, background_texture),
            offset_of!(GpuSceneInfo, background_intensity),
            offset_of!(GpuSceneInfo, pad),
        ],
    );
    assert_layout(
        &module,
        "ShadowView",
        size_of::<ShadowView>(),
        &[
            offset_of!(ShadowView, clip_from_world),
            offset_of!(ShadowView, origin),
            offset_of!(ShadowView, directional),
            offset_of!(ShadowView, direction),
            offset_of!(ShadowView, texel_size),
        ],
    );
    let module = parse("c3rc/project.wgsl", &c3rc::gpu::shader_source());
    assert_layout(
        &module,
        "Settings",
        size_of::<ProjectionSettings>(),
        &[
            offset_of!(ProjectionSettings, eye),
            offset_of!(ProjectionSettings, right),
            offset_of!(ProjectionSettings, up),
            offset_of!(ProjectionSettings, forward),
            offset_of!(ProjectionSettings, lens),
            offset_of!(ProjectionSettings, width),
            offset_of!(ProjectionSettings, height),
            offset_of!(ProjectionSettings, work_items),
            offset_of!(ProjectionSettings, row),
        ],
    );
    assert_layout(
        &module,
        "Point",
        size_of::<GpuPoint>(),
        &[
            offset_of!(GpuPoint, p),
            offset_of!(GpuPoint, n),
            offset_of!(GpuPoint, color),
        ],
    );
    assert_layout(
        &module,
        "Camera",
        size_of::<GpuCamera>(),
        &[
            offset_of!(GpuCamera, v),
            offset_of!(GpuCamera, d),
            offset_of!(GpuCamera, frame),
            offset_of!(GpuCamera, planes),
            offset_of!(GpuCamera, info),
            offset_of!(GpuCamera, ids),
        ],
    );
    let module = parse("cube-map shading", &cube_maps::shader_source());
    assert_layout(
        &module,
        "Reflector",
        size_of::<GpuReflector>(),
        &[
            offset_of!(GpuReflector, center),
            offset_of!(GpuReflector, radius),
            offset_of!(GpuReflector, first_layer),
            offset_of!(GpuReflector, exit_model),
            offset_of!(GpuReflector, pad),
        ],
    );
    let module = parse("image_space.wgsl", &image_space::shader_source());
    assert_layout(
        &module,
        "Settings",
        size_of::<GpuSettings>(),
        &[
            offset_of!(GpuSettings, mode),
            offset_of!(GpuSettings, seeds),
            offset_of!(GpuSettings, iterations),
            offset_of!(GpuSettings, plane_count),
            offset_of!(GpuSettings, index_override),
            offset_of!(GpuSettings, depth_tolerance),
            offset_of!(GpuSettings, inside_steps),
            offset_of!(GpuSettings, exit_iterations),
            offset_of!(GpuSettings, scene_center),
            offset_of!(GpuSettings, scene_radius),
            offset_of!(GpuSettings, scene_min),
            offset_of!(GpuSettings, parallax),
            offset_of!(GpuSettings, scene_max),
            offset_of!(GpuSettings, layers),
            offset_of!(GpuSettings, peeled),
            offset_of!(GpuSettings, refractor_extent),
            offset_of!(GpuSettings, far_depth),
            offset_of!(GpuSettings, bracket),
            offset_of!(GpuSettings, discs),
            offset_of!(GpuSettings, internal_reflection),
            offset_of!(GpuSettings, reflection),
            offset_of!(GpuSettings, fallback),
            offset_of!(GpuSettings, dispersion),
            offset_of!(GpuSettings, pad),
        ],
    );
    assert_layout(
        &module,
        "Plane",
        size_of::<GpuPlane>(),
        &[
            offset_of!(GpuPlane, normal),
            offset_of!(GpuPlane, offset),
            offset_of!(GpuPlane, center),
            offset_of!(GpuPlane, radius),
        ],
    );
    let module = parse("pvrr.wgsl", &pvrr::shader_source());
    assert_layout(
        &module,
        "MirrorMaterial",
        size_of::<GpuMirrorMaterial>(),
        &[
            offset_of!(GpuMirrorMaterial, f0),
            offset_of!(GpuMirrorMaterial, fresnel),
        ],
    );
    let module = parse(
        "distance_maps/layers.wgsl",
        &distance_maps::layers_shader_source(),
    );
    assert_layout(
        &module,
        "LayerView",
        size_of::<GpuLayerView>(),
        &[
            offset_of!(GpuLayerView, clip_from_world),
            offset_of!(GpuLayerView, origin),
            offset_of!(GpuLayerView, select),
            offset_of!(GpuLayerView, peel),
            offset_of!(GpuLayerView, pad),
        ],
    );
    let module = parse(
        "distance_maps/trace.wgsl",
        &distance_maps::trace_shader_source(),
    );
    assert_layout(
        &module,
        "TraceSettings",
        size_of::<GpuTraceSettings>(),
        &[
            offset_of!(GpuTraceSettings, layers),
            offset_of!(GpuTraceSettings, linear_steps),
            offset_of!(GpuTraceSettings, secant_steps),
            offset_of!(GpuTraceSettings, max_depth),
            offset_of!(GpuTraceSettings, min_max),
            offset_of!(GpuTraceSettings, dispersive),
            offset_of!(GpuTraceSettings, output),
            offset_of!(GpuTraceSettings, resolution),
            offset_of!(GpuTraceSettings, skip_start),
            offset_of!(GpuTraceSettings, refine_every_layer),
            offset_of!(GpuTraceSettings, per_mesh),
            offset_of!(GpuTraceSettings, both_branches),
            offset_of!(GpuTraceSettings, exact_fresnel),
            offset_of!(GpuTraceSettings, estimate),
            offset_of!(GpuTraceSettings, pad),
        ],
    );
    assert_layout(
        &module,
        "MapReflector",
        size_of::<GpuMapReflector>(),
        &[
            offset_of!(GpuMapReflector, origin),
            offset_of!(GpuMapReflector, first_map),
            offset_of!(GpuMapReflector, far),
            offset_of!(GpuMapReflector, pad),
        ],
    );
    assert_layout(
        &module,
        "Face",
        size_of::<GpuFace>(),
        &[
            offset_of!(GpuFace, right),
            offset_of!(GpuFace, up),
            offset_of!(GpuFace, forward),
        ],
    );
}
