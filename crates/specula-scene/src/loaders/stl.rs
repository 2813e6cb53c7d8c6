use glam::Vec3;

use crate::{Mesh, SceneError};

/// STL (ASCII or binary). stl_io welds identical vertices, so smooth normals are computed over
/// the welded mesh (STL's facet normals are only flat ones).
pub fn parse(shown: &str, bytes: &[u8]) -> Result<Mesh, SceneError> {
    if bytes.len() < 15 {
        return Err(SceneError::invalid(
            shown,
            format!("STL is too short ({} bytes)", bytes.len()),
        ));
    }
    let is_ascii = bytes.starts_with(b"solid") && bytes.iter().take(512).all(|b| b.is_ascii());
    if !is_ascii {
        if bytes.len() < 84 {
            return Err(SceneError::invalid(
                shown,
                "binary STL is truncated inside its 84-byte header",
            ));
        }
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        let expected = 84 + count * 50;
        if bytes.len() < expected {
            return Err(SceneError::invalid(
                shown,
                format!("binary STL is truncated: header declares {count} triangles ({expected} bytes), file has {} bytes", bytes.len()),
            ));
        }
    }
    let indexed = stl_io::read_stl(&mut std::io::Cursor::new(bytes)).map_err(|e| {
        let reason = match e.kind() {
            std::io::ErrorKind::UnexpectedEof => {
                "the file ends before the data it declares (truncated)".to_string()
            }
            _ => e.to_string(),
        };
        SceneError::invalid(shown, format!("STL: {reason}"))
    })?;
    let positions: Vec<Vec3> = indexed
        .vertices
        .iter()
        .map(|v| Vec3::from_array(v.0))
        .collect();
    let triangles: Vec<[u32; 3]> = indexed
        .faces
        .iter()
        .map(|f| f.vertices.map(|i| i as u32))
        .collect();
    let mut mesh = Mesh {
        exact: None,
        cad: None,
        name: shown.to_string(),
        positions,
        normals: vec![],
        uvs: vec![],
        triangles,
        material: 0,
    };
    mesh.check_topology(shown)?;
    mesh.compute_smooth_normals();
    Ok(mesh)
}
