//! The interactive core every technique plugs into: typed parameters from one registry, the
//! update path for moving objects, frames that create no GPU objects once warm, and the
//! progressive reference.

use glam::Vec3;
use specula_methods::{
    apply_setting, by_name, Context, LiveScene, ParamKind, RenderStill, Technique, METHODS,
};
use specula_scene::Scene;
use specula_trace::Image;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

/// Small maps keep the GPU methods quick on lavapipe.
fn small(technique: &mut dyn Technique) {
    for (name, value) in [("resolution", "96"), ("shadow_resolution", "256")] {
        if technique.info().param(name).is_some() {
            apply_setting(technique, &format!("{name}={value}")).unwrap();
        }
    }
}

fn rmse(a: &Image, b: &Image) -> f32 {
    let sum: f32 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (*p - *q).length_squared() / 3.0)
        .sum();
    (sum / a.pixels.len() as f32).sqrt()
}

#[test]
fn every_parameter_the_parser_accepts_is_listed_and_every_listed_one_is_accepted() {
    for info in METHODS {
        let mut technique = (info.create)();
        assert_eq!(technique.name(), info.name);
        let listed: Vec<String> = technique.parameters().into_iter().map(|(n, _)| n).collect();
        let specs: Vec<&str> = info.params.iter().map(|p| p.name).collect();
        assert_eq!(listed, specs, "{}: reports list the specs", info.name);
        for spec in info.params {
            // Every default parses, is accepted, and is what a fresh technique reports.
            assert_eq!(
                technique.parameter(spec.name),
                spec.default,
                "{}.{}: default",
                info.name,
                spec.name
            );
            apply_setting(
                technique.as_mut(),
                &format!("{}={}", spec.name, spec.default),
            )
            .unwrap_or_else(|e| panic!("{}.{}: {e}", info.name, spec.name));
            // Values outside the kind are rejected with the parameter's name.
            let bad = match spec.kind {
                ParamKind::Integer { max, .. } => Some((max + 1).to_string()),
                ParamKind::Number { max, .. } => Some((max * 2.0 + 1.0).to_string()),
                ParamKind::Flag => Some("maybe".into()),
                ParamKind::Choice(_) => Some("no-such-choice".into()),
                ParamKind::Numbers { .. } => Some("1,x".into()),
                ParamKind::Text { .. } => None,
            };
            if let Some(bad) = bad {
                let error = apply_setting(technique.as_mut(), &format!("{}={bad}", spec.name))
                    .unwrap_err()
                    .to_string();
                // The setting as given, and what would have been accepted.
                assert!(
                    error.contains(&format!("'{}={bad}'", spec.name)) && error.contains("expected"),
                    "{error}"
                );
            }
        }
        // A name no spec lists is rejected, naming the valid ones.
        let error = apply_setting(technique.as_mut(), "no_such_parameter=1")
            .unwrap_err()
            .to_string();
        for spec in info.params {
            assert!(error.contains(spec.name), "{}: {error}", info.name);
        }
    }
    // docs/usage.md's example is accepted.
    let mut pvrr = by_name("pvrr").unwrap();
    apply_setting(pvrr.as_mut(), "markers=true").unwrap();
    assert_eq!(pvrr.parameter("markers"), "true");
}

#[test]
fn the_reference_is_a_registered_cpu_method_that_needs_no_gpu() {
    let info = specula_methods::exact_method();
    assert_eq!(info.name, "reference");
    assert!(!info.needs_gpu && info.progressive);
    let scene = specula_scene::load("door-mirror").unwrap();
    let mut reference = (info.create)();
    let still = reference
        .render_still(&Context::default(), &scene, WIDTH, HEIGHT)
        .unwrap();
    assert!(still.converged);
    let exact = specula_trace::render(
        &scene,
        &specula_trace::SceneAccel::new(&scene),
        &specula_trace::RenderSettings {
            width: WIDTH,
            height: HEIGHT,
            spp: 1,
            max_depth: 8,
        },
        &|_, _| {},
    );
    assert_eq!(still.image.pixels, exact.pixels);
    // A GPU method without a GPU says so.
    let error = by_name("envmap")
        .unwrap()
        .render_still(&Context::default(), &scene, WIDTH, HEIGHT)
        .err()
        .unwrap()
        .to_string();
    assert!(error.contains("needs a GPU"), "{error}");
}

#[test]
fn the_progressive_reference_refines_to_the_full_image() {
    let scene = specula_scene::load("door-mirror").unwrap();
    let live = LiveScene::new(scene.clone());
    let ctx = Context::default();
    // Large enough that one level takes more than the 1 ms budget.
    let (width, height) = (320, 240);
    let mut full = by_name("reference").unwrap();
    let exact = full
        .render(&ctx, &live, &scene.camera, width, height)
        .unwrap()
        .image(&ctx)
        .unwrap();
    let mut progressive = by_name("reference").unwrap();
    apply_setting(progressive.as_mut(), "budget_ms=1").unwrap();
    let mut calls = 0;
    let mut rays = 0;
    let image = loop {
        let frame = progressive
            .render(&ctx, &live, &scene.camera, width, height)
            .unwrap();
        calls += 1;
        rays += frame.counters[0].1;
        if frame.converged {
            break frame.image(&ctx).unwrap();
        }
        assert!(calls < 10_000, "never converged");
    };
    eprintln!("progressive reference: {calls} calls, {rays} camera rays");
    assert!(calls > 1, "a 1 ms budget should take several calls");
    // Every pixel traced exactly once, and the result is the full render's.
    assert_eq!(rays, (width * height) as u64);
    assert_eq!(image.pixels, exact.pixels);
    // A moved camera starts over.
    let mut moved = scene.camera.clone();
    moved.eye += Vec3::new(0.05, 0.0, 0.0);
    let frame = progressive
        .render(&ctx, &live, &moved, width, height)
        .unwrap();
    assert!(!frame.converged);
}

/// The mirror of `door-mirror` moved `step` times by the test's rigid step.
fn move_mirror(live: &mut LiveScene, ctx: &Context, steps: u32) {
    let mirror = live.object("door mirror").unwrap();
    for _ in 0..steps {
        live.translate_object(ctx.gpu.as_ref(), mirror, Vec3::new(0.004, -0.002, 0.003))
            .unwrap();
        live.rotate_object(ctx.gpu.as_ref(), mirror, Vec3::new(0.2, 1.0, 0.1), 1.5)
            .unwrap();
    }
}

#[test]
fn moving_an_object_through_the_update_path_matches_a_fresh_prepare() {
    let Some(ctx) = specula_methods::test_context("update path") else {
        return;
    };
    let scene = specula_scene::load("door-mirror").unwrap();
    for info in METHODS {
        let mut live = LiveScene::new(scene.clone());
        let mut technique = (info.create)();
        small(technique.as_mut());
        technique.prepare(&ctx, &live).unwrap();
        let first = technique
            .render(&ctx, &live, &scene.camera, WIDTH, HEIGHT)
            .unwrap()
            .image(&ctx)
            .unwrap();
        let mut worst: f32 = 0.0;
        let mut last_change: f32 = 0.0;
        for step in 1..=10 {
            move_mirror(&mut live, &ctx, 1);
            let updated = technique
                .render(&ctx, &live, &scene.camera, WIDTH, HEIGHT)
                .unwrap()
                .image(&ctx)
                .unwrap();
            // A fresh technique on a fresh scene moved the same way.
            let mut fresh_live = LiveScene::new(scene.clone());
            move_mirror(&mut fresh_live, &ctx, step);
            let mut fresh = (info.create)();
            small(fresh.as_mut());
            fresh.prepare(&ctx, &fresh_live).unwrap();
            let expected = fresh
                .render(&ctx, &fresh_live, &scene.camera, WIDTH, HEIGHT)
                .unwrap()
                .image(&ctx)
                .unwrap();
            worst = worst.max(rmse(&updated, &expected));
            last_change = rmse(&updated, &first);
        }
        eprintln!(
            "{}: update path against fresh prepare, worst RMSE over 10 steps {worst:.2e}; the move changed the image by RMSE {last_change:.4}",
            info.name
        );
        assert!(
            last_change > 0.01,
            "{}: the move must change the picture",
            info.name
        );
        assert!(worst <= 1e-5, "{}: RMSE {worst}", info.name);
    }
}

/// Every way a method can run on a GPU: each method that needs one or can use one, with the
/// settings that put its optional GPU paths on the GPU (on lavapipe `auto` picks the CPU).
fn gpu_configurations() -> Vec<(&'static str, Vec<&'static str>)> {
    let mut configurations = Vec::new();
    for info in METHODS.iter().filter(|m| m.needs_gpu || m.gpu_optional) {
        configurations.push((info.name, Vec::new()));
        match info.name {
            "c3rc" => configurations.push((info.name, vec!["projection=gpu"])),
            "vertex-tracing" => configurations.push((info.name, vec!["visibility=gpu"])),
            _ => {}
        }
    }
    configurations
}

/// Warm frames held by the live-object check, after the three that settle.
const WARM_FRAMES: usize = 10;

/// Renders one frame and reads it back as the error view and `compare` do; returns what the
/// lifecycle counted the frame and then the readback creating.
fn rendered(
    technique: &mut dyn Technique,
    ctx: &Context,
    live: &LiveScene,
    camera: &specula_scene::Camera,
) -> (specula_gpu::ResourceCounts, specula_gpu::ResourceCounts) {
    let frame = technique.render(ctx, live, camera, WIDTH, HEIGHT).unwrap();
    let before = ctx.resource_counts();
    frame.image(ctx).unwrap();
    (frame.created(), ctx.resource_counts() - before)
}

/// Three frames that settle, then WARM_FRAMES warm ones, held by two independent sources: the
/// lifecycle's creation count (GpuContext's wrappers) must be 0 from the third frame on, in the
/// frame and in its readback, and the objects alive on the device (wgpu-hal's own counters,
/// which see objects made around the wrappers too: views, pipelines, samplers, query sets)
/// must stay as they were after the third. The first two prepare (the second may still make
/// what the first frame's size needed); the third frees: the raster pool drops the G-buffer
/// static cube maps were drawn in once a frame does not use it (measured: envmap,
/// image-space and c3rc free 5 textures and their views there). wgpu-hal 30's Vulkan texture
/// count only goes down (its create_texture does not add), which still shows a change.
/// Returns what broke.
fn warm_frame_failures(
    technique: &mut dyn Technique,
    ctx: &Context,
    live: &LiveScene,
    camera: &specula_scene::Camera,
    what: &str,
) -> Vec<String> {
    let gpu = ctx.gpu("live objects").unwrap();
    let (first, _) = rendered(technique, ctx, live, camera);
    rendered(technique, ctx, live, camera);
    let (third, third_read) = rendered(technique, ctx, live, camera);
    let settled = gpu.live_objects().unwrap();
    eprintln!("{what}: the first frame created {first:?}; alive after the third {settled:?}");
    let mut failures = Vec::new();
    if third.total() != 0 || third_read.total() != 0 {
        failures.push(format!(
            "{what}: the third frame created {third:?}, its readback {third_read:?}"
        ));
    }
    for frame in 1..=WARM_FRAMES {
        let (created, read) = rendered(technique, ctx, live, camera);
        let alive = gpu.live_objects().unwrap();
        if created.total() != 0 || read.total() != 0 {
            failures.push(format!(
                "{what}: warm frame {frame} created {created:?}, its readback {read:?}"
            ));
        }
        if alive != settled {
            failures.push(format!(
                "{what}: after warm frame {frame} the device holds {alive:?}, not {settled:?}"
            ));
        }
    }
    failures
}

#[test]
fn every_gpu_frame_reports_what_it_created_and_a_warm_frame_creates_nothing() {
    let Some(ctx) = specula_methods::test_context("steady state") else {
        return;
    };
    let configurations = gpu_configurations();
    for name in [
        "envmap",
        "pvrr",
        "distance-maps",
        "image-space",
        "c3rc",
        "vertex-tracing",
        "gpu-trace",
    ] {
        assert!(
            configurations.iter().any(|(n, _)| *n == name),
            "{name} runs on a GPU and must be covered"
        );
    }
    let mut failures = Vec::new();
    for scene_name in ["door-mirror", "spectacle-lens"] {
        let scene: Scene = specula_scene::load(scene_name).unwrap();
        let live = LiveScene::new(scene.clone());
        for (name, settings) in &configurations {
            let what = format!("{scene_name}, {name} {}", settings.join(" "));
            let mut technique = by_name(name).unwrap();
            small(technique.as_mut());
            for setting in settings {
                apply_setting(technique.as_mut(), setting).unwrap();
            }
            if *name == "pvrr" {
                apply_setting(technique.as_mut(), "markers=true").unwrap();
            }
            failures.extend(warm_frame_failures(
                technique.as_mut(),
                &ctx,
                &live,
                &scene.camera,
                &what,
            ));
            // With `dynamic`, maps are redrawn every frame, still without creating anything.
            if technique.info().param("dynamic").is_some() {
                apply_setting(technique.as_mut(), "dynamic=true").unwrap();
                let what = format!("{what} dynamic=true");
                failures.extend(warm_frame_failures(
                    technique.as_mut(),
                    &ctx,
                    &live,
                    &scene.camera,
                    &what,
                ));
                let frame = technique
                    .render(&ctx, &live, &scene.camera, WIDTH, HEIGHT)
                    .unwrap();
                let redrawn = frame
                    .counters
                    .iter()
                    .find(|(n, _)| n == "cube map faces rendered")
                    .unwrap()
                    .1;
                assert!(redrawn > 0, "{what}: dynamic redraws its maps");
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A technique that makes GPU objects every frame. `Counted` goes through GpuContext's
/// wrapper and reports nothing: the count is measured by the lifecycle, not told by the
/// technique (which has no way to tell it). `AroundTheLifecycle` calls wgpu itself, as clippy
/// forbids, and keeps what it made: only the device's own counters can see it.
enum CreatesEachFrame {
    Counted,
    AroundTheLifecycle(Vec<wgpu::Sampler>),
}

impl Technique for CreatesEachFrame {
    fn info(&self) -> &'static specula_methods::MethodInfo {
        by_name("envmap").unwrap().info()
    }
    fn params(&self) -> &dyn specula_core::ParamSet {
        &specula_core::NoParams
    }
    fn params_mut(&mut self) -> &mut dyn specula_core::ParamSet {
        // A unit struct: leaking one allocates nothing.
        Box::leak(Box::new(specula_core::NoParams))
    }
    fn invalidate(&mut self, _: specula_methods::Invalidates) {}
    fn prepare(
        &mut self,
        _: &Context,
        _: &LiveScene,
    ) -> Result<(), specula_methods::TechniqueError> {
        Ok(())
    }
    fn draw(
        &mut self,
        ctx: &Context,
        _: &LiveScene,
        _: &specula_scene::Camera,
        width: u32,
        height: u32,
    ) -> Result<specula_methods::Drawn, specula_methods::TechniqueError> {
        let gpu = ctx.gpu("test")?;
        match self {
            CreatesEachFrame::Counted => {
                gpu.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("made every frame"),
                    size: 16,
                    usage: wgpu::BufferUsages::UNIFORM,
                    mapped_at_creation: false,
                });
            }
            #[allow(clippy::disallowed_methods)]
            CreatesEachFrame::AroundTheLifecycle(kept) => kept.push(
                gpu.device
                    .create_sampler(&wgpu::SamplerDescriptor::default()),
            ),
        }
        Ok(specula_methods::Drawn {
            pixels: specula_methods::Pixels::Image(Image::new(width, height)),
            stages: Vec::new(),
            counters: Vec::new(),
            timing: specula_gpu::TimingSource::CpuWallClock,
            warnings: Vec::new(),
            converged: true,
        })
    }
}

#[test]
fn the_lifecycle_counts_what_a_technique_creates_whatever_the_technique_says() {
    let Some(ctx) = specula_methods::test_context("lifecycle count") else {
        return;
    };
    let scene = specula_scene::load("door-mirror").unwrap();
    let live = LiveScene::new(scene.clone());
    let mut technique: Box<dyn Technique> = Box::new(CreatesEachFrame::Counted);
    for _ in 0..3 {
        let frame = technique
            .render(&ctx, &live, &scene.camera, WIDTH, HEIGHT)
            .unwrap();
        assert_eq!(frame.created().buffers, 1);
        assert_eq!(frame.created().total(), 1);
    }
    // Both sources see the counted buffer (it is dropped at once, so the device's count stays
    // flat: the lifecycle's count is what catches it).
    let failures = warm_frame_failures(technique.as_mut(), &ctx, &live, &scene.camera, "counted");
    // The third frame and every warm one.
    assert_eq!(failures.len(), WARM_FRAMES + 1, "{failures:?}");
    assert!(
        failures.iter().all(|f| f.contains("buffers: 1")),
        "{failures:?}"
    );
}

#[test]
fn the_device_counts_what_a_technique_makes_around_the_lifecycle() {
    let Some(ctx) = specula_methods::test_context("live objects") else {
        return;
    };
    let scene = specula_scene::load("door-mirror").unwrap();
    let live = LiveScene::new(scene.clone());
    let mut technique: Box<dyn Technique> =
        Box::new(CreatesEachFrame::AroundTheLifecycle(Vec::new()));
    let failures = warm_frame_failures(
        technique.as_mut(),
        &ctx,
        &live,
        &scene.camera,
        "around the lifecycle",
    );
    eprintln!("{failures:#?}");
    // The lifecycle counts nothing, the device one more sampler each warm frame.
    assert_eq!(failures.len(), WARM_FRAMES, "{failures:?}");
    assert!(
        failures.iter().all(|f| f.contains("device holds")),
        "{failures:?}"
    );
}

#[test]
fn a_refitted_bvh_finds_the_hits_of_a_fresh_build_and_is_rebuilt_when_it_degrades() {
    let scene = specula_scene::load("teapot-box").unwrap();
    let mut live = LiveScene::new(scene);
    let teapot = (0..live.scene().meshes.len())
        .find(|&m| live.scene().materials[live.scene().meshes[m].material].is_specular())
        .unwrap();
    // A small move refits.
    let update = live.rotate_object(None, teapot, Vec3::Y, 20.0).unwrap();
    let specula_methods::AccelUpdate::Refitted { cost_ratio } = update else {
        panic!("a small move should refit: {update:?}");
    };
    eprintln!("teapot turned 20 degrees: refitted, SAH cost {cost_ratio:.3} x the build's");
    let fresh = specula_trace::SceneAccel::new(live.scene());
    live.accel()
        .bvh
        .validate(&live.accel().primitive_bounds())
        .unwrap();
    let camera = &live.scene().camera;
    let (mut hits, mut rays) = (0, 0);
    for y in 0..48 {
        for x in 0..64 {
            let ray = specula_trace::Ray {
                origin: camera.eye,
                dir: camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, 64, 48),
            };
            let a = live.accel().intersect(&ray, f32::INFINITY);
            let b = fresh.intersect(&ray, f32::INFINITY);
            assert_eq!(
                a.map(|h| (h.mesh, h.triangle, h.t)),
                b.map(|h| (h.mesh, h.triangle, h.t))
            );
            rays += 1;
            hits += a.is_some() as u32;
        }
    }
    assert!(hits > rays / 2);
    // Flung far away, the teapot's boxes span the room: the tree is rebuilt.
    let update = live
        .translate_object(None, teapot, Vec3::new(40.0, 0.0, 0.0))
        .unwrap();
    eprintln!("teapot moved 40 m: {update:?}");
    assert!(
        matches!(update, specula_methods::AccelUpdate::Rebuilt { cost_ratio } if cost_ratio > 1.5)
    );
    // A non-rigid move is refused.
    assert!(live
        .move_object(None, teapot, glam::Mat4::from_scale(Vec3::splat(2.0)))
        .is_err());
}
