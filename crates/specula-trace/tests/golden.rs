//! Golden images of built-in scenes at 64×64, compared with FLIP (nv-flip). On failure the test
//! writes `<name>-actual.png` and `<name>-diff.png` (the FLIP error map) beside the golden image.
//! Regenerate goldens after an intended change with `SPECULA_BLESS=1 cargo test --test golden`.
//!
//! Tolerance: mean FLIP ≤ 0.01 over the image and no pixel with FLIP > 0.5. The renderer is
//! deterministic (one ray through each pixel centre), so this only absorbs floating-point
//! differences between builds; any real change in shading, geometry or sampling exceeds it.

use std::path::PathBuf;

use specula_trace::{render, Image, RenderSettings, SceneAccel};

const MEAN_FLIP_MAX: f32 = 0.01;
const PIXEL_FLIP_MAX: f32 = 0.5;

fn check(scene_name: &str) {
    let scene = specula_scene::load(scene_name).expect("built-in scene loads");
    let accel = SceneAccel::new(&scene);
    let settings = RenderSettings {
        width: 64,
        height: 64,
        spp: 1,
        max_depth: 8,
    };
    let actual = render(&scene, &accel, &settings, &|_, _| {});
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let golden_path = dir.join(format!("{scene_name}.png"));
    if std::env::var_os("SPECULA_BLESS").is_some() {
        actual.save_png(&golden_path).unwrap();
        return;
    }
    let golden = Image::load(&golden_path)
        .unwrap_or_else(|e| panic!("{e}; create it with SPECULA_BLESS=1 cargo test --test golden"));
    let (ours, theirs) = (actual.to_srgb8(), golden.to_srgb8());
    assert_eq!(
        (ours.width(), ours.height()),
        (theirs.width(), theirs.height())
    );
    let reference =
        nv_flip::FlipImageRgb8::with_data(theirs.width(), theirs.height(), theirs.as_raw());
    let test = nv_flip::FlipImageRgb8::with_data(ours.width(), ours.height(), ours.as_raw());
    let error_map = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let pool = nv_flip::FlipPool::from_image(&error_map);
    let (mean, max) = (pool.mean(), pool.max_value());
    if mean > MEAN_FLIP_MAX || max > PIXEL_FLIP_MAX {
        actual
            .save_png(&dir.join(format!("{scene_name}-actual.png")))
            .unwrap();
        let diff = error_map.apply_color_lut(&nv_flip::magma_lut());
        image::RgbImage::from_raw(diff.width(), diff.height(), diff.to_vec())
            .unwrap()
            .save(dir.join(format!("{scene_name}-diff.png")))
            .unwrap();
        panic!(
            "{scene_name}: mean FLIP {mean:.4} (max {MEAN_FLIP_MAX}), worst pixel {max:.3} (max {PIXEL_FLIP_MAX}); wrote -actual and -diff images in {}",
            dir.display()
        );
    }
}

#[test]
fn door_mirror_matches_golden() {
    check("door-mirror");
}

#[test]
fn glass_dragon_matches_golden() {
    check("glass-dragon");
}
