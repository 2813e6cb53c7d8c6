//! `pvrr`: at the mirror's vertices the image shows what the ray tracer shows; in between, the
//! error falls as the mirror is refined.

use glam::Vec3;
use specula_methods::by_name;
use specula_scene::Scene;
use specula_trace::reference::primary_hits;
use specula_trace::{render, Image, RenderSettings, SceneAccel};

const SIZE: u32 = 256;

/// Pixel of world point `p`, if it is in the image.
fn pixel_of(scene: &Scene, p: Vec3) -> Option<(u32, u32)> {
    let f = scene.camera.frame();
    let q = p - scene.camera.eye;
    let z = q.dot(f.forward);
    let tan = (scene.camera.fov_y_deg.to_radians() * 0.5).tan();
    let (x, y) = (q.dot(f.right) / (z * tan), q.dot(f.up) / (z * tan));
    let (px, py) = ((x + 1.0) * 0.5 * SIZE as f32, (1.0 - y) * 0.5 * SIZE as f32);
    (z > 0.0 && px >= 0.0 && py >= 0.0 && px < SIZE as f32 && py < SIZE as f32)
        .then_some((px as u32, py as u32))
}

/// Mean colour difference to the reference at the pixels holding the mirror's vertices, and at
/// the pixels holding its triangles' centroids.
fn vertex_and_centroid_errors(scene: &Scene, reference: &Image, image: &Image) -> (f32, f32) {
    let accel = SceneAccel::new(scene);
    let mirror = scene
        .meshes
        .iter()
        .position(|m| m.name == "door mirror")
        .unwrap();
    let mesh = &scene.meshes[mirror];
    let visible = |p: Vec3| {
        let dir = (p - scene.camera.eye).normalize();
        let hit = accel.intersect(
            &specula_trace::Ray {
                origin: scene.camera.eye,
                dir,
            },
            f32::INFINITY,
        );
        hit.is_some_and(|h| h.mesh as usize == mirror)
    };
    let error_at = |points: &mut dyn Iterator<Item = Vec3>| {
        let errors: Vec<f32> = points
            .filter(|&p| visible(p))
            .filter_map(|p| pixel_of(scene, p))
            .map(|(x, y)| (image.get(x, y) - reference.get(x, y)).abs().max_element())
            .collect();
        assert!(errors.len() > 10);
        errors.iter().sum::<f32>() / errors.len() as f32
    };
    // Vertices pulled 0.1 % towards the mirror's centre so their pixel is on the mirror.
    let center = mesh.bounds().center();
    let vertices = error_at(&mut mesh.positions.iter().map(|&v| v + (center - v) * 0.001));
    let centroids = error_at(
        &mut mesh
            .triangles
            .iter()
            .map(|t| t.iter().map(|&i| mesh.positions[i as usize]).sum::<Vec3>() / 3.0),
    );
    (vertices, centroids)
}

/// The reference image and a pvrr frame (checked free of NaN) of `scene` at SIZE².
fn reference_and_pvrr(
    ctx: &specula_gpu::GpuContext,
    scene: &Scene,
) -> (Image, specula_methods::Frame) {
    let accel = SceneAccel::new(scene);
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        spp: 1,
        max_depth: 8,
    };
    let reference = render(scene, &accel, &settings, &|_, _| {});
    let mut pvrr = by_name("pvrr").unwrap();
    pvrr.prepare(ctx, scene).unwrap();
    let frame = pvrr.render(ctx, scene, &scene.camera, SIZE, SIZE).unwrap();
    assert!(frame.image.pixels.iter().all(|p| p.is_finite()));
    (reference, frame)
}

#[test]
fn vertices_show_the_ray_traced_reflection() {
    let Some(ctx) = specula_gpu::test_context("pvrr vertices") else {
        return;
    };
    let scene = specula_scene::load("door-mirror").unwrap();
    let (reference, frame) = reference_and_pvrr(&ctx, &scene);
    let (at_vertices, at_centroids) = vertex_and_centroid_errors(&scene, &reference, &frame.image);
    eprintln!("pvrr door-mirror {SIZE}²: mean error at vertex pixels {at_vertices:.4}, at centroid pixels {at_centroids:.4}");
    assert!(at_vertices < 0.01, "at vertices {at_vertices}");
    assert!(
        at_vertices * 4.0 < at_centroids,
        "vertices {at_vertices} vs centroids {at_centroids}"
    );
}

/// RMSE over the mirror's pixels, pvrr against the reference, with the door mirror tessellated
/// into `n` × `n` quads.
fn mirror_rmse(ctx: &specula_gpu::GpuContext, n: u32) -> f32 {
    let scene = specula_scene::builtin::door_mirror_tessellated(n).unwrap();
    let mirror = scene
        .meshes
        .iter()
        .position(|m| m.name == "door mirror")
        .unwrap();
    let accel = SceneAccel::new(&scene);
    let reference = render(
        &scene,
        &accel,
        &RenderSettings {
            width: SIZE,
            height: SIZE,
            spp: 1,
            max_depth: 8,
        },
        &|_, _| {},
    );
    let mut pvrr = by_name("pvrr").unwrap();
    pvrr.prepare(ctx, &scene).unwrap();
    let image = pvrr
        .render(ctx, &scene, &scene.camera, SIZE, SIZE)
        .unwrap()
        .image;
    let hits = primary_hits(&scene, &accel, SIZE, SIZE);
    let on_mirror: Vec<usize> = (0..hits.len())
        .filter(|&i| hits[i].is_some_and(|h| h.mesh as usize == mirror))
        .collect();
    let sum: f32 = on_mirror
        .iter()
        .map(|&i| (image.pixels[i] - reference.pixels[i]).length_squared() / 3.0)
        .sum();
    (sum / on_mirror.len() as f32).sqrt()
}

#[test]
fn error_falls_as_the_mirror_is_refined() {
    let Some(ctx) = specula_gpu::test_context("pvrr refinement") else {
        return;
    };
    let errors: Vec<(u32, f32)> = [6, 12, 24]
        .iter()
        .map(|&n| ((n + 1) * (n + 1), mirror_rmse(&ctx, n)))
        .collect();
    eprintln!("pvrr door-mirror {SIZE}², (vertices, RMSE on mirror pixels): {errors:?}");
    for pair in errors.windows(2) {
        assert!(
            pair[1].1 < pair[0].1,
            "refining from {} to {} vertices did not reduce the error: {errors:?}",
            pair[0].0,
            pair[1].0
        );
    }
}

/// A concave spherical mirror (R = 2 m) facing a camera 3 m away, with objects well beyond its
/// focal region behind the camera: reflection lines converge in front of the mirror, so the
/// virtual viewpoint lies on the far side of the convergence point and the map is reversed.
fn concave_scene() -> Scene {
    use glam::Mat4;
    use specula_scene::{generators, Background, Camera, Light, Material};
    let mut scene = Scene::new("concave");
    let add = |mut mesh: specula_scene::Mesh,
               material: Material,
               world_from_object: Mat4,
               scene: &mut Scene| {
        mesh.transform(world_from_object);
        mesh.material = scene.materials.len();
        mesh.name = material.name.clone();
        scene.materials.push(material);
        scene.meshes.push(mesh);
    };
    let cap = generators::spherical_cap(2.0, 0.8, true, 6, 24).unwrap();
    add(
        cap,
        Material::mirror("door mirror", Vec3::splat(0.9)),
        Mat4::IDENTITY,
        &mut scene,
    );
    for (k, color) in [
        Vec3::new(0.8, 0.1, 0.1),
        Vec3::new(0.1, 0.7, 0.2),
        Vec3::new(0.2, 0.3, 0.9),
    ]
    .into_iter()
    .enumerate()
    {
        let x = -3.0 + 3.0 * k as f32;
        add(
            generators::cuboid(Vec3::new(2.0, 4.0, 1.0)),
            Material::diffuse("block", color),
            Mat4::from_translation(Vec3::new(x, 0.5, 12.0)),
            &mut scene,
        );
    }
    add(
        generators::plane(glam::Vec2::splat(60.0), 1),
        Material::diffuse("ground", Vec3::splat(0.5)),
        Mat4::from_translation(Vec3::new(0.0, -1.5, 0.0)),
        &mut scene,
    );
    scene.lights.push(Light::Directional {
        direction: Vec3::new(-0.3, -1.0, -0.5).normalize(),
        irradiance: Vec3::splat(2.0),
    });
    scene.ambient = Vec3::splat(0.2);
    scene.background = Background::Color(Vec3::new(0.5, 0.6, 0.8));
    scene.camera = Camera {
        eye: Vec3::new(0.2, 0.1, 3.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg: 12.0,
        aspect: None,
    };
    scene
}

#[test]
fn concave_mirror_vertices_show_the_ray_traced_reflection() {
    let Some(ctx) = specula_gpu::test_context("pvrr concave") else {
        return;
    };
    let scene = concave_scene();
    let (reference, frame) = reference_and_pvrr(&ctx, &scene);
    let (at_vertices, at_centroids) = vertex_and_centroid_errors(&scene, &reference, &frame.image);
    eprintln!("pvrr concave {SIZE}²: mean error at vertex pixels {at_vertices:.4}, at centroid pixels {at_centroids:.4}");
    assert!(at_vertices < 0.02, "at vertices {at_vertices}");
}

#[test]
fn parallel_reflection_lines_fall_back_with_a_warning_and_no_nan() {
    let Some(ctx) = specula_gpu::test_context("pvrr parallel lines") else {
        return;
    };
    let mut scene = specula_scene::load("door-mirror").unwrap();
    // A flat mirror seen from 100 km through a telephoto lens: every reflection line is
    // parallel to within 2e-6 rad, so the least-squares viewpoint does not exist.
    let mirror = scene
        .meshes
        .iter()
        .position(|m| m.name == "door mirror")
        .unwrap();
    let material = scene.meshes[mirror].material;
    let mut flat = specula_scene::generators::plane(glam::Vec2::new(0.2, 0.13), 6);
    flat.transform(glam::Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2));
    flat.material = material;
    flat.name = "door mirror".into();
    scene.meshes[mirror] = flat;
    scene.camera.eye = Vec3::new(0.0, 0.0, 1.0e5);
    scene.camera.target = Vec3::ZERO;
    scene.camera.fov_y_deg = 2.0e-4;
    let mut pvrr = by_name("pvrr").unwrap();
    pvrr.prepare(&ctx, &scene).unwrap();
    let frame = pvrr.render(&ctx, &scene, &scene.camera, 32, 32).unwrap();
    assert!(
        frame.image.pixels.iter().all(|p| p.is_finite()),
        "NaN or inf pixels"
    );
    assert_eq!(frame.warnings.len(), 1, "{:?}", frame.warnings);
    assert!(frame.warnings[0].contains("door mirror") && frame.warnings[0].contains("parallel"));
}
