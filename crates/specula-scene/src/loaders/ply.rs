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

/// Header keywords of PLY; a header line starting with anything else is free text an exporter
/// forgot to mark as a comment.
const HEADER_KEYWORDS: &[&str] = &[
    "ply",
    "format",
    "comment",
    "obj_info",
    "element",
    "property",
    "end_header",
];

/// The file with stray header lines turned into comments (as common tools read them), with a
/// warning; unchanged when the header is clean.
fn commented_header<'a>(
    shown: &str,
    bytes: &'a [u8],
    warnings: &mut Vec<String>,
) -> Result<std::borrow::Cow<'a, [u8]>, SceneError> {
    let end = bytes
        .windows(b"end_header".len())
        .position(|w| w == b"end_header");
    // Without an end_header ply-rs reads header lines to the end: check them all.
    let header = String::from_utf8_lossy(&bytes[..end.unwrap_or(bytes.len())]);
    if let Some(problem) = header_numbers(&header, bytes.len()) {
        return Err(SceneError::invalid(shown, format!("PLY: {problem}")));
    }
    let Some(end) = end else {
        return Ok(std::borrow::Cow::Borrowed(bytes));
    };
    let stray: Vec<usize> = header
        .lines()
        .enumerate()
        .filter(|(_, l)| {
            let first = l.split_whitespace().next();
            first.is_some_and(|w| !HEADER_KEYWORDS.contains(&w))
        })
        .map(|(i, _)| i)
        .collect();
    if stray.is_empty() {
        return Ok(std::borrow::Cow::Borrowed(bytes));
    }
    warnings.push(format!(
        "{shown}:{}: header line without a PLY keyword read as a comment",
        stray[0] + 1
    ));
    let mut fixed = Vec::with_capacity(bytes.len() + 8 * stray.len());
    for (i, line) in header.split_inclusive('\n').enumerate() {
        if stray.contains(&i) {
            fixed.extend_from_slice(b"comment ");
        }
        fixed.extend_from_slice(line.as_bytes());
    }
    fixed.extend_from_slice(&bytes[end..]);
    Ok(std::borrow::Cow::Owned(fixed))
}

/// The header's numbers, checked before ply-rs parses them (it unwraps a number that
/// overflows 64 bits): the format version must be 1.0, and an element count can be no larger
/// than the file (each element takes at least a byte), so a count cannot ask for a huge
/// allocation either.
fn header_numbers(header: &str, file_length: usize) -> Option<String> {
    for (i, line) in header.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["format", _, version, ..] if *version != "1.0" => {
                return Some(format!(
                    "line {}: format version '{}' (only 1.0 exists)",
                    i + 1,
                    version.chars().take(20).collect::<String>()
                ))
            }
            ["element", name, count, ..] => {
                let fits = count.len() <= 19
                    && count
                        .parse::<u64>()
                        .is_ok_and(|c| c as u128 <= file_length as u128);
                if !fits {
                    return Some(format!(
                        "line {}: element '{}' count '{}' is not a number up to the file's size ({file_length} bytes)",
                        i + 1,
                        name.chars().take(40).collect::<String>(),
                        count.chars().take(24).collect::<String>()
                    ));
                }
            }
            _ => {}
        }
    }
    None
}

/// ply-rs's errors as one sentence: its message carries the line, the text and a debug dump of
/// the inner error; keep the line and the text, and say what was expected.
fn readable(error: &std::io::Error) -> String {
    let message = error.to_string();
    let mut parts = message.split("\n\t");
    let head = parts.next().unwrap_or("").trim().trim_end_matches('.');
    let mut text = None;
    let mut detail = None;
    for part in parts {
        if let Some(t) = part.strip_prefix("String: ") {
            text = Some(t.trim().trim_matches('\'').trim().to_string());
        } else if let Some(e) = part.strip_prefix("Error: ") {
            detail = Some(if e.contains("ParseError") {
                "expected a PLY header keyword or value".to_string()
            } else if let Some(start) = e.find("error: \"") {
                e[start + 8..].trim_end_matches(['}', ' ', '"']).to_string()
            } else {
                e.to_string()
            });
        }
    }
    if message.contains("failed to fill whole buffer") {
        return "the file ends before the data its header declares (truncated)".into();
    }
    let head = head
        .replace("Couln't", "could not")
        .replace("Couldn't", "could not");
    if text.as_deref() == Some("")
        && detail
            .as_deref()
            .is_some_and(|d| d.contains("found nothing"))
    {
        let line = head.split(':').next().unwrap_or(&head).to_lowercase();
        return format!(
            "{line}: the file ends before the elements its header declares (truncated)"
        );
    }
    match (text, detail) {
        (Some(t), Some(d)) => format!("{head} \"{t}\": {d}"),
        (Some(t), None) => format!("{head} \"{t}\""),
        (None, Some(d)) => format!("{head}: {d}"),
        (None, None) => head,
    }
}

/// PLY (ASCII or binary): `vertex` elements with x, y, z (and optional nx, ny, nz and u, v or
/// s, t); `face` elements with a `vertex_indices` (or `vertex_index`) list, fan-triangulated.
pub fn parse(shown: &str, bytes: &[u8], warnings: &mut Vec<String>) -> Result<Mesh, SceneError> {
    let bytes = commented_header(shown, bytes, warnings)?;
    let parser = ply_rs::parser::Parser::<ply_rs::ply::DefaultElement>::new();
    let ply = parser
        .read_ply(&mut std::io::Cursor::new(&bytes[..]))
        .map_err(|e| SceneError::invalid(shown, format!("PLY: {}", readable(&e))))?;
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
    let (positions, normals, uvs) = vertex_attributes(shown, vertices)?;
    let triangles = fan_triangles(shown, &ply, positions.len())?;
    let mut mesh = Mesh {
        exact: None,
        cad: None,
        name: shown.to_string(),
        normals: super::per_vertex(normals, positions.len()),
        uvs: super::per_vertex(uvs, positions.len()),
        positions,
        triangles,
        material: 0,
    };
    if mesh.normals.is_empty() {
        mesh.compute_smooth_normals();
    }
    Ok(mesh)
}

/// Each vertex's position, and its normal and texture coordinate where it has them.
type VertexAttributes = (Vec<Vec3>, Vec<Vec3>, Vec<Vec2>);

/// The vertices' positions, normals and texture coordinates (the last two empty or partial
/// where the file has none).
fn vertex_attributes(
    shown: &str,
    vertices: &[ply_rs::ply::DefaultElement],
) -> Result<VertexAttributes, SceneError> {
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
    Ok((positions, normals, uvs))
}

/// The faces' corner lists, checked against the header's count and the vertices, fan-
/// triangulated.
fn fan_triangles(
    shown: &str,
    ply: &ply_rs::ply::Ply<ply_rs::ply::DefaultElement>,
    vertex_count: usize,
) -> Result<Vec<[u32; 3]>, SceneError> {
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
            .find(|&&i| i < 0 || i as usize >= vertex_count)
        {
            return Err(SceneError::invalid(
                shown,
                format!("face {f} uses vertex index {bad}, but there are {vertex_count} vertices"),
            ));
        }
        for k in 1..indices.len() - 1 {
            triangles.push([indices[0] as u32, indices[k] as u32, indices[k + 1] as u32]);
        }
    }
    Ok(triangles)
}
