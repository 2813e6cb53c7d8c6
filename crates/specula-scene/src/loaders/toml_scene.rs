//! TOML scene files: meshes and analytic shapes placed with transforms and materials, a
//! camera, lights and a background. Every table rejects unknown keys. The format is documented
//! with an example in `scenes/example.toml`.

use std::collections::BTreeMap;
use std::path::Path;

use glam::{DVec2, EulerRot, Mat4, Quat, Vec2, Vec3};
use serde::Deserialize;

use crate::freeform::{Freeform, Polynomial, Progressive, SagGrid};
use crate::generators::{self, LensSpec};
use crate::material::{conductor_f0, ior_from_abbe};
use crate::units::{LengthUnit, UpAxis};
use crate::{
    Background, Camera, Light, Material, MaterialKind, Mesh, Prescription, Scene, SceneError,
    Texture,
};

/// A colour or a grey level.
#[derive(Deserialize, Clone, Copy, Debug)]
#[serde(untagged)]
pub enum Color {
    Grey(f32),
    Rgb([f32; 3]),
}

impl Color {
    fn vec3(self) -> Vec3 {
        match self {
            Color::Grey(g) => Vec3::splat(g),
            Color::Rgb(c) => Vec3::from_array(c),
        }
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: Option<String>,
    /// Start from this built-in scene (`specula scenes`) instead of objects listed here; only
    /// `name`, `camera`, `[[move]]` and `[materials.NAME]` replacing one of its materials by
    /// name (e.g. another index of refraction) may be given with it.
    pub base: Option<String>,
    /// Rigid moves of named objects, applied in order after the objects are placed.
    #[serde(default, rename = "move")]
    pub moves: Vec<MoveSpec>,
    pub ambient: Option<Color>,
    pub camera: Option<CameraSpec>,
    pub background: Option<BackgroundSpec>,
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    #[serde(default)]
    pub objects: Vec<ObjectSpec>,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov() -> f32 {
    45.0
}
fn one() -> f32 {
    1.0
}
fn yes() -> bool {
    true
}

/// One rigid move of every mesh named `object`: a translation (world space, metres) or a
/// rotation about a world axis through the object's bounding-box centre, as the viewer does.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MoveSpec {
    pub object: String,
    pub translate: Option<[f32; 3]>,
    pub rotate: Option<RotateSpec>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct RotateSpec {
    pub axis: [f32; 3],
    pub degrees: f32,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    #[serde(default = "default_fov")]
    pub fov_y_deg: f32,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct BackgroundSpec {
    pub color: Option<Color>,
    /// Equirectangular image (PNG, HDR, EXR), relative to the scene file.
    pub image: Option<String>,
    #[serde(default = "one")]
    pub intensity: f32,
}

#[derive(Deserialize, Debug)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum MaterialSpec {
    Unlit {
        color: Option<Color>,
        texture: Option<String>,
        checker: Option<CheckerSpec>,
    },
    Diffuse {
        color: Option<Color>,
        texture: Option<String>,
        checker: Option<CheckerSpec>,
    },
    Mirror {
        /// F0, the reflectance at normal incidence.
        color: Option<Color>,
        /// A metal's index of refraction (one, or one per RGB channel), instead of `color`:
        /// F0 follows from it and `extinction`.
        ior: Option<Color>,
        /// The metal's extinction coefficient k (default 0), with `ior`.
        extinction: Option<Color>,
        #[serde(default = "yes")]
        fresnel: bool,
    },
    Dielectric {
        /// One IOR, or one per RGB channel.
        ior: Color,
        /// Abbe number: derives per-channel IORs from a single `ior`.
        abbe: Option<f32>,
        #[serde(default)]
        thin: bool,
    },
}

/// A procedural checkerboard texture: `squares` × `squares` squares per unit of UV, in two
/// colours (multiplied by the material's `color`).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CheckerSpec {
    pub squares: u32,
    pub colors: [Color; 2],
}

#[derive(Deserialize, Debug)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightSpec {
    Point {
        position: [f32; 3],
        intensity: Color,
    },
    Directional {
        /// The direction light travels.
        direction: [f32; 3],
        irradiance: Color,
    },
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        intensity: Color,
        inner_cone_deg: f32,
        outer_cone_deg: f32,
    },
}

#[derive(Deserialize, Clone, Copy, Debug)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    pub name: Option<String>,
    /// Required, except for a spectacle lens, which makes its glass from its index and Abbe
    /// number when none is given.
    pub material: Option<String>,
    pub translate: Option<[f32; 3]>,
    /// Euler angles in degrees, applied about X, then Y, then Z.
    pub rotate_deg: Option<[f32; 3]>,
    pub scale: Option<Scale>,
    /// Replace the shape's normals by its face normals (a flat-shaded mesh, as files without
    /// normals are in glTF).
    #[serde(default)]
    pub flat: bool,
    pub shape: ShapeSpec,
}

/// One placed part of a `merged` shape.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct PartSpec {
    pub translate: Option<[f32; 3]>,
    pub rotate_deg: Option<[f32; 3]>,
    pub scale: Option<Scale>,
    pub shape: ShapeSpec,
}

fn n48() -> u32 {
    48
}
fn n192() -> u32 {
    192
}
fn n24() -> u32 {
    24
}
fn n16() -> u32 {
    16
}
fn n6() -> u32 {
    6
}
fn n8() -> u32 {
    8
}
fn n1() -> u32 {
    1
}

/// A free-form lens surface (crate::freeform): exactly one of these keys.
#[derive(Deserialize, Debug, Clone)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum SurfaceSpec {
    /// A CSV file of sags in mm, relative to the scene file.
    SagGrid(String),
    /// [[i, j, c], ...]: s = Σ c x^i y^j, millimetres.
    Polynomial(Vec<[f64; 3]>),
    /// The progressive surface built in code, on the base curve's sphere: metres and
    /// dioptres.
    Progressive {
        add: f64,
        corridor_length: f64,
        blend_width: f64,
    },
}

#[derive(Deserialize, Debug)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ShapeSpec {
    Sphere {
        radius: f32,
        #[serde(default = "n48")]
        segments: u32,
        #[serde(default = "n24")]
        rings: u32,
    },
    Cap {
        radius_of_curvature: f32,
        aperture: f32,
        #[serde(default)]
        concave: bool,
        #[serde(default = "n16")]
        rings: u32,
        #[serde(default = "n48")]
        segments: u32,
    },
    /// Bicubic Bézier patch: 16 control points, row by row (default: the door mirror).
    Patch {
        control: Option<Vec<[f32; 3]>>,
        #[serde(default = "n6")]
        resolution: u32,
    },
    Lens {
        /// Signed radii (optics convention, light along +Z); `inf` for a flat surface.
        front_radius: f32,
        back_radius: f32,
        center_thickness: f32,
        diameter: f32,
        #[serde(default = "n16")]
        rings: u32,
        #[serde(default = "n48")]
        segments: u32,
    },
    /// A spectacle lens made from a prescription (crate::spectacle): powers in dioptres, the
    /// axis in TABO degrees, lengths in metres, the base curve in the material's own index.
    SpectacleLens {
        sphere: f64,
        #[serde(default)]
        cylinder: f64,
        #[serde(default)]
        axis: f64,
        index: f64,
        abbe: f64,
        center_thickness: f64,
        /// Required unless the front is free-form (then its power at the vertex).
        base_curve: Option<f64>,
        diameter: f64,
        #[serde(default = "n48")]
        rings: u32,
        #[serde(default = "n192")]
        segments: u32,
        /// A free-form front (crate::freeform) in place of the base curve's sphere.
        front: Option<SurfaceSpec>,
        /// A free-form back in place of the torus solved from sphere, cylinder and axis.
        back: Option<SurfaceSpec>,
        /// A progressive lens's ordered addition, dioptres.
        add: Option<f64>,
        /// Reference points, millimetres in the lens frame (x right, y up).
        distance_reference: Option<[f64; 2]>,
        near_reference: Option<[f64; 2]>,
    },
    Box {
        size: [f32; 3],
    },
    Plane {
        size: [f32; 2],
        #[serde(default = "n1")]
        subdivisions: u32,
    },
    /// The six inward-facing walls of a closed box, floor at y = 0, centred over the origin;
    /// UVs are metres along each wall, so a texture repeats every metre.
    Room {
        size: [f32; 3],
    },
    /// Several shapes, each placed by its own transform, joined into one mesh, as files often
    /// join the objects that share a material.
    Merged {
        parts: Vec<PartSpec>,
    },
    Teapot {
        #[serde(default = "n8")]
        resolution: u32,
    },
    Mesh(MeshShape),
    /// A STEP file's bodies (crate::loaders::step), relative to the scene file: all of them, or
    /// the one `body` names (a product, solid, surface model or shell, or `#id`). `tolerance_mm`
    /// is the tessellation's chord tolerance; `unit` overrides the file's own length unit and
    /// `up = "z"` turns a +Z-up file's +Z onto the world's +Y.
    Step {
        file: String,
        body: Option<String>,
        tolerance_mm: Option<f64>,
        /// As a mesh shape's: read by `file_units` so that an error names the key.
        unit: Option<String>,
        up: Option<String>,
    },
}

/// A mesh file (OBJ, PLY, STL), relative to the scene file. `unit` and `up` say what its
/// coordinates are (default: metres, +Y up), taken to world space before the object's placement.
/// `fit` rescales it instead so its largest extent is `fit` metres, centred over the origin and
/// standing on y = 0.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MeshShape {
    pub file: String,
    pub fit: Option<f32>,
    /// "mm", "cm", "m" or "in"; read here, not by serde, so that an error names the key.
    pub unit: Option<String>,
    /// "y" or "z".
    pub up: Option<String>,
}

/// Moves and scales meshes together so their joint bounding box is centred over the origin in
/// X and Z, stands on y = 0, and has `size` as its largest extent.
pub fn fit_meshes(meshes: &mut [Mesh], size: f32) {
    let bounds = meshes
        .iter()
        .fold(crate::Aabb::EMPTY, |b, m| b.union(&m.bounds()));
    let largest = bounds.extent().max_element();
    if largest <= 0.0 {
        return;
    }
    let scale = size / largest;
    let anchor = Vec3::new(bounds.center().x, bounds.min.y, bounds.center().z);
    for mesh in meshes {
        for p in &mut mesh.positions {
            *p = (*p - anchor) * scale;
        }
    }
}

fn placement(
    translate: Option<[f32; 3]>,
    rotate_deg: Option<[f32; 3]>,
    scale: Option<Scale>,
) -> Result<Mat4, SceneError> {
    let translate = Vec3::from_array(translate.unwrap_or_default());
    let [rx, ry, rz] = rotate_deg.unwrap_or_default().map(f32::to_radians);
    let rotation = Quat::from_euler(EulerRot::ZYX, rz, ry, rx);
    let scale = match scale.unwrap_or(Scale::Uniform(1.0)) {
        Scale::Uniform(s) => Vec3::splat(s),
        Scale::PerAxis(s) => Vec3::from_array(s),
    };
    let m = Mat4::from_scale_rotation_translation(scale, rotation, translate);
    if !m.is_finite() || m.determinant() == 0.0 {
        return Err(SceneError::invalid("transform", "singular or not finite"));
    }
    Ok(m)
}

/// A spectacle-lens shape's prescription and tessellation (None for other shapes), its
/// free-form surfaces read relative to `base`.
fn prescription_of(
    shape: &ShapeSpec,
    base: &Path,
) -> Result<Option<(Prescription, u32, u32)>, SceneError> {
    let ShapeSpec::SpectacleLens {
        sphere,
        cylinder,
        axis,
        index,
        abbe,
        center_thickness,
        base_curve,
        diameter,
        rings,
        segments,
        front,
        back,
        add,
        distance_reference,
        near_reference,
    } = shape
    else {
        return Ok(None);
    };
    let mm = |p: &Option<[f64; 2]>| p.map(|[x, y]| DVec2::new(x, y) * 1e-3);
    let mut p = Prescription {
        sphere: *sphere,
        cylinder: *cylinder,
        axis_deg: *axis,
        index: *index,
        abbe: *abbe,
        center_thickness: *center_thickness,
        base_curve: base_curve.unwrap_or(f64::NAN),
        diameter: *diameter,
        add_d: *add,
        distance_reference: mm(distance_reference),
        near_reference: mm(near_reference),
        ..Prescription::default()
    };
    if let Some(spec) = front {
        let surface = freeform_of(spec, "front", &p, base)?;
        if let Freeform::Progressive(design) = &surface {
            p.distance_reference = p.distance_reference.or(Some(design.far_reference()));
            p.near_reference = p.near_reference.or(Some(design.near_reference()));
            p.add_d = p.add_d.or(Some(design.add_d));
        }
        let [k1, k2] = surface
            .local(0.0, 0.0)
            .map(|l| l.principal_curvatures())
            .ok_or_else(|| SceneError::invalid("front", "the surface has no vertex at (0, 0)"))?;
        let at_vertex = (index - 1.0) * 0.5 * (k1 + k2);
        match base_curve {
            None => p.base_curve = at_vertex,
            Some(given) if (given - at_vertex).abs() > 0.01 => {
                return Err(SceneError::invalid(
                    "base_curve",
                    format!(
                        "{given} D, where the free-form front's power at its vertex is \
                         {at_vertex:.3} D: leave base_curve out, or make them agree"
                    ),
                ))
            }
            Some(_) => {}
        }
        p.front = Some(surface);
    } else if base_curve.is_none() {
        return Err(SceneError::invalid(
            "base_curve",
            "missing: a spectacle lens needs its base curve (unless its front is free-form)",
        ));
    }
    if let Some(spec) = back {
        if matches!(spec, SurfaceSpec::Progressive { .. }) {
            return Err(SceneError::invalid(
                "back",
                "the built-in progressive design is a front surface",
            ));
        }
        p.back = Some(freeform_of(spec, "back", &p, base)?);
    }
    Ok(Some((p, *rings, *segments)))
}

/// The free-form surface a `front` or `back` table names.
fn freeform_of(
    spec: &SurfaceSpec,
    side: &str,
    p: &Prescription,
    base: &Path,
) -> Result<Freeform, SceneError> {
    let bad = |message: String| SceneError::invalid(side, message);
    Ok(match spec {
        SurfaceSpec::SagGrid(file) => {
            let path = base.join(file);
            let text =
                std::fs::read_to_string(&path).map_err(|e| SceneError::io(path.display(), e))?;
            Freeform::SagGrid(std::sync::Arc::new(SagGrid::parse(
                &text,
                &path.display().to_string(),
            )?))
        }
        SurfaceSpec::Polynomial(terms) => {
            let mut out = Vec::with_capacity(terms.len());
            for (k, &[i, j, c]) in terms.iter().enumerate() {
                let power =
                    |v: f64| (v >= 0.0 && v.fract() == 0.0 && v <= 20.0).then_some(v as u32);
                let (Some(i), Some(j)) = (power(i), power(j)) else {
                    return Err(bad(format!(
                        "polynomial[{k}]: the powers {i} and {j} must be whole numbers from 0 \
                         to 20"
                    )));
                };
                if !c.is_finite() {
                    return Err(bad(format!(
                        "polynomial[{k}]: the coefficient {c} is not a number"
                    )));
                }
                if i + j < 2 && c != 0.0 {
                    return Err(bad(format!(
                        "polynomial[{k}]: x^{i} y^{j} would tilt or lift the surface off its \
                         vertex; a sag is measured from the vertex, along the axis"
                    )));
                }
                out.push((i, j, c));
            }
            Freeform::Polynomial(Polynomial { terms: out })
        }
        SurfaceSpec::Progressive {
            add,
            corridor_length,
            blend_width,
        } => {
            let values = [
                ("add", *add),
                ("corridor_length", *corridor_length),
                ("blend_width", *blend_width),
            ];
            if let Some((name, v)) = values.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
                return Err(bad(format!("progressive.{name} = {v}: must be positive")));
            }
            if !p.base_curve.is_finite() {
                return Err(bad(
                    "a progressive front is built on the base curve's sphere: give base_curve"
                        .into(),
                ));
            }
            Freeform::Progressive(Progressive::new(
                p.base_curve / (p.index - 1.0),
                *add,
                p.index,
                *corridor_length,
                *blend_width,
            ))
        }
    })
}

fn shape_meshes(
    shape: &ShapeSpec,
    base: &Path,
    warnings: &mut Vec<String>,
) -> Result<Vec<Mesh>, SceneError> {
    Ok(match shape {
        ShapeSpec::Sphere {
            radius,
            segments,
            rings,
        } => vec![generators::sphere(*radius, *segments, *rings)],
        ShapeSpec::Cap {
            radius_of_curvature,
            aperture,
            concave,
            rings,
            segments,
        } => vec![generators::spherical_cap(
            *radius_of_curvature,
            *aperture,
            *concave,
            *rings,
            *segments,
        )?],
        ShapeSpec::Patch {
            control,
            resolution,
        } => {
            let control = match control {
                None => generators::door_mirror_control_points(),
                Some(points) if points.len() == 16 => {
                    let mut c = [[Vec3::ZERO; 4]; 4];
                    for (k, p) in points.iter().enumerate() {
                        c[k / 4][k % 4] = Vec3::from_array(*p);
                    }
                    c
                }
                Some(points) => {
                    return Err(SceneError::invalid(
                        "patch",
                        format!("needs 16 control points, got {}", points.len()),
                    ))
                }
            };
            vec![generators::bicubic_patch(&control, *resolution)]
        }
        ShapeSpec::Lens {
            front_radius,
            back_radius,
            center_thickness,
            diameter,
            rings,
            segments,
        } => vec![generators::lens(&LensSpec {
            front_radius: *front_radius,
            back_radius: *back_radius,
            center_thickness: *center_thickness,
            diameter: *diameter,
            rings: *rings,
            segments: *segments,
        })?],
        ShapeSpec::SpectacleLens { .. } => {
            let (prescription, rings, segments) =
                prescription_of(shape, base)?.expect("a spectacle lens has one");
            vec![crate::spectacle::spectacle_lens(
                &prescription,
                rings,
                segments,
            )?]
        }
        ShapeSpec::Box { size } => vec![generators::cuboid(Vec3::from_array(*size))],
        ShapeSpec::Plane { size, subdivisions } => {
            vec![generators::plane(Vec2::from_array(*size), *subdivisions)]
        }
        ShapeSpec::Teapot { resolution } => vec![generators::teapot(*resolution)],
        ShapeSpec::Room { size } => vec![generators::room(Vec3::from_array(*size))],
        ShapeSpec::Merged { parts } => {
            let mut joined = Mesh {
                name: "merged".into(),
                ..Default::default()
            };
            for (i, part) in parts.iter().enumerate() {
                let at = |e: SceneError| SceneError::invalid(format!("parts[{i}]"), e.to_string());
                let world_from_part =
                    placement(part.translate, part.rotate_deg, part.scale).map_err(at)?;
                for mut mesh in shape_meshes(&part.shape, base, warnings).map_err(at)? {
                    if mesh.normals.is_empty() {
                        mesh.compute_smooth_normals();
                    }
                    mesh.transform(world_from_part);
                    joined.append(&mesh);
                }
            }
            if joined.triangles.is_empty() {
                return Err(SceneError::invalid("parts", "no part has a triangle"));
            }
            vec![joined]
        }
        ShapeSpec::Step {
            file,
            body,
            tolerance_mm,
            unit,
            up,
        } => {
            let (unit, up) = file_units(unit, up)?;
            let options = super::step::StepOptions {
                body: body.clone(),
                tolerance_mm: tolerance_mm.unwrap_or(super::step::DEFAULT_TOLERANCE_MM),
                unit,
                up,
            };
            step_file(&base.join(file), &options, warnings)?
        }
        ShapeSpec::Mesh(mesh) => mesh_file(mesh, base, warnings)?,
    })
}

/// A STEP file's bodies, its warnings added to the scene's.
fn step_file(
    path: &Path,
    options: &super::step::StepOptions,
    warnings: &mut Vec<String>,
) -> Result<Vec<Mesh>, SceneError> {
    let mut step = super::step::read(path, options)?;
    warnings.append(&mut step.warnings);
    Ok(step.meshes)
}

/// A `mesh` shape's meshes: the file's, taken from its unit and up axis to metres and +Y up,
/// or fitted to `fit` metres.
fn mesh_file(
    shape: &MeshShape,
    base: &Path,
    warnings: &mut Vec<String>,
) -> Result<Vec<Mesh>, SceneError> {
    let (unit, up) = file_units(&shape.unit, &shape.up)?;
    if shape.fit.is_some() && unit.is_some() {
        return Err(SceneError::invalid(
            "unit",
            "give either fit or unit, not both: fit rescales the mesh whatever its unit",
        ));
    }
    let path = base.join(&shape.file);
    let (mut meshes, _, _, mut file_warnings) = super::load_mesh_file(&path)?;
    warnings.append(&mut file_warnings);
    // Without either, the mesh stays as it always loaded (a transform would renormalise
    // the file's normals).
    if unit.is_some() || up != UpAxis::Y {
        let metres_per_unit = unit.map_or(1.0, LengthUnit::metres);
        let world_from_file = crate::units::world_from_file(metres_per_unit, up);
        for mesh in &mut meshes {
            mesh.transform(world_from_file.as_mat4());
        }
    }
    match shape.fit {
        Some(size) => fit_meshes(&mut meshes, size),
        None if unit.is_none() => warnings.extend(crate::plausibility::unitless_file_warning(
            &path.display().to_string(),
            &meshes,
        )),
        None => {}
    }
    Ok(meshes)
}

/// A file shape's `unit` (None where not given) and `up` (+Y where not given).
fn file_units(
    unit: &Option<String>,
    up: &Option<String>,
) -> Result<(Option<LengthUnit>, UpAxis), SceneError> {
    let unit = unit
        .as_deref()
        .map(str::parse)
        .transpose()
        .map_err(|e| SceneError::invalid("unit", e))?;
    let up = up
        .as_deref()
        .map_or(Ok(UpAxis::Y), str::parse)
        .map_err(|e| SceneError::invalid("up", e))?;
    Ok((unit, up))
}

fn material_from_spec(
    name: &str,
    spec: &MaterialSpec,
    base: &Path,
    textures: &mut Vec<Texture>,
) -> Result<Material, SceneError> {
    let grey = |c: &Option<Color>, d: f32| c.map(Color::vec3).unwrap_or(Vec3::splat(d));
    let mut texture_file = None;
    let mut checker_spec = None;
    let material = match spec {
        MaterialSpec::Unlit {
            color,
            texture,
            checker,
        } => {
            texture_file = texture.clone();
            checker_spec = checker.as_ref();
            Material::unlit(name, grey(color, 1.0))
        }
        MaterialSpec::Diffuse {
            color,
            texture,
            checker,
        } => {
            texture_file = texture.clone();
            checker_spec = checker.as_ref();
            Material::diffuse(name, grey(color, if checker.is_some() { 1.0 } else { 0.8 }))
        }
        MaterialSpec::Mirror {
            color,
            ior,
            extinction,
            fresnel,
        } => {
            let f0 = match (color, ior, extinction) {
                (Some(_), Some(_), _) => {
                    return Err(SceneError::invalid(
                        format!("materials.{name}"),
                        "give either color (F0) or ior with extinction, not both",
                    ))
                }
                (_, None, Some(_)) => {
                    return Err(SceneError::invalid(
                        format!("materials.{name}"),
                        "extinction needs ior",
                    ))
                }
                (_, Some(n), k) => conductor_f0(n.vec3(), k.map(Color::vec3).unwrap_or(Vec3::ZERO)),
                (color, None, None) => grey(color, 0.95),
            };
            Material::new(name, MaterialKind::Mirror { fresnel: *fresnel }, f0)
        }
        MaterialSpec::Dielectric { ior, abbe, thin } => {
            let ior = match (ior, abbe) {
                (Color::Grey(n), Some(v)) => ior_from_abbe(*n, *v),
                (Color::Rgb(_), Some(_)) => {
                    return Err(SceneError::invalid(
                        format!("materials.{name}"),
                        "give either one ior with an abbe number, or three iors",
                    ))
                }
                (ior, None) => ior.vec3(),
            };
            Material::new(
                name,
                MaterialKind::Dielectric {
                    ior,
                    thin_walled: *thin,
                },
                Vec3::ONE,
            )
        }
    };
    let mut material = material;
    let texture = match (texture_file, checker_spec) {
        (Some(_), Some(_)) => {
            return Err(SceneError::invalid(
                format!("materials.{name}"),
                "give either texture or checker, not both",
            ))
        }
        (Some(file), None) => Some(Texture::load(&base.join(file), true)?),
        (None, Some(checker)) => Some(checker_texture(name, checker)?),
        (None, None) => None,
    };
    if let Some(texture) = texture {
        textures.push(texture);
        material.texture = Some(textures.len() - 1);
    }
    Ok(material)
}

fn checker_texture(name: &str, spec: &CheckerSpec) -> Result<Texture, SceneError> {
    if !(1..=256).contains(&spec.squares) {
        return Err(SceneError::invalid(
            format!("materials.{name}.checker.squares"),
            format!("{} is not from 1 to 256", spec.squares),
        ));
    }
    let [a, b] = spec.colors.map(Color::vec3);
    // Eight texels a square keep the squares' edges sharp under bilinear filtering.
    Ok(Texture::checker(name, spec.squares, spec.squares * 8, a, b))
}

/// Parses a scene from TOML text; relative file names resolve against `base`.
pub fn parse(shown: &str, text: &str, base: &Path) -> Result<Scene, SceneError> {
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        SceneError::invalid(shown, e.to_string().trim_end().replace('\n', "\n    "))
    })?;
    let mut scene = match &file.base {
        Some(name) => based_scene(shown, &file, name, base)?,
        None => listed_scene(shown, &file, base)?,
    };
    for (i, m) in file.moves.iter().enumerate() {
        apply_move(&mut scene, m)
            .map_err(|e| SceneError::invalid(shown, format!("move[{i}]: {e}")))?;
    }
    scene.finalize(shown)?;
    Ok(scene)
}

/// A built-in scene with the file's name and camera, when given.
fn based_scene(
    shown: &str,
    file: &SceneFile,
    name: &str,
    base: &Path,
) -> Result<Scene, SceneError> {
    let listed = [
        ("ambient", file.ambient.is_some()),
        ("background", file.background.is_some()),
        ("lights", !file.lights.is_empty()),
        ("objects", !file.objects.is_empty()),
    ];
    if let Some((key, _)) = listed.iter().find(|(_, given)| *given) {
        return Err(SceneError::invalid(
            shown,
            format!(
                "{key}: not allowed with base = \"{name}\" (only name, camera, [[move]] and materials replacing the base's are)"
            ),
        ));
    }
    let mut scene = crate::builtin::by_name(name).ok_or_else(|| {
        SceneError::invalid(
            shown,
            format!(
                "base: unknown built-in scene '{name}' (built-in: {})",
                crate::builtin::names().join(", ")
            ),
        )
    })??;
    if let Some(name) = &file.name {
        scene.name = name.clone();
    }
    if let Some(c) = &file.camera {
        scene.camera = camera_from_spec(c);
    }
    for (material_name, spec) in &file.materials {
        let at = |e: String| SceneError::invalid(shown, format!("materials.{material_name}: {e}"));
        let Some(index) = scene
            .materials
            .iter()
            .position(|m| &m.name == material_name)
        else {
            let known: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
            return Err(at(format!(
                "base \"{name}\" has no material of that name (its materials: {})",
                known.join(", ")
            )));
        };
        let mut textures = Vec::new();
        let material = material_from_spec(material_name, spec, base, &mut textures)
            .map_err(|e| at(e.to_string()))?;
        if !textures.is_empty() {
            return Err(at(
                "a texture may not replace a base scene's material".into()
            ));
        }
        scene.materials[index] = material;
    }
    Ok(scene)
}

/// A spectacle lens's given material must be the glass its prescription was computed for.
fn lens_glass_agrees(material: &Material, p: &Prescription) -> Result<(), String> {
    let wanted = p.indices();
    match material.kind {
        MaterialKind::Dielectric {
            ior,
            thin_walled: false,
        } if (ior - wanted).abs().max_element() <= 1e-4 => Ok(()),
        MaterialKind::Dielectric {
            ior,
            thin_walled: false,
        } => Err(format!(
            "'{}' has indices {:.4} / {:.4} / {:.4}, but the prescription's index {} and Abbe \
             number {} give {:.4} / {:.4} / {:.4}: make them agree (e.g. type = \"dielectric\", \
             ior = {}, abbe = {}), or leave material out and the lens makes its own",
            material.name,
            ior.x,
            ior.y,
            ior.z,
            p.index,
            p.abbe,
            wanted.x,
            wanted.y,
            wanted.z,
            p.index,
            p.abbe
        )),
        _ => Err(format!(
            "'{}' is not a solid dielectric: a spectacle lens is glass (leave material out and \
             the lens makes its own)",
            material.name
        )),
    }
}

fn camera_from_spec(c: &CameraSpec) -> Camera {
    Camera {
        eye: Vec3::from_array(c.eye),
        target: Vec3::from_array(c.target),
        up: Vec3::from_array(c.up),
        fov_y_deg: c.fov_y_deg,
        aspect: None,
    }
}

fn apply_move(scene: &mut Scene, m: &MoveSpec) -> Result<(), String> {
    let meshes: Vec<usize> = (0..scene.meshes.len())
        .filter(|&i| scene.meshes[i].name == m.object)
        .collect();
    if meshes.is_empty() {
        let mut names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
        names.dedup();
        return Err(format!(
            "object: no object named '{}' (objects: {})",
            m.object,
            names.join(", ")
        ));
    }
    let world_from_before = match (&m.translate, &m.rotate) {
        (Some(by), None) => {
            let by = Vec3::from_array(*by);
            if !by.is_finite() {
                return Err(format!("translate: not finite: {by}"));
            }
            Mat4::from_translation(by)
        }
        (None, Some(r)) => {
            let bounds = meshes
                .iter()
                .map(|&i| scene.meshes[i].bounds())
                .reduce(|a, b| a.union(&b))
                .expect("at least one mesh");
            crate::mesh::rotation_about(bounds.center(), Vec3::from_array(r.axis), r.degrees)
                .ok_or_else(|| format!("rotate: axis {:?} is zero or not finite, or degrees {} is not finite", r.axis, r.degrees))?
        }
        _ => return Err("give exactly one of translate = [x, y, z] or rotate = { axis = [x, y, z], degrees = a }".into()),
    };
    for i in meshes {
        scene.meshes[i].transform(world_from_before);
    }
    Ok(())
}

/// A scene from the file's own materials, objects and lights.
fn listed_scene(shown: &str, file: &SceneFile, base: &Path) -> Result<Scene, SceneError> {
    let at = |path: String, e: SceneError| SceneError::invalid(shown, format!("{path}: {e}"));
    let mut warnings = Vec::new();
    let mut textures = Vec::new();
    let mut materials = Vec::new();
    let mut material_index = BTreeMap::new();
    for (name, spec) in &file.materials {
        let m = material_from_spec(name, spec, base, &mut textures)
            .map_err(|e| at(format!("materials.{name}"), e))?;
        material_index.insert(name.clone(), materials.len());
        materials.push(m);
    }
    let mut meshes = Vec::new();
    let mut prescriptions = Vec::new();
    for (i, object) in file.objects.iter().enumerate() {
        let path = format!("objects[{i}]");
        let prescription = prescription_of(&object.shape, base)
            .map_err(|e| at(format!("{path}.shape"), e))?
            .map(|(p, _, _)| p);
        let material = object_material(
            shown,
            &path,
            object,
            prescription.as_ref(),
            &material_index,
            &mut materials,
        )?;
        if prescription.is_some() && object.scale.is_some() {
            return Err(SceneError::invalid(
                shown,
                format!(
                    "{path}.scale: a spectacle lens is made to its prescription's size; a scale \
                     would change its powers (or mirror its axis): set the diameter instead"
                ),
            ));
        }
        let world_from_object = placement(object.translate, object.rotate_deg, object.scale)
            .map_err(|e| at(path.clone(), e))?;
        let shape_meshes = shape_meshes(&object.shape, base, &mut warnings)
            .map_err(|e| at(format!("{path}.shape"), e))?;
        // A STEP file's bodies keep their own names under the object's: `door/glass`.
        let several_bodies =
            matches!(object.shape, ShapeSpec::Step { .. }) && shape_meshes.len() > 1;
        for mut mesh in shape_meshes {
            if let Some(name) = &object.name {
                mesh.name = if several_bodies {
                    format!("{name}/{}", mesh.name)
                } else {
                    name.clone()
                };
            }
            mesh.check_topology(shown)?;
            if object.flat {
                mesh.make_flat();
            } else if mesh.normals.is_empty() {
                mesh.compute_smooth_normals();
            }
            mesh.transform(world_from_object);
            mesh.material = material;
            if let Some(p) = &prescription {
                prescriptions.push((mesh.name.clone(), p.clone()));
            }
            meshes.push(mesh);
        }
    }
    let lights = file.lights.iter().map(LightSpec::light).collect::<Vec<_>>();
    let background = background(shown, file, base, &mut textures)?;
    let mut scene = Scene::new(file.name.clone().unwrap_or_else(|| shown.to_string()));
    scene.meshes = meshes;
    scene.materials = materials;
    scene.textures = textures;
    scene.lights = lights;
    scene.background = background;
    scene.ambient = file.ambient.map(Color::vec3).unwrap_or(Vec3::ZERO);
    scene.warnings = warnings;
    scene.prescriptions = prescriptions;
    match &file.camera {
        Some(c) => scene.camera = camera_from_spec(c),
        None => scene.use_default_camera(shown),
    }
    if scene.lights.is_empty()
        && scene
            .materials
            .iter()
            .any(|m| m.kind == MaterialKind::Diffuse)
    {
        scene.warnings.push(format!(
            "{shown}: no [[lights]]: diffuse surfaces receive only the ambient light"
        ));
    }
    Ok(scene)
}

/// An object's material: the named one (which must agree with a spectacle lens's glass), or
/// the glass a spectacle lens's prescription makes.
fn object_material(
    shown: &str,
    path: &str,
    object: &ObjectSpec,
    prescription: Option<&Prescription>,
    material_index: &BTreeMap<String, usize>,
    materials: &mut Vec<Material>,
) -> Result<usize, SceneError> {
    Ok(match (&object.material, prescription) {
        (Some(name), _) => {
            let Some(&material) = material_index.get(name) else {
                let known: Vec<&str> = material_index.keys().map(String::as_str).collect();
                return Err(SceneError::invalid(
                    shown,
                    format!(
                        "{path}.material: unknown material '{name}' (defined: {})",
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                ));
            };
            if let Some(p) = &prescription {
                lens_glass_agrees(&materials[material], p)
                    .map_err(|e| SceneError::invalid(shown, format!("{path}.material: {e}")))?;
            }
            material
        }
        (None, Some(p)) => {
            let name = object
                .name
                .clone()
                .unwrap_or_else(|| "spectacle lens".into());
            materials.push(Material::new(
                format!("{name} glass"),
                MaterialKind::Dielectric {
                    ior: p.indices(),
                    thin_walled: false,
                },
                Vec3::ONE,
            ));
            materials.len() - 1
        }
        (None, None) => {
            return Err(SceneError::invalid(
                shown,
                format!(
                    "{path}.material: missing (only a spectacle-lens shape makes its own \
                     glass)"
                ),
            ))
        }
    })
}

impl LightSpec {
    fn light(&self) -> Light {
        match *self {
            LightSpec::Point {
                position,
                intensity,
            } => Light::Point {
                position: Vec3::from_array(position),
                intensity: intensity.vec3(),
            },
            LightSpec::Directional {
                direction,
                irradiance,
            } => Light::Directional {
                direction: Vec3::from_array(direction).normalize_or_zero(),
                irradiance: irradiance.vec3(),
            },
            LightSpec::Spot {
                position,
                direction,
                intensity,
                inner_cone_deg,
                outer_cone_deg,
            } => Light::Spot {
                position: Vec3::from_array(position),
                direction: Vec3::from_array(direction).normalize_or_zero(),
                intensity: intensity.vec3(),
                inner_cone: inner_cone_deg.to_radians(),
                outer_cone: outer_cone_deg.to_radians(),
            },
        }
    }
}

/// The background: a colour (black by default) or an equirectangular image, loaded into
/// `textures`.
fn background(
    shown: &str,
    file: &SceneFile,
    base: &Path,
    textures: &mut Vec<Texture>,
) -> Result<Background, SceneError> {
    Ok(match &file.background {
        None => Background::Color(Vec3::ZERO),
        Some(BackgroundSpec {
            image: Some(image),
            intensity,
            color,
        }) => {
            if color.is_some() {
                return Err(SceneError::invalid(
                    shown,
                    "background: give either color or image, not both",
                ));
            }
            textures.push(
                Texture::load(&base.join(image), true)
                    .map_err(|e| SceneError::invalid(shown, format!("background.image: {e}")))?,
            );
            Background::Equirect {
                texture: textures.len() - 1,
                intensity: *intensity,
            }
        }
        Some(BackgroundSpec { color, .. }) => {
            Background::Color(color.map(Color::vec3).unwrap_or(Vec3::ZERO))
        }
    })
}

pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let shown = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::io(&shown, e))?;
    parse(&shown, &text, path.parent().unwrap_or(Path::new(".")))
}
