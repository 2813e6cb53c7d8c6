use glam::{Mat3, Mat4, Vec2, Vec3};

use crate::SceneError;

/// Axis-aligned bounding box. An empty box has `min` = +inf and `max` = -inf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// Half the diagonal: the radius of the bounding sphere centred on `center()`.
    pub fn radius(&self) -> f32 {
        self.extent().length() * 0.5
    }

    pub fn surface_area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
}

/// An indexed triangle mesh. Scenes keep meshes in world space; generators return them in object
/// space. `normals` has one unit normal per position; `uvs` is empty or has one per position.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
    /// Index into `Scene::materials`.
    pub material: usize,
}

impl Mesh {
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &p in &self.positions {
            b.grow(p);
        }
        b
    }

    /// Unnormalised face normal (length = 2 × area) of triangle `t`.
    pub fn face_normal_scaled(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize]);
        (b - a).cross(c - a)
    }

    /// Smooth per-vertex normals: the area-weighted average of the adjacent face normals.
    pub fn compute_smooth_normals(&mut self) {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        for t in 0..self.triangles.len() {
            let n = self.face_normal_scaled(t);
            for &i in &self.triangles[t] {
                normals[i as usize] += n;
            }
        }
        for n in &mut normals {
            *n = n.try_normalize().unwrap_or(Vec3::Y);
        }
        self.normals = normals;
    }

    /// Flat shading as glTF requires when NORMAL is absent: every triangle gets its own three
    /// vertices carrying the face normal.
    pub fn make_flat(&mut self) {
        let mut positions = Vec::with_capacity(self.triangles.len() * 3);
        let mut normals = Vec::with_capacity(self.triangles.len() * 3);
        let mut uvs = Vec::new();
        let mut triangles = Vec::with_capacity(self.triangles.len());
        for t in 0..self.triangles.len() {
            let n = self
                .face_normal_scaled(t)
                .try_normalize()
                .unwrap_or(Vec3::Y);
            let base = positions.len() as u32;
            for &i in &self.triangles[t] {
                positions.push(self.positions[i as usize]);
                normals.push(n);
                if !self.uvs.is_empty() {
                    uvs.push(self.uvs[i as usize]);
                }
            }
            triangles.push([base, base + 1, base + 2]);
        }
        self.positions = positions;
        self.normals = normals;
        self.uvs = uvs;
        self.triangles = triangles;
    }

    /// Applies an affine transform; normals go through the inverse transpose. A transform that
    /// mirrors (negative determinant) also flips the winding so faces stay counter-clockwise.
    pub fn transform(&mut self, world_from_object: Mat4) {
        let normal_matrix = Mat3::from_mat4(world_from_object).inverse().transpose();
        for p in &mut self.positions {
            *p = world_from_object.transform_point3(*p);
        }
        for n in &mut self.normals {
            *n = (normal_matrix * *n).try_normalize().unwrap_or(*n);
        }
        if Mat3::from_mat4(world_from_object).determinant() < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
    }

    /// Checks what a renderer relies on: finite positions, normals and UVs, indices in range,
    /// attribute arrays of matching length. `source` names the file for the message.
    pub fn validate(&self, source: &str) -> Result<(), SceneError> {
        self.check_topology(source)?;
        let what =
            |msg: String| SceneError::invalid(source, format!("mesh '{}': {msg}", self.name));
        if self.normals.len() != self.positions.len() {
            return Err(what(format!(
                "{} normals for {} vertices",
                self.normals.len(),
                self.positions.len()
            )));
        }
        if let Some(i) = self.normals.iter().position(|n| !n.is_finite()) {
            return Err(what(format!("normal {i} is not finite")));
        }
        if !self.uvs.is_empty() && self.uvs.len() != self.positions.len() {
            return Err(what(format!(
                "{} texture coordinates for {} vertices",
                self.uvs.len(),
                self.positions.len()
            )));
        }
        if let Some(i) = self.uvs.iter().position(|uv| !uv.is_finite()) {
            return Err(what(format!("texture coordinate {i} is not finite")));
        }
        Ok(())
    }

    /// The part of [`Mesh::validate`] that must hold before normals can be computed: finite
    /// positions and triangle indices in range.
    pub fn check_topology(&self, source: &str) -> Result<(), SceneError> {
        let what =
            |msg: String| SceneError::invalid(source, format!("mesh '{}': {msg}", self.name));
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(what(format!(
                "vertex {i} has a non-finite position {:?}",
                self.positions[i]
            )));
        }
        let count = self.positions.len() as u32;
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&i| i >= count) {
                return Err(what(format!(
                    "triangle {t} uses vertex index {bad}, but there are only {count} vertices"
                )));
            }
        }
        Ok(())
    }

    /// Removes triangles with (near) zero area or repeated vertices; returns how many went.
    pub fn drop_degenerate_triangles(&mut self) -> usize {
        let before = self.triangles.len();
        let positions = &self.positions;
        self.triangles.retain(|&[a, b, c]| {
            if a == b || b == c || a == c {
                return false;
            }
            let (pa, pb, pc) = (
                positions[a as usize],
                positions[b as usize],
                positions[c as usize],
            );
            let scale = (pb - pa).length_squared().max((pc - pa).length_squared());
            let area2 = (pb - pa).cross(pc - pa).length_squared();
            area2 > scale * scale * 1e-12
        });
        before - self.triangles.len()
    }
}

/// The rigid transform turning by `degrees` about the world `axis` through `center`; `None` when
/// the axis is zero or anything is not finite.
pub fn rotation_about(center: Vec3, axis: Vec3, degrees: f32) -> Option<Mat4> {
    let axis = axis.try_normalize()?;
    if !center.is_finite() || !degrees.is_finite() {
        return None;
    }
    Some(
        Mat4::from_translation(center)
            * Mat4::from_axis_angle(axis, degrees.to_radians())
            * Mat4::from_translation(-center),
    )
}
