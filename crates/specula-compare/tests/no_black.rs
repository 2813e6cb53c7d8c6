//! No method draws a specular object black where the reference shows it lit: on a mirror
//! sphere beside a glass sphere, each in the other's view (`scenes/pairs/mirror-and-glass.toml`),
//! cube maps that leave specular objects black drew the glass black inside the mirror (issue
//! 29). Every approximate method, every masked pixel.

use std::path::Path;

use specula_compare::{compare, Options};

/// Rec. 709 luminance of linear RGB.
fn luminance(c: glam::Vec3) -> f32 {
    c.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722))
}

#[test]
fn no_method_draws_a_specular_object_black_where_the_reference_does_not() {
    let Some(ctx) = specula_methods::test_context("no black objects") else {
        return;
    };
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/pairs/mirror-and-glass.toml");
    let scene = specula_scene::load(file.to_str().unwrap()).unwrap();
    let methods = specula_methods::approximate_methods();
    let options = Options {
        width: 96,
        height: 72,
        methods: methods.clone(),
        spp: 1,
        max_depth: 8,
        parameters: vec![],
        frames: 1,
    };
    let c = compare(&scene, &ctx, &options, &|_| {}).unwrap();
    assert!(c.report.failed.is_empty(), "{:?}", c.report.failed);
    let reference = &c.reference;
    let lit: Vec<usize> = (0..reference.pixels.len())
        .filter(|&i| c.classes[i].is_some() && luminance(reference.pixels[i]) > 0.05)
        .collect();
    assert!(lit.len() > 1000, "{} lit specular pixels", lit.len());
    let mut failures = Vec::new();
    for (m, (image, _)) in c.report.methods.iter().zip(&c.method_images) {
        let black = lit
            .iter()
            .filter(|&&i| luminance(image.pixels[i]) < 0.01)
            .count();
        eprintln!(
            "{}: {black} of {} lit specular pixels black",
            m.label,
            lit.len()
        );
        // None, every method (c3rc drew 1, on the mirror sphere's lower rim, before its exact
        // hits closed the gaps between its splats).
        if black > 0 {
            failures.push(format!("{}: {black} pixels", m.label));
        }
    }
    assert!(
        failures.is_empty(),
        "black where the reference is lit: {failures:?}"
    );
}
