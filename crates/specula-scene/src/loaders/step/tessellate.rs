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
use truck_stepio::r#in::alias::{ParametricSurface, ParametricSurface3D, PolygonMesh};
use truck_topology::compress::{CompressedEdgeIndex, CompressedFace};

use super::brep::{BodyBrep, Shell};
use super::entities::Entities;
use crate::cad::{CadFace, CadFaces};
use crate::Mesh;

/// The body's mesh in world space (`world_from_file` applied) with its CAD faces.
pub(super) fn tessellate(
    entities: &Entities,
    name: &str,
    brep: BodyBrep,
    tolerance: f64,
    world_from_file: DMat4,
) -> Result<Mesh, String> {
    let mut mesh = Mesh {
        name: name.to_string(),
        ..Mesh::default()
    };
    let mut faces = Vec::new();
    let mut face_of_triangle = Vec::new();
    let mut uvs = Vec::new();
    let normal_from_file = DMat3::from_mat4(world_from_file).inverse().transpose();
    for (shell, refs) in brep.shells.iter().zip(&brep.faces) {
        let polygons: Vec<Result<PolygonMesh, String>> = (0..shell.faces.len())
            .into_par_iter()
            .map(|f| {
                face_polygon(shell, f, tolerance)
                    .map_err(|why| format!("{}: {why}", entities.describe(refs[f].entity)))
            })
            .collect();
        for ((face, polygon), face_ref) in shell.faces.iter().zip(polygons).zip(refs) {
            let polygon = polygon?;
            let face_index = faces.len() as u32;
            faces.push(CadFace {
                entity: face_ref.entity,
                surface: face.surface.clone(),
                reversed: face_ref.reversed,
            });
            let sign = if face_ref.reversed { -1.0 } else { 1.0 };
            let uv_coords = polygon.uv_coords();
            let mut vertex_of = HashMap::new();
            let mut add_vertex = |v: &truck_stepio::r#in::alias::StandardVertex| -> Option<u32> {
                if let Some(&i) = vertex_of.get(&(v.pos, v.uv)) {
                    return Some(i);
                }
                let uv = v.uv.and_then(|i| uv_coords.get(i))?;
                let uv = DVec2::new(uv.x, uv.y);
                let p = face.surface.subs(uv.x, uv.y);
                let n = face.surface.normal(uv.x, uv.y) * sign;
                let p_world = world_from_file.transform_point3(DVec3::new(p.x, p.y, p.z));
                let n_world = (normal_from_file * DVec3::new(n.x, n.y, n.z)).normalize_or_zero();
                let i = mesh.positions.len() as u32;
                mesh.positions.push(p_world.as_vec3());
                mesh.normals.push(n_world.as_vec3());
                uvs.push(uv);
                vertex_of.insert((v.pos, v.uv), i);
                Some(i)
            };
            let before = mesh.triangles.len();
            for polygon_face in polygon.face_iter() {
                let corners: Vec<u32> = polygon_face
                    .iter()
                    .map(&mut add_vertex)
                    .collect::<Option<_>>()
                    .ok_or_else(|| {
                        format!(
                            "{}: a vertex of its tessellation has no (u, v)",
                            entities.describe(face_ref.entity)
                        )
                    })?;
                for k in 1..corners.len().saturating_sub(1) {
                    let [a, b, c] = [corners[0], corners[k], corners[k + 1]];
                    mesh.triangles.push(if face_ref.reversed {
                        [a, c, b]
                    } else {
                        [a, b, c]
                    });
                    face_of_triangle.push(face_index);
                }
            }
            if mesh.triangles.len() == before {
                return Err(format!(
                    "{}: its tessellation has no triangle (a face of no area, or trimming loops that enclose nothing)",
                    entities.describe(face_ref.entity)
                ));
            }
        }
    }
    mesh.cad = Some(CadFaces {
        faces: Arc::new(faces),
        world_from_object: world_from_file,
        face_of_triangle,
        uv: uvs,
    });
    Ok(mesh)
}

/// Face `f` of `shell` tessellated alone: a shell of that face, its edges and their vertices.
fn face_polygon(shell: &Shell, f: usize, tolerance: f64) -> Result<PolygonMesh, String> {
    let face = &shell.faces[f];
    if face.boundaries.iter().any(Vec::is_empty) {
        return Err("a trimming loop with no edge".into());
    }
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
    meshed
        .faces
        .into_iter()
        .next()
        .and_then(|face| face.surface)
        .ok_or_else(|| {
            "its tessellation failed (truck could not place its trimming loops on its surface); check the face in your CAD system (a sliver, or a loop off its surface)".to_string()
        })
}
