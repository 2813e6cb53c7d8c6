use glam::{Vec2, Vec3};
use ply_rs::ply::Property;

use crate::{Mesh, SceneError};

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v as f64,
        Property::UChar(v) => v as f64,
        Property::Short(v) => v as f64,
        Property::UShort(v) => v as f64,
        Property::Int(v) => v as f64,
        Property::UInt(v) => v as f64,
        Property::Float(v) => v as f64,
        Property::Double(v) => v,
        _ => return None,
    })
}

fn list(p: &Property) -> Option<Vec<i64>> {
    Some(match p {
        Property::ListChar(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListUChar(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListShort(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListUShort(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListInt(v) => v.iter().map(|&x| x as i64).collect(),
        Property::ListUInt(v) => v.iter().map(|&x| x as i64).collect(),
        _ => return None,
    })
}

/// PLY (ASCII or binary): `vertex` elements with x, y, z (and optional nx, ny, nz and u, v or
/// s, t); `face` elements with a `vertex_indices` (or `vertex_index`) list, fan-triangulated.
pub fn parse(shown: &str, bytes: &[u8]) -> Result<Mesh, SceneError> {
    let parser = ply_rs::parser::Parser::<ply_rs::ply::DefaultElement>::new();
    let ply = parser
        .read_ply(&mut std::io::Cursor::new(bytes))
        .map_err(|e| SceneError::invalid(shown, format!("PLY: {e}")))?;
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| SceneError::invalid(shown, "PLY has no 'vertex' element"))?;
    let declared = ply
        .header
        .elements
        .get("vertex")
        .map(|e| e.count)
        .unwrap_or(0);
    if vertices.len() != declared {
        return Err(SceneError::invalid(
            shown,
            format!(
                "PLY is truncated: header declares {declared} vertices, file has {}",
                vertices.len()
            ),
        ));
    }
    let get = |element: &ply_rs::ply::DefaultElement, names: &[&str]| -> Option<f64> {
        names.iter().find_map(|n| element.get(*n).and_then(scalar))
    };
    let mut positions = Vec::with_capacity(vertices.len());
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for (i, v) in vertices.iter().enumerate() {
        let (Some(x), Some(y), Some(z)) = (get(v, &["x"]), get(v, &["y"]), get(v, &["z"])) else {
            return Err(SceneError::invalid(
                shown,
                format!("vertex {i} lacks x, y or z"),
            ));
        };
        positions.push(Vec3::new(x as f32, y as f32, z as f32));
        if let (Some(nx), Some(ny), Some(nz)) = (get(v, &["nx"]), get(v, &["ny"]), get(v, &["nz"]))
        {
            normals.push(
                Vec3::new(nx as f32, ny as f32, nz as f32)
                    .try_normalize()
                    .unwrap_or(Vec3::Y),
            );
        }
        if let (Some(u), Some(t)) = (
            get(v, &["u", "s", "texture_u"]),
            get(v, &["v", "t", "texture_v"]),
        ) {
            uvs.push(Vec2::new(u as f32, 1.0 - t as f32));
        }
    }
    let faces = ply
        .payload
        .get("face")
        .map(Vec::as_slice)
        .unwrap_or_default();
    let declared_faces = ply
        .header
        .elements
        .get("face")
        .map(|e| e.count)
        .unwrap_or(0);
    if faces.len() != declared_faces {
        return Err(SceneError::invalid(
            shown,
            format!(
                "PLY is truncated: header declares {declared_faces} faces, file has {}",
                faces.len()
            ),
        ));
    }
    let mut triangles = Vec::with_capacity(faces.len());
    for (f, face) in faces.iter().enumerate() {
        let indices = ["vertex_indices", "vertex_index"]
            .iter()
            .find_map(|n| face.get(*n).and_then(list))
            .ok_or_else(|| {
                SceneError::invalid(shown, format!("face {f} has no vertex_indices list"))
            })?;
        if indices.len() < 3 {
            return Err(SceneError::invalid(
                shown,
                format!("face {f} has {} corner(s)", indices.len()),
            ));
        }
        if let Some(&bad) = indices
            .iter()
            .find(|&&i| i < 0 || i as usize >= positions.len())
        {
            return Err(SceneError::invalid(
                shown,
                format!(
                    "face {f} uses vertex index {bad}, but there are {} vertices",
                    positions.len()
                ),
            ));
        }
        for k in 1..indices.len() - 1 {
            triangles.push([indices[0] as u32, indices[k] as u32, indices[k + 1] as u32]);
        }
    }
    let mut mesh = Mesh {
        name: shown.to_string(),
        normals: if normals.len() == positions.len() {
            normals
        } else {
            vec![]
        },
        uvs: if uvs.len() == positions.len() {
            uvs
        } else {
            vec![]
        },
        positions,
        triangles,
        material: 0,
    };
    if mesh.normals.is_empty() {
        mesh.compute_smooth_normals();
    }
    Ok(mesh)
}
