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

    /// Whether the boxes overlap or lie within `gap` of each other.
    pub fn overlaps(&self, other: &Aabb, gap: f32) -> bool {
        (self.min - gap).cmple(other.max).all() && (other.min - gap).cmple(self.max).all()
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
    /// The analytic surface these triangles tessellate, where a generator made them from one
    /// (a bicubic patch, a sphere, a spherical cap): what analyses sample instead of the
    /// triangles. Moves with the mesh; gone once its triangles are changed otherwise.
    pub exact: Option<crate::exact::ExactSurface>,
    /// The CAD faces these triangles tessellate, where a STEP file gave them: each triangle's
    /// face and each vertex's (u, v) on it. Moves with the mesh and follows a subset; gone once
    /// its triangles are changed otherwise.
    pub cad: Option<crate::cad::CadFaces>,
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
        // Faceted on purpose: the triangles are the surface now.
        self.exact = None;
        self.cad = None;
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

    /// Appends `other`'s vertices and triangles (renumbered), keeping this mesh's name and
    /// material. UVs stay one per position: the side without them gets (0, 0).
    pub fn append(&mut self, other: &Mesh) {
        // A joined mesh's triangles no longer index one body's faces.
        self.cad = None;
        let base = self.positions.len() as u32;
        let with_uvs = !self.uvs.is_empty() || !other.uvs.is_empty();
        if with_uvs {
            self.uvs.resize(self.positions.len(), Vec2::ZERO);
        }
        self.positions.extend(&other.positions);
        self.normals.extend(&other.normals);
        if with_uvs {
            if other.uvs.is_empty() {
                self.uvs.resize(self.positions.len(), Vec2::ZERO);
            } else {
                self.uvs.extend(&other.uvs);
            }
        }
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }

    /// Applies an affine transform; normals go through the inverse transpose. A transform that
    /// mirrors (negative determinant) also flips the winding so faces stay counter-clockwise.
    pub fn transform(&mut self, world_from_object: Mat4) {
        if let Some(exact) = &mut self.exact {
            exact.transform(world_from_object);
        }
        if let Some(cad) = &mut self.cad {
            cad.world_from_object = world_from_object.as_dmat4() * cad.world_from_object;
        }
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
        if let Some(cad) = &self.cad {
            cad.validate(self.triangles.len(), self.positions.len())
                .map_err(what)?;
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
        let keep: Vec<bool> = self
            .triangles
            .iter()
            .map(|&[a, b, c]| {
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
            })
            .collect();
        let mut kept = keep.iter();
        self.triangles.retain(|_| *kept.next().unwrap_or(&false));
        if let Some(cad) = &mut self.cad {
            let mut kept = keep.iter();
            cad.face_of_triangle
                .retain(|_| *kept.next().unwrap_or(&false));
        }
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

/// Vertices closer than this fraction of the mesh's bounding-box diagonal are one vertex when
/// finding connected parts (a mesh with split normals or UV seams stays one surface).
pub const WELD_TOLERANCE: f32 = 1e-5;

/// The most parts a mesh is split into; past it (a particle cloud, a mesh of loose triangles)
/// the mesh stays whole.
pub const MAX_PARTS: usize = 256;

impl Mesh {
    /// The mesh's separate objects, as triangle lists in order of first triangle: triangles
    /// that share a vertex (welded by position within [`WELD_TOLERANCE`] of the box diagonal)
    /// are connected, and connected parts whose bounding boxes overlap stay one object (a
    /// teapot's lid, spout and handle touch its body without sharing vertices). One entry when
    /// the mesh is one object, or has more than [`MAX_PARTS`] parts.
    pub fn separate_objects(&self) -> Vec<Vec<usize>> {
        let all = || vec![(0..self.triangles.len()).collect::<Vec<_>>()];
        if self.triangles.is_empty() {
            return all();
        }
        let bounds = self.bounds();
        let cell = ((bounds.max - bounds.min).length() * WELD_TOLERANCE).max(f32::MIN_POSITIVE);
        // Welded vertex id per position: positions falling in one grid cell are one vertex.
        let mut welded = std::collections::HashMap::new();
        let vertex_ids: Vec<usize> = self
            .positions
            .iter()
            .map(|p| {
                let key = ((*p - bounds.min) / cell).round().as_ivec3();
                let next = welded.len();
                *welded.entry(key).or_insert(next)
            })
            .collect();
        let mut sets = DisjointSets::new(welded.len());
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| vertex_ids[i as usize]);
            sets.union(a, b);
            sets.union(a, c);
        }
        // Parts in order of their first triangle.
        let mut part_of_root = std::collections::HashMap::new();
        let mut parts: Vec<Vec<usize>> = Vec::new();
        for (i, t) in self.triangles.iter().enumerate() {
            let root = sets.find(vertex_ids[t[0] as usize]);
            let part = *part_of_root.entry(root).or_insert_with(|| {
                parts.push(Vec::new());
                parts.len() - 1
            });
            parts[part].push(i);
        }
        if parts.len() == 1 || parts.len() > MAX_PARTS {
            return all();
        }
        let boxes: Vec<Aabb> = parts
            .iter()
            .map(|tris| {
                let mut b = Aabb::EMPTY;
                for &t in tris {
                    for i in self.triangles[t] {
                        b.grow(self.positions[i as usize]);
                    }
                }
                b
            })
            .collect();
        let mut objects = DisjointSets::new(parts.len());
        for i in 0..parts.len() {
            for j in i + 1..parts.len() {
                if boxes[i].overlaps(&boxes[j], cell) {
                    objects.union(i, j);
                }
            }
        }
        let mut object_of_root = std::collections::HashMap::new();
        let mut result: Vec<Vec<usize>> = Vec::new();
        for (i, part) in parts.into_iter().enumerate() {
            let root = objects.find(i);
            let object = *object_of_root.entry(root).or_insert_with(|| {
                result.push(Vec::new());
                result.len() - 1
            });
            result[object].extend(part);
        }
        for object in &mut result {
            object.sort_unstable();
        }
        result
    }

    /// The mesh made of `triangles` only (its vertices compacted), named `name`.
    pub fn subset(&self, name: String, triangles: &[usize]) -> Mesh {
        let mut remap = vec![u32::MAX; self.positions.len()];
        let mut mesh = Mesh {
            name,
            material: self.material,
            ..Mesh::default()
        };
        for &t in triangles {
            let tri = self.triangles[t].map(|i| {
                let i = i as usize;
                if remap[i] == u32::MAX {
                    remap[i] = mesh.positions.len() as u32;
                    mesh.positions.push(self.positions[i]);
                    if !self.normals.is_empty() {
                        mesh.normals.push(self.normals[i]);
                    }
                    if !self.uvs.is_empty() {
                        mesh.uvs.push(self.uvs[i]);
                    }
                }
                remap[i]
            });
            mesh.triangles.push(tri);
        }
        mesh.cad = self.cad.as_ref().map(|cad| {
            let mut uv = vec![glam::DVec2::ZERO; mesh.positions.len()];
            for (old, &new) in remap.iter().enumerate() {
                if new != u32::MAX {
                    uv[new as usize] = cad.uv[old];
                }
            }
            crate::cad::CadFaces {
                faces: cad.faces.clone(),
                world_from_object: cad.world_from_object,
                face_of_triangle: triangles.iter().map(|&t| cad.face_of_triangle[t]).collect(),
                uv,
            }
        });
        mesh
    }
}

/// Union-find with path halving.
struct DisjointSets(Vec<usize>);

impl DisjointSets {
    fn new(n: usize) -> Self {
        DisjointSets((0..n).collect())
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }

    fn union(&mut self, a: usize, b: usize) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b)] = a.min(b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators;

    fn merged(parts: &[Mesh]) -> Mesh {
        let mut out = Mesh::default();
        for part in parts {
            out.append(part);
        }
        out
    }

    #[test]
    fn append_renumbers_and_keeps_one_uv_per_position() {
        let plane = generators::plane(Vec2::ONE, 1);
        let mut without_uvs = generators::cuboid(Vec3::ONE);
        without_uvs.uvs.clear();
        let mut mesh = without_uvs.clone();
        mesh.append(&plane);
        assert_eq!(
            mesh.positions.len(),
            without_uvs.positions.len() + plane.positions.len()
        );
        assert_eq!(mesh.uvs.len(), mesh.positions.len());
        assert_eq!(mesh.uvs[without_uvs.positions.len()..], plane.uvs[..]);
        let last = *mesh.triangles.last().unwrap();
        let expected = plane
            .triangles
            .last()
            .unwrap()
            .map(|i| i + without_uvs.positions.len() as u32);
        assert_eq!(last, expected);
        mesh.validate("appended").unwrap();
        // Onto an empty mesh (the start of every join), the UVs come along.
        let mut joined = Mesh::default();
        joined.append(&plane);
        assert_eq!(joined.uvs, plane.uvs);
    }

    #[test]
    fn two_spheres_apart_are_two_objects_and_keep_their_triangles() {
        let mut a = generators::sphere(0.5, 24, 12);
        let mut b = a.clone();
        a.transform(Mat4::from_translation(Vec3::new(-2.0, 0.0, 0.0)));
        b.transform(Mat4::from_translation(Vec3::new(2.0, 0.0, 0.0)));
        let mesh = merged(&[a.clone(), b.clone()]);
        let objects = mesh.separate_objects();
        assert_eq!(objects.len(), 2);
        assert_eq!(objects[0], (0..a.triangles.len()).collect::<Vec<_>>());
        // The subset has b's triangles in order, corner for corner (vertices renumbered).
        let second = mesh.subset("b".into(), &objects[1]);
        let corners = |m: &Mesh| -> Vec<(Vec3, Vec3)> {
            m.triangles
                .iter()
                .flat_map(|t| t.map(|i| (m.positions[i as usize], m.normals[i as usize])))
                .collect()
        };
        assert!(corners(&second) == corners(&b), "b's corners differ");
    }

    #[test]
    fn split_normals_touching_parts_and_a_teapot_stay_one_object() {
        // Flat shading duplicates every vertex: welding by position keeps it one surface.
        let mut flat = generators::sphere(0.5, 16, 8);
        flat.make_flat();
        assert_eq!(flat.separate_objects().len(), 1);
        // The teapot's lid, spout and handle share no vertex with the body, but touch it.
        assert_eq!(generators::teapot(6).separate_objects().len(), 1);
        // Two boxes side by side with a gap well under the weld tolerance's scale still split.
        let a = generators::cuboid(Vec3::ONE);
        let mut b = a.clone();
        b.transform(Mat4::from_translation(Vec3::new(1.1, 0.0, 0.0)));
        assert_eq!(merged(&[a, b]).separate_objects().len(), 2);
    }
}
