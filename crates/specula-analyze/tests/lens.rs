//! `lens` against ophthalmic optics' closed forms: a thick lens's back vertex power, Prentice's
//! rule with the equivalent power, a toric prescription given back, lateral colour as prism over
//! the Abbe number, Tscherning's oblique astigmatism, the built-in lens's back vertex power.

use glam::{DVec3, Vec3};
use specula_analyze::lens::{analyze, default_options, Cell, LensTracer, Options, Report};
use specula_analyze::mirror_surface::SurfaceModel;
use specula_scene::generators::{self, LensSpec};
use specula_scene::spectacle::spectacle_lens;
use specula_scene::{Camera, Material, MaterialKind, Mesh, Prescription, Scene};

/// A scene of `lens` (made in the lens frame: light along +Z, back vertex at z = `thickness`)
/// seen by a camera 12 mm behind the back vertex, looking along −Z.
fn scene_of(lens: Mesh, indices: Vec3, thickness: f32) -> Scene {
    let mut scene = Scene::new("lens closed form");
    scene.materials.push(Material::new(
        "glass",
        MaterialKind::Dielectric {
            ior: indices,
            thin_walled: false,
        },
        Vec3::ONE,
    ));
    let mut lens = lens;
    lens.name = "lens".into();
    lens.material = 0;
    scene.meshes.push(lens);
    scene.camera = Camera {
        eye: Vec3::new(0.0, 0.0, thickness + 0.012),
        target: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        fov_y_deg: 50.0,
        aspect: None,
    };
    scene
}

fn spherical(r1: f32, r2: f32, t: f32, n: f32, diameter: f32) -> Scene {
    let lens = generators::lens(&LensSpec {
        front_radius: r1,
        back_radius: r2,
        center_thickness: t,
        diameter,
        rings: 40,
        segments: 96,
    })
    .unwrap();
    scene_of(lens, Vec3::new(n - 0.01, n, n + 0.01), t)
}

fn run(scene: &Scene, adjust: impl FnOnce(&mut Options)) -> Report {
    let mut options = default_options(scene, 0).unwrap();
    adjust(&mut options);
    analyze(scene, &options, &|_| {}).unwrap()
}

fn cell(report: &Report, h: f64, v: f64) -> &Cell {
    report
        .grid
        .iter()
        .find(|c| (c.gaze_deg[0] - h).abs() < 1e-9 && (c.gaze_deg[1] - v).abs() < 1e-9)
        .unwrap()
}

/// Back vertex power and equivalent power of a thick spherical lens.
fn thick_lens(r1: f64, r2: f64, t: f64, n: f64) -> (f64, f64) {
    let f1 = (n - 1.0) / r1;
    let f2 = (1.0 - n) / r2;
    (f1 / (1.0 - t / n * f1) + f2, f1 + f2 - t / n * f1 * f2)
}

#[test]
fn a_thick_lens_s_centre_power_is_its_back_vertex_power() {
    for (what, r1, r2, t) in [
        ("plus (biconvex)", 0.10f32, -0.15f32, 0.006f32),
        ("minus (biconcave)", -0.12, 0.09, 0.0015),
        ("meniscus", 0.12, 0.075, 0.002),
    ] {
        let n = 1.6;
        let scene = spherical(r1, r2, t, n, 0.05);
        let report = run(&scene, |o| {
            o.gaze.h_max_deg = 5.0;
            o.gaze.v_max_deg = 5.0;
        });
        let (vertex, _) = thick_lens(f64::from(r1), f64::from(r2), f64::from(t), f64::from(n));
        let c = &report.centre;
        let (sphere, cylinder) = (c.sphere_d.unwrap(), c.cylinder_d.unwrap());
        eprintln!(
            "{what}: sphere {sphere:.5} D, cylinder {cylinder:.5} D against the back vertex \
             power {vertex:.5} D; finite differences changed by {:.2e} D",
            report.finite_difference_change_d
        );
        // Measured 2026-12-02: 1.2e-4 to 2.7e-4 D off, no cylinder (the issue asks 0.01 D).
        assert!((sphere - vertex).abs() < 6e-4, "{what}");
        assert!(cylinder.abs() < 1e-4, "{what}");
    }
}

#[test]
fn a_small_gaze_off_centre_gives_prentice_s_prism_with_the_equivalent_power() {
    // Prentice's rule with the equivalent power holds at the lens's principal planes: c is the
    // chief ray's height where it crosses the second principal plane, e′ = −(t/n)·F1/Fe from
    // the back vertex towards the eye. (At the back surface itself the meniscus would be 7.8 %
    // off: a thick lens's prism follows its principal planes.)
    for (what, r1, r2, t) in [
        ("meniscus (minus)", 0.12f32, 0.075f32, 0.002f32),
        ("biconvex (plus)", 0.10, -0.15, 0.006),
    ] {
        let n = 1.6;
        let scene = spherical(r1, r2, t, n, 0.05);
        let report = run(&scene, |o| {
            o.gaze.h_max_deg = 2.5;
            o.gaze.v_max_deg = 2.5;
        });
        let (r1, r2, t, n) = (f64::from(r1), f64::from(r2), f64::from(t), f64::from(n));
        let (_, equivalent) = thick_lens(r1, r2, t, n);
        let f1 = (n - 1.0) / r1;
        let principal = -(t / n) * f1 / equivalent;
        let to_plane = report.vertex_sphere_radius_m - principal;
        for (h, v) in [(2.5, 0.0), (0.0, -2.5), (2.5, 2.5)] {
            let c = cell(&report, h, v);
            let height_cm = to_plane
                * f64::hypot(f64::tan(f64::to_radians(h)), f64::tan(f64::to_radians(v)))
                * 100.0;
            let [ph, pv] = c.prism_d.unwrap();
            let prism = ph.hypot(pv);
            let expected = height_cm * equivalent.abs();
            let relative = (prism - expected).abs() / expected;
            eprintln!(
                "{what} at ({h}, {v})°: {prism:.5} Δ (h {ph:.5}, v {pv:.5}) against c·Fe = \
                 {height_cm:.4} cm × {equivalent:.4} D = {expected:.5} Δ ({:.3} %; principal \
                 plane {:.2} mm from the back vertex)",
                relative * 100.0,
                principal * 1e3
            );
            // Measured 2026-12-02: 0.04 % to 0.22 % (the issue asks 3 %).
            assert!(relative < 0.005, "{what} at ({h}, {v})");
            // A minus lens's base lies towards its edge, a plus lens's towards its centre: for
            // the right eye looking right (temporally) base out, looking down base down.
            let base_towards_edge = equivalent < 0.0;
            if h > 0.0 {
                assert_eq!(
                    ph > 0.0,
                    base_towards_edge,
                    "{what}: base out for a minus lens"
                );
            }
            if v < 0.0 {
                assert_eq!(
                    pv < 0.0,
                    base_towards_edge,
                    "{what}: base down for a minus lens"
                );
            }
        }
    }
}

fn prescription(sphere: f64, cylinder: f64, axis_deg: f64) -> Prescription {
    Prescription {
        sphere,
        cylinder,
        axis_deg,
        index: 1.6,
        abbe: 42.0,
        center_thickness: 0.002,
        base_curve: 4.0,
        diameter: 0.05,
        ..Prescription::default()
    }
}

fn generated(p: &Prescription, rings: u32, segments: u32) -> Scene {
    let mut scene = scene_of(
        spectacle_lens(p, rings, segments).unwrap(),
        p.indices(),
        p.center_thickness as f32,
    );
    scene.prescriptions.push(("lens".into(), p.clone()));
    scene
}

#[test]
fn a_toric_lens_from_the_generator_gives_back_its_prescription_at_the_centre() {
    for (sphere, cylinder, axis) in [(-2.0, -1.0, 30.0), (1.5, -2.0, 90.0), (-4.0, -0.75, 165.0)] {
        let p = prescription(sphere, cylinder, axis);
        let scene = generated(&p, 48, 192);
        let report = run(&scene, |o| {
            o.gaze.h_max_deg = 0.0;
            o.gaze.v_max_deg = 0.0;
        });
        let c = &report.centre;
        let (s, cyl, a) = (
            c.sphere_d.unwrap(),
            c.cylinder_d.unwrap(),
            c.axis_deg.unwrap(),
        );
        let axis_error = ((a - axis + 90.0).rem_euclid(180.0) - 90.0).abs();
        eprintln!(
            "{sphere} / {cylinder} × {axis}: {s:.6} / {cyl:.6} × {a:.4}; power error {:.2e} D, \
             unwanted cylinder {:.2e} D",
            c.power_error_d.unwrap(),
            c.unwanted_cylinder_d.unwrap()
        );
        // Measured 2026-12-02: within 1e-4 D and 0.005° (the issue asks 0.01 D and 1°).
        assert!((s - sphere).abs() < 3e-4 && (cyl - cylinder).abs() < 3e-4);
        assert!(axis_error < 0.05, "{axis_error}");
        assert!(c.unwanted_cylinder_d.unwrap() < 3e-4 && c.power_error_d.unwrap().abs() < 3e-4);
    }
}

#[test]
fn a_minus_cylinder_at_axis_90_is_most_minus_across_the_horizontal_meridian() {
    // Independently of the generator's and the analysis's conventions: parallel rays along +Z
    // (towards the eye), 1 mm either side of the axis horizontally and vertically, and the
    // power each pair meets: −(slope change) / (height change), in world coordinates.
    let p = prescription(-1.0, -2.0, 90.0);
    let scene = generated(&p, 48, 192);
    let tracer = LensTracer::new(&scene.meshes[0]);
    let power = |offset: DVec3| {
        let slope = |sign: f64| {
            let origin = DVec3::new(0.0, 0.0, -0.05) + offset * sign;
            let out = tracer.trace(origin, DVec3::Z, 1.6).unwrap().dir;
            (out / out.z).dot(offset.normalize())
        };
        -(slope(1.0) - slope(-1.0)) / (2.0 * offset.length())
    };
    let horizontal = power(DVec3::new(1e-3, 0.0, 0.0));
    let vertical = power(DVec3::new(0.0, 1e-3, 0.0));
    eprintln!("world: {horizontal:.4} D across x, {vertical:.4} D across y");
    assert!(
        horizontal < vertical - 1.9,
        "the horizontal meridian is the most minus"
    );
    let report = run(&scene, |o| {
        o.gaze.h_max_deg = 0.0;
        o.gaze.v_max_deg = 0.0;
    });
    assert!((report.centre.axis_deg.unwrap() - 90.0).abs() < 1.0);
}

#[test]
fn lateral_colour_is_the_prism_over_the_abbe_number() {
    let p = prescription(-4.0, 0.0, 0.0);
    let scene = generated(&p, 48, 192);
    let report = run(&scene, |o| {
        o.gaze.h_max_deg = 20.0;
        o.gaze.v_max_deg = 20.0;
        o.gaze.step_deg = 10.0;
    });
    for (h, v) in [(10.0, 0.0), (20.0, 0.0), (0.0, -20.0), (20.0, 20.0)] {
        let c = cell(&report, h, v);
        let [ph, pv] = c.prism_d.unwrap();
        // The deviation's angle at n_d over V, in arcminutes.
        let deviation = (ph.hypot(pv) / 100.0).atan();
        let expected = deviation / p.abbe * (180.0 / std::f64::consts::PI) * 60.0;
        let colour = c.lateral_colour_arcmin.unwrap();
        let relative = (colour - expected).abs() / expected;
        eprintln!(
            "({h}, {v})°: lateral colour {colour:.4}′ against prism / V = {expected:.4}′ ({:.2} %)",
            relative * 100.0
        );
        // Measured 2026-12-02: 1.2 % to 1.8 % (the issue asks 5 %).
        assert!(relative < 0.036);
    }
}

#[test]
fn oblique_astigmatism_follows_tscherning_over_the_front_base_curve() {
    // A −4 D lens (n 1.523, t 2 mm, 60 mm), its centre of rotation 27 mm behind the back
    // vertex, looking 30° to the side, for front base curves 0 to +7 D.
    let mut sweep = Vec::new();
    for tenth in 0..=70 {
        let base_curve = f64::from(tenth) / 10.0;
        let p = Prescription {
            sphere: -4.0,
            cylinder: 0.0,
            axis_deg: 0.0,
            index: 1.523,
            abbe: 58.0,
            center_thickness: 0.002,
            base_curve,
            diameter: 0.06,
            ..Prescription::default()
        };
        let scene = generated(&p, 48, 192);
        let report = run(&scene, |o| {
            o.gaze.h_max_deg = 30.0;
            o.gaze.v_max_deg = 0.0;
            o.gaze.step_deg = 30.0;
        });
        let c = cell(&report, 30.0, 0.0);
        sweep.push((
            base_curve,
            c.cylinder_d.unwrap().abs(),
            c.mean_power_d.unwrap(),
        ));
    }
    for (base, cylinder, mean) in sweep.iter().step_by(5) {
        eprintln!("base {base:.1} D: cylinder {cylinder:.3} D, mean power {mean:.3} D");
    }
    let flat = sweep[0].1;
    let (best_base, best) = sweep
        .iter()
        .map(|(b, c, _)| (*b, *c))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    eprintln!("flat front: {flat:.3} D; the least, {best:.4} D at base {best_base:.1} D");
    assert!(flat >= 0.6, "a flat front gives {flat} D");
    assert!(best <= 0.05 && (4.0..=6.0).contains(&best_base));
}

#[test]
fn the_built_in_spectacle_lens_has_its_back_vertex_power_at_the_centre() {
    let scene = specula_scene::load("spectacle-lens").unwrap();
    let lens = specula_analyze::object(&scene, "--lens", "spectacle lens").unwrap();
    let mut options = default_options(&scene, lens).unwrap();
    options.gaze.h_max_deg = 0.0;
    options.gaze.v_max_deg = 0.0;
    let report = analyze(&scene, &options, &|_| {}).unwrap();
    // R1 0.12 m, R2 0.075 m, t 2 mm at n_d 1.61.
    let (vertex, _) = thick_lens(0.12, 0.075, 0.002, 1.61);
    let sphere = report.centre.sphere_d.unwrap();
    eprintln!(
        "centre {sphere:.5} D against the back vertex power {vertex:.5} D (thin-lens sum −3.05 D)"
    );
    assert!((vertex - -3.018).abs() < 5e-4);
    // Measured 2026-12-02: 3.5e-4 D off (its coarse mesh: 10 rings).
    assert!((sphere - vertex).abs() < 8e-4);
}

#[test]
fn a_plane_parallel_plate_has_no_power_prism_colour_or_distortion_at_any_gaze() {
    // Refraction in and out of parallel faces leaves every ray's direction as it was.
    let scene = spherical(f32::INFINITY, f32::INFINITY, 0.003, 1.6, 0.08);
    let report = run(&scene, |o| o.gaze.step_deg = 10.0);
    let mut largest = [0.0f64; 5];
    for c in &report.grid {
        let figures = [
            c.mean_power_d.unwrap().abs(),
            c.cylinder_d.unwrap().abs(),
            c.prism_d.map(|[h, v]| h.hypot(v)).unwrap(),
            c.lateral_colour_arcmin.unwrap(),
            c.distortion_percent.unwrap().abs(),
        ];
        for (l, f) in largest.iter_mut().zip(figures) {
            *l = l.max(f);
        }
    }
    eprintln!(
        "largest over ±30°: mean power {:.1e} D, cylinder {:.1e} D, prism {:.1e} Δ, colour \
         {:.1e}′, distortion {:.1e} %; spectacle magnification {:?}",
        largest[0], largest[1], largest[2], largest[3], largest[4], report.spectacle_magnification
    );
    // Measured: 0 to 5e-13 (rounding).
    assert!(largest.iter().all(|l| *l < 1e-9), "{largest:?}");
    assert!(report
        .spectacle_magnification
        .iter()
        .all(|m| (m - 1.0).abs() < 1e-9));
}

#[test]
fn a_toric_lens_converges_as_its_tessellation_doubles() {
    // Interpolated normals reproduce a sphere exactly and a torus only approximately: the
    // generator's default (48 rings × 192 segments) against twice as fine, over ±30°.
    let p = Prescription {
        diameter: 0.065,
        ..prescription(-3.0, -1.0, 30.0)
    };
    let figures = |rings: u32, segments: u32| {
        let report = run(&generated(&p, rings, segments), |o| {
            o.gaze.step_deg = 10.0;
            o.surface = SurfaceModel::Mesh;
        });
        report
            .grid
            .iter()
            .map(|c| (c.mean_power_d.unwrap(), c.cylinder_d.unwrap()))
            .collect::<Vec<_>>()
    };
    let (default, fine) = (figures(48, 192), figures(96, 384));
    let largest = default
        .iter()
        .zip(&fine)
        .map(|(a, b)| (a.0 - b.0).abs().max((a.1 - b.1).abs()))
        .fold(0.0, f64::max);
    eprintln!("48 × 192 against 96 × 384 rings × segments: {largest:.2e} D at most");
    // Measured 2026-12-02: 3.7e-3 D (at a 30°, 30° corner).
    assert!(largest < 7e-3);
}

#[test]
fn a_near_object_s_exit_vergence_follows_the_thick_lens_vergence_equations() {
    // Object at 0.4 m from the centre of rotation, on the axis: its vergence at the front
    // vertex L1 = −1/u, then L1' = L1 + F1, L2 = L1' / (1 − (t/n) L1'), L2' = L2 + F2 at the back
    // vertex, which the vertex sphere touches at the centre.
    let (r1, r2, t, n) = (0.12f32, 0.075f32, 0.002f32, 1.6f32);
    let scene = spherical(r1, r2, t, n, 0.05);
    let report = run(&scene, |o| {
        o.gaze.h_max_deg = 0.0;
        o.gaze.v_max_deg = 0.0;
        o.object_distance_m = Some(0.4);
    });
    let (r1, r2, t, n) = (f64::from(r1), f64::from(r2), f64::from(t), f64::from(n));
    let u = 0.4 - (report.vertex_sphere_radius_m + t);
    let l1 = -1.0 / u + (n - 1.0) / r1;
    let expected = l1 / (1.0 - t / n * l1) + (1.0 - n) / r2;
    let sphere = report.centre.sphere_d.unwrap();
    eprintln!("near: {sphere:.5} D against {expected:.5} D");
    // Measured 2026-12-02: −5.68888 D against −5.68876 D (1.2e-4 D).
    assert!(
        (sphere - expected).abs() < 3e-4,
        "{sphere} against {expected}"
    );
    // An object nearer than the lens is refused.
    let mut options = default_options(&scene, 0).unwrap();
    options.object_distance_m = Some(0.02);
    let error = analyze(&scene, &options, &|_| {}).unwrap_err().to_string();
    assert!(error.contains("at or behind the lens"), "{error}");
}

#[test]
fn an_oblique_minus_cylinder_s_axis_is_where_an_examiner_reads_it() {
    // Axis 45 (TABO, from the examiner's right, the wearer's left): the sphere meridian runs up
    // to the wearer's left, so in world coordinates (x the wearer's right) the direction
    // (−1, 1) meets the sphere power and (1, 1) the more minus sphere + cylinder. A left/right
    // mirror of the conventions would swap them.
    let p = prescription(-1.0, -2.0, 45.0);
    let scene = generated(&p, 48, 192);
    let tracer = LensTracer::new(&scene.meshes[0]);
    let power = |offset: DVec3| {
        let slope = |sign: f64| {
            let origin = DVec3::new(0.0, 0.0, -0.05) + offset * sign;
            let out = tracer.trace(origin, DVec3::Z, 1.6).unwrap().dir;
            (out / out.z).dot(offset.normalize())
        };
        -(slope(1.0) - slope(-1.0)) / (2.0 * offset.length())
    };
    let up_left = power(DVec3::new(-1e-3, 1e-3, 0.0));
    let up_right = power(DVec3::new(1e-3, 1e-3, 0.0));
    eprintln!("world: {up_left:.4} D along (−1, 1), {up_right:.4} D along (1, 1)");
    // Measured 2026-12-02: −0.9951 and −2.9858 D (a 1 mm pair sees a little spherical
    // aberration).
    assert!((up_left - -1.0).abs() < 0.01 && (up_right - -3.0).abs() < 0.03);
    let report = run(&scene, |o| {
        o.gaze.h_max_deg = 0.0;
        o.gaze.v_max_deg = 0.0;
    });
    assert!((report.centre.axis_deg.unwrap() - 45.0).abs() < 0.05);
}

#[test]
fn spectacle_magnification_is_the_shape_factor_times_the_power_factor_from_the_pupil() {
    // SM = 1 / (1 − (t/n) F1) × 1 / (1 − h Fv), h from the back vertex to the entrance pupil
    // (3 mm behind the cornea, 12 mm in front of the centre of rotation); the same with h the
    // distance to the centre of rotation is the rotating eye's field magnification.
    let (r1, r2, t, n) = (0.12f32, 0.075f32, 0.002f32, 1.6f32);
    let scene = spherical(r1, r2, t, n, 0.05);
    let report = run(&scene, |o| {
        o.gaze.h_max_deg = 0.0;
        o.gaze.v_max_deg = 0.0;
    });
    let (r1, r2, t, n) = (f64::from(r1), f64::from(r2), f64::from(t), f64::from(n));
    let (vertex, _) = thick_lens(r1, r2, t, n);
    let f1 = (n - 1.0) / r1;
    let expected = |h: f64| 1.0 / (1.0 - t / n * f1) / (1.0 - h * vertex);
    let to_centre = report.vertex_sphere_radius_m;
    let to_pupil = to_centre - (report.rotation_behind_cornea_mm - 3.0) * 1e-3;
    for (name, [h, v], expected) in [
        (
            "spectacle",
            report.spectacle_magnification,
            expected(to_pupil),
        ),
        (
            "rotating eye's",
            report.rotating_eye_magnification,
            expected(to_centre),
        ),
    ] {
        eprintln!(
            "{name} magnification {h:.6}, {v:.6} against {expected:.6} ({:.1e} apart)",
            (h - expected).abs().max((v - expected).abs())
        );
        // Measured 2026-12-04 on the exact surfaces: 1.6e-7 and 2.5e-7 apart (the ±0.1°
        // central differences).
        assert!((h - expected).abs() < 5e-7 && (v - expected).abs() < 5e-7);
    }
    assert!((to_pupil - 0.015).abs() < 1e-9, "{to_pupil}");
}
