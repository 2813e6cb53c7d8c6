//! The paper's verification overlay (Figures 1 and 14) as a measurement: with `markers=true`
//! a red ball sits at every vertex's exact hit P, so in the picture each ball should be centred
//! on its vertex. Measured on `door-mirror` (reflection) and `spectacle-lens` (double
//! refraction), in pixels of a 512 × 512 image.
//!
//! A ball's picture is its map image warped linearly per triangle, so a big ball's centroid
//! drifts from the vertex by a fraction of its radius wherever neighbouring triangles magnify
//! differently. The balls are therefore small (0.2 % of their distance) and the frame is
//! rendered at 4 × 512 per side so that each ball still covers enough pixels; distances are
//! reported in 512-pixel units.

use glam::{Vec2, Vec3};
use specula_methods::by_name;
use specula_methods::pvrr::MARKER_RADIANCE;
use specula_methods::RenderStill;
use specula_scene::Scene;
use specula_trace::reference::primary_hits;
use specula_trace::{Ray, SceneAccel};

const SIZE: u32 = 512;
/// Rendering scale: the frame is SCALE × SIZE pixels per side.
const SCALE: u32 = 4;
const RENDER: u32 = SIZE * SCALE;

/// Continuous pixel coordinates of world point `p` (pixel centres at + 0.5).
fn screen_of(scene: &Scene, p: Vec3) -> Option<Vec2> {
    let f = scene.camera.frame();
    let q = p - scene.camera.eye;
    let z = q.dot(f.forward);
    let tan = (scene.camera.fov_y_deg.to_radians() * 0.5).tan();
    let (x, y) = (q.dot(f.right) / (z * tan), q.dot(f.up) / (z * tan));
    (z > 0.0).then(|| Vec2::new((x + 1.0) * 0.5, (1.0 - y) * 0.5) * RENDER as f32)
}

struct Measured {
    /// Per vertex whose ball is wholly on the reflector: distance (512-pixels) from the vertex
    /// to the centroid of its ball's pixels.
    interior: Vec<f32>,
    /// Per vertex on the reflector's outline (ball clipped, centroid pulled inwards, or a
    /// neighbouring vertex hidden): distance from the vertex to the nearest pixel of its ball.
    outline: Vec<f32>,
    visible: usize,
    /// Visible vertices whose neighbours are too close on screen to tell their balls apart.
    crowded: usize,
}

/// Renders `scene` with pvrr with and without markers and measures, for every visible vertex
/// of mesh `reflector_name`, where its ball appears.
fn measure(
    ctx: &specula_methods::Context,
    scene: &Scene,
    reflector_name: &str,
    ior: Option<&str>,
) -> Measured {
    let reflector = scene
        .meshes
        .iter()
        .position(|m| m.name == reflector_name)
        .unwrap();
    let mesh = &scene.meshes[reflector];
    let mut pvrr = by_name("pvrr").unwrap();
    for (name, value) in [
        ("markers", "true"),
        ("marker_size", "0.002"),
        ("resolution", "2048"),
    ] {
        specula_methods::apply_setting(pvrr.as_mut(), &format!("{}={}", name, value)).unwrap();
    }
    if let Some(ior) = ior {
        specula_methods::apply_setting(pvrr.as_mut(), &format!("{}={}", "ior", ior)).unwrap();
    }
    let image = pvrr.render_still(ctx, scene, RENDER, RENDER).unwrap().image;
    assert!(image.pixels.iter().all(|p| p.is_finite()));
    if let Ok(dir) = std::env::var("SPECULA_DEBUG_DIR") {
        let path = format!("{dir}/{reflector_name}-markers.png");
        image.save_png(std::path::Path::new(&path)).unwrap();
    }
    let accel = SceneAccel::new(scene);
    let hits = primary_hits(scene, &accel, RENDER, RENDER);
    let on_reflector = |x: i32, y: i32| {
        (0..RENDER as i32).contains(&x)
            && (0..RENDER as i32).contains(&y)
            && hits[(y as u32 * RENDER + x as u32) as usize]
                .is_some_and(|h| h.mesh as usize == reflector)
    };
    // Markers are far brighter than anything lit: a pixel belongs to a ball when its red is
    // over half the markers' radiance.
    let marker = |x: i32, y: i32| image.get(x as u32, y as u32).x > 0.5 * MARKER_RADIANCE;
    let visible = |v: Vec3| {
        let to = v - scene.camera.eye;
        let distance = to.length();
        let ray = Ray {
            origin: scene.camera.eye,
            dir: to / distance,
        };
        accel
            .intersect(&ray, distance * (1.0 + 1e-4))
            .is_some_and(|h| h.mesh as usize == reflector && h.t > distance * (1.0 - 2e-3))
    };
    let mut neighbours = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
            neighbours[i].push(j);
            neighbours[j].push(i);
        }
    }
    let mut grazing = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        let to_eye = (scene.camera.eye - a).normalize();
        if normal.dot(to_eye).abs() < 0.3 {
            for &i in t {
                grazing[i as usize] = true;
            }
        }
    }
    let mut measured = Measured {
        interior: Vec::new(),
        outline: Vec::new(),
        visible: 0,
        crowded: 0,
    };
    let scale = SCALE as f32;
    for (i, &v) in mesh.positions.iter().enumerate() {
        let Some(s) = screen_of(scene, v).filter(|_| visible(v)) else {
            continue;
        };
        if !(0.0..RENDER as f32).contains(&s.x) || !(0.0..RENDER as f32).contains(&s.y) {
            continue;
        }
        measured.visible += 1;
        let spacing = neighbours[i]
            .iter()
            .filter_map(|&j| screen_of(scene, mesh.positions[j]))
            .map(|t| t.distance(s))
            .filter(|&d| d > 1e-3)
            .fold(f32::INFINITY, f32::min)
            .min(60.0 * scale);
        if spacing < 6.0 * scale {
            measured.crowded += 1;
            continue;
        }
        // The ball: the connected marker pixels, within half the spacing of the vertex, around
        // the marker pixel nearest to it (another vertex's ball may show in the window too).
        let window = spacing * 0.5;
        let r = window.ceil() as i32;
        let (cx, cy) = (s.x.floor() as i32, s.y.floor() as i32);
        let centre = |x: i32, y: i32| Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let in_window = |x: i32, y: i32| centre(x, y).distance(s) <= window;
        let mut clipped = false;
        let mut seed: Option<(i32, i32)> = None;
        for y in cy - r..=cy + r {
            for x in cx - r..=cx + r {
                if !in_window(x, y) {
                    continue;
                }
                if !on_reflector(x, y) {
                    clipped = true;
                } else if marker(x, y)
                    && seed.is_none_or(|(sx, sy)| {
                        centre(x, y).distance(s) < centre(sx, sy).distance(s)
                    })
                {
                    seed = Some((x, y));
                }
            }
        }
        let seed = seed.unwrap_or_else(|| panic!("vertex {i}: no ball near {s:?}"));
        let nearest = centre(seed.0, seed.1).distance(s);
        let mut ball = vec![seed];
        let mut seen = std::collections::HashSet::from([seed]);
        let mut k = 0;
        while k < ball.len() {
            let (x, y) = ball[k];
            k += 1;
            for (nx, ny) in [(x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)] {
                if in_window(nx, ny)
                    && on_reflector(nx, ny)
                    && marker(nx, ny)
                    && seen.insert((nx, ny))
                {
                    ball.push((nx, ny));
                }
            }
        }
        let centroid = ball.iter().map(|&(x, y)| centre(x, y)).sum::<Vec2>() / ball.len() as f32;
        {
            // A ball next to hidden geometry, or next to a triangle seen edge-on (a lens rim),
            // is stretched along that sliver: on the outline, too.
            if clipped || !neighbours[i].iter().all(|&j| visible(mesh.positions[j])) || grazing[i] {
                measured.outline.push(nearest / scale);
            } else {
                measured.interior.push(centroid.distance(s) / scale);
            }
        }
    }
    measured
}

fn check(name: &str, reflector: &str, ior: Option<&str>) {
    let Some(ctx) = specula_methods::test_context(name) else {
        return;
    };
    let scene = specula_scene::load(name).unwrap();
    let m = measure(&ctx, &scene, reflector, ior);
    let worst = |d: &[f32]| d.iter().copied().fold(0.0f32, f32::max);
    let mean = m.interior.iter().sum::<f32>() / m.interior.len().max(1) as f32;
    eprintln!(
        "pvrr markers {name} (ior {ior:?}) at {SIZE}²: {} visible vertices ({} too crowded to separate); {} interior: ball centroid to vertex mean {mean:.2} px, worst {:.2} px; {} on the outline: nearest ball pixel worst {:.2} px",
        m.visible,
        m.crowded,
        m.interior.len(),
        worst(&m.interior),
        m.outline.len(),
        worst(&m.outline)
    );
    assert!(m.interior.len() >= 10, "too few interior vertices measured");
    // Measured 2026-11-30: interior worst 0.25 px (door-mirror), outline worst 0.30 px
    // (spectacle-lens); bounds 2x.
    assert!(worst(&m.interior) <= 0.5, "a ball is off its vertex");
    assert!(
        worst(&m.outline) <= 0.6,
        "an outline vertex's ball is off it"
    );
}

#[test]
fn door_mirror_balls_sit_on_their_vertices_within_a_pixel() {
    check("door-mirror", "door mirror", None);
}

#[test]
fn spectacle_lens_balls_sit_on_their_vertices_within_a_pixel() {
    // The lens disperses (1.60, 1.61, 1.62), and where its channels' hit points coincide their
    // three marker balls would overlap in the shared map; each index is measured on its own.
    for ior in ["1.60", "1.61", "1.62"] {
        check("spectacle-lens", "spectacle lens", Some(ior));
    }
}
