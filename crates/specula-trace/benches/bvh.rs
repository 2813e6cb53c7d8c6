//! BVH build time and primary-ray throughput on the Stanford dragon (`dragon_res2`, 202,520
//! triangles, from ../shared/meshes), single thread and all threads, on the same rays as the
//! Embree peer benchmark (shared/bench/embree_rays.py; see docs/benchmarks.md).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use rayon::prelude::*;
use specula_trace::primary_rays::embree_benchmark_rays;
use specula_trace::SceneAccel;

fn dragon_triangles() -> Option<Vec<[Vec3; 3]>> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/meshes/dragon_res2.obj.gz");
    if !path.exists() {
        eprintln!(
            "\n!!! SKIPPED: {} is absent; the BVH benchmark needs it !!!\n",
            path.display()
        );
        return None;
    }
    let (meshes, ..) = specula_scene::loaders::load_mesh_file(&path).expect("dragon loads");
    Some(
        meshes
            .iter()
            .flat_map(|m| {
                m.triangles
                    .iter()
                    .map(|t| t.map(|i| m.positions[i as usize]))
            })
            .collect(),
    )
}

fn bench(c: &mut Criterion) {
    let Some(triangles) = dragon_triangles() else {
        return;
    };
    let ids: Vec<(u32, u32)> = (0..triangles.len() as u32).map(|t| (0, t)).collect();
    let positions: Vec<Vec3> = triangles.iter().flatten().copied().collect();
    let rays = embree_benchmark_rays(&positions, 1024);

    let mut build = c.benchmark_group("bvh_build");
    build.sample_size(10);
    build.bench_function("dragon_res2", |b| {
        b.iter(|| SceneAccel::from_triangles(triangles.clone(), ids.clone()))
    });
    build.finish();

    let accel = SceneAccel::from_triangles(triangles.clone(), ids.clone());
    let hits = rays
        .iter()
        .filter(|r| accel.intersect(r, f32::INFINITY).is_some())
        .count();
    eprintln!(
        "dragon_res2: {} triangles, {} rays, hits {hits} (compare with Embree's count)",
        triangles.len(),
        rays.len()
    );

    let mut trace = c.benchmark_group("primary_rays");
    trace.sample_size(10);
    trace.throughput(Throughput::Elements(rays.len() as u64));
    trace.bench_function("single_thread", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| accel.intersect(r, f32::INFINITY).is_some())
                .count()
        })
    });
    trace.bench_function("all_threads", |b| {
        b.iter(|| {
            rays.par_iter()
                .filter(|r| accel.intersect(r, f32::INFINITY).is_some())
                .count()
        })
    });
    trace.finish();

    // A whole frame of the same rays as the reference renders it (the dragon unlit, the same
    // camera; directions equal to rounding), warm as the kernel above is: what a frame spends
    // beyond traversal.
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let centre = (lo + hi) / 2.0;
    let mut scene = specula_scene::Scene::new("dragon, unlit");
    scene
        .materials
        .push(specula_scene::Material::unlit("white", Vec3::ONE));
    scene.meshes.push(specula_scene::Mesh {
        name: "dragon".into(),
        positions: positions.clone(),
        triangles: (0..triangles.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect(),
        material: 0,
        ..Default::default()
    });
    scene.camera = specula_scene::Camera {
        eye: centre + Vec3::new(0.0, 0.0, 2.2 * (hi - lo).length() / 2.0),
        target: centre,
        up: Vec3::Y,
        fov_y_deg: 40.0,
        aspect: None,
    };
    let settings = specula_trace::reference::RenderSettings {
        width: 1024,
        height: 1024,
        spp: 1,
        max_depth: 8,
    };
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool");
    let mut frame = c.benchmark_group("reference_frame");
    frame.sample_size(10);
    frame.throughput(Throughput::Elements(rays.len() as u64));
    frame.bench_function("single_thread", |b| {
        b.iter(|| {
            one_thread
                .install(|| specula_trace::reference::render(&scene, &accel, &settings, &|_, _| {}))
        })
    });
    frame.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
