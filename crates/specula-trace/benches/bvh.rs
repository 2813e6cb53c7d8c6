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
}

criterion_group!(benches, bench);
criterion_main!(benches);
