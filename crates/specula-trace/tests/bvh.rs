//! BVH invariants on awkward inputs, and closest/any-hit queries against brute force.

use glam::Vec3;
use proptest::prelude::*;
use specula_scene::Aabb;
use specula_trace::{Bvh, Ray, SceneAccel};

fn boxes(triangles: &[[Vec3; 3]]) -> Vec<Aabb> {
    triangles
        .iter()
        .map(|t| {
            let mut b = Aabb::EMPTY;
            t.iter().for_each(|&p| b.grow(p));
            b
        })
        .collect()
}

/// The accelerator, with both of its trees checked: the binary one and the 8-wide one
/// collapsed from it (against the triangles in leaf order).
fn accel(triangles: &[[Vec3; 3]]) -> SceneAccel {
    let ids = (0..triangles.len() as u32).map(|i| (0, i)).collect();
    let accel = SceneAccel::from_triangles(triangles.to_vec(), ids);
    accel
        .bvh
        .validate(&boxes(triangles))
        .unwrap_or_else(|e| panic!("invalid BVH: {e}"));
    let leaf_order: Vec<[Vec3; 3]> = accel.triangles.iter().map(|t| t.map(Vec3::from)).collect();
    accel
        .wide
        .validate(&boxes(&leaf_order))
        .unwrap_or_else(|e| panic!("invalid wide BVH: {e}"));
    accel
}

fn validated(triangles: &[[Vec3; 3]]) -> Bvh {
    let bounds = boxes(triangles);
    let bvh = Bvh::build(&bounds);
    bvh.validate(&bounds)
        .unwrap_or_else(|e| panic!("invalid BVH: {e}"));
    bvh
}

/// Brute-force closest hit, with the same intersection routine as the BVH path (a one-triangle
/// accelerator per triangle).
fn brute_force(triangles: &[[Vec3; 3]], ray: &Ray) -> Option<(f32, u32)> {
    triangles
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            accel(&[*t])
                .intersect(ray, f32::INFINITY)
                .map(|h| (h.t, i as u32))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

fn grid(n: usize, z: f32) -> Vec<[Vec3; 3]> {
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let p = |a: usize, b: usize| {
                Vec3::new(a as f32 / n as f32 - 0.5, b as f32 / n as f32 - 0.5, z)
            };
            tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    tris
}

#[test]
fn empty_input_gives_a_valid_tree_that_is_never_hit() {
    validated(&[]);
    let ray = Ray {
        origin: Vec3::ZERO,
        dir: Vec3::Z,
    };
    assert!(accel(&[]).intersect(&ray, f32::INFINITY).is_none());
    assert!(!accel(&[]).occluded(&ray, f32::INFINITY));
}

#[test]
fn single_triangle() {
    let tri = [[
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ]];
    let bvh = validated(&tri);
    assert_eq!(bvh.nodes.len(), 1);
    let hit = accel(&tri)
        .intersect(
            &Ray {
                origin: Vec3::new(0.0, 0.0, 2.0),
                dir: -Vec3::Z,
            },
            f32::INFINITY,
        )
        .expect("hit");
    assert!((hit.t - 2.0).abs() < 1e-6);
}

#[test]
fn degenerate_triangles_are_valid_and_never_hit() {
    let tris = vec![
        [Vec3::ZERO, Vec3::ZERO, Vec3::ZERO],
        [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        [Vec3::Y, Vec3::Y, Vec3::Z],
    ];
    validated(&tris);
    let a = accel(&tris);
    for dir in [Vec3::X, -Vec3::Z, Vec3::new(1.0, 1.0, 1.0).normalize()] {
        assert!(a
            .intersect(
                &Ray {
                    origin: Vec3::new(0.5, 0.0, 1.0),
                    dir
                },
                f32::INFINITY
            )
            .is_none());
    }
}

fn spread_triangles(s: f32) -> Vec<[Vec3; 3]> {
    (0..50)
        .map(|i| {
            let o = Vec3::new(i as f32 * s, 0.0, -s);
            [o, o + Vec3::new(s, 0.0, 0.0), o + Vec3::new(0.0, s, 0.0)]
        })
        .collect()
}

#[test]
fn huge_coordinates() {
    // Surface areas overflow to infinity at this scale: the build must still be valid.
    validated(&spread_triangles(1e30));
    accel(&spread_triangles(1e30));
    // Queries stay exact at geographic scales (10,000 km in metres); the watertight test's
    // products overflow f32 far beyond that (around 1e12), which no scene here approaches.
    let s = 1e7f32;
    let tris = spread_triangles(s);
    validated(&tris);
    let ray = Ray {
        origin: Vec3::new(10.2 * s, 0.3 * s, 0.0),
        dir: -Vec3::Z,
    };
    let hit = accel(&tris).intersect(&ray, f32::INFINITY).expect("hit");
    assert_eq!(hit.triangle, 10);
    assert!((hit.t - s).abs() <= s * 1e-6);
}

#[test]
fn coplanar_triangles_and_coincident_centroids() {
    validated(&grid(16, 0.0));
    accel(&grid(16, 0.0));
    // Many copies of one triangle: every centroid is the same point.
    let copies = vec![[Vec3::ZERO, Vec3::X, Vec3::Y]; 100];
    accel(&copies);
    let bvh = validated(&copies);
    assert!(bvh.depth() <= specula_trace::bvh::MAX_DEPTH);
}

#[test]
fn watertight_no_ray_slips_through_shared_edges_and_vertices() {
    let n = 8;
    let a = accel(&grid(n, 0.0));
    // Rays aimed exactly at every grid vertex and edge midpoint of a closed surface must hit.
    for j in 0..=2 * n {
        for i in 0..=2 * n {
            let target = Vec3::new(
                i as f32 / (2 * n) as f32 - 0.5,
                j as f32 / (2 * n) as f32 - 0.5,
                0.0,
            );
            if target.x.abs() >= 0.5 || target.y.abs() >= 0.5 {
                continue;
            }
            for origin in [Vec3::new(0.3, 0.7, 1.3), Vec3::new(-0.9, 0.1, 0.7)] {
                let ray = Ray {
                    origin,
                    dir: (target - origin).normalize(),
                };
                assert!(
                    a.intersect(&ray, f32::INFINITY).is_some(),
                    "ray to {target:?} from {origin:?} slipped through"
                );
            }
        }
    }
}

fn vec3(range: f32) -> impl Strategy<Value = Vec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn closest_and_any_hit_agree_with_brute_force(
        tris in prop::collection::vec((vec3(1.0), vec3(0.3), vec3(0.3)), 1..120),
        rays in prop::collection::vec((vec3(2.0), vec3(1.0)), 1..24),
    ) {
        let triangles: Vec<[Vec3; 3]> = tris.iter().map(|&(c, a, b)| [c, c + a, c + b]).collect();
        validated(&triangles);
        let a = accel(&triangles);
        for &(origin, dir) in &rays {
            let Some(dir) = dir.try_normalize() else { continue };
            let ray = Ray { origin, dir };
            let got = a.intersect(&ray, f32::INFINITY);
            let want = brute_force(&triangles, &ray);
            prop_assert_eq!(got.is_some(), want.is_some());
            if let (Some(got), Some((t, _))) = (got, want) {
                prop_assert!((got.t - t).abs() <= 1e-5 * t.max(1.0), "t {} vs brute force {}", got.t, t);
            }
            prop_assert_eq!(a.occluded(&ray, f32::INFINITY), want.is_some());
            if let Some((t, _)) = want {
                prop_assert!(!a.occluded(&ray, t * 0.999));
            }
        }
    }
}

#[test]
fn validators_catch_corrupted_trees() {
    let triangles = grid(8, 0.0);
    let bounds = boxes(&triangles);
    let mut bvh = Bvh::build(&bounds);
    bvh.nodes[1].max[0] -= 0.5;
    assert!(bvh
        .validate(&bounds)
        .unwrap_err()
        .contains("does not contain"));
    let mut bvh = Bvh::build(&bounds);
    bvh.primitives[0] = bvh.primitives[1];
    assert!(bvh.validate(&bounds).is_err());

    let mut a = accel(&triangles);
    let leaf_order: Vec<[Vec3; 3]> = a.triangles.iter().map(|t| t.map(Vec3::from)).collect();
    a.wide.nodes[0].max_x[0][0] -= 0.5;
    assert!(a
        .wide
        .validate(&boxes(&leaf_order))
        .unwrap_err()
        .contains("does not contain"));
}
