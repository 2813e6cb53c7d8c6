//! A body's faces as triangles, by truck's tessellation (constrained Delaunay in each face's
//! (u, v) domain, refined to the chord tolerance), kept with the face each triangle belongs to
//! and each vertex's (u, v) on it. Normals are the exact surface's at each vertex, not the
//! facets'. Each face is tessellated on its own (in parallel) so that a face that fails is
//! named; the edges it shares are cut into the same points on both sides.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DMat3, DMat4, DVec2, DVec3};
use rayon::prelude::*;
use truck_meshalgo::tessellation::RobustMeshableShape;
use truck_stepio::r#in::alias::{ParametricSurface, ParametricSurface3D};
use truck_topology::compress::{CompressedEdgeIndex, CompressedFace};

use super::brep::{BodyBrep, Shell};
use super::entities::Entities;
use crate::cad::{CadFace, CadFaces};
use crate::Mesh;

/// A face's tessellation: (u, v) per vertex, triangles anticlockwise about Su × Sv.
pub(super) struct FacePolygon {
    pub uv: Vec<DVec2>,
    pub triangles: Vec<[u32; 3]>,
}

/// The body's mesh in world space (`world_from_file` applied) with its CAD faces, and a
/// warning for each face that took the grid fallback.
pub(super) fn tessellate(
    entities: &Entities,
    name: &str,
    brep: BodyBrep,
    tolerance: f64,
    world_from_file: DMat4,
) -> Result<(Mesh, Vec<String>), String> {
    let mut mesh = Mesh {
        name: name.to_string(),
        ..Mesh::default()
    };
    let mut warnings = Vec::new();
    let mut faces = Vec::new();
    let mut face_of_triangle = Vec::new();
    let mut uvs = Vec::new();
    let normal_from_file = DMat3::from_mat4(world_from_file).inverse().transpose();
    for (shell, refs) in brep.shells.iter().zip(&brep.faces) {
        let polygons: Vec<Result<(FacePolygon, bool), String>> = (0..shell.faces.len())
            .into_par_iter()
            .map(|f| {
                face_polygon(shell, f, tolerance)
                    .map_err(|why| format!("{}: {why}", entities.describe(refs[f].entity)))
            })
            .collect();
        for ((face, polygon), face_ref) in shell.faces.iter().zip(polygons).zip(refs) {
            let (polygon, gridded) = polygon?;
            if gridded {
                warnings.push(format!(
                    "{}: truck's tessellation failed; tessellated on a (u, v) grid clipped to its trimming loops, so its rim is stepped",
                    entities.describe(face_ref.entity)
                ));
            }
            if polygon.triangles.is_empty() {
                return Err(format!(
                    "{}: its tessellation has no triangle (a face of no area, or trimming loops that enclose nothing)",
                    entities.describe(face_ref.entity)
                ));
            }
            let face_index = faces.len() as u32;
            faces.push(CadFace {
                entity: face_ref.entity,
                surface: face.surface.clone(),
                reversed: face_ref.reversed,
            });
            let sign = if face_ref.reversed { -1.0 } else { 1.0 };
            let base = mesh.positions.len() as u32;
            for &uv in &polygon.uv {
                let p = face.surface.subs(uv.x, uv.y);
                let n = face.surface.normal(uv.x, uv.y) * sign;
                let p_world = world_from_file.transform_point3(DVec3::new(p.x, p.y, p.z));
                let n_world = (normal_from_file * DVec3::new(n.x, n.y, n.z)).normalize_or_zero();
                mesh.positions.push(p_world.as_vec3());
                mesh.normals.push(n_world.as_vec3());
                uvs.push(uv);
            }
            for &[a, b, c] in &polygon.triangles {
                let [a, b, c] = [a + base, b + base, c + base];
                mesh.triangles.push(if face_ref.reversed {
                    [a, c, b]
                } else {
                    [a, b, c]
                });
                face_of_triangle.push(face_index);
            }
        }
    }
    mesh.cad = Some(CadFaces {
        faces: Arc::new(faces),
        world_from_object: world_from_file,
        face_of_triangle,
        uv: uvs,
    });
    Ok((mesh, warnings))
}

/// Face `f` of `shell`, tessellated by truck, or on the grid where truck's fails (`true`).
fn face_polygon(shell: &Shell, f: usize, tolerance: f64) -> Result<(FacePolygon, bool), String> {
    let face = &shell.faces[f];
    if face.boundaries.iter().any(Vec::is_empty) {
        return Err("a trimming loop with no edge".into());
    }
    if let Some(polygon) = truck_polygon(shell, f, tolerance)? {
        return Ok((polygon, false));
    }
    let boundaries: Vec<Vec<(usize, bool)>> = face
        .boundaries
        .iter()
        .map(|wire| wire.iter().map(|e| (e.index, e.orientation)).collect())
        .collect();
    let gridded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        super::fallback::grid_polygon(&face.surface, &shell.edges, &boundaries, tolerance)
    }))
    .ok()
    .flatten();
    gridded.map(|polygon| (polygon, true)).ok_or_else(|| {
        "its tessellation failed (neither truck nor the (u, v) grid could place its trimming loops on its surface); check the face in your CAD system (a sliver, or a loop off its surface)".to_string()
    })
}

/// Face `f` tessellated alone by truck: a shell of that face, its edges and their vertices;
/// `None` where truck could not.
fn truck_polygon(shell: &Shell, f: usize, tolerance: f64) -> Result<Option<FacePolygon>, String> {
    let face = &shell.faces[f];
    let mut single = Shell {
        vertices: vec![],
        edges: vec![],
        faces: vec![],
    };
    let mut vertex_map = HashMap::new();
    let mut edge_map = HashMap::new();
    let mut boundaries = Vec::new();
    for boundary in &face.boundaries {
        let mut wire = Vec::new();
        for index in boundary {
            let local = *edge_map.entry(index.index).or_insert_with(|| {
                let mut edge = shell.edges[index.index].clone();
                for vertex in [&mut edge.vertices.0, &mut edge.vertices.1] {
                    *vertex = *vertex_map.entry(*vertex).or_insert_with(|| {
                        single.vertices.push(shell.vertices[*vertex]);
                        single.vertices.len() - 1
                    });
                }
                single.edges.push(edge);
                single.edges.len() - 1
            });
            wire.push(CompressedEdgeIndex {
                index: local,
                orientation: index.orientation,
            });
        }
        boundaries.push(wire);
    }
    single.faces.push(CompressedFace {
        surface: face.surface.clone(),
        boundaries,
        orientation: true,
    });
    // truck's tessellation panics on some malformed input (an edge whose curve does not meet
    // its vertices, a loop that does not close) rather than returning an error: such a face
    // becomes this face's error instead of a crash.
    let meshed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        single.robust_triangulation(tolerance)
    }))
    .map_err(|_| {
        "the file broke truck's tessellation (a malformed face the reader's checks did not catch)"
            .to_string()
    })?;
    let Some(polygon) = meshed
        .faces
        .into_iter()
        .next()
        .and_then(|face| face.surface)
    else {
        return Ok(None);
    };
    let uv_coords = polygon.uv_coords();
    let mut vertex_of = HashMap::new();
    let mut result = FacePolygon {
        uv: vec![],
        triangles: vec![],
    };
    for corners in polygon.face_iter() {
        let mut indices = Vec::with_capacity(corners.len());
        for v in corners {
            let Some(uv) = v.uv.and_then(|i| uv_coords.get(i)) else {
                return Ok(None);
            };
            let index = *vertex_of.entry((v.pos, v.uv)).or_insert_with(|| {
                result.uv.push(DVec2::new(uv.x, uv.y));
                result.uv.len() as u32 - 1
            });
            indices.push(index);
        }
        for k in 1..indices.len().saturating_sub(1) {
            result
                .triangles
                .push([indices[0], indices[k], indices[k + 1]]);
        }
    }
    Ok(Some(result))
}
