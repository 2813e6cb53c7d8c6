//! STL, ASCII or binary.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(mut mesh) = specula_scene::loaders::stl::parse("fuzz.stl", data) {
        if mesh.check_topology("fuzz.stl").is_ok() {
            let _ = mesh.validate("fuzz.stl");
            mesh.drop_degenerate_triangles();
        }
    }
});
