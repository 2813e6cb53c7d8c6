//! `c3rc` against the exact reference and against `envmap` on the paper's claim (Mei, Popescu
//! and Sacks, *A hybrid backward-forward method for interactive reflections*, 2007, Figure 2): environment mapping is
//! wrong for objects close to the reflector; the hybrid method is right there.

use std::path::Path;

use specula_compare::{compare, Options};

fn flips(scene: &specula_scene::Scene, ctx: &specula_methods::Context) -> (f64, f64) {
    let options = Options {
        width: 320,
        height: 240,
        methods: vec!["c3rc".into(), "envmap".into()],
        spp: 1,
        max_depth: 8,
        parameters: Vec::new(),
        frames: 1,
    };
    let c = compare(scene, ctx, &options, &|_| {}).unwrap();
    let flip = |name: &str| {
        c.report
            .methods
            .iter()
            .find(|m| m.method == name)
            .unwrap()
            .metrics
            .as_ref()
            .expect("mirrors only: c3rc shades them itself")
            .mean_flip
    };
    (flip("c3rc"), flip("envmap"))
}

#[test]
fn nearby_objects_are_right_where_envmap_is_wrong() {
    let Some(ctx) = specula_methods::test_context("c3rc against envmap") else {
        return;
    };
    // Mean FLIP on the mirror's pixels at 320 × 240, measured 2026-12-03 on lavapipe with
    // `specula compare mirror-teapot-bunny scenes/suite/mirror-sphere-nearby.toml --methods
    // c3rc,envmap --frames 1` (the same compare as here): mirror-teapot-bunny c3rc 0.0199
    // (2026-12-01, before exact hits and the far field's depth: 0.0750), envmap 0.2070; the
    // suite's mirror sphere with nearby objects c3rc 0.0162 (0.0570), envmap 0.3194.
    let teapot = specula_scene::load("mirror-teapot-bunny").unwrap();
    let (c3rc, envmap) = flips(&teapot, &ctx);
    eprintln!("mirror-teapot-bunny: c3rc {c3rc:.4}, envmap {envmap:.4}");
    // The goal: at most half of envmap's (measured 0.10 of it).
    assert!(c3rc <= 0.5 * envmap, "c3rc {c3rc} vs envmap {envmap}");
    // 2× the measurement.
    assert!(c3rc < 0.04, "c3rc {c3rc}");
    let nearby = specula_scene::load(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenes/suite/mirror-sphere-nearby.toml")
            .to_str()
            .unwrap(),
    )
    .unwrap();
    let (c3rc, envmap) = flips(&nearby, &ctx);
    eprintln!("suite/mirror-sphere-nearby: c3rc {c3rc:.4}, envmap {envmap:.4}");
    // 2× the measurement (the goal was 0.06).
    assert!(c3rc <= 0.033, "c3rc {c3rc}");
    assert!(c3rc < 0.25 * envmap, "c3rc {c3rc} vs envmap {envmap}");
}
