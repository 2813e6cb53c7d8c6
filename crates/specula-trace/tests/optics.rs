//! Closed-form optics: each test compares the tracer's optics (and, for the slab, lens and
//! mirror, its geometry and surface orientation) with a textbook answer.

use glam::{Mat4, Vec3};
use specula_scene::generators::{self, LensSpec};
use specula_scene::{Material, Mesh, Scene};
use specula_trace::optics::*;
use specula_trace::reference::{offset_origin, surface_point};
use specula_trace::{Ray, SceneAccel};

fn one_mesh_scene(mut mesh: Mesh, material: Material, world_from_object: Mat4) -> Scene {
    mesh.transform(world_from_object);
    mesh.material = 0;
    let mut scene = Scene::new("test");
    scene.meshes.push(mesh);
    scene.materials.push(material);
    scene
}

/// Follows only the refracted branch (or the reflected one for mirrors) through the scene, as
/// the reference tracer does at each interface; returns the rays between interfaces.
fn follow(scene: &Scene, mut ray: Ray, bounces: usize) -> Vec<Ray> {
    let accel = SceneAccel::new(scene);
    let mut path = vec![ray];
    for _ in 0..bounces {
        let Some(hit) = accel.intersect(&ray, f32::INFINITY) else {
            break;
        };
        let sp = surface_point(scene, &ray, &hit);
        let dir = match scene.materials[sp.material].kind {
            specula_scene::MaterialKind::Dielectric { ior, .. } => {
                let eta = if sp.backface { ior.x } else { 1.0 / ior.x };
                refract(ray.dir, sp.ns, eta)
                    .expect("no total internal reflection on this path")
                    .normalize()
            }
            _ => reflect(ray.dir, sp.ns),
        };
        ray = Ray {
            origin: offset_origin(sp.p, sp.ng, dir),
            dir,
        };
        path.push(ray);
    }
    path
}

/// Where a ray in the XZ or YZ plane crosses the optical (Z) axis.
fn axis_crossing(ray: &Ray) -> f32 {
    let (h, dh) = if ray.dir.x.abs() > ray.dir.y.abs() {
        (ray.origin.x, ray.dir.x)
    } else {
        (ray.origin.y, ray.dir.y)
    };
    ray.origin.z - h / dh * ray.dir.z
}

#[test]
fn fresnel_at_normal_incidence_is_four_percent_for_n_1_5() {
    assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
    // The same from inside the glass.
    assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
}

#[test]
fn reflectance_plus_independent_transmittance_is_one() {
    // T from the Fresnel transmission amplitudes, computed independently of R.
    for &(n_i, n_t) in &[(1.0f64, 1.5f64), (1.5, 1.0), (1.0, 2.4), (1.33, 1.0)] {
        for k in 0..=89 {
            let theta_i = (k as f64).to_radians();
            let cos_i = theta_i.cos();
            let sin_t = n_i / n_t * theta_i.sin();
            if sin_t >= 1.0 {
                assert_eq!(fresnel_dielectric(cos_i as f32, (n_i / n_t) as f32), 1.0);
                continue;
            }
            let cos_t = (1.0 - sin_t * sin_t).sqrt();
            let t_s = 2.0 * n_i * cos_i / (n_i * cos_i + n_t * cos_t);
            let t_p = 2.0 * n_i * cos_i / (n_t * cos_i + n_i * cos_t);
            let transmittance = (n_t * cos_t) / (n_i * cos_i) * 0.5 * (t_s * t_s + t_p * t_p);
            let r = fresnel_dielectric(cos_i as f32, (n_i / n_t) as f32) as f64;
            assert!(
                (r + transmittance - 1.0).abs() < 1e-5,
                "n {n_i}->{n_t} at {k}°: R {r} + T {transmittance}"
            );
        }
    }
}

#[test]
fn critical_angle_and_total_internal_reflection() {
    let critical = critical_angle(1.5, 1.0);
    assert!((critical.to_degrees() - 41.8103).abs() < 1e-3);
    let n = Vec3::Z;
    for (degrees, expect_tir) in [(41.0f32, false), (42.5, true), (60.0, true), (10.0, false)] {
        let a = degrees.to_radians();
        let d = Vec3::new(a.sin(), 0.0, -a.cos());
        assert_eq!(refract(d, n, 1.5).is_none(), expect_tir, "{degrees}°");
        if expect_tir {
            assert_eq!(fresnel_dielectric(a.cos(), 1.5), 1.0);
        } else {
            let t = refract(d, n, 1.5).unwrap();
            // Snell: n_i sin θi = n_t sin θt.
            assert!((1.5 * a.sin() - t.x / t.length()).abs() < 1e-5);
        }
    }
}

#[test]
fn schlick_matches_f0_at_normal_incidence_and_one_at_grazing() {
    let f0 = Vec3::new(0.9, 0.6, 0.3);
    assert!((fresnel_schlick(f0, 1.0) - f0).length() < 1e-6);
    assert!((fresnel_schlick(f0, 0.0) - Vec3::ONE).length() < 1e-6);
}

#[test]
fn glass_slab_shifts_a_ray_laterally_by_the_closed_form_amount() {
    let (thickness, n, theta_i) = (0.1f32, 1.5f32, 40.0f32.to_radians());
    let slab = generators::cuboid(Vec3::new(2.0, 2.0, thickness));
    let scene = one_mesh_scene(slab, Material::glass("glass", n), Mat4::IDENTITY);
    let start = Vec3::new(-0.5 * theta_i.tan(), 0.0, 0.5);
    let ray = Ray {
        origin: start,
        dir: Vec3::new(theta_i.sin(), 0.0, -theta_i.cos()),
    };
    let path = follow(&scene, ray, 2);
    assert_eq!(path.len(), 3);
    let exit = path[2];
    assert!(
        (exit.dir - ray.dir).length() < 1e-5,
        "exit direction {:?} parallel to entry",
        exit.dir
    );
    // Perpendicular distance between the entry line and the exit line.
    let offset = exit.origin - start;
    let shift = (offset - offset.dot(ray.dir) * ray.dir).length();
    let theta_t = (theta_i.sin() / n).asin();
    let expected = thickness * (theta_i - theta_t).sin() / theta_t.cos();
    assert!(
        (shift - expected).abs() < 1e-4,
        "shift {shift} vs {expected}"
    );
}

#[test]
fn plano_convex_lens_focuses_at_its_back_focal_length() {
    let (radius, thickness, n) = (0.1f32, 0.005f32, 1.5f32);
    let spec = LensSpec {
        front_radius: radius,
        back_radius: f32::INFINITY,
        center_thickness: thickness,
        diameter: 0.04,
        rings: 64,
        segments: 128,
    };
    let scene = one_mesh_scene(
        generators::lens(&spec).unwrap(),
        Material::glass("glass", n),
        Mat4::IDENTITY,
    );
    // Thick-lens formula with a flat back: f = R / (n − 1); BFL = f − t (n − 1) f / (n R).
    let f = radius / (n - 1.0);
    let bfl = f - thickness * (n - 1.0) * f / (n * radius);
    for h in [0.0005f32, 0.001, -0.0007] {
        let ray = Ray {
            origin: Vec3::new(h, 0.0, -0.05),
            dir: Vec3::Z,
        };
        let path = follow(&scene, ray, 2);
        assert_eq!(path.len(), 3);
        let focus = axis_crossing(&path[2]) - thickness;
        assert!(
            (focus - bfl).abs() / bfl < 0.01,
            "ray at h = {h}: focus {focus} m vs BFL {bfl} m"
        );
    }
}

#[test]
fn concave_mirror_images_a_point_by_the_mirror_equation() {
    let r = 1.0f32;
    let cap = generators::spherical_cap(r, 0.2, true, 64, 128).unwrap();
    let scene = one_mesh_scene(cap, Material::mirror("mirror", Vec3::ONE), Mat4::IDENTITY);
    // 1/s + 1/s' = 2/R with the source on the axis at s = 3 R.
    let s = 3.0 * r;
    let expected = 1.0 / (2.0 / r - 1.0 / s);
    for h in [0.002f32, 0.004] {
        let source = Vec3::new(0.0, 0.0, s);
        let target = Vec3::new(h, 0.0, 0.0);
        let ray = Ray {
            origin: source,
            dir: (target - source).normalize(),
        };
        let path = follow(&scene, ray, 1);
        assert_eq!(path.len(), 2);
        let image = axis_crossing(&path[1]);
        assert!(
            (image - expected).abs() / expected < 0.01,
            "image at {image} vs {expected}"
        );
    }
}

#[test]
fn a_thin_sheet_sums_each_polarisation_s_two_faces_apart() {
    // n = 1.5: the sheet reflects ½ [2R_s / (1 + R_s) + 2R_p / (1 + R_p)]; 2R / (1 + R) of the
    // mean R is 0.68 % high at 31°, 3.3 % at 45°, 7.8 % at 60° (the figures).
    for (deg, high) in [(31.0f64, 0.0068), (45.0, 0.0326), (60.0, 0.0783)] {
        let cos_i = deg.to_radians().cos();
        let sin_t = deg.to_radians().sin() / 1.5;
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let rs = ((cos_i - 1.5 * cos_t) / (cos_i + 1.5 * cos_t)).powi(2);
        let rp = ((1.5 * cos_i - cos_t) / (1.5 * cos_i + cos_t)).powi(2);
        let sheet = 0.5 * (2.0 * rs / (1.0 + rs) + 2.0 * rp / (1.0 + rp));
        let traced = f64::from(thin_sheet_reflectance(cos_i as f32, 1.5));
        assert!(
            (traced - sheet).abs() < 1e-6,
            "{deg}°: {traced} against {sheet}"
        );
        let (s, p) = fresnel_dielectric_sp(cos_i as f32, 1.0 / 1.5);
        assert!((f64::from(s) - rs).abs() < 1e-6 && (f64::from(p) - rp).abs() < 1e-6);
        let mean = 0.5 * (rs + rp);
        let old = 2.0 * mean / (1.0 + mean);
        assert!(
            (old / sheet - 1.0 - high).abs() < 1e-4,
            "{deg}°: {}",
            old / sheet - 1.0
        );
    }
}
