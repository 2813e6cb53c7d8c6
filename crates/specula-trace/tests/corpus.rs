//! A public corpus of real and deliberately malformed files (Debian's `assimp-testmodels`:
//! glTF, glTF2, OBJ, PLY and STL folders under /usr/share/assimp/models): every file ends in an
//! image (finite pixels) or a clear error naming the file, never a panic. Runs where the corpus
//! is installed (scripts/setup.sh installs it); a missing corpus fails the test unless the runner
//! opts out with `SPECULA_ALLOW_SKIP=corpus`.

use std::path::{Path, PathBuf};

use specula_trace::{render, RenderSettings, SceneAccel};

const CORPUS: &str = "/usr/share/assimp/models";
const FOLDERS: [&str; 5] = ["glTF", "glTF2", "OBJ", "PLY", "STL"];
const EXTENSIONS: [&str; 5] = ["gltf", "glb", "obj", "ply", "stl"];

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            files(&path, out);
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| EXTENSIONS.contains(&e.to_lowercase().as_str()))
        {
            out.push(path);
        }
    }
}

#[test]
fn every_corpus_file_renders_or_gives_a_clear_error() {
    if !Path::new(CORPUS).is_dir() {
        specula_testkit::missing(
            specula_testkit::Requirement::Corpus,
            "corpus test",
            &format!("{CORPUS} is not a folder"),
        );
        return;
    }
    let mut paths = Vec::new();
    for folder in FOLDERS {
        files(&Path::new(CORPUS).join(folder), &mut paths);
    }
    paths.sort();
    assert!(paths.len() > 50, "only {} corpus files found", paths.len());
    let (mut rendered, mut refused, mut failures) = (0, 0, Vec::new());
    for path in &paths {
        let shown = path.display().to_string();
        let outcome = std::panic::catch_unwind(|| match specula_scene::load(&shown) {
            Ok(scene) => {
                let accel = SceneAccel::new(&scene);
                let settings = RenderSettings {
                    width: 16,
                    height: 12,
                    spp: 1,
                    max_depth: 4,
                };
                let image = render(&scene, &accel, &settings, &|_, _| {});
                match image.pixels.iter().all(|p| p.is_finite()) {
                    true => Ok(true),
                    false => Err("non-finite pixels".to_string()),
                }
            }
            Err(e) => {
                let message = e.to_string();
                // Clear: names the file, one sentence, no parser's debug dump.
                let clear =
                    message.contains(&shown) && !message.contains(" { ") && !message.contains('\t');
                match clear {
                    true => Ok(false),
                    false => Err(format!("unclear error: {message}")),
                }
            }
        });
        match outcome {
            Ok(Ok(true)) => rendered += 1,
            Ok(Ok(false)) => refused += 1,
            Ok(Err(problem)) => failures.push(format!("{shown}: {problem}")),
            Err(_) => failures.push(format!("{shown}: panicked")),
        }
    }
    eprintln!(
        "corpus: {} files, {rendered} rendered, {refused} refused with a clear error",
        paths.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
