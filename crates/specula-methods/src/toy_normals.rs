//! `toy-normals`: a test-only technique that shows the G-buffer's normals (n / 2 + 1/2 as
//! colour). It exists to hold what adding a technique takes: this one file and one line of the
//! crate root's `techniques!` list; the frame lifecycle does the rest.

use specula_core::lifecycle::{GpuFrame, GpuTechnique};
use specula_core::raster::{self, BindGroupsBySlot, RasterPass};
use specula_core::{
    GpuMethod, GpuScene, Invalidates, LiveScene, MethodInfo, Param, ParamKind,
    TechniqueError,
};
use specula_gpu::shaders;
use specula_gpu::util::{bind_group, layout_entry, texture_binding};
use specula_gpu::GpuContext;

specula_core::params! {
    /// toy-normals' parameters.
    pub struct Params {
        shadow_resolution: u32 = raster::SHADOW_RESOLUTION,
        scale: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 1.0 },
            default: "0.5",
            doc: "colour = scale x normal + 0.5 (compiled into the shader)",
            invalidates: Invalidates::Resources,
        },
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "toy-normals",
    summary: "the G-buffer's normals as colour (a test of what adding a technique takes)",
    exact: false,
    needs_gpu: true,
    gpu_optional: false,
    progressive: false,
    delegates: &[],
    params: Params::SPECS,
    presets: &[],
    create: || Box::new(GpuMethod::<ToyNormals>::default()),
};

const SHADER: &str = "
@group(0) @binding(0) var g_normal: texture_2d<f32>;

@fragment
fn fs_shade(in: FullscreenOut) -> @location(0) vec4<f32> {
    let n = textureLoad(g_normal, vec2<i32>(in.clip.xy), 0).xyz;
    return vec4<f32>(SCALE * n + vec3<f32>(0.5), 1.0);
}
";

#[derive(Default)]
pub struct ToyNormals {
    pub params: Params,
}

pub struct Prepared {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    scene_bind_group: wgpu::BindGroup,
    bind_groups: BindGroupsBySlot,
}

impl GpuTechnique for ToyNormals {
    type Prepared = Prepared;
    type Params = Params;
    const INFO: &'static MethodInfo = &INFO;

    fn params(&self) -> &Params {
        &self.params
    }

    fn params_mut(&mut self) -> &mut Params {
        &mut self.params
    }

    fn prepare(
        &mut self,
        gpu: &GpuContext,
        live: &LiveScene,
        _: Option<&RasterPass>,
    ) -> Result<Prepared, TechniqueError> {
        let device = &gpu.device;
        let source = SHADER.replace("SCALE", &format!("{:?}", self.params.scale));
        Ok(gpu.validated("toy-normals set-up", || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("toy-normals"),
                source: wgpu::ShaderSource::Wgsl(shaders::compose(&["camera.wgsl"], &source).into()),
            });
            let float = wgpu::TextureSampleType::Float { filterable: false };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("toy-normals"),
                entries: &[layout_entry(
                    0,
                    wgpu::ShaderStages::FRAGMENT,
                    texture_binding(float, wgpu::TextureViewDimension::D2),
                )],
            });
            let scene_layout = GpuScene::bind_group_layout(device);
            let pipeline =
                raster::shading_pipeline(device, "toy-normals", &module, &layout, &scene_layout);
            Prepared {
                pipeline,
                layout,
                scene_bind_group: live.gpu(gpu).bind_group(gpu, &scene_layout),
                bind_groups: BindGroupsBySlot::default(),
            }
        })?)
    }

    fn shade(&mut self, p: &mut Prepared, frame: &mut GpuFrame<'_>) -> Result<(), TechniqueError> {
        let (gpu, g) = (frame.gpu, frame.g());
        gpu.validated("toy-normals", || {
            let group = p.bind_groups.get_or_make(frame.raster(), g, || {
                let [_, _, normal, _] = g.views();
                bind_group(
                    gpu,
                    "toy-normals",
                    &p.layout,
                    &[wgpu::BindingResource::TextureView(&normal)],
                )
            });
            raster::fullscreen_pass(
                gpu,
                "toy-normals",
                &p.pipeline,
                &[group, &p.scene_bind_group],
                frame.output(),
            )
        })?;
        frame.lap("normals")?;
        frame.count("raster passes", 1);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use specula_core::raster::{read_rgba32f, RasterPass, RasterSpec};
    use specula_core::{apply_setting, LiveScene, RenderStill};

    /// Registered by its one line, made and run by name like every method, it shows exactly
    /// scale × the G-buffer's normal + 1/2 at every pixel, before and after a parameter change.
    #[test]
    fn a_technique_added_by_one_file_and_one_line_runs_through_the_lifecycle() {
        let Some(ctx) = specula_core::test_context("toy-normals") else {
            return;
        };
        let gpu = ctx.gpu.as_ref().expect("a test context has a GPU");
        let scene = specula_scene::load("door-mirror").unwrap();
        let (width, height) = (40, 30);
        let live = LiveScene::new(scene.clone());
        let raster = RasterPass::new(gpu, &live, RasterSpec::scene(1024)).unwrap();
        let uniform =
            specula_core::raster::camera_uniform(&scene.camera, &scene.bounds(), width, height);
        let g = raster.render(gpu, live.gpu(gpu), &uniform, None).unwrap();
        let normals = read_rgba32f(gpu, &g.normal).unwrap();
        let mut technique = crate::by_name("toy-normals").unwrap();
        for scale in [0.5f32, 0.25] {
            apply_setting(technique.as_mut(), &format!("scale={scale}")).unwrap();
            let still = technique
                .render_still(&ctx, &scene, width, height)
                .unwrap();
            assert_eq!(still.counters, [("raster passes".to_string(), 1)]);
            let stages: Vec<&str> = still.stages.iter().map(|s| s.stage.as_str()).collect();
            assert_eq!(stages, ["g-buffer", "normals"]);
            let mut largest = 0.0f32;
            for (shown, n) in still.image.pixels.iter().zip(&normals.pixels) {
                largest = largest.max((*shown - (scale * *n + glam::Vec3::splat(0.5))).abs().max_element());
            }
            assert!(largest <= 1e-6, "scale {scale}: {largest}");
            // Not a constant image: the mirror's and the town's normals differ.
            let first = still.image.pixels[0];
            assert!(still.image.pixels.iter().any(|p| (*p - first).length() > 0.1));
        }
    }
}
