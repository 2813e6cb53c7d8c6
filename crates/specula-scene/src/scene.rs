use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::{Aabb, Camera, Light, Material, Mesh, SceneError, Texture};

/// What a ray that leaves the scene sees.
#[derive(Clone, Debug, PartialEq)]
pub enum Background {
    Color(Vec3),
    /// An equirectangular (latitude–longitude) image: +Y is up, the image's centre column looks
    /// down -Z, u grows towards +X (see docs/conventions.md).
    Equirect {
        texture: usize,
        intensity: f32,
    },
}

impl Background {
    pub fn radiance(&self, direction: Vec3, textures: &[Texture]) -> Vec3 {
        match *self {
            Background::Color(c) => c,
            Background::Equirect { texture, intensity } => {
                textures[texture].sample(equirect_uv(direction)) * intensity
            }
        }
    }
}

/// Texture coordinate of a unit world direction in an equirectangular map.
pub fn equirect_uv(direction: Vec3) -> Vec2 {
    let u = 0.5 + direction.x.atan2(-direction.z) / (2.0 * PI);
    let v = direction.y.clamp(-1.0, 1.0).acos() / PI;
    Vec2::new(u, v)
}

/// A complete scene: world-space meshes (metres) with their materials, lights, a camera and a
/// background. `warnings` collects what the loaders accepted but want a user to know.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub background: Background,
    /// Constant ambient radiance that diffuse surfaces reflect (albedo × ambient) in addition to
    /// their lights, so that shadowed parts are not pitch black. Default zero.
    pub ambient: Vec3,
    pub warnings: Vec<String>,
    /// The prescription each spectacle lens made from one was made from, by object name (what
    /// `specula analyze lens` compares the lens's powers with).
    pub prescriptions: Vec<(String, crate::Prescription)>,
}

impl Scene {
    /// A scene with nothing in it yet: black background, no ambient light, and a placeholder
    /// camera that loaders replace (or frame with [`Scene::use_default_camera`]).
    pub fn new(name: impl Into<String>) -> Scene {
        Scene {
            name: name.into(),
            meshes: vec![],
            materials: vec![],
            textures: vec![],
            lights: vec![],
            camera: Scene::default_camera(&Aabb::EMPTY),
            background: Background::Color(Vec3::ZERO),
            ambient: Vec3::ZERO,
            warnings: vec![],
            prescriptions: vec![],
        }
    }

    /// For a file that has no camera: frames the scene with [`Scene::default_camera`] and says
    /// so in a warning naming `source`.
    pub fn use_default_camera(&mut self, source: &str) {
        self.camera = Scene::default_camera(&self.bounds());
        self.warnings.push(format!(
            "{source}: no camera; chose a default framing from +Z looking at the bounding box centre"
        ));
    }

    pub fn bounds(&self) -> Aabb {
        self.meshes
            .iter()
            .fold(Aabb::EMPTY, |b, m| b.union(&m.bounds()))
    }

    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }

    /// The view chosen when a scene has no camera: from +Z and a little above, looking at the
    /// centre of the bounding box, far enough that its bounding sphere fits a 45° field of view.
    pub fn default_camera(bounds: &Aabb) -> Camera {
        let (center, radius) = if bounds.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (bounds.center(), bounds.radius().max(1e-3))
        };
        let fov_y_deg: f32 = 45.0;
        let distance = radius / (fov_y_deg.to_radians() * 0.5).sin() * 1.05;
        let direction = Vec3::new(0.0, 0.35, 1.0).normalize();
        Camera {
            eye: center + direction * distance,
            target: center,
            up: Vec3::Y,
            fov_y_deg,
            aspect: None,
        }
    }

    /// Replaces each mirror or glass mesh that holds several separate objects (files often merge
    /// objects by material) by one mesh per object, named `NAME#1`, `NAME#2`..., so that every
    /// technique treats each as its own reflector and the viewer can move each. See
    /// [`Mesh::separate_objects`]; a warning says what was split. Only the meshes `chosen`
    /// picks are looked at (the others were split when loaded).
    pub(crate) fn split_separate_reflectors(
        &mut self,
        source: &str,
        chosen: impl Fn(&Mesh) -> bool,
    ) {
        let mut meshes = Vec::with_capacity(self.meshes.len());
        for mesh in std::mem::take(&mut self.meshes) {
            let objects = match chosen(&mesh) && self.materials[mesh.material].is_specular() {
                true => mesh.separate_objects(),
                false => Vec::new(),
            };
            if objects.len() <= 1 {
                meshes.push(mesh);
                continue;
            }
            self.warnings.push(format!(
                "{source}: mesh '{}' holds {} separate objects: split into '{}#1'...'{}#{}', one reflector each",
                mesh.name,
                objects.len(),
                mesh.name,
                mesh.name,
                objects.len()
            ));
            for (i, triangles) in objects.iter().enumerate() {
                meshes.push(mesh.subset(format!("{}#{}", mesh.name, i + 1), triangles));
            }
        }
        self.meshes = meshes;
    }

    /// Checks every part of the scene and drops degenerate triangles (one warning with the
    /// count); warns of a mirror or glass object whose size suggests a wrong length unit.
    /// Loaders call this last; `source` names the file in messages.
    pub fn finalize(&mut self, source: &str) -> Result<(), SceneError> {
        let mut dropped = 0;
        for mesh in &mut self.meshes {
            mesh.check_topology(source)?;
            if mesh.normals.is_empty() {
                mesh.compute_smooth_normals();
            }
            mesh.validate(source)?;
            if mesh.material >= self.materials.len() {
                return Err(SceneError::invalid(
                    source,
                    format!(
                        "mesh '{}' uses material {} of {}",
                        mesh.name,
                        mesh.material,
                        self.materials.len()
                    ),
                ));
            }
            dropped += mesh.drop_degenerate_triangles();
        }
        if dropped > 0 {
            self.warnings.push(format!(
                "{source}: dropped {dropped} degenerate triangle(s) (zero area or repeated vertices)"
            ));
        }
        self.meshes.retain(|m| !m.triangles.is_empty());
        self.split_separate_reflectors(source, |_| true);
        for (i, material) in self.materials.iter().enumerate() {
            if !material.color.is_finite() {
                return Err(SceneError::invalid(
                    source,
                    format!("material {i} ('{}') has a non-finite colour", material.name),
                ));
            }
            if let crate::MaterialKind::Dielectric { ior, .. } = material.kind {
                if !ior.is_finite() || ior.min_element() <= 0.0 {
                    return Err(SceneError::invalid(
                        source,
                        format!(
                            "material {i} ('{}') has an invalid index of refraction {ior}",
                            material.name
                        ),
                    ));
                }
            }
            if let Some(t) = material.texture {
                if t >= self.textures.len() {
                    return Err(SceneError::invalid(
                        source,
                        format!(
                            "material {i} ('{}') uses texture {t} of {}",
                            material.name,
                            self.textures.len()
                        ),
                    ));
                }
            }
        }
        if let Some(i) = self.lights.iter().position(|l| !l.is_valid()) {
            return Err(SceneError::invalid(
                source,
                format!(
                    "light {i} has a non-finite or negative parameter: {:?}",
                    self.lights[i]
                ),
            ));
        }
        if !self.camera.is_valid() {
            return Err(SceneError::invalid(
                source,
                format!(
                    "invalid camera {:?} (eye must differ from target; 0 < fov < 180°)",
                    self.camera
                ),
            ));
        }
        if !self.ambient.is_finite() {
            return Err(SceneError::invalid(source, "ambient is not finite"));
        }
        // Finalizing a scene twice (as after editing a loaded one) must not repeat its warnings.
        for warning in crate::plausibility::optic_size_warnings(self, source) {
            if !self.warnings.contains(&warning) {
                self.warnings.push(warning);
            }
        }
        Ok(())
    }
}
