//! File loaders. Each turns one file format into a [`Scene`]; errors name the file and, where
//! the format has them, the line (OBJ, TOML) or JSON path (glTF).

pub mod gltf_check;
pub mod gltf_file;
pub mod obj;
pub mod ply;
pub mod step;
pub mod stl;
pub mod toml_scene;

use std::path::Path;

use glam::Vec3;

use crate::{Background, Light, Material, Mesh, Scene, SceneError};

pub use obj::parse_obj;

fn lowercase_extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// Loads any supported file, chosen by extension (case-insensitive).
pub fn load_file(path: &Path) -> Result<Scene, SceneError> {
    let shown = path.display().to_string();
    let extension = lowercase_extension(path);
    if !matches!(
        extension.as_str(),
        "toml" | "gltf" | "glb" | "obj" | "ply" | "stl" | "step" | "stp"
    ) {
        return Err(SceneError::UnknownScene {
            name: shown,
            available: crate::builtin::names().join(", "),
        });
    }
    if !path.exists() {
        return Err(SceneError::io(
            &shown,
            std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        ));
    }
    match extension.as_str() {
        "toml" => toml_scene::load(path),
        "gltf" | "glb" => gltf_file::load(path),
        "step" | "stp" => step::load(path),
        _ => {
            let (meshes, materials, textures, mut warnings) = load_mesh_file(path)?;
            warnings.extend(crate::plausibility::unitless_file_warning(&shown, &meshes));
            let mut scene = scene_from_meshes(&shown, meshes, materials, textures);
            scene.warnings.append(&mut warnings);
            scene.finalize(&shown)?;
            Ok(scene)
        }
    }
}

/// Meshes (object space), their materials and textures, and warnings from an OBJ, PLY or STL
/// file. Materials are indexed from 0 within the result.
pub type MeshFile = (Vec<Mesh>, Vec<Material>, Vec<crate::Texture>, Vec<String>);

pub fn load_mesh_file(path: &Path) -> Result<MeshFile, SceneError> {
    let shown = path.display().to_string();
    let extension = lowercase_extension(path);
    let bytes = std::fs::read(path).map_err(|e| SceneError::io(&shown, e))?;
    let bytes = if shown.ends_with(".gz") {
        gunzip(&shown, &bytes)?
    } else {
        bytes
    };
    match extension.as_str() {
        "obj" | "gz" => obj::load(path, &bytes),
        "ply" => {
            let mut warnings = Vec::new();
            let mesh = ply::parse(&shown, &bytes, &mut warnings)?;
            Ok((vec![mesh], vec![default_material()], vec![], warnings))
        }
        "stl" => Ok((
            vec![stl::parse(&shown, &bytes)?],
            vec![default_material()],
            vec![],
            vec![],
        )),
        other => Err(SceneError::invalid(
            &shown,
            format!("'.{other}' is not a mesh format (use .obj, .obj.gz, .ply or .stl)"),
        )),
    }
}

fn gunzip(shown: &str, bytes: &[u8]) -> Result<Vec<u8>, SceneError> {
    use std::io::Read;
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(bytes)
        .read_to_end(&mut out)
        .map_err(|e| SceneError::invalid(shown, format!("cannot decompress: {e}")))?;
    Ok(out)
}

/// A vertex attribute kept where the file gives one value per vertex; otherwise none, and the
/// mesh derives it.
fn per_vertex<T>(attribute: Vec<T>, vertices: usize) -> Vec<T> {
    if attribute.len() == vertices {
        attribute
    } else {
        Vec::new()
    }
}

pub fn default_material() -> Material {
    Material::diffuse("default", Vec3::splat(0.8))
}

/// Wraps bare meshes in a scene: default framing and, since mesh files carry no lights, a
/// directional key light from over the viewer's shoulder plus a little ambient. Both are said.
pub(crate) fn scene_from_meshes(
    shown: &str,
    meshes: Vec<Mesh>,
    materials: Vec<Material>,
    textures: Vec<crate::Texture>,
) -> Scene {
    let mut scene = Scene::new(shown);
    scene.meshes = meshes;
    scene.materials = materials;
    scene.textures = textures;
    scene.background = Background::Color(Vec3::splat(0.05));
    scene.use_default_camera(shown);
    add_default_lighting(&mut scene, shown);
    scene
}

/// Adds a key light from above the camera's right shoulder and a little ambient light.
pub fn add_default_lighting(scene: &mut Scene, shown: &str) {
    let frame = scene.camera.frame();
    let direction = (frame.forward - 0.6 * frame.right - 0.8 * frame.up).normalize();
    scene.lights.push(Light::Directional {
        direction,
        irradiance: Vec3::splat(2.5),
    });
    scene.ambient = Vec3::splat(0.15);
    scene.warnings.push(format!(
        "{shown}: no lights in the file; added a directional key light and ambient 0.15"
    ));
}
