//! What the loader tests share: writing a file, the error a file gives, and checking that an
//! error message names what it should.

use std::path::{Path, PathBuf};

use specula_scene::load;

pub fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

pub fn error_of(path: &Path) -> String {
    match load(path.to_str().unwrap()) {
        Ok(_) => panic!("{} loaded but should not have", path.display()),
        Err(e) => e.to_string(),
    }
}

pub fn assert_mentions(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(
            message.contains(part),
            "error message {message:?} should mention {part:?}"
        );
    }
}

pub const TOML_SCENE: &str = r#"
name = "all shapes"
ambient = 0.1
[camera]
eye = [0, 1, 4]
target = [0, 0, 0]
fov_y_deg = 40
[background]
color = [0.1, 0.2, 0.3]
[materials.grey]
type = "diffuse"
color = 0.5
[materials.chrome]
type = "mirror"
color = [0.9, 0.9, 0.9]
fresnel = false
[materials.flint]
type = "dielectric"
ior = 1.6
abbe = 36
[[lights]]
type = "point"
position = [0, 3, 0]
intensity = 5
[[lights]]
type = "spot"
position = [0, 3, 0]
direction = [0, -1, 0]
intensity = [5, 5, 5]
inner_cone_deg = 10
outer_cone_deg = 20
[[objects]]
material = "grey"
shape = { type = "plane", size = [4, 4], subdivisions = 2 }
[[objects]]
material = "chrome"
translate = [1, 0.5, 0]
shape = { type = "sphere", radius = 0.5 }
[[objects]]
material = "chrome"
rotate_deg = [0, 90, 0]
shape = { type = "cap", radius_of_curvature = 1.0, aperture = 0.5, concave = true }
[[objects]]
material = "chrome"
shape = { type = "patch" }
[[objects]]
material = "flint"
translate = [0, 1, 1]
shape = { type = "lens", front_radius = 0.2, back_radius = -0.2, center_thickness = 0.02, diameter = 0.1 }
[[objects]]
material = "flint"
shape = { type = "lens", front_radius = inf, back_radius = -0.3, center_thickness = 0.01, diameter = 0.1 }
[[objects]]
material = "grey"
scale = [1, 2, 1]
shape = { type = "box", size = [0.2, 0.2, 0.2] }
[[objects]]
material = "grey"
scale = 0.1
shape = { type = "teapot", resolution = 4 }
[[objects]]
material = "grey"
shape = { type = "mesh", file = "quad.obj", fit = 0.5 }
"#;
