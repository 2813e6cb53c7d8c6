//! Vertex tracing's invariants on the CPU (no GPU needed): the image does not depend on how
//! the frame is cut into packages (what makes the MPI image equal the single-process one), the
//! progressive mode starts from the Gouraud preview and ends on the one-call image, a hidden
//! reflector costs no ray (§3), and the counters add up.

use glam::{Mat4, Vec3};
use specula_methods::vertex_tracing::INFO;
use specula_methods::{apply_parameters, Context, Frame, LiveScene, Technique};
use specula_scene::{Camera, Material, Scene};

const WIDTH: u32 = 192;
const HEIGHT: u32 = 144;

fn technique(params: &[&str]) -> Box<dyn Technique> {
    let mut t = (INFO.create)();
    let mut all = vec!["visibility=cpu".to_string()];
    all.extend(params.iter().map(|p| p.to_string()));
    apply_parameters(t.as_mut(), &all).unwrap();
    t
}

fn render(t: &mut dyn Technique, live: &LiveScene, camera: &Camera) -> (Frame, Vec<Vec3>) {
    let ctx = Context::default();
    let frame = t.render(&ctx, live, camera, WIDTH, HEIGHT).unwrap();
    let image = frame.image(&ctx).unwrap();
    (frame, image.pixels)
}

fn counter(frame: &Frame, name: &str) -> u64 {
    frame
        .counters
        .iter()
        .find(|(n, _)| n.starts_with(name))
        .unwrap_or_else(|| panic!("no counter {name}"))
        .1
}

#[test]
fn the_image_does_not_depend_on_how_the_frame_is_cut_into_packages() {
    let live = LiveScene::new(specula_scene::load("truck-cover").unwrap());
    let camera = live.scene().camera.clone();
    let (frame, whole) = render(technique(&[]).as_mut(), &live, &camera);
    assert!(counter(&frame, "edges split") > 100, "the test must refine");
    assert!(counter(&frame, "filled pixels") > 0, "the test must fill");
    for size in ["1", "5", "64", "100000"] {
        let setting = format!("package_triangles={size}");
        let (_, cut) = render(technique(&[&setting]).as_mut(), &live, &camera);
        let differing = whole
            .iter()
            .zip(&cut)
            .filter(|(a, b)| a.to_array().map(f32::to_bits) != b.to_array().map(f32::to_bits))
            .count();
        assert_eq!(differing, 0, "{setting}: {differing} pixels differ");
    }
}

#[test]
fn progressive_mode_starts_from_the_preview_and_ends_on_the_one_call_image() {
    let live = LiveScene::new(specula_scene::load("truck-cover").unwrap());
    let camera = live.scene().camera.clone();
    let (_, one_call) = render(technique(&[]).as_mut(), &live, &camera);
    let mut t = technique(&["budget_ms=1"]);
    let (first, _) = render(t.as_mut(), &live, &camera);
    assert!(!first.converged);
    assert_eq!(
        counter(&first, "edges split"),
        0,
        "the first image is the preview"
    );
    assert_eq!(counter(&first, "filled pixels"), 0);
    assert!(counter(&first, "vertex rays") > 0);
    let mut steps = 1;
    let last = loop {
        let (frame, pixels) = render(t.as_mut(), &live, &camera);
        steps += 1;
        assert!(steps < 10_000, "never converged");
        if frame.converged {
            break pixels;
        }
    };
    assert!(steps > 2, "a 1 ms budget must take several steps ({steps})");
    assert!(
        last == one_call,
        "the refined image differs from the one-call image"
    );
    // A moved camera starts over from the preview.
    let mut moved = camera.clone();
    moved.eye += Vec3::new(0.01, 0.0, 0.0);
    let (restarted, _) = render(t.as_mut(), &live, &moved);
    assert!(!restarted.converged);
    assert_eq!(counter(&restarted, "edges split"), 0);
}

/// A mirror behind a wall, and one beside it: only the visible one is traced.
fn hidden_mirror_scene(visible: bool) -> Scene {
    let mut scene = Scene::new("hidden mirror");
    scene.materials = vec![
        Material::mirror("mirror", Vec3::splat(0.9)),
        Material::diffuse("wall", Vec3::splat(0.5)),
    ];
    let mut mirror = specula_scene::generators::plane(glam::Vec2::splat(0.5), 8);
    let x = if visible { 1.6 } else { 0.0 };
    mirror.transform(Mat4::from_translation(Vec3::new(x, 0.0, -1.0)) * Mat4::from_rotation_x(1.2));
    mirror.name = "mirror".into();
    mirror.material = 0;
    let mut wall = specula_scene::generators::cuboid(Vec3::new(1.0, 1.0, 0.1));
    wall.name = "wall".into();
    wall.material = 1;
    scene.meshes = vec![mirror, wall];
    scene.camera = Camera {
        eye: Vec3::new(0.0, 0.0, 3.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg: 60.0,
        aspect: None,
    };
    scene
}

#[test]
fn a_hidden_reflector_costs_no_ray() {
    let hidden = LiveScene::new(hidden_mirror_scene(false));
    let camera = hidden.scene().camera.clone();
    let (frame, _) = render(technique(&[]).as_mut(), &hidden, &camera);
    assert_eq!(counter(&frame, "reflector pixels"), 0);
    assert_eq!(counter(&frame, "vertex rays"), 0);
    assert!(frame.warnings.iter().any(|w| w.contains("no reflector")));
    let seen = LiveScene::new(hidden_mirror_scene(true));
    let (frame, _) = render(technique(&[]).as_mut(), &seen, &camera);
    assert!(counter(&frame, "reflector pixels") > 0);
    assert!(counter(&frame, "vertex rays") > 0);
}

#[test]
fn counters_add_up_and_switches_take_effect() {
    let live = LiveScene::new(specula_scene::load("truck-cover").unwrap());
    let camera = live.scene().camera.clone();
    let (full, _) = render(technique(&[]).as_mut(), &live, &camera);
    assert_eq!(
        counter(&full, "samples"),
        counter(&full, "vertex rays") + counter(&full, "filled pixels")
    );
    let (unfilled, _) = render(technique(&["fill=false"]).as_mut(), &live, &camera);
    assert_eq!(
        counter(&unfilled, "filled pixels"),
        counter(&unfilled, "stray pixels"),
        "without filling only stray pixels are traced"
    );
    let (preview, _) = render(
        technique(&["refine=false", "fill=false"]).as_mut(),
        &live,
        &camera,
    );
    assert_eq!(counter(&preview, "edges split"), 0);
    assert!(counter(&preview, "vertex rays") < counter(&unfilled, "vertex rays"));
    // The preview traces each original vertex of the traced triangles once.
    let cover = &live.scene().meshes[live.object("cover glass").unwrap()];
    assert!(counter(&preview, "vertex rays") <= cover.positions.len() as u64);
}
