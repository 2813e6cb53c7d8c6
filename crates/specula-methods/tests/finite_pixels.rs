//! Property: no method, with its defaults or a preset (every label), ever writes a NaN or
//! infinite pixel, whatever the camera. Random
//! cameras (a fixed seed, so a failure reproduces) inside and around every built-in scene and
//! every scene of the suite (`scenes/suite`):
//! eyes from inside the objects to twice the scene's radius away, any direction, fields of
//! view from 10° to 120°.

use glam::Vec3;
use specula_methods::LiveScene;
use specula_scene::Camera;

/// Cameras per scene.
const CAMERAS: usize = 4;
const SIZE: (u32, u32) = (40, 30);

/// xorshift64*: a tiny deterministic generator, uniform in [0, 1).
struct Random(u64);

impl Random {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn direction(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
            if let Some(d) = v.try_normalize().filter(|_| v.length() <= 1.0) {
                return d;
            }
        }
    }
}

#[test]
fn no_method_writes_a_non_finite_pixel_from_random_cameras() {
    let Some(ctx) = specula_methods::test_context("finite pixels") else {
        return;
    };
    let mut random = Random(0x5EED_CAFE_F00D_D00D);
    let mut failures = Vec::new();
    let suite = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/suite");
    let mut suite_files: Vec<String> = std::fs::read_dir(&suite)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.display().to_string())
        .collect();
    suite_files.sort();
    assert!(
        suite_files.len() >= 10,
        "the suite is missing: {suite_files:?}"
    );
    let names = specula_scene::builtin::names()
        .into_iter()
        .map(|n| n.to_string())
        .chain(suite_files);
    for name in names {
        let scene = specula_scene::load(&name).unwrap();
        let bounds = scene.bounds();
        let (centre, radius) = (bounds.center(), bounds.radius());
        let cameras: Vec<Camera> = (0..CAMERAS)
            .map(|_| {
                let eye = centre + random.direction() * radius * (0.05 + 1.95 * random.next());
                let target = centre + random.direction() * radius * 0.3 * random.next();
                Camera {
                    eye,
                    target: if target.distance(eye) > 1e-4 {
                        target
                    } else {
                        eye + Vec3::Z
                    },
                    up: Vec3::Y,
                    fov_y_deg: 10.0 + 110.0 * random.next(),
                    aspect: None,
                }
            })
            .collect();
        // One technique per method and scene, prepared once and turned to each camera, as a
        // user turns the viewer's: preparing (and compiling shaders) once per camera made this
        // the slowest test of the suite, and the first camera still gets a fresh frame.
        let live = LiveScene::new(scene.clone());
        for label in specula_methods::all_labels() {
            let mut technique = label.create().unwrap();
            // Cheap settings: this is about every pixel being finite, not about quality.
            specula_methods::apply_known_parameters(
                technique.as_mut(),
                &[
                    "depth=1".into(),
                    "resolution=64".into(),
                    "max_depth=2".into(),
                    "points=5000".into(),
                ],
            )
            .unwrap();
            if let Err(e) = technique.prepare(&ctx, &live) {
                failures.push(format!("{name}: {label} failed to prepare: {e}"));
                continue;
            }
            for (c, camera) in cameras.iter().enumerate() {
                let image = technique
                    .render(&ctx, &live, camera, SIZE.0, SIZE.1)
                    .and_then(|frame| frame.image(&ctx));
                match image {
                    Ok(image) => {
                        let bad = image.pixels.iter().filter(|p| !p.is_finite()).count();
                        if bad > 0 {
                            failures.push(format!(
                                "{name} camera {c} ({camera:?}): {label} wrote {bad} non-finite pixels"
                            ));
                        }
                    }
                    Err(e) => failures.push(format!("{name} camera {c}: {label} failed: {e}")),
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
