//! PLY, ASCII or binary.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let mut warnings = Vec::new();
    if let Ok(mut mesh) = specula_scene::loaders::ply::parse("fuzz.ply", data, &mut warnings) {
        if mesh.check_topology("fuzz.ply").is_ok() {
            let _ = mesh.validate("fuzz.ply");
            mesh.drop_degenerate_triangles();
        }
    }
});
