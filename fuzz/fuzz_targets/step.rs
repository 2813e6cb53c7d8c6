//! STEP (ISO 10303-21) text: a clear error or bodies, never a panic. A coarse chord tolerance
//! keeps each input's tessellation short, so that the fuzzer spends its time on the reader.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let options = specula_scene::loaders::step::StepOptions {
        tolerance_mm: 5.0,
        ..Default::default()
    };
    let _ = specula_scene::loaders::step::parse("fuzz.step", text, &options);
});
