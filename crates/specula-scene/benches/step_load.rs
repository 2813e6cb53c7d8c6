//! Loading and tessellating a STEP file of 1,000 rational B-spline faces: a convex mirror of
//! radius 1,600 mm, 1,000 mm × 625 mm, cut into 40 × 25 faces that share their edges, in
//! millimetres, written by specula's STEP writer; read at the default chord tolerance
//! (0.05 mm). Parse, table, topology, tessellation and the face map, all of it.
//!
//!   cargo bench -p specula-scene --bench step_load

use criterion::{criterion_group, criterion_main, Criterion};
use specula_scene::loaders::step::examples;
use specula_scene::loaders::step::write::{NurbsPatch, StepWriter};
use specula_scene::loaders::step::{self, StepOptions};
use specula_scene::units::LengthUnit;

const RADIUS_MM: f64 = 1600.0;
const COLUMNS: usize = 40;
const ROWS: usize = 25;

fn thousand_faces() -> String {
    let half_width = (500.0 / RADIUS_MM).asin();
    let half_height = (312.5 / RADIUS_MM).asin();
    let mut writer = StepWriter::new();
    let mut faces = Vec::new();
    for i in 0..COLUMNS {
        let u0 = -half_width + 2.0 * half_width * i as f64 / COLUMNS as f64;
        let u1 = -half_width + 2.0 * half_width * (i + 1) as f64 / COLUMNS as f64;
        for j in 0..ROWS {
            let v0 = -half_height + 2.0 * half_height * j as f64 / ROWS as f64;
            let v1 = -half_height + 2.0 * half_height * (j + 1) as f64 / ROWS as f64;
            let patch = NurbsPatch::sphere_region(RADIUS_MM, (u0, u1), 1, (v0, v1))
                .map_points(examples::facing_z(RADIUS_MM));
            faces.push(writer.patch_face(&patch));
        }
    }
    writer.body("mirror", &faces, false);
    writer.finish(LengthUnit::Mm)
}

fn bench(c: &mut Criterion) {
    let text = thousand_faces();
    let file = step::parse("bench.step", &text, &StepOptions::default()).expect("the file loads");
    assert_eq!(file.faces, COLUMNS * ROWS);
    eprintln!(
        "{} faces, {} triangles, {} bytes of STEP",
        file.faces,
        file.meshes[0].triangles.len(),
        text.len()
    );
    let mut group = c.benchmark_group("step");
    group.sample_size(10);
    group.bench_function("load and tessellate 1,000 B-spline faces", |b| {
        b.iter(|| step::parse("bench.step", &text, &StepOptions::default()).expect("loads"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
