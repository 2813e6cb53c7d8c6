use std::path::Path;

use glam::{Vec2, Vec3};

use super::MeshFile;
use crate::{Material, MaterialKind, Mesh, SceneError, Texture};

/// Checks an OBJ's text line by line before tobj parses it, so that errors can name the line:
/// numbers that do not parse or are not finite, faces with fewer than three corners, and
/// indices out of range.
fn lint(shown: &str, text: &str) -> Result<(), SceneError> {
    let at = |line: usize, msg: String| SceneError::invalid(format!("{shown}:{line}"), msg);
    let (mut positions, mut texcoords, mut normals) = (0i64, 0i64, 0i64);
    // Positive indices may point forward, so they are checked once all vertices are counted.
    let mut forward_checks: Vec<(usize, usize, i64)> = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let number = number + 1;
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let (min_values, kind) = match keyword {
            "v" => (3, 0),
            "vt" => (1, 1),
            "vn" => (3, 2),
            "f" => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Err(at(
                        number,
                        format!(
                            "face has {} corner(s); at least 3 are needed",
                            corners.len()
                        ),
                    ));
                }
                for corner in corners {
                    for (slot, field) in corner.split('/').enumerate().take(3) {
                        if field.is_empty() && slot > 0 {
                            continue;
                        }
                        let index: i64 = field.parse().map_err(|_| {
                            at(number, format!("face corner '{corner}' is not an index"))
                        })?;
                        let count = [positions, texcoords, normals][slot];
                        if index == 0 || (index < 0 && -index > count) {
                            return Err(at(
                                number,
                                format!(
                                    "face index {index} is out of range ({count} defined so far)"
                                ),
                            ));
                        }
                        if index > 0 {
                            forward_checks.push((number, slot, index));
                        }
                    }
                }
                continue;
            }
            _ => continue,
        };
        let values: Vec<&str> = words.collect();
        if values.len() < min_values {
            return Err(at(
                number,
                format!(
                    "'{keyword}' needs at least {min_values} numbers, found {}",
                    values.len()
                ),
            ));
        }
        for value in values.iter().take(3) {
            let x: f32 = value
                .parse()
                .map_err(|_| at(number, format!("'{value}' is not a number")))?;
            if !x.is_finite() {
                return Err(at(
                    number,
                    format!("'{keyword}' has a non-finite value '{value}'"),
                ));
            }
        }
        match kind {
            0 => positions += 1,
            1 => texcoords += 1,
            _ => normals += 1,
        }
    }
    let names = ["vertex", "texture coordinate", "normal"];
    for (line, slot, index) in forward_checks {
        let count = [positions, texcoords, normals][slot];
        if index > count {
            return Err(at(
                line,
                format!(
                    "face refers to {} {index}, but the file has {count}",
                    names[slot]
                ),
            ));
        }
    }
    Ok(())
}

fn load_options() -> tobj::LoadOptions {
    tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    }
}

/// Parses OBJ text (no MTL) into one mesh per object, all with material 0.
pub fn parse_obj(shown: &str, text: &str) -> Result<Vec<Mesh>, SceneError> {
    lint(shown, text)?;
    let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &load_options(), |_| {
        Ok((Vec::new(), Default::default()))
    })
    .map_err(|e| SceneError::invalid(shown, format!("OBJ: {e}")))?;
    Ok(models
        .into_iter()
        .map(|m| mesh_from_model(m, None))
        .collect())
}

fn mesh_from_model(model: tobj::Model, material: Option<usize>) -> Mesh {
    let m = model.mesh;
    let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(Vec3::from_slice).collect();
    let normals: Vec<Vec3> = if m.normals.len() == m.positions.len() {
        m.normals
            .chunks_exact(3)
            .map(|n| Vec3::from_slice(n).try_normalize().unwrap_or(Vec3::Y))
            .collect()
    } else {
        Vec::new()
    };
    // OBJ's v runs up the image; ours (as glTF's) runs down.
    let uvs: Vec<Vec2> = if m.texcoords.len() / 2 == positions.len() {
        m.texcoords
            .chunks_exact(2)
            .map(|t| Vec2::new(t[0], 1.0 - t[1]))
            .collect()
    } else {
        Vec::new()
    };
    let triangles = m
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    let mut mesh = Mesh {
        exact: None,
        cad: None,
        name: model.name,
        positions,
        normals,
        uvs,
        triangles,
        material: material.or(m.material_id).unwrap_or(0),
    };
    if mesh.normals.is_empty() {
        mesh.compute_smooth_normals();
    }
    mesh
}

/// MTL → specula: `illum` 3 or 5 (reflection) → mirror with F0 = Ks; `illum` 4, 6, 7 or 9
/// (refraction) or `d` < 1 with `Ni` → dielectric with IOR Ni; `illum` 0 → unlit Kd; anything
/// else → diffuse Kd (× map_Kd).
fn material_from_mtl(
    base: &Path,
    m: &tobj::Material,
    textures: &mut Vec<Texture>,
    warnings: &mut Vec<String>,
) -> Material {
    let kd = Vec3::from_array(m.diffuse.unwrap_or([0.8; 3]));
    let ks = Vec3::from_array(m.specular.unwrap_or([0.9; 3]));
    let illum = m.illumination_model.unwrap_or(2);
    let transparent = m.dissolve.is_some_and(|d| d < 1.0);
    let kind = match illum {
        0 => MaterialKind::Unlit,
        3 | 5 => MaterialKind::Mirror { fresnel: true },
        4 | 6 | 7 | 9 => MaterialKind::Dielectric {
            ior: Vec3::splat(m.optical_density.unwrap_or(1.5)),
            thin_walled: false,
        },
        _ if transparent && m.optical_density.is_some() => MaterialKind::Dielectric {
            ior: Vec3::splat(m.optical_density.unwrap_or(1.5)),
            thin_walled: false,
        },
        _ => MaterialKind::Diffuse,
    };
    let color = match kind {
        MaterialKind::Mirror { .. } => ks,
        MaterialKind::Dielectric { .. } => Vec3::ONE,
        _ => kd,
    };
    let mut material = Material::new(m.name.clone(), kind, color);
    if let Some(file) = &m.diffuse_texture {
        match Texture::load(&base.join(file), true) {
            Ok(t) => {
                material.texture = Some(textures.len());
                textures.push(t);
            }
            Err(e) => warnings.push(format!("material '{}': texture ignored: {e}", m.name)),
        }
    }
    material
}

/// The file as text: UTF-8, or (as common tools read it) with stray non-UTF-8 bytes, say in a
/// comment or a name, replaced and a warning. UTF-16 is refused by name.
fn text_of<'a>(
    shown: &str,
    bytes: &'a [u8],
    warnings: &mut Vec<String>,
) -> Result<std::borrow::Cow<'a, str>, SceneError> {
    if bytes.starts_with(&[0xFE, 0xFF]) || bytes.starts_with(&[0xFF, 0xFE]) {
        return Err(SceneError::invalid(
            shown,
            "UTF-16 text is not supported: save the OBJ file as UTF-8 (or ASCII)",
        ));
    }
    let text = String::from_utf8_lossy(bytes);
    if let std::borrow::Cow::Owned(_) = text {
        let line = 1 + match std::str::from_utf8(bytes) {
            Err(e) => bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count(),
            Ok(_) => 0,
        };
        warnings.push(format!(
            "{shown}:{line}: bytes that are not UTF-8 (first on this line) replaced by U+FFFD"
        ));
    }
    Ok(text)
}

/// `usemtl` with no name (an exporter's empty material) makes tobj fail the whole file: such
/// lines are dropped with a warning, and their faces get the default material.
fn drop_unnamed_usemtl<'a>(
    shown: &str,
    text: &'a str,
    warnings: &mut Vec<String>,
) -> std::borrow::Cow<'a, str> {
    let unnamed = |line: &str| line.split_whitespace().collect::<Vec<_>>() == ["usemtl"];
    let Some(first) = text.lines().position(unnamed) else {
        return std::borrow::Cow::Borrowed(text);
    };
    warnings.push(format!(
        "{shown}:{}: 'usemtl' without a material name; its faces use the default material",
        first + 1
    ));
    std::borrow::Cow::Owned(
        text.lines()
            .filter(|l| !unnamed(l))
            .collect::<Vec<_>>()
            .join("\n"),
    )
}

pub fn load(path: &Path, bytes: &[u8]) -> Result<MeshFile, SceneError> {
    let shown = path.display().to_string();
    let mut warnings = Vec::new();
    let text = text_of(&shown, bytes, &mut warnings)?;
    lint(&shown, &text)?;
    let text = drop_unnamed_usemtl(&shown, &text, &mut warnings);
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let (models, mtl) = tobj::load_obj_buf(&mut text.as_bytes(), &load_options(), |mtl_path| {
        tobj::load_mtl(base.join(mtl_path))
    })
    .map_err(|e| SceneError::invalid(&shown, format!("OBJ: {e}")))?;
    let mut textures = Vec::new();
    let mut materials: Vec<Material> = match mtl {
        Ok(list) => list
            .iter()
            .map(|m| material_from_mtl(&base, m, &mut textures, &mut warnings))
            .collect(),
        Err(e) => {
            if text.lines().any(|l| l.trim_start().starts_with("mtllib")) {
                warnings.push(format!(
                    "{shown}: material library not loaded ({e}); using a grey diffuse material"
                ));
            }
            Vec::new()
        }
    };
    let default_index = materials.len();
    materials.push(super::default_material());
    let meshes = models
        .into_iter()
        .map(|model| {
            let material = model
                .mesh
                .material_id
                .filter(|&i| i < default_index)
                .unwrap_or(default_index);
            mesh_from_model(model, Some(material))
        })
        .collect();
    Ok((meshes, materials, textures, warnings))
}
