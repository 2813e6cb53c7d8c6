//! OBJ (its MTL library looked up in a folder that does not exist).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("/nonexistent-specula-fuzz/fuzz.obj");
    if let Ok((meshes, ..)) = specula_scene::loaders::obj::load(path, data) {
        for mut mesh in meshes {
            if mesh.check_topology("fuzz.obj").is_ok() {
                let _ = mesh.validate("fuzz.obj");
                mesh.drop_degenerate_triangles();
            }
        }
    }
});
