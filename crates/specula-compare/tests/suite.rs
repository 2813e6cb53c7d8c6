//! Every technique held to its figures on the scene suite (`scenes/suite`), at 96 × 72: mean
//! FLIP against the exact reference on the mirror and dielectric pixels each technique shades
//! itself. Each bound is 1.5× what was measured (MEASURED), never more than the measurement +
//! 0.05, and never more than halfway from the measurement to the figure a black image gets on
//! the same pixels (computed here, with the same metrics code), so that every bound can fail;
//! the test also asserts each bound is below that black figure. Pixels a technique hands to
//! another method (`MethodInfo::delegates`: c3rc's refractors are envmap's) are not held to a
//! bound of the technique's: their figure must equal the delegate's own on the same pixels. A
//! technique that gets better should have its figures lowered here. Merged-mesh scenes must
//! also render like the same objects as separate meshes (the 10 %, or 0.005).
//!
//! Each seed technique's published algorithm (its `paper` preset, label `METHOD:paper`) is held
//! the same way beside it on a subset of the scenes (PAPER_MEASURED), to keep the test's time.
//!
//! The proof that the bounds bite: `realistic_wrong_outputs_break_every_bound` feeds each bound
//! the wrong outputs a real defect makes (the method's image shifted by one pixel, with red and
//! blue swapped, or sRGB-encoded twice; its own pixels replaced by envmap's, or for envmap's
//! own column the reference blurred by 3 pixels; the same method's image of another scene),
//! prints which wrong output breaks how many
//! bounds, and requires every bound to be broken by at least one, but where the method's own
//! figure is already within 5 % of a black image's (envmap on mirror-in-glass: no realistic
//! output is much worse; the bound holds it from getting worse). docs/benchmarks.md has the
//! table.

use std::path::Path;
use std::sync::OnceLock;

use specula_compare::metrics::{class_mask, flip_map, measure};
use specula_compare::{compare, method_figures, Comparison, Options};
use specula_trace::Image;

const WIDTH: u32 = 96;
const HEIGHT: u32 = 72;
const METHODS: [&str; 6] = [
    "envmap",
    "pvrr",
    "distance-maps",
    "image-space",
    "c3rc",
    "vertex-tracing",
];

/// The published algorithms, held on the scenes of PAPER_MEASURED.
const PAPER_METHODS: [&str; 5] = [
    "pvrr:paper",
    "distance-maps:paper",
    "image-space:paper",
    "c3rc:paper",
    "vertex-tracing:paper",
];

/// Mean FLIP per scene on the pixels each method shades itself, for envmap, pvrr,
/// distance-maps, image-space, c3rc, vertex-tracing (DELEGATED: the method hands every masked
/// pixel of the scene to another: c3rc on the glass scenes, all of whose specular pixels are
/// glass), measured 2026-12-01 on lavapipe (llvmpipe) with `cargo test -p specula-compare
/// --test suite -- --nocapture`, which prints these rows, each cell's bound and a black image's
/// figure. pvrr's column was measured again 2026-12-02, after its view volumes were fitted to
/// the hits and its zooming region drawn from a zooming view (issue 28): every scene lower but
/// thin-sheet, 0.3122 -> 0.3134. Then envmap's, pvrr's and image-space's (and image-space:paper's
/// in PAPER_MEASURED) again, the same day, after cube maps drew the specular objects they
/// show from those objects' own maps and pvrr traced its corners on other reflectors where no
/// nested level shows them (issue 29): lower on the scenes with two reflectors (lit-room
/// 0.2197 -> 0.2165, 0.1293 -> 0.1144, 0.0958 -> 0.0833; mirrors-merged 0.1822 -> 0.1751,
/// 0.0608 -> 0.0569, 0.0380 -> 0.0307; pvrr on mirror-bunny 0.0813 -> 0.0663 and
/// mirror-sphere-nearby 0.0254 -> 0.0245), within 0.0004 elsewhere (image-space on the glass
/// pairs 0.1093 -> 0.1089). pvrr runs with depth=1, as these figures were first measured
/// (before its frame budget, nested reflections took ~18 s a frame on the merged scenes here;
/// bounded, depth 2 takes 0.67–1.13× depth 1's time at the same or better FLIP,
/// docs/methods/pvrr.md). c3rc's column was measured again the same day after its exact hits,
/// the far field's depth and a camera for every triangle (issue 29): concave-mirror 0.0575 ->
/// 0.0315, lit-room 0.1417 -> 0.0482, mirror-bunny 0.0955 -> 0.0542, mirror-sphere-nearby
/// 0.1034 -> 0.0351, mirror-sphere 0.0931 -> 0.0188, the mirror pairs 0.1338 -> 0.0379. No
/// suite scene shows mirror and glass pixels both (the mirror in mirror-in-glass is seen only
/// through the glass), so every figure a method keeps is what it was over the whole mask (the
/// same as on 2026-11-30). vertex-tracing's column was measured again 2026-12-03 (issue 38): at
/// this size its `tracing=auto` (issue 27) traces every reflector per pixel, the reference's
/// own rays, on every scene but glass-block and thin-sheet, so its figure there is 0 exactly
/// and its bound 0 (one pixel off fails); its vertex path is held by PAPER_MEASURED's
/// `vertex-tracing:paper` (`tracing=vertices`) and by crates/specula-methods/tests.
#[rustfmt::skip]
const MEASURED: &[(&str, [Option<f64>; 6])] = &[
    ("concave-mirror",        [own(0.3541), own(0.0101), own(0.0556), own(0.0699), own(0.0315), own(0.0)]),
    ("glass-block",           [own(0.3592), own(0.3297), own(0.0563), own(0.1785), DELEGATED,   own(0.0039)]),
    ("glass-lens",            [own(0.3871), own(0.0738), own(0.0250), own(0.1077), DELEGATED,   own(0.0)]),
    ("glass-merged",          [own(0.3469), own(0.0640), own(0.0233), own(0.1089), DELEGATED,   own(0.0)]),
    ("glass-separate",        [own(0.3469), own(0.0642), own(0.0233), own(0.1089), DELEGATED,   own(0.0)]),
    ("glass-sphere",          [own(0.3789), own(0.0246), own(0.0193), own(0.1013), DELEGATED,   own(0.0)]),
    ("lit-room",              [own(0.2165), own(0.1144), own(0.0392), own(0.0833), own(0.0482), own(0.0)]),
    ("mirror-bunny",          [own(0.2307), own(0.0663), own(0.0542), own(0.0893), own(0.0542), own(0.0)]),
    ("mirror-in-glass",       [own(0.8132), own(0.0920), own(0.2519), own(0.7021), DELEGATED,   own(0.0)]),
    ("mirror-sphere-nearby",  [own(0.2196), own(0.0245), own(0.0461), own(0.0630), own(0.0351), own(0.0)]),
    ("mirror-sphere",         [own(0.2022), own(0.0157), own(0.0122), own(0.0167), own(0.0188), own(0.0)]),
    ("mirrors-merged",        [own(0.1751), own(0.0569), own(0.0139), own(0.0307), own(0.0379), own(0.0)]),
    ("mirrors-separate",      [own(0.1751), own(0.0568), own(0.0139), own(0.0307), own(0.0379), own(0.0)]),
    ("thin-sheet",            [own(0.3543), own(0.3134), own(0.0952), own(0.0297), DELEGATED,   own(0.0074)]),
];

/// Mean FLIP of the published algorithms (PAPER_METHODS, in that order) on a subset of the
/// scenes: a mirror that magnifies, a mirror with objects near it, a merged mirror scene, a glass
/// ball and a lens; measured 2026-12-02 as MEASURED was (pvrr:paper at its own depth, 2: the
/// `depth=1` the run sets is written `pvrr.depth=1`, for specula's pvrr only). image-space
/// shades mirrors with envmap's cube maps; without parallax (the paper's lookup) that is
/// envmap's figure exactly. vertex-tracing's published algorithm is more accurate than its
/// defaults here, at more rays: docs/methods/vertex-tracing.md has why. Measured again 2026-12-03 (issue
/// 38) with two-level cube maps off in the paper presets: image-space:paper on mirrors-merged
/// 0.1751 -> 0.1822 (envmap's maps with one level), c3rc:paper unchanged; vertex-tracing:paper
/// 0.0022 -> 0.0020, 0.0036 -> 0.0033, 0.0016 -> 0.0011 (since the per-pixel choice of issue
/// 27), pvrr:paper 0.1119 -> 0.1118.
#[rustfmt::skip]
const PAPER_MEASURED: &[(&str, [Option<f64>; 5])] = &[
    ("concave-mirror",        [own(0.1118), own(0.0797), own(0.3541), own(0.1968), own(0.0029)]),
    ("glass-lens",            [own(0.4757), own(0.1543), own(0.1392), DELEGATED,   own(0.0020)]),
    ("glass-sphere",          [own(0.2482), own(0.1990), own(0.2122), DELEGATED,   own(0.0033)]),
    ("mirror-sphere-nearby",  [own(0.4604), own(0.0519), own(0.2196), own(0.1797), own(0.0028)]),
    ("mirrors-merged",        [own(0.4346), own(0.0650), own(0.1822), own(0.2389), own(0.0011)]),
];

/// A method's figure on the pixels it shades itself.
const fn own(mean_flip: f64) -> Option<f64> {
    Some(mean_flip)
}

/// The method hands every masked pixel of the scene to another method.
const DELEGATED: Option<f64> = None;

/// Bound = min(MEASURED × MARGIN, MEASURED + CAP, halfway from MEASURED to a black image's
/// figure). The last term binds on one cell only: envmap on mirror-in-glass measures 0.8132
/// where a black image gets 0.8493 (its cube maps hold the mirror inside the glass as black),
/// so its bound is 0.8312, 1.02× the measurement.
const MARGIN: f64 = 1.5;
const CAP: f64 = 0.05;

fn bound(measured: f64, black: f64) -> f64 {
    (measured * MARGIN)
        .min(measured + CAP)
        .min(0.5 * (measured + black))
}

fn suite_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/suite")
}

/// One suite scene compared, with its row of MEASURED (and of PAPER_MEASURED where it has one):
/// `labels[m]` was measured `measured[m]`.
struct SceneRun {
    name: String,
    labels: Vec<&'static str>,
    measured: Vec<Option<f64>>,
    comparison: Comparison,
}

/// Every suite scene compared once, shared by the tests of this file. Each test asks for its
/// GPU context itself first (`specula_methods::test_context`), so that every test without one
/// fails or logs its own skip: none passes quietly on another's.
fn runs(ctx: &specula_methods::Context) -> &'static [SceneRun] {
    static RUNS: OnceLock<Vec<SceneRun>> = OnceLock::new();
    RUNS.get_or_init(|| {
        let mut files: Vec<_> = std::fs::read_dir(suite_dir())
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        let names: Vec<String> = files
            .iter()
            .map(|f| f.file_stem().unwrap().to_string_lossy().into_owned())
            .collect();
        let listed: Vec<&str> = MEASURED.iter().map(|(n, _)| *n).collect();
        assert_eq!(
            names, listed,
            "the suite's scenes and this test's table differ"
        );
        for (name, _) in PAPER_MEASURED {
            assert!(
                listed.contains(name),
                "PAPER_MEASURED's {name} is not a suite scene"
            );
        }
        let runs = files
            .iter()
            .zip(MEASURED)
            .map(|(file, (name, measured))| {
                let mut labels = METHODS.to_vec();
                let mut measured = measured.to_vec();
                if let Some((_, paper)) = PAPER_MEASURED.iter().find(|(n, _)| n == name) {
                    labels.extend(PAPER_METHODS);
                    measured.extend(paper);
                }
                let options = Options {
                    width: WIDTH,
                    height: HEIGHT,
                    methods: labels.iter().map(|m| m.to_string()).collect(),
                    spp: 1,
                    max_depth: 8,
                    parameters: vec!["pvrr.depth=1".into()],
                    frames: 1,
                };
                let scene = specula_scene::load(file.to_str().unwrap()).unwrap();
                let comparison = compare(&scene, ctx, &options, &|_| {}).unwrap();
                assert!(
                    comparison.report.failed.is_empty(),
                    "{name}: {:?}",
                    comparison.report.failed
                );
                SceneRun {
                    name: name.to_string(),
                    labels,
                    measured,
                    comparison,
                }
            })
            .collect();
        runs
    })
}

/// Mean FLIP of `image` against the scene's reference on the pixels `mask` holds.
fn flip_on(run: &SceneRun, image: &Image, mask: &[bool]) -> f64 {
    let reference = &run.comparison.reference;
    measure(reference, image, &flip_map(reference, image), mask).mean_flip
}

/// The check: `image` as method `m`'s output on `run`'s scene, measured as `compare` measures
/// it (its own surfaces apart from those it delegates), against MEASURED's bound on its own
/// surfaces, and on each delegated surface against the delegate's own figure there. Returns
/// what fails.
fn check(run: &SceneRun, m: usize, image: &Image) -> Vec<String> {
    let method = run.labels[m];
    let info = specula_methods::Label::parse(method).unwrap().info;
    let c = &run.comparison;
    let (own, delegated) = method_figures(
        info,
        &c.reference,
        image,
        &flip_map(&c.reference, image),
        &c.classes,
    );
    let mut failures = Vec::new();
    match (own, run.measured[m]) {
        (Some(own), Some(measured)) => {
            let bound = own_bound(run, m).unwrap();
            if own.mean_flip > bound {
                failures.push(format!(
                    "{method} on {}: mean FLIP {:.4} > {bound:.4} (measured {measured})",
                    run.name, own.mean_flip
                ));
            }
        }
        (None, None) => {}
        (own, measured) => failures.push(format!(
            "{method} on {}: figures {own:?}, the table {measured:?}",
            run.name
        )),
    }
    for d in &delegated {
        let Some(k) = run.labels.iter().position(|name| *name == d.delegate) else {
            failures.push(format!("{method}: delegate {} not compared", d.delegate));
            continue;
        };
        let mask = class_mask(&c.classes, |class| class == d.material);
        let theirs = flip_on(run, &c.method_images[k].0, &mask);
        // Exactly equal, measured 2026-12-01 on the six glass scenes and mirror-in-glass: c3rc's
        // glass pixels are envmap's shading pass over cube maps drawn as envmap draws them (a
        // mirror's nearby objects are left out of that mirror's map only), and its other
        // pixels are the same raster. FLIP filters spatially, so a scene where a c3rc mirror
        // pixel bordered a glass pixel could move the glass pixels' figure; the suite has none.
        if d.metrics.mean_flip != theirs {
            failures.push(format!(
                "{method} on {}: its {} pixels have mean FLIP {:.6}, {}'s own there {theirs:.6}",
                run.name, d.material, d.metrics.mean_flip, d.delegate
            ));
        }
    }
    failures
}

/// Method `m`'s bound on the pixels it shades itself on `run`'s scene (None: it delegates them
/// all).
fn own_bound(run: &SceneRun, m: usize) -> Option<f64> {
    let measured = run.measured[m]?;
    Some(bound(
        measured,
        flip_on(run, &black(run), &own_mask(run, m)),
    ))
}

/// The pixels method `m` shades itself on `run`'s scene.
fn own_mask(run: &SceneRun, m: usize) -> Vec<bool> {
    let info = specula_methods::Label::parse(run.labels[m]).unwrap().info;
    class_mask(&run.comparison.classes, |c| info.delegate_for(c).is_none())
}

fn black(run: &SceneRun) -> Image {
    Image::new(
        run.comparison.reference.width,
        run.comparison.reference.height,
    )
}

#[test]
fn every_technique_holds_its_figures_on_every_suite_scene() {
    let Some(ctx) = specula_methods::test_context("scene suite figures") else {
        return;
    };
    let runs = runs(&ctx);
    let mut failures = Vec::new();
    for run in runs {
        let report = &run.comparison.report;
        let row: Vec<String> = report
            .methods
            .iter()
            .map(|m| match &m.metrics {
                Some(x) => format!("own({:.4})", x.mean_flip),
                None => "DELEGATED".into(),
            })
            .collect();
        eprintln!("(\"{}\", [{}]),", run.name, row.join(", "));
        for (m, method) in run.labels.iter().enumerate() {
            let image = &run.comparison.method_images[m].0;
            // The check measures as compare does.
            let metrics = report.methods[m].metrics.as_ref().map(|x| x.mean_flip);
            let mask = own_mask(run, m);
            assert_eq!(
                metrics,
                mask.contains(&true).then(|| flip_on(run, image, &mask)),
                "{method} on {}",
                run.name
            );
            // Every bound can fail: a black image on the same pixels is above it (by the
            // bound's halfway term, unless the measurement itself is no better than black).
            if let Some(measured) = run.measured[m] {
                let black = flip_on(run, &black(run), &mask);
                let bound = bound(measured, black);
                eprintln!("    {method}: bound {bound:.4}, a black image {black:.4}");
                if bound >= black {
                    failures.push(format!(
                        "{method} on {}: the bound {bound:.4} cannot fail: a black image gets {black:.4}",
                        run.name
                    ));
                }
            }
            for d in &report.methods[m].delegated {
                eprintln!(
                    "    {method}: {} {} pixels delegated to {}: {:.6}",
                    d.metrics.mask_pixels, d.material, d.delegate, d.metrics.mean_flip
                );
            }
            failures.extend(check(run, m, image));
        }
    }
    let figure = |name: &str, m: usize| {
        let run = runs.iter().find(|r| r.name == name).unwrap();
        run.comparison.report.methods[m]
            .metrics
            .as_ref()
            .map(|x| x.mean_flip)
    };
    for (merged, separate) in [
        ("mirrors-merged", "mirrors-separate"),
        ("glass-merged", "glass-separate"),
    ] {
        for (m, method) in METHODS.iter().enumerate() {
            match (figure(merged, m), figure(separate, m)) {
                (Some(a), Some(b)) if (a - b).abs() > (0.1 * b).max(0.005) => {
                    failures.push(format!(
                    "{method}: {merged} {a:.4} is not within 10 % (or 0.005) of {separate} {b:.4}"
                ))
                }
                (Some(_), Some(_)) | (None, None) => {}
                (a, b) => failures.push(format!("{method}: {merged} {a:?}, {separate} {b:?}")),
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `image` moved right by one pixel (the left column kept): a raster or camera off by a pixel.
fn shifted_by_one_pixel(image: &Image) -> Image {
    let mut shifted = image.clone();
    let w = image.width as usize;
    for (y, row) in shifted.pixels.chunks_mut(w).enumerate() {
        row[1..].copy_from_slice(&image.pixels[y * w..(y + 1) * w - 1]);
    }
    shifted
}

/// `image` with the pixels `mask` holds taken from `other`.
fn with_pixels_of(image: &Image, other: &Image, mask: &[bool]) -> Image {
    let mut mixed = image.clone();
    for (i, _) in mask.iter().enumerate().filter(|(_, &m)| m) {
        mixed.pixels[i] = other.pixels[i];
    }
    mixed
}

/// `image` box-blurred over (2 × radius + 1)² pixels, clamped at the border.
fn blurred(image: &Image, radius: i32) -> Image {
    let (w, h) = (image.width as i32, image.height as i32);
    let at = |x: i32, y: i32| image.pixels[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize];
    let mut out = image.clone();
    for y in 0..h {
        for x in 0..w {
            let mut sum = glam::Vec3::ZERO;
            for dy in -radius..=radius {
                for dx in -radius..=radius {
                    sum += at(x + dx, y + dy);
                }
            }
            out.pixels[(y * w + x) as usize] = sum / ((2 * radius + 1) as f32).powi(2);
        }
    }
    out
}

/// `image` with red and blue swapped: a BGRA target read as RGBA.
fn red_and_blue_swapped(image: &Image) -> Image {
    let mut swapped = image.clone();
    for p in &mut swapped.pixels {
        *p = glam::Vec3::new(p.z, p.y, p.x);
    }
    swapped
}

/// `image` sRGB-encoded once more: a linear value written to an sRGB target by hand.
fn encoded_twice(image: &Image) -> Image {
    let mut encoded = image.clone();
    for p in &mut encoded.pixels {
        *p = p
            .to_array()
            .map(specula_trace::image_io::linear_to_srgb)
            .into();
    }
    encoded
}

/// A scene's name without `-merged` or `-separate`: the two of a pair render the same picture.
fn family(name: &str) -> &str {
    name.trim_end_matches("-merged")
        .trim_end_matches("-separate")
}

/// The wrong outputs a real defect would give in place of method `m`'s image on `runs[r]`.
fn wrong_outputs(runs: &[SceneRun], r: usize, m: usize) -> Vec<(&'static str, Image)> {
    let run = &runs[r];
    let own = &run.comparison.method_images[m].0;
    let mut wrong = vec![
        ("shifted by one pixel", shifted_by_one_pixel(own)),
        ("red and blue swapped", red_and_blue_swapped(own)),
        ("sRGB-encoded twice", encoded_twice(own)),
    ];
    if run.labels[m] == "envmap" {
        wrong.push((
            "the reference blurred by 3 pixels",
            blurred(&run.comparison.reference, 3),
        ));
    } else {
        let envmap = run.labels.iter().position(|l| *l == "envmap").unwrap();
        wrong.push((
            "its own pixels envmap's",
            with_pixels_of(
                own,
                &run.comparison.method_images[envmap].0,
                &own_mask(run, m),
            ),
        ));
    }
    // The next scene in the list (of another family) that this method ran on.
    let other = (1..runs.len())
        .map(|k| &runs[(r + k) % runs.len()])
        .find(|o| family(&o.name) != family(&run.name) && o.labels.contains(&run.labels[m]))
        .unwrap();
    let k = other
        .labels
        .iter()
        .position(|l| *l == run.labels[m])
        .unwrap();
    wrong.push((
        "another scene's image",
        other.comparison.method_images[k].0.clone(),
    ));
    wrong
}

#[test]
fn realistic_wrong_outputs_break_every_bound() {
    let Some(ctx) = specula_methods::test_context("scene suite wrong outputs") else {
        return;
    };
    let runs = runs(&ctx);
    // (wrong output, bounds it broke, bounds it was fed)
    let mut tally: Vec<(&str, usize, usize)> = Vec::new();
    let mut unbroken = Vec::new();
    let mut as_bad_as_black = Vec::new();
    let mut bounds = 0;
    for (r, run) in runs.iter().enumerate() {
        for (m, method) in run.labels.iter().enumerate() {
            let Some(bound) = own_bound(run, m) else {
                continue;
            };
            bounds += 1;
            let mask = own_mask(run, m);
            let mut broken = Vec::new();
            for (what, image) in wrong_outputs(runs, r, m) {
                let figure = flip_on(run, &image, &mask);
                let breaks = figure > bound;
                eprintln!(
                    "{method} on {}: {what}: {figure:.4} against the bound {bound:.4}{}",
                    run.name,
                    if breaks { " (broken)" } else { "" }
                );
                match tally.iter_mut().find(|(w, _, _)| *w == what) {
                    Some(row) => {
                        row.1 += breaks as usize;
                        row.2 += 1;
                    }
                    None => tally.push((what, breaks as usize, 1)),
                }
                if breaks {
                    broken.push(what);
                }
            }
            if broken.is_empty() {
                // A method already within 5 % of a black image's figure has no realistic wrong
                // output far worse than itself: its bound can only hold it from getting worse.
                let own = flip_on(run, &run.comparison.method_images[m].0, &mask);
                let black = flip_on(run, &black(run), &mask);
                let cell = format!("{method} on {} (bound {bound:.4})", run.name);
                if own >= 0.95 * black {
                    eprintln!("{cell}: {own:.4}, no better than a black image ({black:.4})");
                    as_bad_as_black.push(cell);
                } else {
                    unbroken.push(cell);
                }
            }
        }
    }
    eprintln!("\n| wrong output | bounds it breaks |\n|---|---|");
    for (what, broke, fed) in &tally {
        eprintln!("| {what} | {broke} of {fed} |");
    }
    let broken = bounds - unbroken.len() - as_bad_as_black.len();
    eprintln!("| any of them | {broken} of {bounds} |");
    eprintln!(
        "no better than a black image (within 5 %): {}",
        as_bad_as_black.join(", ")
    );
    assert!(
        unbroken.is_empty(),
        "bounds no wrong output breaks (too loose): {}",
        unbroken.join(", ")
    );
}

#[test]
fn the_bound_is_one_and_a_half_times_the_measurement_capped() {
    assert!((bound(0.02, 0.9) - 0.03).abs() < 1e-12);
    assert!((bound(0.2, 0.9) - 0.25).abs() < 1e-12);
    assert!((bound(0.8, 0.84) - 0.82).abs() < 1e-12);
    let rows = MEASURED.iter().map(|(_, r)| &r[..]);
    for row in rows.chain(PAPER_MEASURED.iter().map(|(_, r)| &r[..])) {
        for measured in row.iter().flatten() {
            assert!(bound(*measured, 1.0) <= measured + CAP + 1e-12);
            // A measurement of 0 (the reference's own pixels) is held to 0.
            assert!(bound(*measured, 1.0) > *measured || *measured == 0.0);
        }
    }
}

/// pvrr's zooming region (issue 28) on a concave mirror that magnifies the wall behind the eye
/// and a ball lens (`scenes/zooming`), and on the suite's lens and glass sphere: mean FLIP at
/// the suite's size with pvrr's defaults (depth 2), measured 2026-12-02 on lavapipe with
/// `cargo test -p specula-compare --test suite zooming -- --nocapture`: (scene file under
/// `scenes/`, the goal, measured). Before the zooming view and view volumes fitted to
/// the hits, at 320 × 240: 0.204, 0.277, 0.154, 0.242 (CHANGELOG.md).
#[rustfmt::skip]
const ZOOMING_MEASURED: &[(&str, Option<f64>, f64)] = &[
    ("zooming/concave-magnifier.toml", Some(0.12), 0.0184),
    ("zooming/ball-lens.toml",         None,       0.0399),
    ("suite/glass-lens.toml",          Some(0.10), 0.0740),
    ("suite/glass-sphere.toml",        Some(0.10), 0.0246),
];

/// The project's bound (2× the measurement, at most the measurement + 0.05), and the goal.
fn zooming_bound(measured: f64, goal: Option<f64>) -> f64 {
    (2.0 * measured)
        .min(measured + CAP)
        .min(goal.unwrap_or(f64::INFINITY))
}

#[test]
fn pvrr_meets_its_zooming_region_goals() {
    let Some(ctx) = specula_methods::test_context("pvrr zooming goals") else {
        return;
    };
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut failures = Vec::new();
    for &(file, goal, measured) in ZOOMING_MEASURED {
        let scene = specula_scene::load(scenes.join(file).to_str().unwrap()).unwrap();
        let options = Options {
            width: WIDTH,
            height: HEIGHT,
            methods: vec!["pvrr".into(), "pvrr:paper".into()],
            spp: 1,
            max_depth: 8,
            parameters: Vec::new(),
            frames: 1,
        };
        let c = compare(&scene, &ctx, &options, &|_| {}).unwrap();
        let figure = |m: usize| c.report.methods[m].metrics.as_ref().unwrap().mean_flip;
        let (pvrr, paper) = (figure(0), figure(1));
        let bound = zooming_bound(measured, goal);
        eprintln!(
            "{file}: pvrr {pvrr:.4} (bound {bound:.4}, goal {goal:?}), pvrr:paper {paper:.4}"
        );
        if pvrr > bound {
            failures.push(format!("{file}: pvrr {pvrr:.4} > {bound:.4}"));
        }
        // The bound can fail: the published algorithm's zooming region is above it.
        if paper <= bound {
            failures.push(format!(
                "{file}: pvrr:paper {paper:.4} is within the bound {bound:.4}"
            ));
        }
        // Where a goal is set, the zooming view beats the fallback it replaced (every vertex
        // whose hit lies behind its viewpoint ray traced): measured 0.1577 on the magnifier,
        // 0.0881 on the lens, 0.0246 (no zooming view planned) on the glass sphere.
        if goal.is_some() {
            let traced_options = Options {
                methods: vec!["pvrr".into()],
                parameters: vec!["zooming=traced".into()],
                ..options
            };
            let traced = compare(&scene, &ctx, &traced_options, &|_| {}).unwrap();
            let traced = traced.report.methods[0].metrics.as_ref().unwrap().mean_flip;
            eprintln!("{file}: pvrr zooming=traced {traced:.4}");
            if pvrr > traced {
                failures.push(format!(
                    "{file}: the zooming view {pvrr:.4} > traced {traced:.4}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// c3rc on scenes of the classes issue 29 sets goals for (`scenes/c3rc`, `scenes/zooming`): a
/// mirror sphere in a closed checkered room with a box and a ball, unlit and lit, and posed
/// otherwise; a concave mirror magnifying a near wall, twice; and the suite's concave mirror,
/// where a far object stands in front of the near room: mean FLIP with c3rc's defaults at
/// compare's default size, 320 × 240, measured 2026-12-02 on lavapipe with `specula compare
/// SCENE --methods c3rc,c3rc:paper` (the test prints its own figures): (scene file under
/// `scenes/`, the goal, measured). Before exact hits and the far field's depth: 0.1033,
/// 0.0707, 0.0858, 0.2261, 0.1700, 0.1221 (CHANGELOG.md).
#[rustfmt::skip]
const C3RC_MEASURED: &[(&str, Option<f64>, f64)] = &[
    ("c3rc/closed-room.toml",          Some(0.06), 0.0008),
    ("c3rc/closed-room-lit.toml",      Some(0.06), 0.0107),
    ("c3rc/closed-room-corner.toml",   Some(0.06), 0.0113),
    ("zooming/concave-magnifier.toml", Some(0.15), 0.0259),
    ("c3rc/concave-wall.toml",         Some(0.15), 0.0145),
    ("suite/concave-mirror.toml",      None,       0.0302),
];

#[test]
fn c3rc_meets_its_closed_room_and_magnifier_goals() {
    let Some(ctx) = specula_methods::test_context("c3rc goals") else {
        return;
    };
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut failures = Vec::new();
    for &(file, goal, measured) in C3RC_MEASURED {
        let scene = specula_scene::load(scenes.join(file).to_str().unwrap()).unwrap();
        let options = Options {
            width: 320,
            height: 240,
            methods: vec!["c3rc".into(), "c3rc:paper".into()],
            spp: 1,
            max_depth: 8,
            parameters: Vec::new(),
            frames: 1,
        };
        let c = compare(&scene, &ctx, &options, &|_| {}).unwrap();
        let figure = |m: usize| c.report.methods[m].metrics.as_ref().unwrap().mean_flip;
        let (c3rc, paper) = (figure(0), figure(1));
        let bound = zooming_bound(measured, goal);
        eprintln!(
            "{file}: c3rc {c3rc:.4} (bound {bound:.4}, goal {goal:?}), c3rc:paper {paper:.4}"
        );
        if c3rc > bound {
            failures.push(format!("{file}: c3rc {c3rc:.4} > {bound:.4}"));
        }
        // The bound can fail: the published algorithm is above it.
        if paper <= bound {
            failures.push(format!(
                "{file}: c3rc:paper {paper:.4} is within the bound {bound:.4}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
