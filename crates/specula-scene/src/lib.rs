//! specula's scene model: triangle meshes in world space (metres), materials, lights, a camera
//! and a background, plus the loaders (glTF 2.0, OBJ+MTL, PLY, STL, TOML scene files), the
//! analytic generators and the built-in scenes.
//!
//! Conventions (see docs/conventions.md): right-handed, +Y up, units are metres; a camera looks
//! down its local -Z; meshes are stored already transformed to world space; triangles wind
//! counter-clockwise around their outward normal.

pub mod builtin;
pub mod cad;
pub mod camera;
pub mod error;
pub mod exact;
pub mod exact_lens;
pub mod freeform;
pub mod generators;
pub mod light;
pub mod loaders;
pub mod material;
pub mod material_override;
pub mod mesh;
mod plausibility;
pub mod scene;
pub mod spectacle;
pub mod texture;
pub mod units;

pub use camera::{Camera, PixelRays};
pub use error::SceneError;
pub use exact::{ExactShape, ExactSurface};
pub use exact_lens::{ExactLens, LensSurface, SurfaceShape};
pub use freeform::Freeform;
pub use light::Light;
pub use material::{Material, MaterialKind};
pub use material_override::{MaterialChoice, MaterialOverride, MaterialOverrideError};
pub use mesh::{Aabb, Mesh};
pub use scene::{Background, Scene};
pub use spectacle::Prescription;
pub use texture::Texture;

/// Loads a scene by built-in name or file path (`.toml`, `.gltf`, `.glb`, `.obj`, `.ply`, `.stl`).
pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
    if let Some(scene) = builtin::by_name(name_or_path) {
        return scene;
    }
    loaders::load_file(std::path::Path::new(name_or_path))
}
