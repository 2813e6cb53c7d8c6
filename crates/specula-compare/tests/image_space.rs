//! `image-space` against the exact reference on scenes made for the paper's claims (Wyman,
//! *Interactive image-space refraction of nearby geometry*, 2005): the iterative lookup beats Kay–Greenberg's
//! (§4.3 vs §4.1), seven seeds at 512² find every nearby feature larger than ten pixels
//! (Figure 9), and peeled layers take light through more than the paper's two interfaces.

use glam::Vec3;
use specula_compare::{compare, Comparison, Options};
use specula_scene::Scene;

fn load(dir: &tempfile::TempDir, name: &str, text: &str) -> Scene {
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    specula_scene::load(path.to_str().unwrap()).unwrap()
}

fn run(
    ctx: &specula_methods::Context,
    scene: &Scene,
    size: u32,
    parameters: &[&str],
) -> Comparison {
    let options = Options {
        width: size,
        height: size,
        methods: vec!["image-space".into()],
        spp: 1,
        max_depth: 8,
        parameters: parameters.iter().map(|p| p.to_string()).collect(),
        frames: 1,
    };
    compare(scene, ctx, &options, &|_| {}).unwrap()
}

const SPHERE_BEFORE_CHECKER: &str = r#"
name = "glass sphere before a checkered plane"
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40

[materials.checker]
type = "unlit"
checker = { squares = 10, colors = [[0.9, 0.9, 0.85], [0.1, 0.2, 0.5]] }

[materials.glass]
type = "dielectric"
ior = 1.5

[[objects]]
name = "checkered plane"
material = "checker"
translate = [0.0, 0.0, -1.0]
rotate_deg = [90, 0, 0]
shape = { type = "plane", size = [10.0, 10.0] }

[[objects]]
name = "glass sphere"
material = "glass"
shape = { type = "sphere", radius = 0.6, segments = 96, rings = 48 }
"#;

#[test]
fn iterative_lookup_beats_kay_greenberg_before_a_checkered_plane() {
    let Some(ctx) = specula_methods::test_context("image-space checker") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = load(&dir, "checker.toml", SPHERE_BEFORE_CHECKER);
    let flip = |mode: &str| {
        let c = run(&ctx, &scene, 128, &[&format!("mode={mode}")]);
        c.report.methods[0].metrics.as_ref().unwrap().mean_flip
    };
    let (iterative, kay_greenberg) = (flip("iterative"), flip("kay-greenberg"));
    println!("mean FLIP on the sphere: iterative {iterative:.4}, kay-greenberg {kay_greenberg:.4}");
    // Measured at 128² (lavapipe), 2026-12-01 with `cargo test -p specula-compare --test
    // image_space -- --nocapture`: iterative 0.0493, Kay–Greenberg 0.4637; the bound is 1.5× the
    // iterative figure (it was 0.1, over the measurement + 0.05).
    assert!(iterative < 0.074, "iterative {iterative}");
    assert!(iterative < kay_greenberg);
}

/// Nine coloured squares (0.3 m: 35 pixels at 512², 6 m from the eye; 5 cm before the plane,
/// which the raster's depth buffer separates) on a dark plane behind a glass ball.
fn features_scene() -> String {
    let mut text = String::from(
        r#"
name = "features behind a glass ball"
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40

[materials.dark]
type = "unlit"
color = 0.02

[materials.glass]
type = "dielectric"
ior = 1.5

[[objects]]
name = "plane"
material = "dark"
translate = [0.0, 0.0, -3.0]
rotate_deg = [90, 0, 0]
shape = { type = "plane", size = [20.0, 20.0] }

[[objects]]
name = "glass ball"
material = "glass"
shape = { type = "sphere", radius = 0.6, segments = 96, rings = 48 }
"#,
    );
    for (k, colour) in FEATURE_COLOURS.iter().enumerate() {
        let (x, y) = ((k % 3) as f32 - 1.0, (k / 3) as f32 - 1.0);
        text += &format!(
            r#"
[materials.f{k}]
type = "unlit"
color = [{}, {}, {}]

[[objects]]
name = "feature {k}"
material = "f{k}"
translate = [{}, {}, -2.95]
rotate_deg = [90, 0, 0]
shape = {{ type = "plane", size = [0.3, 0.3] }}
"#,
            colour[0],
            colour[1],
            colour[2],
            0.9 * x,
            0.9 * y
        );
    }
    text
}

const FEATURE_COLOURS: [[f32; 3]; 9] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 0.5, 0.0],
    [1.0, 1.0, 1.0],
    [0.5, 0.0, 1.0],
];

/// The feature a pixel shows, by its brightness-normalised colour; None for dark pixels and
/// colours near no feature's.
fn feature_of(p: Vec3) -> Option<usize> {
    let bright = p.max_element();
    if bright < 0.3 {
        return None;
    }
    let c = p / bright;
    let (k, distance) = FEATURE_COLOURS
        .iter()
        .enumerate()
        .map(|(k, f)| (k, (Vec3::from_array(*f) - c).length()))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    (distance < 0.25).then_some(k)
}

#[test]
fn seven_seeds_at_512_find_every_feature_larger_than_ten_pixels() {
    let Some(ctx) = specula_methods::test_context("image-space figure 9") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = load(&dir, "features.toml", &features_scene());
    let c = run(&ctx, &scene, 512, &["seeds=7"]);
    let image = &c.method_images[0].0;
    // The ball's pixels: its projected disc, shrunk by 3 % to keep off the silhouette.
    let centre = Vec3::ZERO;
    let to_eye = Vec3::new(0.0, 0.0, 3.0) - centre;
    let angular_radius = (0.6 / to_eye.length()).asin();
    let pixel_angle = (20f32.to_radians().tan() * 2.0) / 512.0;
    let disc = (angular_radius.tan() / pixel_angle) * 0.97;
    let mut reference_counts = [0usize; 9];
    let mut method_counts = [0usize; 9];
    for y in 0..512u32 {
        for x in 0..512u32 {
            let (dx, dy) = (x as f32 + 0.5 - 256.0, y as f32 + 0.5 - 256.0);
            if (dx * dx + dy * dy).sqrt() > disc {
                continue;
            }
            if let Some(k) = feature_of(c.reference.get(x, y)) {
                reference_counts[k] += 1;
            }
            if let Some(k) = feature_of(image.get(x, y)) {
                method_counts[k] += 1;
            }
        }
    }
    println!("through the ball, pixels per feature: reference {reference_counts:?}, image-space {method_counts:?}");
    let mut seen = 0;
    for k in 0..9 {
        // A feature the reference shows larger than 10 × 10 pixels through the ball.
        if reference_counts[k] >= 100 {
            seen += 1;
            // Measured: every feature at 0.966 or more of the reference's pixels (also with 1
            // or 2 seeds: the bracketed secant finds them); the bound allows twice the loss.
            assert!(
                method_counts[k] as f64 >= 0.93 * reference_counts[k] as f64,
                "feature {k}: {} pixels, the reference {}",
                method_counts[k],
                reference_counts[k]
            );
        }
    }
    assert!(seen >= 5, "only {seen} features seen through the ball");
}

const TWO_BALLS: &str = r#"
name = "two glass balls before a checkered wall"
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 30

[materials.checker]
type = "unlit"
checker = { squares = 10, colors = [[0.9, 0.9, 0.85], [0.1, 0.2, 0.5]] }

[materials.glass]
type = "dielectric"
ior = 1.3

[[objects]]
name = "checkered wall"
material = "checker"
translate = [0.0, 0.0, -2.0]
rotate_deg = [90, 0, 0]
shape = { type = "plane", size = [10.0, 10.0] }

[[objects]]
name = "front ball"
material = "glass"
translate = [0.0, 0.0, 0.5]
shape = { type = "sphere", radius = 0.35, segments = 64, rings = 32 }

[[objects]]
name = "back ball"
material = "glass"
translate = [0.0, 0.0, -0.6]
shape = { type = "sphere", radius = 0.5, segments = 64, rings = 32 }
"#;

#[test]
fn peeled_layers_follow_light_through_a_second_ball() {
    let Some(ctx) = specula_methods::test_context("image-space layers") else {
        return;
    };
    // Light through the front ball's centre crosses four interfaces: two balls. The paper's two
    // interfaces see the wall straight through the second ball.
    let dir = tempfile::tempdir().unwrap();
    let scene = load(&dir, "two-balls.toml", TWO_BALLS);
    let flip = |layers: u32| {
        let c = run(&ctx, &scene, 128, &[&format!("layers={layers}")]);
        c.report.methods[0].metrics.as_ref().unwrap().mean_flip
    };
    let (two, four) = (flip(1), flip(2));
    println!("mean FLIP on the balls: 2 interfaces {two:.4}, 4 interfaces {four:.4}");
    // Measured at 128², 2026-12-01: 0.2877 with layers=1, 0.0532 with layers=2; the bound is
    // 1.5× the latter (it was 0.11, over the measurement + 0.05).
    assert!(four < 0.08, "layers=2: {four}");
    assert!(four < 0.5 * two, "layers=2 {four} vs layers=1 {two}");
}
