//! The continuous 3-ray camera of c3rc against closed forms and brute force (no GPU).

use glam::DVec3;
use proptest::prelude::*;
use specula_methods::c3rc::camera::{real_roots, C3rc};
use specula_methods::c3rc::points::{PointCloud, TreeLimits};

/// A camera whose rays spread (`spread` > 0) or converge (< 0) from a triangle in z = 0,
/// with a twist that tilts the sweeping triangle.
fn camera(spread: f64, twist: f64) -> C3rc {
    let v = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];
    let centre = (v[0] + v[1] + v[2]) / 3.0;
    let d = std::array::from_fn(|i| {
        let out = v[i] - centre;
        (DVec3::Z + out * spread + DVec3::new(-out.y, out.x, 0.0) * twist).normalize()
    });
    C3rc { v, d }
}

/// Rays that converge (towards a point 0.67 above the base) with two of them tilted
/// sideways: they cross each other's sweeping plane between λ ≈ 0.66 and 0.90.
fn crossing_camera() -> C3rc {
    let v = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];
    let centre = (v[0] + v[1] + v[2]) / 3.0;
    let tilt = [
        DVec3::new(-2.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::ZERO,
    ];
    let d = std::array::from_fn(|i| (DVec3::Z - (v[i] - centre) * 1.5 + tilt[i]).normalize());
    C3rc { v, d }
}

/// The point of the camera's interpolated ray at barycentric `b` and sweep `lambda`.
fn point_at(c: &C3rc, b: [f64; 3], lambda: f64) -> DVec3 {
    (0..3).map(|i| c.sweep_vertex(i, lambda) * b[i]).sum()
}

#[test]
fn roots_of_known_polynomials() {
    // (x − 1)(x − 2)(x − 3) = x³ − 6x² + 11x − 6.
    let (r, n) = real_roots([-6.0, 11.0, -6.0, 1.0]);
    assert_eq!(n, 3);
    for (got, want) in r.iter().zip([1.0, 2.0, 3.0]) {
        assert!((got - want).abs() < 1e-12, "{r:?}");
    }
    // (x − 0.5)(x² + 1): one real root.
    let (r, n) = real_roots([-0.5, 1.0, -0.5, 1.0]);
    assert_eq!(n, 1);
    assert!((r[0] - 0.5).abs() < 1e-12);
    // A quadratic and a line.
    let (r, n) = real_roots([2.0, -3.0, 1.0, 0.0]);
    assert_eq!(n, 2);
    assert!(
        (r[0] - 1.0).abs() < 1e-12 && (r[1] - 2.0).abs() < 1e-12,
        "{r:?}"
    );
    let (r, n) = real_roots([4.0, -2.0, 0.0, 0.0]);
    assert_eq!(n, 1);
    assert!((r[0] - 2.0).abs() < 1e-12);
}

#[test]
fn a_point_on_a_construction_ray_projects_to_that_rays_vertex() {
    for c in [camera(0.3, 0.0), camera(-0.4, 0.2), camera(0.8, -0.5)] {
        for i in 0..3 {
            for lambda in [0.0, 0.1, 0.7, 2.5] {
                let q = c.sweep_vertex(i, lambda);
                let (projections, count) = c.project(q, false);
                let hit = projections[..count]
                    .iter()
                    .find(|p| (p.lambda - lambda).abs() < 1e-6)
                    .unwrap_or_else(|| panic!("ray {i} at {lambda}: {projections:?}"));
                for (k, b) in hit.bary.iter().enumerate() {
                    let want = if k == i { 1.0 } else { 0.0 };
                    assert!(
                        (b - want).abs() < 1e-6,
                        "ray {i} at {lambda}: {:?}",
                        hit.bary
                    );
                }
                assert!((hit.base_point(&c) - c.v[i]).length() < 1e-6);
            }
        }
    }
}

#[test]
fn projection_is_continuous_across_an_edge_two_cameras_share() {
    // Two reflector triangles of a curved mirror share the edge v1–v2; their cameras share
    // its two rays.
    let eye = DVec3::new(0.2, 0.3, 3.0);
    let surface = |x: f64, y: f64| DVec3::new(x, y, -0.3 * (x * x + y * y));
    let normal = |x: f64, y: f64| DVec3::new(0.6 * x, 0.6 * y, 1.0).normalize();
    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
    let v = corners.map(|(x, y)| surface(x, y));
    let n = corners.map(|(x, y)| normal(x, y));
    let a = C3rc::reflector([v[0], v[1], v[2]], [n[0], n[1], n[2]], eye);
    let b = C3rc::reflector([v[3], v[2], v[1]], [n[3], n[2], n[1]], eye);
    // Points along a path crossing the shared wall: the base point moves continuously.
    let on_wall = |s: f64, lambda: f64| {
        a.v[1] * (1.0 - s) + a.v[2] * s + (a.d[1] * (1.0 - s) + a.d[2] * s) * lambda
    };
    let across = (a.v[3 - 3] - (a.v[1] + a.v[2]) * 0.5).normalize() * -1.0;
    for s in [0.2, 0.5, 0.8] {
        for lambda in [0.3, 1.0, 2.0] {
            let mut last: Option<DVec3> = None;
            for step in -20..=20 {
                let q = on_wall(s, lambda) + across * (step as f64 * 1e-4);
                let found: Vec<DVec3> = [&a, &b]
                    .iter()
                    .flat_map(|c| {
                        let (p, k) = c.project(q, false);
                        p[..k].iter().map(|p| p.base_point(c)).collect::<Vec<_>>()
                    })
                    .collect();
                assert!(
                    !found.is_empty(),
                    "s {s}, λ {lambda}, step {step}: no projection"
                );
                let here = found[0];
                if let Some(prev) = last {
                    let jump = (here - prev).length();
                    assert!(
                        jump < 1e-3,
                        "s {s}, λ {lambda}, step {step}: base point jumps {jump}"
                    );
                }
                last = Some(here);
            }
        }
    }
}

#[test]
fn a_configuration_with_two_valid_projections_yields_both() {
    // Rays that converge and cross with a twist: the sweeping triangle turns over and cuts
    // its earlier positions (the paper's Figure 4). Search its view volume for points with two
    // projections, and check each against brute force: the camera's own interpolated rays,
    // sampled densely over the base, pass through the point exactly where the cubic says.
    let c = crossing_camera();
    let intervals = c.multiple_projection_intervals();
    assert!(
        !intervals.is_empty(),
        "this camera's rays cross its sweeping plane"
    );
    let mut found = 0;
    for k in 0..4000 {
        let f = |s: u64| ((k * 7919 + s * 104729) % 1000) as f64 / 1000.0;
        let (mut b1, mut b2) = (f(1), f(2));
        if b1 + b2 > 1.0 {
            (b1, b2) = (1.0 - b1, 1.0 - b2);
        }
        let q = point_at(&c, [b1, b2, 1.0 - b1 - b2], 3.0 * f(3));
        let (projections, count) = c.project(q, false);
        if count < 2 {
            continue;
        }
        found += 1;
        // Multiple projections need the sweeping triangle to turn over: one of them lies
        // where the construction rays are not all on one side.
        let inside = |l: f64| {
            intervals
                .iter()
                .any(|&(lo, hi)| l >= lo - 1e-6 && l <= hi + 1e-6)
        };
        assert!(
            projections[..count].iter().any(|p| inside(p.lambda)),
            "{projections:?} outside {intervals:?}"
        );
        for p in &projections[..count] {
            // The interpolated ray through this base point passes through q at λ.
            let back = point_at(&c, p.bary, p.lambda);
            assert!((back - q).length() < 1e-7, "{p:?}: {back} vs {q}");
            assert!(p.bary.iter().all(|b| (-1e-9..=1.0 + 1e-9).contains(b)));
        }
        // Brute force over the base, independent of the cubic: from a grid of starting
        // points, Newton's method on Σ bᵢ (vᵢ + λ dᵢ) = q converges to every solution; the
        // distinct ones inside the base are the projections.
        let mut solutions: Vec<[f64; 3]> = Vec::new();
        let n = 24;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (mut b1, mut b2, mut lambda) = (i as f64 / n as f64, j as f64 / n as f64, 1.0);
                for _ in 0..60 {
                    let b = [b1, b2, 1.0 - b1 - b2];
                    let residual = point_at(&c, b, lambda) - q;
                    let w: Vec<DVec3> = (0..3).map(|k| c.sweep_vertex(k, lambda)).collect();
                    let jacobian = glam::DMat3::from_cols(
                        w[0] - w[2],
                        w[1] - w[2],
                        c.d[0] * b[0] + c.d[1] * b[1] + c.d[2] * b[2],
                    );
                    if jacobian.determinant().abs() < 1e-14 {
                        break;
                    }
                    let step = jacobian.inverse() * residual;
                    (b1, b2, lambda) = (b1 - step.x, b2 - step.y, lambda - step.z);
                }
                let b = [b1, b2, 1.0 - b1 - b2];
                let converged = (point_at(&c, b, lambda) - q).length() < 1e-10;
                let inside = b.iter().all(|x| (-1e-9..=1.0 + 1e-9).contains(x)) && lambda >= 0.0;
                if converged
                    && inside
                    && !solutions
                        .iter()
                        .any(|s| (s[0] - b1).abs() + (s[1] - b2).abs() < 1e-6)
                {
                    solutions.push([b1, b2, lambda]);
                }
            }
        }
        assert_eq!(
            solutions.len(),
            count,
            "q {q}: Newton {solutions:?}, cubic {projections:?}"
        );
        for p in &projections[..count] {
            assert!(
                solutions
                    .iter()
                    .any(
                        |s| (s[0] - p.bary[0]).abs() + (s[1] - p.bary[1]).abs() < 1e-6
                            && (s[2] - p.lambda).abs() < 1e-6
                    ),
                "{p:?} not among {solutions:?}"
            );
        }
        if found >= 5 {
            break;
        }
    }
    assert!(found >= 5, "points with two projections found: {found}");
    // A spreading camera never projects a point twice.
    assert!(camera(0.5, 0.0).multiple_projection_intervals().is_empty());
}

fn arbitrary_camera() -> impl Strategy<Value = C3rc> {
    (
        prop::array::uniform3(prop::array::uniform3(-1.0f64..1.0)),
        prop::array::uniform3(prop::array::uniform3(-0.8f64..0.8)),
        -2.0f64..2.0,
    )
        .prop_filter_map("degenerate base", |(v, jitter, spread)| {
            let v = v.map(DVec3::from_array);
            let normal = (v[1] - v[0]).cross(v[2] - v[0]);
            if normal.length() < 0.05 {
                return None;
            }
            let centre = (v[0] + v[1] + v[2]) / 3.0;
            let up = normal.normalize();
            let d = std::array::from_fn(|i| {
                (up + (v[i] - centre) * spread + DVec3::from_array(jitter[i])).normalize()
            });
            Some(C3rc { v, d })
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// The box test never culls a box holding a point of the view volume: a point is drawn
    /// inside the volume and a box placed around it (often a small box inside one face's
    /// span, or a box containing the base: the cases the paper's two conditions miss).
    #[test]
    fn the_box_test_never_culls_a_box_holding_a_visible_point(
        c in arbitrary_camera(),
        b in prop::array::uniform2(0.0f64..1.0),
        lambda in 0.0f64..4.0,
        below in prop::array::uniform3(0.0f64..1.0),
        above in prop::array::uniform3(0.0f64..1.0),
        scale in prop::sample::select(vec![1e-3, 0.05, 0.5, 3.0]),
    ) {
        let (mut b1, mut b2) = (b[0], b[1]);
        if b1 + b2 > 1.0 {
            (b1, b2) = (1.0 - b1, 1.0 - b2);
        }
        let q = point_at(&c, [b1, b2, 1.0 - b1 - b2], lambda);
        prop_assert!(c.contains(q), "the drawn point is in the volume");
        let lo = q - DVec3::from_array(below) * scale;
        let hi = q + DVec3::from_array(above) * scale;
        prop_assert!(c.may_see_box(lo, hi, &c.fold_boxes(&c.multiple_projection_intervals(), c.lambda_bound(lo, hi))), "culled a box around {q}: [{lo}, {hi}]");
    }

    /// Against brute force on arbitrary boxes: if any of a grid of points in the box has a
    /// valid projection, the box is kept.
    #[test]
    fn the_box_test_agrees_with_brute_force(
        c in arbitrary_camera(),
        lo in prop::array::uniform3(-3.0f64..3.0),
        size in prop::array::uniform3(0.01f64..2.0),
    ) {
        let lo = DVec3::from_array(lo);
        let hi = lo + DVec3::from_array(size);
        let n = 6;
        let mut visible = false;
        'grid: for i in 0..=n {
            for j in 0..=n {
                for k in 0..=n {
                    let t = DVec3::new(i as f64, j as f64, k as f64) / n as f64;
                    if c.contains(lo + (hi - lo) * t) {
                        visible = true;
                        break 'grid;
                    }
                }
            }
        }
        if visible {
            prop_assert!(c.may_see_box(lo, hi, &c.fold_boxes(&c.multiple_projection_intervals(), c.lambda_bound(lo, hi))), "culled [{lo}, {hi}]");
        }
    }
}

#[test]
fn the_box_test_culls_boxes_far_from_the_volume() {
    // Conservative, but not trivially so: boxes behind the base or off to the side go.
    let c = camera(0.2, 0.0);
    assert!(c.multiple_projection_intervals().is_empty());
    assert!(!c.may_see_box(
        DVec3::new(-1.0, -1.0, -3.0),
        DVec3::new(2.0, 2.0, -0.5),
        &[]
    ));
    assert!(!c.may_see_box(DVec3::new(5.0, 5.0, 0.5), DVec3::new(6.0, 6.0, 1.0), &[]));
    assert!(c.may_see_box(DVec3::new(0.1, 0.1, 1.0), DVec3::new(0.2, 0.2, 1.1), &[]));
    // A box that holds the whole base triangle (an arc inside one face).
    assert!(c.may_see_box(DVec3::splat(-0.5), DVec3::splat(1.5), &[]));
}

#[test]
fn the_papers_box_test_keeps_boxes_a_narrow_volume_passes_through_and_misses_a_straddling_one() {
    let c = camera(0.2, 0.0);
    let kept_by_both = |lo: DVec3, hi: DVec3| {
        c.corner_inside_or_face_meets_wall(lo, hi) && c.may_see_box(lo, hi, &[])
    };
    // The volume (a prism over the base) passes through a large box from one face to the
    // opposite one: no wall crosses a box edge and no corner is inside, but the walls' arcs lie
    // inside the faces (condition 2 of §5.2).
    assert!(kept_by_both(
        DVec3::new(-1.0, -1.0, 2.0),
        DVec3::new(2.0, 2.0, 3.0)
    ));
    // A box that straddles the base's inside, with its tested corner (`lo`) behind the base:
    // the paper's conditions cull it, the conservative test keeps it.
    let (lo, hi) = (DVec3::new(0.2, 0.2, -0.1), DVec3::new(0.3, 0.3, 0.1));
    assert!(
        c.contains(DVec3::new(0.25, 0.25, 0.05)),
        "the box holds a visible point"
    );
    assert!(!c.corner_inside_or_face_meets_wall(lo, hi));
    assert!(c.may_see_box(lo, hi, &[]));
}

proptest! {
    /// The paper's test keeps no box the conservative test culls: the conservative one only adds.
    #[test]
    fn the_conservative_box_test_keeps_every_box_the_papers_keeps(
        c in arbitrary_camera(),
        lo in prop::array::uniform3(-3.0f64..3.0),
        size in prop::array::uniform3(0.01f64..2.0),
    ) {
        let lo = DVec3::from_array(lo);
        let hi = lo + DVec3::from_array(size);
        if c.corner_inside_or_face_meets_wall(lo, hi) {
            prop_assert!(c.may_see_box(lo, hi, &c.fold_boxes(&c.multiple_projection_intervals(), c.lambda_bound(lo, hi))));
        }
    }
}

#[test]
fn the_eight_way_tree_holds_every_point_once_within_its_boxes() {
    let mesh = specula_scene::generators::sphere(1.0, 64, 32);
    let limits = TreeLimits {
        leaf_points: 64,
        max_depth: 12,
    };
    let cloud = PointCloud::sample(0, &mesh, glam::Mat4::IDENTITY, 2000.0, 1.0, limits);
    cloud.validate().unwrap();
    let area = 4.0 * std::f32::consts::PI;
    let expected = area * 2000.0;
    assert!(
        (cloud.len() as f32 - expected).abs() < 0.03 * expected,
        "{} points for {expected}",
        cloud.len()
    );
    assert!(cloud.stats.points_per_leaf <= 64.0 && cloud.stats.points_per_leaf > 8.0);
    assert!(cloud.stats.average_depth > 1.0);
    // Points lie on the sphere, normals point out.
    for (p, n) in cloud.p_object.iter().zip(&cloud.n_object) {
        assert!((p.length() - 1.0).abs() < 5e-3, "{p}");
        assert!(n.dot(*p) > 0.99);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// The plane bound and the affine cubic agree with the camera: a point of the volume is
    /// inside the planes, and the precomputed cubic equals the direct one.
    #[test]
    fn the_plane_bound_holds_the_volume_and_the_affine_cubic_is_the_cubic(
        c in arbitrary_camera(),
        b in prop::array::uniform2(0.0f64..1.0),
        lambda in 0.0f64..4.0,
        q in prop::array::uniform3(-3.0f64..3.0),
    ) {
        let (mut b1, mut b2) = (b[0], b[1]);
        if b1 + b2 > 1.0 {
            (b1, b2) = (1.0 - b1, 1.0 - b2);
        }
        let inside = point_at(&c, [b1, b2, 1.0 - b1 - b2], lambda);
        prop_assert!(c.plane_bound().may_contain(inside));
        prop_assert!(c.plane_bound().may_meet_box(inside, inside));
        let q = DVec3::from_array(q);
        let (direct, affine) = (c.projection_cubic(q), c.projector().cubic(q));
        for k in 0..4 {
            prop_assert!((direct[k] - affine[k]).abs() <= 1e-9 * (1.0 + direct[k].abs()), "{direct:?} vs {affine:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// The normal-cone test never skips a node with a point facing some point of the sphere.
    #[test]
    fn the_normal_cone_test_never_skips_a_node_facing_the_sphere(
        centre in prop::array::uniform3(-3.0f32..3.0),
        radius in 0.01f32..1.0,
        seed in 0u32..1000,
    ) {
        // A patch of a sphere: nodes with narrow and wide normal cones.
        let mesh = specula_scene::generators::sphere(1.0, 16, 8);
        let limits = TreeLimits { leaf_points: 32, max_depth: 6 };
        let cloud = PointCloud::sample(seed as usize, &mesh, glam::Mat4::IDENTITY, 300.0, 1.0, limits);
        let centre = glam::Vec3::from_array(centre);
        // Points on and inside the sphere (its centre and six poles).
        let targets: Vec<glam::Vec3> = [glam::Vec3::ZERO, glam::Vec3::X, -glam::Vec3::X, glam::Vec3::Y, -glam::Vec3::Y, glam::Vec3::Z, -glam::Vec3::Z]
            .iter()
            .map(|d| centre + *d * radius)
            .collect();
        for node in cloud.nodes.iter().filter(|n| n.leaf) {
            if node.may_face(centre, radius) {
                continue;
            }
            for i in node.first as usize..(node.first + node.count) as usize {
                for t in &targets {
                    let facing = cloud.n_object[i].dot(*t - cloud.p_object[i]);
                    prop_assert!(facing <= 1e-4, "skipped a point facing {t}: {facing}");
                }
            }
        }
    }
}
