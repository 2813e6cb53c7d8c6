//! glTF 2.0 (`.gltf` with its buffers and images, or `.glb`), mapped as DESIGN.md says.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3};

use crate::material::ior_from_abbe;
use crate::{Camera, Light, Material, MaterialKind, Mesh, Scene, SceneError, Texture};

/// The extensions specula maps; a file requiring any other is refused (gltf_check).
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_materials_unlit",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_ior",
    "KHR_materials_dispersion",
    "KHR_lights_punctual",
];

/// Camera aspect ratios (width / height) outside this range are ignored with a warning.
const MIN_ASPECT: f32 = 0.05;
const MAX_ASPECT: f32 = 20.0;

struct Loader<'a> {
    shown: String,
    buffers: &'a [gltf::buffer::Data],
    images: &'a [gltf::image::Data],
    scene: Scene,
    /// glTF material index (None = the default material) → scene material index.
    material_map: HashMap<Option<usize>, usize>,
    /// glTF image index → scene texture index.
    texture_map: HashMap<usize, usize>,
    camera_found: bool,
    warned: std::collections::HashSet<String>,
}

impl Loader<'_> {
    fn warn_once(&mut self, feature: &str, what: String) {
        if self.warned.insert(feature.to_string()) {
            self.scene.warnings.push(format!("{}: {what}", self.shown));
        }
    }

    fn texture(&mut self, image_index: usize) -> Result<usize, SceneError> {
        if let Some(&t) = self.texture_map.get(&image_index) {
            return Ok(t);
        }
        let data = &self.images[image_index];
        let name = format!("{} images[{image_index}]", self.shown);
        let img = image_to_dynamic(data).ok_or_else(|| {
            SceneError::invalid(&name, format!("unsupported pixel format {:?}", data.format))
        })?;
        let texture = Texture::from_image(&name, img, true)?;
        self.scene.textures.push(texture);
        let index = self.scene.textures.len() - 1;
        self.texture_map.insert(image_index, index);
        Ok(index)
    }

    fn material(&mut self, m: gltf::Material) -> Result<usize, SceneError> {
        if let Some(&i) = self.material_map.get(&m.index()) {
            return Ok(i);
        }
        let path = match m.index() {
            Some(i) => format!("materials[{i}]"),
            None => "default material".to_string(),
        };
        let pbr = m.pbr_metallic_roughness();
        let color = Vec3::from_slice(&pbr.base_color_factor()[..3]);
        let transmission = m
            .transmission()
            .map(|t| t.transmission_factor())
            .unwrap_or(0.0);
        let kind = if m.unlit() {
            MaterialKind::Unlit
        } else if transmission > 0.0 {
            if transmission < 1.0 {
                self.warn_once(
                    &format!("{path}.transmission"),
                    format!(
                        "{path}: transmission {transmission} < 1 is treated as fully transmissive"
                    ),
                );
            }
            let ior = m.ior().unwrap_or(1.5);
            let dispersion = m
                .extensions()
                .and_then(|e| e.get("KHR_materials_dispersion"))
                .and_then(|d| d.get("dispersion"))
                .and_then(|d| d.as_f64())
                .unwrap_or(0.0) as f32;
            let ior = if dispersion > 0.0 {
                ior_from_abbe(ior, 20.0 / dispersion)
            } else {
                Vec3::splat(ior)
            };
            let thin_walled = m
                .volume()
                .map(|v| v.thickness_factor() <= 0.0)
                .unwrap_or(true);
            if thin_walled {
                self.warn_once(
                    "thin-walled",
                    format!("{path}: KHR_materials_transmission without KHR_materials_volume (thickness > 0) is thin-walled per the glTF spec: rendered as a thin sheet (Fresnel reflection, straight-through transmission)"),
                );
            }
            MaterialKind::Dielectric { ior, thin_walled }
        } else if pbr.metallic_factor() == 1.0 && pbr.roughness_factor() == 0.0 {
            MaterialKind::Mirror { fresnel: true }
        } else {
            MaterialKind::Diffuse
        };
        if m.emissive_factor() != [0.0; 3] && kind != MaterialKind::Unlit {
            self.warn_once(
                "emissive",
                format!("{path}: emissive colour is not supported (ignored)"),
            );
        }
        let name = m.name().map(str::to_string).unwrap_or_else(|| path.clone());
        let mut material = Material::new(name, kind, color);
        if let Some(info) = pbr.base_color_texture() {
            if info.tex_coord() != 0 {
                self.warn_once("texcoord", format!("{path}: only TEXCOORD_0 is supported"));
            }
            material.texture = Some(self.texture(info.texture().source().index())?);
        }
        self.scene.materials.push(material);
        let index = self.scene.materials.len() - 1;
        self.material_map.insert(m.index(), index);
        Ok(index)
    }

    fn visit(&mut self, node: gltf::Node, parent: Mat4) -> Result<(), SceneError> {
        let world_from_node = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let node_path = format!("nodes[{}]", node.index());
        if !world_from_node.is_finite() {
            return Err(SceneError::invalid(
                &self.shown,
                format!("{node_path}: transform is not finite"),
            ));
        }
        if let Some(camera) = node.camera() {
            self.camera(camera, world_from_node, &node_path);
        }
        if let Some(light) = node.light() {
            self.light(light, world_from_node);
        }
        if let Some(mesh) = node.mesh() {
            self.mesh(mesh, world_from_node)?;
        }
        for child in node.children() {
            self.visit(child, world_from_node)?;
        }
        Ok(())
    }

    fn camera(&mut self, camera: gltf::Camera, world_from_camera: Mat4, node_path: &str) {
        if self.camera_found {
            return;
        }
        match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let eye = world_from_camera.transform_point3(Vec3::ZERO);
                let forward = world_from_camera.transform_vector3(-Vec3::Z).normalize();
                // The aspect ratio sets image heights: a wild one is ignored, not obeyed.
                let aspect = p
                    .aspect_ratio()
                    .filter(|a| !(MIN_ASPECT..=MAX_ASPECT).contains(a));
                if let Some(a) = aspect {
                    self.warn_once(
                        "aspect",
                        format!("{node_path}: camera aspectRatio {a} is outside {MIN_ASPECT}..{MAX_ASPECT} (ignored)"),
                    );
                }
                self.scene.camera = Camera {
                    eye,
                    target: eye + forward,
                    up: world_from_camera.transform_vector3(Vec3::Y).normalize(),
                    fov_y_deg: p.yfov().to_degrees(),
                    aspect: p
                        .aspect_ratio()
                        .filter(|a| (MIN_ASPECT..=MAX_ASPECT).contains(a)),
                };
                self.camera_found = true;
            }
            gltf::camera::Projection::Orthographic(_) => self.warn_once(
                "orthographic",
                format!("{node_path}: orthographic cameras are not supported (skipped)"),
            ),
        }
    }

    fn light(&mut self, light: gltf::khr_lights_punctual::Light, world_from_light: Mat4) {
        let color = Vec3::from_array(light.color()) * light.intensity();
        let position = world_from_light.transform_point3(Vec3::ZERO);
        let direction = world_from_light.transform_vector3(-Vec3::Z).normalize();
        if light.range().is_some() {
            self.warn_once(
                "range",
                "light range is ignored (lights fall off with 1/d²)".to_string(),
            );
        }
        self.scene.lights.push(match light.kind() {
            gltf::khr_lights_punctual::Kind::Directional => Light::Directional {
                direction,
                irradiance: color,
            },
            gltf::khr_lights_punctual::Kind::Point => Light::Point {
                position,
                intensity: color,
            },
            gltf::khr_lights_punctual::Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => Light::Spot {
                position,
                direction,
                intensity: color,
                inner_cone: inner_cone_angle,
                outer_cone: outer_cone_angle,
            },
        });
    }

    fn mesh(&mut self, mesh: gltf::Mesh, world_from_object: Mat4) -> Result<(), SceneError> {
        for primitive in mesh.primitives() {
            let path = format!("meshes[{}].primitives[{}]", mesh.index(), primitive.index());
            let at = |msg: String| SceneError::invalid(&self.shown, format!("{path}{msg}"));
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                self.warn_once(
                    "mode",
                    format!(
                        "{path}: primitive mode {:?} is not supported (only triangles; skipped)",
                        primitive.mode()
                    ),
                );
                continue;
            }
            for (semantic, accessor) in primitive.attributes() {
                check_accessor(&accessor, self.buffers)
                    .map_err(|m| at(format!(".attributes.{semantic:?}: {m}")))?;
            }
            if let Some(accessor) = primitive.indices() {
                check_accessor(&accessor, self.buffers)
                    .map_err(|m| at(format!(".indices: {m}")))?;
            }
            let reader = primitive.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| at(".attributes: no POSITION".to_string()))?
                .map(Vec3::from_array)
                .collect();
            if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
                return Err(at(format!(
                    ".attributes.POSITION: vertex {i} is not finite ({:?})",
                    positions[i]
                )));
            }
            let normals: Vec<Vec3> = reader
                .read_normals()
                .map(|it| it.map(Vec3::from_array).collect())
                .unwrap_or_default();
            let uvs: Vec<Vec2> = reader
                .read_tex_coords(0)
                .map(|it| it.into_f32().map(Vec2::from_array).collect())
                .unwrap_or_default();
            let indices: Vec<u32> = match reader.read_indices() {
                Some(it) => it.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(at(format!(
                    ".indices: {} indices is not a multiple of 3",
                    indices.len()
                )));
            }
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(at(format!(
                    ".indices: index {bad} is out of range ({} vertices)",
                    positions.len()
                )));
            }
            let material = self.material(primitive.material())?;
            let mut m = Mesh {
                exact: None,
                cad: None,
                name: mesh
                    .name()
                    .map(str::to_string)
                    .unwrap_or_else(|| path.clone()),
                normals: super::per_vertex(normals, positions.len()),
                uvs: super::per_vertex(uvs, positions.len()),
                positions,
                triangles: indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
                material,
            };
            if m.normals.is_empty() {
                m.make_flat();
            }
            m.transform(world_from_object);
            self.scene.meshes.push(m);
        }
        Ok(())
    }
}

/// Checks that an accessor's elements lie inside its buffer view and the view inside its
/// buffer, so that reading it cannot run past the data.
fn check_accessor(accessor: &gltf::Accessor, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    let Some(view) = accessor.view() else {
        return Ok(());
    };
    let buffer_len = buffers
        .get(view.buffer().index())
        .map(|b| b.0.len())
        .unwrap_or(0);
    if view.offset() + view.length() > buffer_len {
        return Err(format!(
            "bufferViews[{}] (bytes {}..{}) runs past its buffer ({buffer_len} bytes)",
            view.index(),
            view.offset(),
            view.offset() + view.length()
        ));
    }
    let element = accessor.size();
    let stride = view.stride().unwrap_or(element);
    if accessor.count() > 0 {
        let end = accessor.offset() + stride * (accessor.count() - 1) + element;
        if end > view.length() {
            return Err(format!(
                "accessors[{}] needs {end} bytes of bufferViews[{}], which has {}",
                accessor.index(),
                view.index(),
                view.length()
            ));
        }
    }
    Ok(())
}

fn image_to_dynamic(data: &gltf::image::Data) -> Option<image::DynamicImage> {
    use gltf::image::Format;
    let (w, h, px) = (data.width, data.height, data.pixels.clone());
    Some(match data.format {
        Format::R8 => image::DynamicImage::ImageLuma8(image::ImageBuffer::from_raw(w, h, px)?),
        Format::R8G8 => image::DynamicImage::ImageLumaA8(image::ImageBuffer::from_raw(w, h, px)?),
        Format::R8G8B8 => image::DynamicImage::ImageRgb8(image::ImageBuffer::from_raw(w, h, px)?),
        Format::R8G8B8A8 => {
            image::DynamicImage::ImageRgba8(image::ImageBuffer::from_raw(w, h, px)?)
        }
        _ => return None,
    })
}

pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let shown = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| SceneError::io(&shown, e))?;
    convert(&shown, &bytes, || gltf::import(path))
}

/// A glTF or GLB document from memory, with its buffers and images embedded (data URIs or the
/// GLB's binary chunk); external files are not read. For fuzzing and tests.
pub fn load_slice(shown: &str, bytes: &[u8]) -> Result<Scene, SceneError> {
    convert(shown, bytes, || gltf::import_slice(bytes))
}

fn convert(
    shown: &str,
    bytes: &[u8],
    import: impl FnOnce() -> gltf::Result<(
            gltf::Document,
            Vec<gltf::buffer::Data>,
            Vec<gltf::image::Data>,
        )> + std::panic::UnwindSafe,
) -> Result<Scene, SceneError> {
    let shown = shown.to_string();
    super::gltf_check::json_of(bytes)
        .and_then(super::gltf_check::check)
        .map_err(|e| SceneError::invalid(&shown, format!("glTF: {e}")))?;
    // The checks above keep the gltf crate away from what made it panic; should a file still
    // find a panic in it, it becomes this file's error rather than a crash.
    let (document, buffers, images) = std::panic::catch_unwind(import)
        .map_err(|_| {
            SceneError::invalid(
                &shown,
                "glTF: the file broke the glTF parser (a malformed file the checks did not catch)",
            )
        })?
        .map_err(|e| {
            let reason = match e.to_string() {
                m if m.contains("failed to fill whole buffer") => {
                    "the file ends before the data it declares (truncated)".to_string()
                }
                m => m,
            };
            SceneError::invalid(&shown, format!("glTF: {reason}"))
        })?;
    let mut loader = Loader {
        shown: shown.clone(),
        buffers: &buffers,
        images: &images,
        scene: Scene::new(&shown),
        material_map: HashMap::new(),
        texture_map: HashMap::new(),
        camera_found: false,
        warned: Default::default(),
    };
    for extension in document.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&extension) {
            loader.warn_once(
                extension,
                format!("extension {extension} is not supported (ignored)"),
            );
        }
    }
    let Some(gltf_scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return Err(SceneError::invalid(&shown, "glTF has no scene"));
    };
    for node in gltf_scene.nodes() {
        loader.visit(node, Mat4::IDENTITY)?;
    }
    let camera_found = loader.camera_found;
    let mut scene = loader.scene;
    if !camera_found {
        scene.use_default_camera(&shown);
    }
    if scene.lights.is_empty()
        && scene
            .materials
            .iter()
            .any(|m| m.kind != MaterialKind::Unlit)
    {
        super::add_default_lighting(&mut scene, &shown);
    }
    scene.finalize(&shown)?;
    Ok(scene)
}
