use std::fmt;

/// Everything that can be wrong with a scene's input. Each variant names the file (or built-in
/// scene) and, where there is one, the line or JSON path.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    // The reason is in the message, not an error source: error chains print it once.
    #[error("{path}: cannot read: {reason}")]
    Io {
        path: String,
        reason: std::io::Error,
    },
    #[error("{path}: {message}")]
    Invalid { path: String, message: String },
    #[error("'{name}' is neither a built-in scene ({available}) nor a file with a known extension (.toml, .gltf, .glb, .obj, .ply, .stl, .step, .stp)")]
    UnknownScene { name: String, available: String },
    /// A material given from outside the scene (`--material NAME=KIND`) to an object it does
    /// not have.
    #[error("{scene}: no object '{name}' to make {material}; the scene's objects are: {objects}")]
    UnknownObject {
        scene: String,
        name: String,
        material: String,
        objects: String,
    },
}

impl SceneError {
    pub fn invalid(path: impl fmt::Display, message: impl fmt::Display) -> Self {
        SceneError::Invalid {
            path: path.to_string(),
            message: message.to_string(),
        }
    }

    pub fn io(path: impl fmt::Display, source: std::io::Error) -> Self {
        SceneError::Io {
            path: path.to_string(),
            reason: source,
        }
    }
}
