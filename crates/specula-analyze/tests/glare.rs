//! `glare` against closed forms: a flat metal plate (F0 = 1) shows a small emitter exactly to the
//! eye points whose line to the emitter's mirror image crosses the plate, at the emitter's own
//! luminance; a thick glass pane's front reflection has the unpolarised Fresnel reflectance at
//! its angle; a ball seen in a metal plate covers its mirror image's solid angle, its centroid
//! at the image's centre.

use glam::{Mat4, Vec3};
use specula_analyze::frame::{Eyes, VehicleFrame};
use specula_analyze::glare::{self, Glare, Options, Source};
use specula_scene::{generators, Camera, Material, MaterialKind, Mesh, Scene};
use specula_trace::SceneAccel;

fn placed(mut mesh: Mesh, name: &str, material: usize, world_from_object: Mat4) -> Mesh {
    mesh.name = name.into();
    mesh.material = material;
    for p in &mut mesh.positions {
        *p = world_from_object.transform_point3(*p);
    }
    for n in &mut mesh.normals {
        *n = world_from_object.transform_vector3(*n).normalize();
    }
    mesh
}

/// A scene of a reflecting `surface` (material 0) and a small unlit white ball (material 1,
/// radius `radius`) at `emitter`, seen from `eye`.
fn scene(
    surface: Mesh,
    surface_material: Material,
    emitter: Vec3,
    radius: f32,
    eye: Vec3,
) -> Scene {
    let mut scene = Scene::new("glare closed form");
    scene.materials.push(surface_material);
    scene
        .materials
        .push(Material::unlit("emitter", Vec3::splat(4.0)));
    scene
        .meshes
        .push(placed(surface, "surface", 0, Mat4::IDENTITY));
    scene.meshes.push(placed(
        generators::sphere(radius, 24, 12),
        "emitter",
        1,
        Mat4::from_translation(emitter),
    ));
    scene.camera = Camera {
        eye,
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg: 40.0,
        aspect: None,
    };
    scene
}

fn options(width: u32, height: u32) -> Options {
    Options {
        surface: 0,
        source: Source::Named(1),
        source_luminance: None,
        display: None,
        width,
        height,
        max_depth: 8,
        threshold: 1e-3,
    }
}

/// The analysis in the scene camera's vehicle frame (looking along −z unless the camera says
/// otherwise).
fn analyze(
    scene: &Scene,
    accel: &SceneAccel,
    eyes: &[Vec3],
    options: &Options,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Glare, specula_analyze::AnalyzeError> {
    let frame = VehicleFrame::for_eyes(&scene.camera, None, &Eyes::Camera).unwrap();
    glare::analyze(scene, accel, eyes, &frame, options, progress)
}

#[test]
fn a_metal_plate_shows_the_emitter_to_the_eyes_whose_line_to_its_image_crosses_it() {
    // A 0.4 m square plate in z = 0 facing +z; the emitter beside the eyes.
    let plate = placed(
        generators::plane(glam::Vec2::splat(0.4), 1),
        "plate",
        0,
        Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    let metal = Material::new("metal", MaterialKind::Mirror { fresnel: false }, Vec3::ONE);
    let emitter = Vec3::new(0.35, 0.0, 0.6);
    let centre = Vec3::new(0.05, 0.0, 0.6);
    let scene = scene(plate, metal, emitter, 0.02, centre);
    let plate_mesh = &scene.meshes[0];
    let bounds = plate_mesh.bounds();
    assert!(
        (bounds.max.z - bounds.min.z).abs() < 1e-6 && bounds.max.x > 0.19,
        "the plate lies in z = 0: {bounds:?}"
    );
    let frame = VehicleFrame::new(&scene.camera, Some(Vec3::NEG_Z)).unwrap();
    let columns = 9;
    let eyes = Eyes::Eyebox {
        width: 0.4,
        height: 0.1,
        columns,
        rows: 3,
    }
    .points(centre, &frame)
    .unwrap();
    let accel = SceneAccel::new(&scene);
    let glare = analyze(&scene, &accel, &eyes, &options(160, 120), &|_| {}).unwrap();

    // Where each eye's line to the emitter's mirror image meets the plate's plane.
    let image = Vec3::new(emitter.x, emitter.y, -emitter.z);
    let step = 0.4 / (columns - 1) as f32 * 0.5; // an eye step, on the plate
    let (mut with, mut without) = (0, 0);
    for (eye, figures) in eyes.iter().zip(&glare.report.eyes) {
        let t = eye.z / (eye.z - image.z);
        let p = *eye + (image - *eye) * t;
        let inside = p.x.abs() <= bounds.max.x && p.y.abs() <= bounds.max.y;
        let margin = (p.x.abs() - bounds.max.x).abs();
        eprintln!(
            "eye {eye}: meets the plane at {p}, inside {inside}; glare {} (relative {:.4})",
            figures.glare, figures.max_luminance_factor
        );
        if margin > step {
            assert_eq!(figures.glare, inside, "eye {eye}");
        }
        if figures.glare {
            with += 1;
            // Measured: 1 exactly (F0 = 1, no Fresnel): the source's own luminance.
            assert!((figures.max_luminance_factor - 1.0).abs() < 1e-3);
        } else {
            without += 1;
        }
    }
    eprintln!("{with} eye points with glare, {without} without");
    assert!(with * 10 >= eyes.len() * 3 && without * 10 >= eyes.len() * 3);
    let share = glare.report.share_with_glare;
    assert!((share - with as f64 / eyes.len() as f64).abs() < 1e-12);
    assert!(glare.report.worst_eye.is_some());
}

/// The pixel of a `width` × `height` image from `camera` whose ray is nearest direction `dir`.
fn pixel_towards(camera: &Camera, width: u32, height: u32, dir: Vec3) -> usize {
    let towards = dir.normalize();
    let along = |i: u32| {
        camera
            .ray_direction(
                (i % width) as f32 + 0.5,
                (i / width) as f32 + 0.5,
                width,
                height,
            )
            .dot(towards)
    };
    (0..width * height)
        .max_by(|a, b| along(*a).total_cmp(&along(*b)))
        .expect("an image has pixels") as usize
}

/// The Fresnel reflectances (R_s, R_p) from air into index `n` at incidence `cos_i`, from the
/// Fresnel equations.
fn fresnel_sp(cos_i: f64, n: f64) -> (f64, f64) {
    let sin_t = (1.0 - cos_i * cos_i).sqrt() / n;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    let rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    (rs * rs, rp * rp)
}

/// The unpolarised Fresnel reflectance: the mean of s and p.
fn fresnel(cos_i: f64, n: f64) -> f64 {
    let (rs, rp) = fresnel_sp(cos_i, n);
    0.5 * (rs + rp)
}

/// A thin sheet's unpolarised reflectance, each polarisation's two faces summed apart.
fn sheet_reflectance(cos_i: f64, n: f64) -> f64 {
    let (rs, rp) = fresnel_sp(cos_i, n);
    0.5 * (2.0 * rs / (1.0 + rs) + 2.0 * rp / (1.0 + rp))
}

#[test]
fn a_thick_glass_pane_s_front_reflection_has_the_fresnel_reflectance_of_its_angle() {
    let thickness = 0.06;
    let pane = generators::cuboid(Vec3::new(0.3, 0.3, thickness));
    let emitter = Vec3::new(0.25, 0.0, 0.45);
    let eye = Vec3::new(-0.25, 0.0, 0.45);
    let scene = scene(pane, Material::glass("glass", 1.5), emitter, 0.008, eye);
    let accel = SceneAccel::new(&scene);
    let glare = analyze(&scene, &accel, &[eye], &options(640, 480), &|_| {}).unwrap();
    let figures = &glare.report.eyes[0];
    assert!(figures.glare);
    // The front face's specular point for the emitter's centre.
    let front = thickness * 0.5;
    let image = Vec3::new(emitter.x, emitter.y, 2.0 * front - emitter.z);
    let p = eye + (image - eye) * ((eye.z - front) / (eye.z - image.z));
    let cos_i = f64::from((eye - p).normalize().z);
    let expected = fresnel(cos_i, 1.5);
    // The pixel whose ray goes through the specular point (the box's rim and back face show the
    // emitter too, by other paths, elsewhere in the image).
    let images = &glare.images[0];
    let (width, height) = (640, 480);
    let pixel = pixel_towards(&images.camera, width, height, p - eye);
    let relative = images.factor[pixel];
    eprintln!(
        "front reflection at {:.2}°: relative luminance {relative:.5}, Fresnel {expected:.5}",
        cos_i.acos().to_degrees()
    );
    // Measured: 4.8e-4 (the pixel's ray is not exactly the centre's); the issue asks 2 %.
    assert!((relative - expected).abs() / expected < 1e-3);
    assert!(figures.max_luminance_factor >= relative);
}

#[test]
fn bad_input_and_no_glare() {
    let plate = placed(
        generators::plane(glam::Vec2::splat(0.4), 1),
        "plate",
        0,
        Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    let metal = Material::new("metal", MaterialKind::Mirror { fresnel: false }, Vec3::ONE);
    // The emitter behind the plate: no path reaches it by a reflection.
    let eye = Vec3::new(0.0, 0.0, 0.6);
    let scene = scene(plate, metal, Vec3::new(0.0, 0.0, -0.5), 0.02, eye);
    let accel = SceneAccel::new(&scene);
    let glare = analyze(&scene, &accel, &[eye], &options(64, 48), &|_| {}).unwrap();
    assert!(!glare.report.eyes[0].glare);
    assert_eq!(glare.report.share_with_glare, 0.0);
    assert_eq!(glare.report.worst_eye, None);

    let swapped = Options {
        surface: 1,
        source: Source::Named(0),
        ..options(64, 48)
    };
    let error = swapped.validate(&scene).unwrap_err().to_string();
    assert!(error.contains("--surface 'emitter' is unlit"), "{error}");
    let mirror_source = Options {
        source: Source::Named(0),
        ..options(64, 48)
    };
    let error = mirror_source.validate(&scene).unwrap_err().to_string();
    assert!(error.contains("--source 'surface'"), "{error}");
}

#[test]
fn an_ellipsoidal_cover_shows_the_eye_at_one_focus_what_sits_at_the_other() {
    // Seed 004's closed form: every ray from one focus reflects through the other.
    let (a, b) = (1.0f32, 0.6f32);
    let c = (a * a - b * b).sqrt();
    let mut cover = generators::sphere(1.0, 128, 64);
    for p in &mut cover.positions {
        *p *= Vec3::new(a, b, b);
    }
    for n in &mut cover.normals {
        // Normals of a scaled sphere: the inverse transpose of the scale.
        *n = (*n / Vec3::new(a, b, b)).normalize();
    }
    let metal = Material::new("metal", MaterialKind::Mirror { fresnel: false }, Vec3::ONE);
    let eye = Vec3::new(-c, 0.0, 0.0);
    let (width, height) = (96, 72);
    // The share of the cover's pixels that show an emitter at `at`, and the largest relative
    // luminance.
    let shown = |at: Vec3| {
        let scene = scene(cover.clone(), metal.clone(), at, 0.04, eye);
        let accel = SceneAccel::new(&scene);
        // One reflection: inside a closed mirror, later bounces reach the emitter anyway.
        let one_bounce = Options {
            max_depth: 1,
            ..options(width, height)
        };
        let glare = analyze(&scene, &accel, &[eye], &one_bounce, &|_| {}).unwrap();
        let images = &glare.images[0];
        let (mut cover_pixels, mut with_glare) = (0, 0);
        for i in 0..width * height {
            let dir = images.camera.ray_direction(
                (i % width) as f32 + 0.5,
                (i / width) as f32 + 0.5,
                width,
                height,
            );
            let hit = accel.intersect(&specula_trace::Ray { origin: eye, dir }, f32::INFINITY);
            if hit.is_some_and(|h| h.mesh == 0) {
                cover_pixels += 1;
                with_glare += usize::from(images.factor[i as usize] > 1e-3);
            }
        }
        assert!(cover_pixels > 1000);
        (
            with_glare as f64 / cover_pixels as f64,
            glare.report.eyes[0].max_luminance_factor,
        )
    };
    let (at_focus, relative) = shown(Vec3::new(c, 0.0, 0.0));
    // The same emitter a little off the focus: the cover shows it only in part.
    let (off_focus, _) = shown(Vec3::new(c - 0.3, 0.0, 0.0));
    eprintln!("the cover shows the emitter on {at_focus:.4} of its pixels at the focus, {off_focus:.4} 0.3 m off it");
    assert_eq!(at_focus, 1.0);
    assert!((relative - 1.0).abs() < 1e-3);
    assert!(off_focus < 0.5);
}

#[test]
fn a_window_over_a_dial_veils_it_by_the_sheet_s_reflectance() {
    // A thin glass sheet (n = 1.5) in z = 0 over an unlit dial of radiance L_d in z = −0.2; the
    // emitter (L_s = 4) beside the eye. Where the emitter's reflection falls on the dial:
    // glare r·L_s over (1 − r)·L_d, r = ½ Σ_σ 2R_σ / (1 + R_σ) (a sheet's two faces, per
    // polarisation).
    let sheet = Material::new(
        "sheet",
        MaterialKind::Dielectric {
            ior: Vec3::splat(1.5),
            thin_walled: true,
        },
        Vec3::ONE,
    );
    let pane = placed(
        generators::plane(glam::Vec2::splat(0.4), 1),
        "sheet",
        0,
        Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    let emitter = Vec3::new(0.3, 0.0, 0.5);
    let eye = Vec3::new(-0.3, 0.0, 0.5);
    let mut scene = scene(pane, sheet, emitter, 0.01, eye);
    let dial_radiance = 0.5;
    scene
        .materials
        .push(Material::unlit("dial", Vec3::splat(dial_radiance)));
    scene.meshes.push(placed(
        generators::plane(glam::Vec2::splat(2.0), 1),
        "dial",
        2,
        Mat4::from_translation(Vec3::new(0.0, 0.0, -0.2))
            * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    ));
    let accel = SceneAccel::new(&scene);
    let (width, height) = (320, 240);
    let glare = analyze(&scene, &accel, &[eye], &options(width, height), &|_| {}).unwrap();
    let images = &glare.images[0];
    // The pixel through the specular point of the emitter's centre.
    let image = Vec3::new(emitter.x, emitter.y, -emitter.z);
    let p = eye + (image - eye) * (eye.z / (eye.z - image.z));
    let pixel = pixel_towards(&images.camera, width, height, p - eye);
    let y = specula_analyze::glare::luminance;
    let veiling = y(images.glare[pixel]) / y(images.radiance[pixel] - images.glare[pixel]);
    let cos_i = f64::from((eye - p).normalize().z);
    let r = sheet_reflectance(cos_i, 1.5);
    let expected = r * 4.0 / ((1.0 - r) * dial_radiance as f64);
    eprintln!("veiling ratio {veiling:.5}, closed form {expected:.5}");
    // Measured 2026-12-02: 9.5e-4 (the pixel's ray is not exactly the centre's).
    assert!((veiling - expected).abs() / expected < 2e-3);
    assert!(glare.report.eyes[0].max_veiling_ratio.unwrap() >= veiling * 0.999);
}

#[test]
fn a_ball_seen_in_a_metal_plate_covers_its_mirror_image_s_solid_angle_about_its_centre() {
    // A 0.4 m plate in z = 0 facing +z (F0 = 1) and a 3 cm ball: in the plate the eye sees the
    // ball's mirror image, a ball of the same radius at distance D, whose solid angle is
    // 2π(1 − √(1 − r²/D²)) and whose centre's direction is the glare's centroid.
    let plate = placed(
        generators::plane(glam::Vec2::splat(0.4), 1),
        "plate",
        0,
        Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    let metal = Material::new("metal", MaterialKind::Mirror { fresnel: false }, Vec3::ONE);
    let (emitter, radius) = (Vec3::new(0.1, 0.05, 0.5), 0.03);
    let eye = Vec3::new(-0.1, 0.0, 0.6);
    let mut scene = scene(plate, metal, emitter, radius, eye);
    // Finely tessellated, so that its outline is a circle's to 0.05 % of its area.
    scene.meshes[1] = placed(
        generators::sphere(radius, 192, 96),
        "emitter",
        1,
        Mat4::from_translation(emitter),
    );
    let accel = SceneAccel::new(&scene);
    let (width, height) = (1280, 960);
    let glare = analyze(&scene, &accel, &[eye], &options(width, height), &|_| {}).unwrap();
    let figures = &glare.report.eyes[0];

    let image = Vec3::new(emitter.x, emitter.y, -emitter.z);
    let distance = f64::from(image.distance(eye));
    let ratio = f64::from(radius) / distance;
    let expected = std::f64::consts::TAU * (1.0 - (1.0 - ratio * ratio).sqrt());
    let relative = (figures.solid_angle_sr - expected).abs() / expected;
    // The image centre's pixel position, inverting the camera's ray_direction.
    let camera = &glare.images[0].camera;
    let frame = camera.frame();
    let d = image - eye;
    let tan_half = (camera.fov_y_deg.to_radians() * 0.5).tan();
    let aspect = width as f32 / height as f32;
    let depth = d.dot(frame.forward);
    let centre = [
        (d.dot(frame.right) / depth / (tan_half * aspect) + 1.0) * 0.5 * width as f32,
        (1.0 - d.dot(frame.up) / depth / tan_half) * 0.5 * height as f32,
    ];
    let centroid = figures.centroid_px.expect("glare seen");
    let off = glam::Vec2::from(centroid).distance(glam::Vec2::from(centre));
    eprintln!(
        "{} glare pixels: {:.6e} sr against {expected:.6e} sr (relative {relative:.2e}); centroid \
         {centroid:?} against {centre:?} ({off:.3} px)",
        figures.glare_pixels, figures.solid_angle_sr
    );
    assert!(figures.glare_pixels > 1000, "{}", figures.glare_pixels);
    // Measured 2026-12-02: 1.6e-3 (the pixels along the outline, one ray each) and 0.04 px.
    assert!(relative < 3.5e-3, "solid angle off by {relative}");
    assert!(off < 0.1, "centroid {off} px off");
}
