//! `glare` against closed forms: a flat metal plate (F0 = 1) shows a small emitter exactly to the
//! eye points whose line to the emitter's mirror image crosses the plate, at the emitter's own
//! luminance; a thick glass pane's front reflection has the unpolarised Fresnel reflectance at
//! its angle; a ball seen in a metal plate covers its mirror image's solid angle, its centroid
//! at the image's centre.

use glam::{Mat4, Vec3};
use specula_analyze::analysis::eye_points::Eyes;
use specula_analyze::frame::VehicleFrame;
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
    assert!(error.contains("surface 'emitter' is unlit"), "{error}");
    let mirror_source = Options {
        source: Source::Named(0),
        ..options(64, 48)
    };
    let error = mirror_source.validate(&scene).unwrap_err().to_string();
    assert!(error.contains("source 'surface'"), "{error}");
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

/// Bisection for the incidence (radians) at which a ray from `eye_height` above a slab's front
/// face (index `n`, thickness `t`) reaches `across` metres sideways at the back face's mirror
/// point and returns to the same height: (h − ... ) tan θi + t tan θt = across.
fn back_reflection_incidence(eye_height: f64, t: f64, across: f64, n: f64) -> f64 {
    let reach = |theta: f64| {
        let theta_t = (theta.sin() / n).asin();
        eye_height * theta.tan() + t * theta_t.tan()
    };
    let (mut lo, mut hi) = (0.0, std::f64::consts::FRAC_PI_2 - 1e-6);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if reach(mid) < across {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn a_thick_slab_shows_two_images_each_with_its_polarisations_summed_apart() {
    // A 6 cm slab (n = 1.5) and a small emitter (L = 4): the front image has R(θ) (the mean of
    // R_s and R_p); the back face's image, refracted in, reflected inside and refracted out,
    // has ½ Σ_σ (1 − R_σ)² R_σ (the inner reflectance equals the outer one at the refracted
    // angle), not (1 − R)² R of the mean.
    let thickness = 0.06f32;
    let pane = generators::cuboid(Vec3::new(1.2, 0.4, thickness));
    let emitter = Vec3::new(0.5, 0.0, 0.5);
    let eye = Vec3::new(-0.5, 0.0, 0.5);
    let scene = scene(pane, Material::glass("glass", 1.5), emitter, 0.015, eye);
    let accel = SceneAccel::new(&scene);
    let (width, height) = (960, 720);
    let glare = analyze(&scene, &accel, &[eye], &options(width, height), &|_| {}).unwrap();
    let images = &glare.images[0];
    let front = f64::from(thickness) * 0.5;
    let height_above = f64::from(eye.z) - front;
    let across = f64::from(emitter.x - eye.x) * 0.5;
    // The pixels whose rays meet the front face where the chief rays of the two images do;
    // each pixel's own ray sets its incidence, the same at both faces (they are parallel).
    let theta_front = (across / height_above).atan();
    let theta_back = back_reflection_incidence(height_above, f64::from(thickness), across, 1.5);
    let pixel = |theta: f64| {
        let x = f64::from(eye.x) + height_above * theta.tan();
        let towards = Vec3::new(x as f32, 0.0, front as f32) - eye;
        let i = pixel_towards(&images.camera, width, height, towards);
        let dir = images.camera.ray_direction(
            (i as u32 % width) as f32 + 0.5,
            (i as u32 / width) as f32 + 0.5,
            width,
            height,
        );
        (images.factor[i], fresnel_sp(f64::from(-dir.z), 1.5))
    };
    let (front_factor, (rs, rp)) = pixel(theta_front);
    let expected_front = 0.5 * (rs + rp);
    let (back_factor, (bs, bp)) = pixel(theta_back);
    let expected_back = 0.5 * ((1.0 - bs).powi(2) * bs + (1.0 - bp).powi(2) * bp);
    let unpolarised_back = (1.0 - 0.5 * (bs + bp)).powi(2) * 0.5 * (bs + bp);
    let off_front = (front_factor - expected_front).abs() / expected_front;
    let off_back = (back_factor - expected_back).abs() / expected_back;
    let rule_gap = (unpolarised_back - expected_back).abs() / expected_back;
    eprintln!(
        "front image at {:.2}°: {front_factor:.6} against {expected_front:.6} ({off_front:.1e}); \
         back image at {:.2}°: {back_factor:.6} against {expected_back:.6} ({off_back:.1e}); the \
         unpolarised rule's {unpolarised_back:.6} is {rule_gap:.1e} off",
        theta_front.to_degrees(),
        theta_back.to_degrees()
    );
    // Measured 2026-12-04: 1.2e-7 and 5.2e-8 (f32 rounding; the issue asks 0.2 %), the
    // unpolarised rule 7.5 % off.
    assert!(off_front < 5e-7, "front {off_front}");
    assert!(off_back < 5e-7, "back {off_back}");
    assert!(
        rule_gap > 2.0 * off_back,
        "the test tells the two rules apart"
    );
}

/// A scene with a flat `metal` plate (0.4 m square in z = 0, facing +z, F0 = `f0`) and nothing
/// else: the sun is met where paths leave it.
fn plate_in_the_sun(f0: f32, eye: Vec3) -> Scene {
    let mut scene = Scene::new("a plate in the sun");
    scene.materials.push(Material::new(
        "metal",
        MaterialKind::Mirror { fresnel: false },
        Vec3::splat(f0),
    ));
    scene.meshes.push(placed(
        generators::plane(glam::Vec2::splat(0.4), 1),
        "plate",
        0,
        Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
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

fn sun_options(sun: glare::Sun, width: u32, height: u32) -> Options {
    Options {
        source: Source::Sun(sun),
        ..options(width, height)
    }
}

#[test]
fn the_sun_in_a_flat_mirror_is_seen_from_the_eyes_whose_mirror_line_crosses_it_at_r_e_over_omega() {
    let (f0, centre) = (0.9f32, Vec3::new(0.05, 0.0, 0.6));
    let scene = plate_in_the_sun(f0, centre);
    let frame = VehicleFrame::new(&scene.camera, Some(Vec3::NEG_Z)).unwrap();
    assert!(frame.forward.abs_diff_eq(Vec3::NEG_Z, 1e-6) && frame.right.abs_diff_eq(Vec3::X, 1e-6));
    // Behind the driver and to the right, low: its mirror image lies ahead, to the right.
    let sun = glare::Sun {
        azimuth_deg: 155.0,
        elevation_deg: 10.0,
        illuminance_lx: 100_000.0,
    };
    let s = sun.direction(&frame);
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
    let glare = glare::analyze(
        &scene,
        &accel,
        &eyes,
        &frame,
        &sun_options(sun, 160, 120),
        &|_| {},
    )
    .unwrap();
    let omega = glare::sun::disc_solid_angle();
    assert!((omega - 6.72e-5).abs() < 0.005e-5, "Ω = {omega}");
    let expected = f64::from(f0) * 100_000.0 / omega;
    // Each eye looks along the sun's mirror image, (s.x, s.y, −s.z).
    let image = Vec3::new(s.x, s.y, -s.z);
    let step = 0.4 / (columns - 1) as f32 * 0.5;
    let (mut with, mut without) = (0, 0);
    for (eye, figures) in eyes.iter().zip(&glare.report.eyes) {
        let p = *eye + image * (eye.z / -image.z);
        let inside = p.x.abs() <= 0.2 && p.y.abs() <= 0.2;
        let margin = (p.x.abs() - 0.2).abs().min((p.y.abs() - 0.2).abs());
        if margin > step {
            assert_eq!(figures.glare, inside, "eye {eye} meets the plane at {p}");
        }
        if !figures.glare {
            without += 1;
            continue;
        }
        with += 1;
        let luminance = figures.max_luminance_cd_m2.unwrap();
        let solid = figures.solid_angle_sr / omega;
        eprintln!(
            "eye {eye}: {luminance:.6e} cd/m² against R·E/Ω = {expected:.6e}; the image covers \
             {solid:.4} Ω in {} pixels",
            figures.glare_pixels
        );
        assert!((luminance - expected).abs() / expected < 1e-6);
        assert!((figures.max_luminance_factor - f64::from(f0)).abs() < 1e-6);
        if margin > step {
            // Measured 2026-12-04: within 0.74 % (the disc's share of each pixel, from 256
            // samples).
            assert!((solid - 1.0).abs() < 0.015, "solid angle {solid} Ω");
        }
    }
    eprintln!("{with} eye points see the sun, {without} do not");
    assert!(with >= 6 && without >= 6, "{with} {without}");
}

#[test]
fn a_display_under_known_glare_has_the_contrast_of_the_formula() {
    // A thin pane (n = 1.5) over an unlit display; a named source of 2,000 cd/m² reflected in
    // the pane over it. Where its image falls: (τ L_s + L_g) / (τ L_b + L_g), τ = 1 − r,
    // L_g = r × 2,000, r the sheet's reflectance at the specular angle.
    let pane = placed(
        generators::plane(glam::Vec2::splat(0.4), 1),
        "pane",
        0,
        Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    let sheet = Material::new(
        "sheet",
        MaterialKind::Dielectric {
            ior: Vec3::splat(1.5),
            thin_walled: true,
        },
        Vec3::ONE,
    );
    let (emitter, eye) = (Vec3::new(0.3, 0.0, 0.5), Vec3::new(-0.3, 0.0, 0.5));
    let mut scene = scene(pane, sheet, emitter, 0.02, eye);
    scene
        .materials
        .push(Material::unlit("display", Vec3::splat(0.2)));
    scene.meshes.push(placed(
        generators::plane(glam::Vec2::splat(2.0), 1),
        "display",
        2,
        Mat4::from_translation(Vec3::new(0.0, 0.0, -0.1))
            * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    ));
    let display = glare::Display {
        mesh: 2,
        symbol_cd_m2: 250.0,
        background_cd_m2: 5.0,
        min_contrast: 3.0,
    };
    let with_display = Options {
        source_luminance: Some(2_000.0),
        display: Some(display),
        ..options(320, 240)
    };
    let accel = SceneAccel::new(&scene);
    let glare = analyze(&scene, &accel, &[eye], &with_display, &|_| {}).unwrap();
    let figures = &glare.report.eyes[0];
    let d = figures.display.as_ref().expect("display figures");
    let p = Vec3::ZERO; // the specular point: the pane's centre, half-way between them
    let cos_i = f64::from((eye - p).normalize().z);
    let r = sheet_reflectance(cos_i, 1.5);
    let (tau, lg) = (1.0 - r, r * 2_000.0);
    let expected = (tau * 250.0 + lg) / (tau * 5.0 + lg);
    assert!((display.contrast(tau, lg) - expected).abs() < 1e-12);
    let off = (d.min_contrast - expected).abs() / expected;
    eprintln!(
        "lowest contrast {:.5} against {expected:.5} ({off:.1e}); without glare {}; {} display \
         pixels, τ {:.5} (1 − r at the centre {tau:.5}), washed out {:.4}",
        d.min_contrast, d.contrast_without_glare, d.pixels, d.transmittance, d.washed_out_share
    );
    assert_eq!(d.contrast_without_glare, 50.0);
    // The darkest pixel is the image's brightest, near the specular point: r varies little
    // across the image (measured 2026-12-04: 2.3e-3).
    assert!(off < 5e-3, "{off}");
    assert!(expected < 3.0 && d.washed_out_share > 0.0 && d.washed_out_share < 0.2);
    // Every washed-out pixel shows the glare, and is below the threshold by the formula.
    let images = &glare.images[0];
    for (i, washed) in images.washed_out.iter().enumerate() {
        if *washed {
            assert!(images.factor[i] > 0.0);
            assert!(images.glare_cd_m2[i] > 0.0);
        }
    }
}

#[test]
fn a_sweep_s_lookup_equals_tracing_each_sun_position() {
    let scene = specula_scene::builtin::by_name("truck-cover")
        .unwrap()
        .unwrap();
    let accel = SceneAccel::new(&scene);
    let frame = VehicleFrame::new(&scene.camera, None).unwrap();
    let surface = specula_analyze::object(&scene, "--surface", "cover glass").unwrap();
    let display = specula_analyze::object(&scene, "--display", "dial").unwrap();
    let eyes = Eyes::Eyebox {
        width: 0.2,
        height: 0.1,
        columns: 3,
        rows: 1,
    }
    .points(scene.camera.eye, &frame)
    .unwrap();
    let base = glare::Sun {
        azimuth_deg: 0.0,
        elevation_deg: 45.0,
        illuminance_lx: 100_000.0,
    };
    let options = Options {
        surface,
        display: Some(glare::Display {
            mesh: display,
            symbol_cd_m2: 300.0,
            background_cd_m2: 10.0,
            min_contrast: 3.0,
        }),
        threshold: 1e-3,
        ..sun_options(base, 96, 72)
    };
    let spec = glare::sweep::SweepSpec {
        azimuth: [120.0, 180.0],
        elevation: [4.0, 24.0],
        step_deg: 4.0,
    };
    let swept = glare::sweep::sweep(
        &scene,
        &accel,
        &eyes,
        &frame,
        &options,
        &spec,
        None,
        &|_| {},
    )
    .unwrap();
    let sweep = swept.report.sweep.as_ref().unwrap();
    let (mut glaring, mut washed) = (0, 0);
    for effect in &sweep.positions {
        let sun = glare::Sun {
            azimuth_deg: effect.azimuth_deg,
            elevation_deg: effect.elevation_deg,
            ..base
        };
        let direct = Options {
            source: Source::Sun(sun),
            ..options.clone()
        };
        let traced = glare::analyze(&scene, &accel, &eyes, &frame, &direct, &|_| {}).unwrap();
        let by_tracing = glare::sweep::SunEffect::of(
            effect.azimuth_deg,
            effect.elevation_deg,
            &traced.report.eyes,
        );
        assert_eq!(*effect, by_tracing);
        glaring += usize::from(effect.glare());
        washed += usize::from(effect.washed_out());
    }
    let worst = &sweep.positions[sweep.worst_position];
    let sun = glare::Sun {
        azimuth_deg: worst.azimuth_deg,
        elevation_deg: worst.elevation_deg,
        ..base
    };
    let direct = Options {
        source: Source::Sun(sun),
        ..options.clone()
    };
    let traced = glare::analyze(&scene, &accel, &eyes, &frame, &direct, &|_| {}).unwrap();
    assert_eq!(swept.report.eyes, traced.report.eyes);
    eprintln!(
        "{} positions, {glaring} with glare, {washed} washed out: the lookup equals the trace",
        sweep.positions.len()
    );
    assert!(glaring > 0 && glaring < sweep.positions.len() && washed > 0);
}

#[test]
fn the_sun_stands_where_the_closed_forms_put_it() {
    use glare::sun::{day_of_year, declination, solar_position};
    assert_eq!(day_of_year("2026-06-21").unwrap(), 172);
    assert_eq!(day_of_year("2024-12-31").unwrap(), 366);
    assert!(day_of_year("2026-02-29")
        .unwrap_err()
        .to_string()
        .starts_with("date: "));
    assert!(day_of_year("21/06/2026").is_err());
    // 21 June: the declination is the obliquity, 23.44°; at 48° N the noon sun stands
    // 90° − 48° + 23.44° high, due south.
    let delta = declination(172).to_degrees();
    assert!((delta - 23.44).abs() < 0.05, "δ = {delta}");
    let (azimuth, elevation) = solar_position(48.0, 172, 12.0);
    assert!((azimuth - 180.0).abs() < 1e-9 && (elevation - (42.0 + delta)).abs() < 1e-9);
    // At an equinox the sun rises due east at 6 h solar time, for any latitude.
    let equinox = (60..100)
        .min_by(|a, b| declination(*a).abs().total_cmp(&declination(*b).abs()))
        .unwrap();
    let (azimuth, elevation) = solar_position(48.0, equinox, 6.0);
    let residual = declination(equinox).to_degrees();
    assert!(
        (azimuth - 90.0).abs() < 0.5 && elevation.abs() < 0.5,
        "{azimuth} {elevation} {residual}"
    );
    // Symmetric about noon: morning east, afternoon west.
    let (am, _) = solar_position(48.0, 172, 9.0);
    let (pm, _) = solar_position(48.0, 172, 15.0);
    assert!((am + pm - 360.0).abs() < 1e-9 && am < 180.0);
}

#[test]
fn bad_sun_display_and_sweep_inputs_are_clear_errors() {
    let scene = plate_in_the_sun(0.9, Vec3::new(0.0, 0.0, 0.6));
    let sun = |elevation_deg: f64, illuminance_lx: f64| glare::Sun {
        azimuth_deg: 180.0,
        elevation_deg,
        illuminance_lx,
    };
    let error = |options: Options| options.validate(&scene).unwrap_err().to_string();
    assert!(error(sun_options(sun(-3.0, 1e5), 8, 8)).contains("below the horizon"));
    assert!(error(sun_options(sun(95.0, 1e5), 8, 8)).contains("at most 90°"));
    assert!(error(sun_options(sun(30.0, -1.0), 8, 8)).contains("sun_illuminance"));
    let spec = |step_deg: f64, elevation: [f64; 2]| glare::sweep::SweepSpec {
        azimuth: [0.0, 90.0],
        elevation,
        step_deg,
    };
    assert!(spec(0.0, [10.0, 20.0])
        .validate()
        .unwrap_err()
        .to_string()
        .contains("positive step"));
    assert!(spec(5.0, [-10.0, 20.0])
        .validate()
        .unwrap_err()
        .to_string()
        .contains("below the horizon"));
    assert!(spec(5.0, [30.0, 20.0]).validate().is_err());
}
