//! TOML scene files (mesh files they name are looked up in a folder that does not exist).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let base = std::path::Path::new("/nonexistent-specula-fuzz");
        let _ = specula_scene::loaders::toml_scene::parse("fuzz.toml", text, base);
    }
});
