//! Every WGSL file validates with naga; host structs match their WGSL layouts; CPU and GPU
//! optics agree on the same inputs.

use glam::Vec3;
use specula_gpu::shaders::{self, CameraUniform};

fn validate(name: &str, source: &str) -> naga::Module {
    specula_gpu::util::validate_wgsl(name, source).unwrap_or_else(|e| panic!("{e}"))
}

/// What specular_pixel.wgsl reads from its including shader, declared as its comment lists it
/// (each shader at bindings of its own).
const SPECULAR_PIXEL_INCLUDER: &str = "
@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var g_color: texture_2d<f32>;
@group(0) @binding(2) var g_position: texture_2d<f32>;
@group(0) @binding(3) var g_normal: texture_2d<f32>;
@group(0) @binding(4) var g_ids: texture_2d<u32>;
@group(0) @binding(5) var<storage, read> mesh_reflector: array<i32>;
";

#[test]
fn every_common_shader_validates() {
    // Each file with the ones listed before it (lighting.wgsl builds on scene and cubemap), and
    // what a file leaves to its including shader.
    let mut prefix = String::new();
    for (name, source) in shaders::COMMON {
        prefix.push_str(source);
        prefix.push('\n');
        match *name {
            "specular_pixel.wgsl" => validate(name, &format!("{prefix}{SPECULAR_PIXEL_INCLUDER}")),
            _ => validate(name, &prefix),
        };
    }
    // The includer's part is what the file's comment says it is.
    for line in SPECULAR_PIXEL_INCLUDER.lines().filter(|l| !l.is_empty()) {
        let declaration = line.split_once(") var").expect("a binding").1;
        assert!(
            shaders::SPECULAR_PIXEL.contains(&format!("//   var{declaration}")),
            "specular_pixel.wgsl does not list{declaration}"
        );
    }
}

/// (member name, byte offset) of a WGSL struct, and its size.
fn wgsl_layout(module: &naga::Module, struct_name: &str) -> (Vec<(String, u32)>, u32) {
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(struct_name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                return (
                    members
                        .iter()
                        .map(|m| (m.name.clone().unwrap(), m.offset))
                        .collect(),
                    *span,
                );
            }
        }
    }
    panic!("no struct {struct_name}");
}

#[test]
fn camera_uniform_matches_its_wgsl_layout() {
    let module = validate("camera.wgsl", shaders::CAMERA);
    let (members, size) = wgsl_layout(&module, "Camera");
    assert_eq!(size as usize, std::mem::size_of::<CameraUniform>());
    let host = [
        (
            "clip_from_world",
            std::mem::offset_of!(CameraUniform, clip_from_world),
        ),
        ("eye_world", std::mem::offset_of!(CameraUniform, eye_world)),
        (
            "tan_half_fov_y",
            std::mem::offset_of!(CameraUniform, tan_half_fov_y),
        ),
        (
            "right_world",
            std::mem::offset_of!(CameraUniform, right_world),
        ),
        ("aspect", std::mem::offset_of!(CameraUniform, aspect)),
        ("up_world", std::mem::offset_of!(CameraUniform, up_world)),
        ("width", std::mem::offset_of!(CameraUniform, width)),
        (
            "forward_world",
            std::mem::offset_of!(CameraUniform, forward_world),
        ),
        ("height", std::mem::offset_of!(CameraUniform, height)),
    ];
    assert_eq!(members.len(), host.len());
    for ((wgsl_name, wgsl_offset), (host_name, host_offset)) in members.iter().zip(host) {
        assert_eq!(
            (wgsl_name.as_str(), *wgsl_offset as usize),
            (host_name, host_offset)
        );
    }
}

const OPTICS_KERNEL: &str = r#"
struct Case { d: vec4<f32>, n: vec4<f32> };
struct Out { reflected: vec4<f32>, refracted: vec4<f32>, fresnel: vec4<f32> };
@group(0) @binding(0) var<storage, read> cases: array<Case>;
@group(0) @binding(1) var<storage, read_write> outs: array<Out>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&cases)) { return; }
    let d = cases[i].d.xyz;
    let n = cases[i].n.xyz;
    let eta = cases[i].d.w;
    let cos_i = -dot(d, n);
    let f0 = vec3<f32>(cases[i].n.w, 0.5, 0.9);
    outs[i].reflected = vec4<f32>(reflect(d, n), 0.0);
    outs[i].refracted = vec4<f32>(refract(d, n, eta), 0.0);
    outs[i].fresnel = vec4<f32>(fresnel_dielectric(cos_i, eta), fresnel_schlick(f0, cos_i).x, thin_sheet_reflectance(cos_i, 1.0 / eta), 0.0);
}
"#;

#[test]
fn cpu_and_wgsl_optics_agree() {
    let Some(ctx) = specula_gpu::test_context("cpu_and_wgsl_optics_agree") else {
        return;
    };
    let source = shaders::compose(&["optics.wgsl"], OPTICS_KERNEL);
    validate("optics kernel", &source);
    // Incidence angles from 0 to 89°, into and out of glass, with a tilted normal.
    let mut cases: Vec<[f32; 8]> = Vec::new();
    for k in 0..90 {
        for &eta in &[1.0 / 1.5, 1.5, 1.0 / 2.4] {
            let a = (k as f32).to_radians();
            let n = Vec3::new(0.2, 0.3, 1.0).normalize();
            let t = n.any_orthonormal_vector();
            let d = (a.sin() * t - a.cos() * n).normalize();
            cases.push([d.x, d.y, d.z, eta, n.x, n.y, n.z, 0.04 + k as f32 / 100.0]);
        }
    }
    let input = ctx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("cases"),
        contents: bytemuck::cast_slice(&cases),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let out_size = (cases.len() * 48) as u64;
    let output = ctx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("outs"),
        size: out_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = ctx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: out_size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("optics kernel"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
    let pipeline = ctx
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("optics"),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
    let bind_group = ctx.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: output.as_entire_binding(),
            },
        ],
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, out_size);
    ctx.queue.submit([encoder.finish()]);
    let slice = readback.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.unwrap());
    ctx.wait().unwrap();
    let bytes = slice.get_mapped_range().unwrap().to_vec();
    let outs: &[[f32; 12]] = bytemuck::cast_slice(&bytes);
    use specula_trace::optics;
    for (case, out) in cases.iter().zip(outs) {
        let (d, eta, n) = (
            Vec3::new(case[0], case[1], case[2]),
            case[3],
            Vec3::new(case[4], case[5], case[6]),
        );
        let cos_i = -d.dot(n);
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(
            close(Vec3::from_slice(&out[0..3]), optics::reflect(d, n)),
            "reflect {case:?}"
        );
        // WGSL's refract returns zero under total internal reflection; the CPU returns None.
        let cpu_refracted = optics::refract(d, n, eta).unwrap_or(Vec3::ZERO);
        assert!(
            close(Vec3::from_slice(&out[4..7]), cpu_refracted),
            "refract {case:?}"
        );
        assert!(
            (out[8] - optics::fresnel_dielectric(cos_i, eta)).abs() < 1e-5,
            "fresnel {case:?}"
        );
        let f0 = Vec3::new(case[7], 0.5, 0.9);
        assert!(
            (out[9] - optics::fresnel_schlick(f0, cos_i).x).abs() < 1e-5,
            "schlick {case:?}"
        );
        assert!(
            (out[10] - optics::thin_sheet_reflectance(cos_i, 1.0 / eta)).abs() < 1e-5,
            "sheet {case:?}"
        );
    }
}
