//! glTF / GLB from memory (embedded buffers only): a clear error or a scene, never a panic.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = specula_scene::loaders::gltf_file::load_slice("fuzz.gltf", data);
});
