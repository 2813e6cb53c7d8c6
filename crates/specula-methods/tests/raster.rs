//! The scene raster pass against the exact reference on the pixels that see no specular
//! surface (the specular ones are the techniques' job).

use specula_methods::raster::{self, RasterPass, RasterSpec};
use specula_methods::LiveScene;
use specula_trace::{render, Image, RenderSettings, SceneAccel};

/// Mean FLIP over pixels where the raster G-buffer shows no mirror or dielectric, at 128×128
/// with 1024² shadow maps, measured 2026-12-01 on lavapipe with `cargo test -p specula-methods
/// --test raster -- --nocapture`: 0.0013 (teapot-box), 0.0054 (mirror-teapot-bunny); the
/// differences are shadow-map texels at shadow edges and silhouette pixels. Bounds about 1.5×
/// each (one bound of 0.01 for both was 7.7× the teapot-box figure).
const MEAN_FLIP_MAX_TEAPOT_BOX: f32 = 0.002;
const MEAN_FLIP_MAX_MIRROR_TEAPOT_BUNNY: f32 = 0.008;

fn flip_map(reference: &Image, test: &Image) -> Vec<f32> {
    let to_flip = |i: &Image| {
        let rgb = i.to_srgb8();
        nv_flip::FlipImageRgb8::with_data(rgb.width(), rgb.height(), rgb.as_raw())
    };
    nv_flip::flip(
        to_flip(reference),
        to_flip(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    )
    .to_vec()
}

fn check(scene_name: &str, mean_flip_max: f32) -> f32 {
    let Some(ctx) = specula_gpu::test_context(scene_name) else {
        return 0.0;
    };
    let scene = specula_scene::load(scene_name).unwrap();
    let (width, height) = (128, 128);
    let accel = SceneAccel::new(&scene);
    let reference = render(
        &scene,
        &accel,
        &RenderSettings {
            width,
            height,
            spp: 1,
            max_depth: 8,
        },
        &|_, _| {},
    );
    let live = LiveScene::new(scene.clone());
    let gpu_scene = live.gpu(&ctx);
    let pass = RasterPass::new(&ctx, &live, RasterSpec::scene(1024)).unwrap();
    let camera = raster::camera_uniform(&scene.camera, &scene.bounds(), width, height);
    let g = pass.render(&ctx, gpu_scene, &camera, None).unwrap();
    let mut image = g.read_color(&ctx).unwrap();
    let ids = g.read_ids(&ctx).unwrap();
    assert!(image.pixels.iter().all(|p| p.is_finite()));
    let specular = |i: usize| {
        ids[i][0] != 0
            && scene.materials[scene.meshes[ids[i][0] as usize - 1].material].is_specular()
    };
    // FLIP filters spatially: give the specular pixels the reference's values so their (large,
    // expected) difference does not bleed into the neighbouring pixels being judged.
    for i in (0..ids.len()).filter(|&i| specular(i)) {
        image.pixels[i] = reference.pixels[i];
    }
    let flip = flip_map(&reference, &image);
    let diffuse: Vec<usize> = (0..ids.len()).filter(|&i| !specular(i)).collect();
    assert!(
        diffuse.len() > 1000,
        "{scene_name}: too few non-specular pixels"
    );
    let mean = diffuse.iter().map(|&i| flip[i]).sum::<f32>() / diffuse.len() as f32;
    eprintln!(
        "{scene_name}: mean FLIP on {} non-specular pixels: {mean:.4}",
        diffuse.len()
    );
    if mean > mean_flip_max {
        let dir = std::env::temp_dir();
        image
            .save_png(&dir.join(format!("{scene_name}-raster-actual.png")))
            .unwrap();
        reference
            .save_png(&dir.join(format!("{scene_name}-raster-reference.png")))
            .unwrap();
        panic!(
            "{scene_name}: mean FLIP {mean:.4} > {mean_flip_max}; images in {}",
            dir.display()
        );
    }
    // The ID buffer agrees with the reference's primary hits.
    let hits = specula_trace::reference::primary_hits(&scene, &accel, width, height);
    let agree = hits
        .iter()
        .zip(&ids)
        .filter(|(hit, id)| hit.map(|h| [h.mesh + 1, h.triangle]).unwrap_or([0, 0]) == **id)
        .count();
    let share = agree as f32 / (width * height) as f32;
    eprintln!(
        "{scene_name}: ID buffer agrees with the reference's primary hits on {:.2} % of pixels",
        share * 100.0
    );
    assert!(
        share > 0.97,
        "{scene_name}: ID buffer agrees on only {share}"
    );
    mean
}

#[test]
fn teapot_box_non_specular_pixels_match_the_reference() {
    check("teapot-box", MEAN_FLIP_MAX_TEAPOT_BOX);
}

#[test]
fn mirror_teapot_bunny_non_specular_pixels_match_the_reference() {
    check("mirror-teapot-bunny", MEAN_FLIP_MAX_MIRROR_TEAPOT_BUNNY);
}

#[test]
fn geometry_targets_match_the_shaded_pass_without_colour_or_shadows() {
    let Some(ctx) = specula_gpu::test_context("geometry targets") else {
        return;
    };
    let scene = specula_scene::load("teapot-box").unwrap();
    let (width, height) = (64, 48);
    let live = LiveScene::new(scene.clone());
    let camera = raster::camera_uniform(&scene.camera, &scene.bounds(), width, height);
    let shaded = RasterPass::new(&ctx, &live, RasterSpec::scene(256)).unwrap();
    let geometry_spec = RasterSpec {
        targets: raster::Targets::Geometry,
        ..RasterSpec::scene(256)
    };
    let geometry = RasterPass::new(&ctx, &live, geometry_spec).unwrap();
    geometry.begin_frame(&ctx, &live).unwrap();
    let g = geometry
        .render(&ctx, live.gpu(&ctx), &camera, None)
        .unwrap();
    let s = shaded.render(&ctx, live.gpu(&ctx), &camera, None).unwrap();
    assert_eq!(g.read_ids(&ctx).unwrap(), s.read_ids(&ctx).unwrap());
    for (a, b) in [(&g.position, &s.position), (&g.normal, &s.normal)] {
        assert_eq!(
            raster::read_rgba32f(&ctx, a).unwrap().pixels,
            raster::read_rgba32f(&ctx, b).unwrap().pixels
        );
    }
    let ids = g.read_ids(&ctx).unwrap();
    let colour = g.read_color(&ctx).unwrap();
    let geometry_pixels = (0..ids.len()).filter(|&i| ids[i][0] != 0);
    assert!(geometry_pixels.clone().count() > 1000);
    assert!(geometry_pixels
        .into_iter()
        .all(|i| colour.pixels[i] == glam::Vec3::ZERO));
    assert!(s
        .read_color(&ctx)
        .unwrap()
        .pixels
        .iter()
        .any(|c| *c != glam::Vec3::ZERO));
}

#[test]
fn the_pool_keeps_one_frames_g_buffers_and_drops_other_sizes() {
    let Some(ctx) = specula_gpu::test_context("g-buffer pool") else {
        return;
    };
    let live = LiveScene::new(specula_scene::load("door-mirror").unwrap());
    let pass = RasterPass::new(&ctx, &live, RasterSpec::scene(64)).unwrap();
    let frame = |sizes: &[(u32, u32)]| {
        pass.begin_frame(&ctx, &live).unwrap();
        let before = ctx.resource_counts();
        for &(w, h) in sizes {
            pass.acquire(&ctx, w, h);
        }
        (ctx.resource_counts() - before).textures
    };
    assert_eq!(
        frame(&[(64, 48), (64, 48)]),
        10,
        "two new G-buffers of 5 textures"
    );
    assert_eq!(
        frame(&[(64, 48), (64, 48)]),
        0,
        "a steady frame reuses them"
    );
    assert_eq!(pass.pooled(), 2);
    // A resized view: the old size is dropped after one frame without it.
    assert_eq!(frame(&[(32, 24)]), 5);
    assert_eq!(pass.pooled(), 3);
    assert_eq!(frame(&[(32, 24)]), 0);
    assert_eq!(pass.pooled(), 1);
}

/// A camera at the origin looking down −z, 32 × 32, 60° wide, depth from 0.1 to `far`.
fn looking_down_z(far: f32) -> specula_gpu::shaders::CameraUniform {
    specula_gpu::shaders::CameraUniform::new(
        glam::Vec3::ZERO,
        glam::Vec3::X,
        glam::Vec3::Y,
        glam::Vec3::NEG_Z,
        60.0,
        32,
        32,
        0.1,
        far,
    )
}

/// Two planes facing the eye down −z: an unlit red one 1 away, a diffuse grey one 2 away, a
/// light beside the eye.
fn two_planes() -> LiveScene {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two-planes.toml");
    std::fs::write(
        &path,
        r#"
name = "two planes"
ambient = 0.1
[camera]
eye = [0.0, 0.0, 0.0]
target = [0.0, 0.0, -1.0]
[materials.red]
type = "unlit"
color = [1.0, 0.0, 0.0]
[materials.grey]
type = "diffuse"
color = 0.8
[[lights]]
type = "point"
position = [0.0, 0.3, 0.5]
intensity = 2.0
[[objects]]
name = "near"
material = "red"
translate = [0.0, 0.0, -1.0]
rotate_deg = [90, 0, 0]
shape = { type = "plane", size = [0.4, 0.4] }
[[objects]]
name = "far"
material = "grey"
translate = [0.0, 0.0, -2.0]
rotate_deg = [90, 0, 0]
shape = { type = "plane", size = [4.0, 4.0] }
"#,
    )
    .unwrap();
    LiveScene::new(specula_scene::load(path.to_str().unwrap()).unwrap())
}

/// The reversed depth test of pvrr's zooming view: the farthest surface between the near and
/// far planes is kept, lit on its side away from the camera; where none lies in that range
/// the G-buffer keeps what it held.
#[test]
fn the_farthest_draw_keeps_the_farthest_surface_in_range_lit_from_behind() {
    let Some(ctx) = specula_gpu::test_context("farthest surface") else {
        return;
    };
    let live = two_planes();
    let pass = RasterPass::new(&ctx, &live, RasterSpec::scene(64)).unwrap();
    pass.begin_frame(&ctx, &live).unwrap();
    let gpu = live.gpu(&ctx);
    let centre = |g: &raster::GBuffer| g.read_color(&ctx).unwrap().get(16, 16);
    let corner = |g: &raster::GBuffer| g.read_color(&ctx).unwrap().get(1, 1);
    let nearest = pass.render(&ctx, gpu, &looking_down_z(3.0), None).unwrap();
    let (red, lit_grey) = (centre(&nearest), corner(&nearest));
    assert!(red.x > 0.99 && red.y < 0.01, "{red}");
    assert!(lit_grey.x > 0.1, "{lit_grey}");
    // Both planes in range: the far one, lit from behind (ambient only: 0.8 × 0.1).
    let g = pass.render(&ctx, gpu, &looking_down_z(3.0), None).unwrap();
    pass.draw_farthest_into(&ctx, gpu, &looking_down_z(3.0), &[], None, &g)
        .unwrap();
    let (far_centre, far_corner) = (centre(&g), corner(&g));
    assert!(
        (far_centre - glam::Vec3::splat(0.08)).abs().max_element() < 1e-3,
        "{far_centre}"
    );
    assert!(
        (far_corner - glam::Vec3::splat(0.08)).abs().max_element() < 1e-3,
        "{far_corner}"
    );
    // The far plane before the grey one: the red one is the farthest in range, drawn over a
    // G-buffer that holds the background only (a view whose far plane is before both).
    let g = pass.render(&ctx, gpu, &looking_down_z(0.5), None).unwrap();
    let background = corner(&g);
    assert_ne!(centre(&g), red);
    pass.draw_farthest_into(&ctx, gpu, &looking_down_z(1.5), &[], None, &g)
        .unwrap();
    assert_eq!(centre(&g), red);
    assert_eq!(corner(&g), background, "nothing in range: kept");
    // Nothing in range: everything kept.
    let g = pass.render(&ctx, gpu, &looking_down_z(3.0), None).unwrap();
    pass.draw_farthest_into(&ctx, gpu, &looking_down_z(0.5), &[], None, &g)
        .unwrap();
    assert_eq!(
        g.read_color(&ctx).unwrap().pixels,
        nearest.read_color(&ctx).unwrap().pixels
    );
}
