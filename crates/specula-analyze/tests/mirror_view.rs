//! `mirror-view` against closed forms: a flat rectangular mirror (its footprint is the
//! quadrilateral cut on the ground by the rays from the eye's mirror image through the mirror's
//! corners; its solid angle is the rectangle's seen from the mirror image) and a convex
//! spherical mirror (the field of view's edge is the rim's reflection, by the law of reflection
//! at the rim normals).

use glam::{Vec2, Vec3};
use specula_analyze::frame::VehicleFrame;
use specula_analyze::mirror_surface::SurfaceModel;
use specula_analyze::mirror_view::{analyze, Obstacles, Options, Region};
use specula_scene::{Camera, Material, Mesh, Scene};
use specula_trace::SceneAccel;

fn camera(eye: Vec3) -> Camera {
    Camera {
        eye,
        target: eye + Vec3::NEG_Z,
        up: Vec3::Y,
        fov_y_deg: 40.0,
        aspect: None,
    }
}

fn options(scene: &Scene, eye: Vec3, region: Option<Region>) -> Options {
    let options = Options {
        region,
        ..options_unchecked(eye)
    };
    options.validate(scene).unwrap();
    options
}

/// A flat rectangle, `width` × `height`, centred on `centre`, facing `normal`.
struct Rectangle {
    centre: Vec3,
    normal: Vec3,
    u: Vec3,
    v: Vec3,
    width: f32,
    height: f32,
}

impl Rectangle {
    fn tilted(centre: Vec3, tilt_down: f32) -> Rectangle {
        let normal = Vec3::new(0.0, -tilt_down, 1.0).normalize();
        let u = Vec3::X;
        Rectangle {
            centre,
            normal,
            u,
            v: normal.cross(u),
            width: 0.2,
            height: 0.12,
        }
    }

    fn corners(&self) -> [Vec3; 4] {
        let (hu, hv) = (self.u * self.width * 0.5, self.v * self.height * 0.5);
        [
            self.centre - hu - hv,
            self.centre + hu - hv,
            self.centre + hu + hv,
            self.centre - hu + hv,
        ]
    }

    fn mesh(&self) -> Mesh {
        let c = self.corners();
        Mesh {
            exact: None,
            cad: None,
            name: "mirror".into(),
            positions: c.to_vec(),
            normals: vec![self.normal; 4],
            uvs: Vec::new(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            material: 0,
        }
    }

    /// The eye's mirror image in the rectangle's plane.
    fn image_of(&self, eye: Vec3) -> Vec3 {
        eye - 2.0 * (eye - self.centre).dot(self.normal) * self.normal
    }
}

fn scene_with(mirror: Mesh, eye: Vec3) -> Scene {
    let mut scene = Scene::new("closed form");
    scene.materials.push(Material::mirror("mirror", Vec3::ONE));
    scene.meshes.push(mirror);
    scene.camera = camera(eye);
    scene
}

/// Solid angle of a rectangle seen from a point at distance `d` from its plane: the rectangle
/// spans [x0, x1] × [y0, y1] in the plane's axes, measured from the point's foot. Each corner term is the solid angle of a rectangle with a corner at the foot,
/// atan(xy / (d √(x² + y² + d²))), odd in x and y, so four of them with signs make any
/// rectangle.
fn rectangle_solid_angle(d: f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let corner = |x: f64, y: f64| (x * y / (d * (x * x + y * y + d * d).sqrt())).atan();
    corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0)
}

fn polygon_area(points: &[Vec2]) -> f64 {
    let n = points.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            f64::from(a.x) * f64::from(b.y) - f64::from(b.x) * f64::from(a.y)
        })
        .sum::<f64>()
        .abs()
}

#[test]
fn a_flat_mirror_shows_the_quadrilateral_and_the_solid_angle_of_its_mirror_image() {
    let eye = Vec3::new(0.05, 1.2, 0.0);
    let mirror = Rectangle::tilted(Vec3::new(0.0, 1.15, -1.0), 0.3);
    let scene = scene_with(mirror.mesh(), eye);
    let accel = SceneAccel::new(&scene);
    let view = analyze(&scene, &accel, &[eye], &options(&scene, eye, None), &|_| {}).unwrap();
    let figures = &view.report.eyes[0].figures;

    let image = mirror.image_of(eye);
    let footprint: Vec<Vec2> = mirror
        .corners()
        .iter()
        .map(|c| {
            let t = image.y / (image.y - c.y);
            assert!(
                t > 1.0,
                "every corner ray reaches the ground beyond the mirror"
            );
            let g = image + (*c - image) * t;
            assert!(g.distance(eye) < 100.0);
            Vec2::new(g.x, g.z)
        })
        .collect();
    let area = polygon_area(&footprint);
    let relative = (figures.ground_area_m2 - area).abs() / area;
    eprintln!(
        "footprint: {:.6} m² against {area:.6} m² (relative {relative:.3e})",
        figures.ground_area_m2
    );
    // Measured 2026-12-02: 1.09e-5 (the ground grid's cells along the edges); the issue asks 1 %.
    assert!(
        relative < 2.5e-5,
        "ground area off by {:.3} %",
        relative * 100.0
    );

    let foot = image - (image - mirror.centre).dot(mirror.normal) * mirror.normal;
    let d = f64::from((image - foot).length());
    let offset = mirror.centre - foot;
    let (cu, cv) = (
        f64::from(offset.dot(mirror.u)),
        f64::from(offset.dot(mirror.v)),
    );
    let (hw, hh) = (
        f64::from(mirror.width) * 0.5,
        f64::from(mirror.height) * 0.5,
    );
    let solid_angle = rectangle_solid_angle(d, cu - hw, cu + hw, cv - hh, cv + hh);
    let relative = (figures.solid_angle_sr - solid_angle).abs() / solid_angle;
    eprintln!(
        "solid angle: {:.8} sr against {solid_angle:.8} sr (relative {relative:.3e})",
        figures.solid_angle_sr
    );
    // Measured: 6.8e-7 (a flat mirror's spherical triangles tile its image exactly; f32 rays).
    assert!(
        relative < 1.5e-6,
        "solid angle off by {:.4} %",
        relative * 100.0
    );
    // One eye: the ambinocular figures are its own, to the direction grid's resolution.
    let all = &view.report.figures;
    assert!((all.ground_area_m2 - figures.ground_area_m2).abs() < 1e-9);
    // The union's solid angle is counted on the direction grid: measured 5.2e-5.
    let union_error = (all.solid_angle_sr - solid_angle).abs() / solid_angle;
    eprintln!("union solid angle off by {union_error:.3e}");
    assert!(union_error < 1.1e-4);
}

#[test]
fn a_region_half_inside_the_footprint_is_half_seen_and_half_blind() {
    let eye = Vec3::new(0.0, 1.2, 0.0);
    let mirror = Rectangle::tilted(Vec3::new(0.0, 1.15, -1.0), 0.3);
    let scene = scene_with(mirror.mesh(), eye);
    let accel = SceneAccel::new(&scene);
    let image = mirror.image_of(eye);
    let ground = |c: Vec3| {
        let g = image + (c - image) * (image.y / (image.y - c.y));
        Vec2::new(g.x, g.z)
    };
    // A region across the footprint's right edge, well inside its near and far edges.
    let corners = mirror.corners().map(ground);
    let near = corners[0]
        .y
        .min(corners[1].y)
        .max(corners[2].y.min(corners[3].y));
    let far = corners[0]
        .y
        .max(corners[1].y)
        .min(corners[2].y.max(corners[3].y));
    let (z0, z1) = (near.min(far), near.max(far));
    let inner = (z1 - z0) * 0.25;
    let half_width = corners
        .iter()
        .map(|c| c.x.abs())
        .fold(f32::INFINITY, f32::min);
    let region = Region::new(-half_width * 0.5, z0 + inner, 3.0 * half_width, z1 - inner).unwrap();
    let view = analyze(
        &scene,
        &accel,
        &[eye],
        &options(&scene, eye, Some(region)),
        &|_| {},
    )
    .unwrap();
    let all = &view.report.figures;
    let seen = all.region_seen_by_any.unwrap();
    assert_eq!(all.region_seen_by_all, Some(seen));
    let blind = all.blind_area_m2.unwrap();
    assert!((blind - region.area() * (1.0 - seen)).abs() < 1e-9);
    // The exact share: clip the region by the footprint quadrilateral, numerically fine.
    let inside = |p: Vec2| {
        (0..4).all(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % 4]);
            (b - a).perp_dot(p - a) * (corners[2] - corners[0]).perp_dot(corners[1] - corners[0])
                <= 0.0
        })
    };
    let n = 400;
    let mut count = 0;
    for i in 0..n {
        for j in 0..n {
            let p = Vec2::new(
                region.x0 + (region.x1 - region.x0) * (i as f32 + 0.5) / n as f32,
                region.z0 + (region.z1 - region.z0) * (j as f32 + 0.5) / n as f32,
            );
            count += usize::from(inside(p));
        }
    }
    let expected = count as f64 / (n * n) as f64;
    eprintln!("region seen {seen:.6}, expected {expected:.6}");
    assert!(
        expected > 0.2 && expected < 0.8,
        "the region straddles the footprint"
    );
    // Measured: 1.6e-5 apart (both count cells).
    assert!(
        (seen - expected).abs() < 4e-5,
        "seen {seen}, expected {expected}"
    );
}

#[test]
fn a_convex_mirror_s_field_of_view_is_bounded_by_its_rim_s_reflections() {
    let radius = 1.2;
    let aperture = 0.3;
    let mut cap =
        specula_scene::generators::spherical_cap(radius, aperture, false, 24, 96).unwrap();
    cap.name = "convex".into();
    cap.material = 0;
    let eye = Vec3::new(0.1, 0.05, 1.5);
    let scene = scene_with(cap, eye);
    let accel = SceneAccel::new(&scene);
    let mut options = options(&scene, eye, None);
    // The ground far below: every reflected ray may miss it; this test is about directions.
    options.ground_y = -100.0;
    let view = analyze(&scene, &accel, &[eye], &options, &|_| {}).unwrap();
    let figures = &view.report.eyes[0].figures;

    // The rim's reflections, exactly: rim point, its sphere normal, the law of reflection.
    let centre = Vec3::new(0.0, 0.0, -radius);
    let theta = (aperture * 0.5 / radius).asin();
    let frame = options.frame;
    let rim: Vec<Vec3> = (0..3600)
        .map(|k| {
            let phi = k as f32 / 3600.0 * std::f32::consts::TAU;
            let n = Vec3::new(
                phi.cos() * theta.sin(),
                phi.sin() * theta.sin(),
                theta.cos(),
            );
            let p = centre + n * radius;
            let d = (p - eye).normalize();
            d - 2.0 * d.dot(n) * n
        })
        .collect();
    let reference = frame.horizontal(rim.iter().copied().sum()).unwrap();
    let (mut h, mut v) = ((f64::MAX, f64::MIN), (f64::MAX, f64::MIN));
    for r in &rim {
        let (x, y) = (frame.horizontal_deg(*r, reference), frame.elevation_deg(*r));
        h = (h.0.min(x), h.1.max(x));
        v = (v.0.min(y), v.1.max(y));
    }
    let (horizontal, vertical) = (h.1 - h.0, v.1 - v.0);
    eprintln!(
        "extents {:.5}° × {:.5}° against the rim's {horizontal:.5}° × {vertical:.5}°",
        figures.horizontal_deg, figures.vertical_deg
    );
    // Measured: 0.0006° and 0.0033° (the issue asks 0.2°).
    assert!((figures.horizontal_deg - horizontal).abs() < 0.0015);
    assert!((figures.vertical_deg - vertical).abs() < 0.007);
    assert!(view.report.eyes[0].converged);
}

#[test]
fn a_hidden_mirror_shows_nothing_and_says_so_with_finite_zeros() {
    let eye = Vec3::new(0.0, 1.2, 0.0);
    let mirror = Rectangle::tilted(Vec3::new(0.0, 1.15, -1.0), 0.3);
    let mut scene = scene_with(mirror.mesh(), eye);
    // A wall between the eye and the mirror.
    scene.materials.push(Material::diffuse("wall", Vec3::ONE));
    let mut wall = Rectangle::tilted(Vec3::new(0.0, 1.2, -0.5), 0.0);
    (wall.width, wall.height) = (2.0, 2.0);
    scene.meshes.push(Mesh {
        name: "wall".into(),
        material: 1,
        ..wall.mesh()
    });
    let accel = SceneAccel::new(&scene);
    let region = Region::new(-1.0, 1.0, 1.0, 3.0).unwrap();
    let view = analyze(
        &scene,
        &accel,
        &[eye],
        &options(&scene, eye, Some(region)),
        &|_| {},
    )
    .unwrap();
    let r = &view.report;
    assert_eq!(r.eyes[0].seen_samples, 0);
    for f in [&r.figures, &r.eyes[0].figures] {
        assert_eq!(
            (
                f.horizontal_deg,
                f.vertical_deg,
                f.solid_angle_sr,
                f.ground_area_m2
            ),
            (0.0, 0.0, 0.0, 0.0)
        );
        assert_eq!(f.region_seen_by_any, Some(0.0));
        assert_eq!(f.blind_area_m2, Some(region.area()));
    }
    assert!(r.ground_cell_m.is_finite() && r.direction_cell_deg.is_finite());
}

#[test]
fn a_window_pane_hides_nothing_and_solid_glass_hides_the_mirror() {
    let eye = Vec3::new(0.05, 1.2, 0.0);
    let mirror = Rectangle::tilted(Vec3::new(0.0, 1.15, -1.0), 0.3);
    let seen_through = |pane: Material| {
        let mut scene = scene_with(mirror.mesh(), eye);
        scene.materials.push(pane);
        let mut glass = Rectangle::tilted(Vec3::new(0.0, 1.2, -0.5), 0.0);
        (glass.width, glass.height) = (2.0, 2.0);
        scene.meshes.push(Mesh {
            name: "pane".into(),
            material: 1,
            ..glass.mesh()
        });
        let accel = SceneAccel::new(&scene);
        analyze(&scene, &accel, &[eye], &options(&scene, eye, None), &|_| {})
            .unwrap()
            .report
            .eyes[0]
            .figures
            .solid_angle_sr
    };
    let open = {
        let scene = scene_with(mirror.mesh(), eye);
        let accel = SceneAccel::new(&scene);
        analyze(&scene, &accel, &[eye], &options(&scene, eye, None), &|_| {})
            .unwrap()
            .report
            .eyes[0]
            .figures
            .solid_angle_sr
    };
    let sheet = Material::new(
        "window",
        specula_scene::MaterialKind::Dielectric {
            ior: Vec3::splat(1.5),
            thin_walled: true,
        },
        Vec3::ONE,
    );
    assert_eq!(seen_through(sheet), open);
    assert_eq!(seen_through(Material::glass("block", 1.5)), 0.0);
}

#[test]
fn bad_input_is_named() {
    let eye = Vec3::new(0.0, 1.2, 0.0);
    let mirror = Rectangle::tilted(Vec3::new(0.0, 1.15, -1.0), 0.3);
    let mut scene = scene_with(mirror.mesh(), eye);
    let unknown = specula_analyze::object(&scene, "--mirror", "mirrr").unwrap_err();
    assert!(
        unknown.to_string().contains("unknown --mirror 'mirrr'")
            && unknown.to_string().contains("mirror"),
        "{unknown}"
    );
    let no_area = Region::new(0.0, 1.0, 2.0, 1.0).unwrap_err();
    assert!(no_area.to_string().starts_with("region: "), "{no_area}");
    let mut bad = options(&scene, eye, None);
    bad.range_m = 0.0;
    assert!(bad
        .validate(&scene)
        .unwrap_err()
        .to_string()
        .starts_with("range: "));
    scene.materials[0] = Material::diffuse("wall", Vec3::ONE);
    let wall = options_unchecked(eye).validate(&scene).unwrap_err();
    assert!(wall.to_string().contains("not a mirror"), "{wall}");
}

fn options_unchecked(eye: Vec3) -> Options {
    Options {
        mirror: 0,
        frame: VehicleFrame::new(&camera(eye), Some(Vec3::NEG_Z)).unwrap(),
        ground_y: 0.0,
        range_m: 100.0,
        region: None,
        tolerance: 0.002,
        tolerance_deg: 0.02,
        max_samples: 400_000,
        surface: SurfaceModel::Mesh,
        obstacles: Obstacles::Scene,
    }
}

#[test]
fn two_eyes_see_the_union_and_the_intersection_of_their_footprints() {
    let eyes = [Vec3::new(-0.1, 1.2, 0.0), Vec3::new(0.12, 1.25, 0.05)];
    let mirror = Rectangle::tilted(Vec3::new(0.0, 1.15, -1.0), 0.3);
    let scene = scene_with(mirror.mesh(), eyes[0]);
    let accel = SceneAccel::new(&scene);
    // Each eye's footprint, exactly: the quadrilateral cut by its mirror image's corner rays.
    let quads: Vec<[Vec2; 4]> = eyes
        .iter()
        .map(|eye| {
            let image = mirror.image_of(*eye);
            mirror.corners().map(|c| {
                let g = image + (c - image) * (image.y / (image.y - c.y));
                Vec2::new(g.x, g.z)
            })
        })
        .collect();
    let inside = |q: &[Vec2; 4], p: Vec2| {
        let orientation = (q[1] - q[0]).perp_dot(q[2] - q[0]);
        (0..4).all(|i| (q[(i + 1) % 4] - q[i]).perp_dot(p - q[i]) * orientation >= 0.0)
    };
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for p in quads.iter().flatten() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let region = Region::new(lo.x, lo.y, hi.x, hi.y).unwrap();
    let n = 600;
    let (mut any, mut all) = (0usize, 0usize);
    for i in 0..n {
        for j in 0..n {
            let p = lo
                + (hi - lo) * Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let seen = quads.iter().filter(|q| inside(q, p)).count();
            any += usize::from(seen > 0);
            all += usize::from(seen == 2);
        }
    }
    let cells = (n * n) as f64;
    let union_area = region.area() * any as f64 / cells;
    let options = options(&scene, eyes[0], Some(region));
    let view = analyze(&scene, &accel, &eyes, &options, &|_| {}).unwrap();
    let f = &view.report.figures;
    eprintln!(
        "union {:.6} m² against {union_area:.6}; seen by any {:.6} against {:.6}, by all {:.6} against {:.6}",
        f.ground_area_m2,
        f.region_seen_by_any.unwrap(),
        any as f64 / cells,
        f.region_seen_by_all.unwrap(),
        all as f64 / cells
    );
    assert!(all > 0 && all < any, "the footprints overlap in part");
    // Measured 2026-12-02: 7.5e-4 relative, and 1.3e-4 / 5.4e-4 (both sides count on grids).
    assert!((f.ground_area_m2 - union_area).abs() / union_area < 1.5e-3);
    assert!((f.region_seen_by_any.unwrap() - any as f64 / cells).abs() < 3e-4);
    assert!((f.region_seen_by_all.unwrap() - all as f64 / cells).abs() < 1.1e-3);
}

#[test]
fn a_zero_area_triangle_in_the_mirror_changes_no_figure() {
    // Meshes built through the library (not the loaders, which drop them) may carry degenerate
    // triangles: they cover nothing and must not turn a figure into NaN.
    let eye = Vec3::new(0.05, 1.2, 0.0);
    let mirror = Rectangle::tilted(Vec3::new(0.0, 1.15, -1.0), 0.3);
    let clean = scene_with(mirror.mesh(), eye);
    let mut mesh = mirror.mesh();
    mesh.triangles.push([0, 0, 1]);
    mesh.triangles.push([1, 2, 2]);
    let degenerate = scene_with(mesh, eye);
    let figures = |scene: &Scene| {
        let accel = SceneAccel::new(scene);
        let view = analyze(scene, &accel, &[eye], &options(scene, eye, None), &|_| {}).unwrap();
        view.report.figures
    };
    let (a, b) = (figures(&clean), figures(&degenerate));
    for (x, y) in [
        (a.horizontal_deg, b.horizontal_deg),
        (a.vertical_deg, b.vertical_deg),
        (a.solid_angle_sr, b.solid_angle_sr),
        (a.ground_area_m2, b.ground_area_m2),
    ] {
        assert!(y.is_finite(), "{b:?}");
        assert!((x - y).abs() <= 1e-6 * x.abs(), "{a:?}\n{b:?}");
    }
}
