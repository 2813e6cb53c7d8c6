//! A mesh's CAD faces: the exact surfaces a STEP file's faces lie on, which face each triangle
//! tessellates, and each vertex's (u, v) on its face ([`crate::Mesh::cad`]). The tessellation
//! is what renderers draw; the faces are what exact work (Newton refinement of a hit, an
//! analysis's normal sections) samples.
//!
//! Surfaces stay in their file's coordinates and unit, shared between the meshes cut from
//! one body; `world_from_object` takes them to world space (metres, +Y up), so moving a mesh
//! moves its faces. Anything that changes the triangles otherwise than by [`crate::Mesh::transform`]
//! or a subset keeps the map consistent or drops it.

use std::sync::Arc;

use glam::{DMat4, DVec2, DVec3};
use truck_stepio::r#in::alias::{ParametricSurface, Surface};

/// One face of a STEP file's B-rep.
#[derive(Clone, Debug)]
pub struct CadFace {
    /// The file's entity number of the face (`#123`), for messages.
    pub entity: u64,
    /// The face's surface in file coordinates, with STEP's `same_sense` applied: its normal
    /// Su × Sv points to the face's outside unless `reversed`.
    pub surface: Surface,
    /// An `ORIENTED_FACE` (or a reversed shell) turned the face over: its outside is −Su × Sv.
    pub reversed: bool,
}

/// The faces a mesh's triangles tessellate.
#[derive(Clone, Debug)]
pub struct CadFaces {
    pub faces: Arc<Vec<CadFace>>,
    /// World from the file's coordinates (scale to metres, up axis, the scene's placement).
    pub world_from_object: DMat4,
    /// For each triangle, its face in `faces`.
    pub face_of_triangle: Vec<u32>,
    /// For each vertex, its (u, v) on the face of the triangles that use it.
    pub uv: Vec<DVec2>,
}

impl PartialEq for CadFaces {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.faces, &other.faces)
            && self.world_from_object == other.world_from_object
            && self.face_of_triangle == other.face_of_triangle
            && self.uv == other.uv
    }
}

impl CadFaces {
    /// Checks the map against its mesh's counts: one face per triangle, each in range, one
    /// finite (u, v) per vertex.
    pub fn validate(&self, triangles: usize, vertices: usize) -> Result<(), String> {
        if self.face_of_triangle.len() != triangles || self.uv.len() != vertices {
            return Err(format!(
                "CAD face map has {} faces for {triangles} triangles and {} (u, v) for {vertices} vertices",
                self.face_of_triangle.len(),
                self.uv.len()
            ));
        }
        if let Some(t) = self
            .face_of_triangle
            .iter()
            .position(|&f| f as usize >= self.faces.len())
        {
            return Err(format!(
                "triangle {t} names CAD face {} of {}",
                self.face_of_triangle[t],
                self.faces.len()
            ));
        }
        if let Some(v) = self.uv.iter().position(|uv| !uv.is_finite()) {
            return Err(format!(
                "vertex {v} has a non-finite (u, v) on its CAD face"
            ));
        }
        Ok(())
    }

    /// The world-space point of `vertex` on its face's exact surface.
    pub fn point_world(&self, vertex: usize, face: usize) -> DVec3 {
        let uv = self.uv[vertex];
        let p = self.faces[face].surface.subs(uv.x, uv.y);
        self.world_from_object
            .transform_point3(DVec3::new(p.x, p.y, p.z))
    }
}
