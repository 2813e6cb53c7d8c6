//! Inputs the fuzzers (scripts/fuzz.sh) found crashing a loader, kept so each stays fixed:
//! every file in tests/fuzz_regressions/ must load or give an error naming it, without a panic.
//! The loader is chosen by the file's prefix (`gltf-`, `obj-`, `ply-`, `step-`, `stl-`, `toml-`).

use std::path::Path;

use specula_scene::loaders::{gltf_file, obj, ply, step, stl, toml_scene};

#[test]
fn every_fuzz_finding_is_an_error_or_a_scene_not_a_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let bytes = std::fs::read(&path).unwrap();
        let outcome = std::panic::catch_unwind(|| {
            let message = |e: specula_scene::SceneError| e.to_string();
            match name.split('-').next().unwrap() {
                "gltf" => gltf_file::load_slice(&name, &bytes)
                    .map(|_| ())
                    .map_err(message),
                "obj" => obj::load(&path, &bytes).map(|_| ()).map_err(message),
                "ply" => ply::parse(&name, &bytes, &mut Vec::new())
                    .map(|_| ())
                    .map_err(message),
                "stl" => stl::parse(&name, &bytes).map(|_| ()).map_err(message),
                "step" => step::parse(
                    &name,
                    &String::from_utf8_lossy(&bytes),
                    &step::StepOptions::default(),
                )
                .map(|_| ())
                .map_err(message),
                "toml" => toml_scene::parse(&name, &String::from_utf8_lossy(&bytes), &dir)
                    .map(|_| ())
                    .map_err(message),
                other => panic!("{name}: unknown loader prefix '{other}'"),
            }
        });
        match outcome {
            Ok(Ok(())) => {}
            // Not the loader's last-resort message for a panic it caught: the input must be
            // refused by a check.
            Ok(Err(message)) => assert!(
                message.contains(&name) && !message.contains("broke the"),
                "{name}: {message}"
            ),
            Err(_) => panic!("{name}: the loader panicked"),
        }
        count += 1;
    }
    assert!(count > 0, "no regression inputs in {}", dir.display());
}
