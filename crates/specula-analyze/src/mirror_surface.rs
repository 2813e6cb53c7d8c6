//! The mirror surface an analysis samples, in one of three models:
//!
//! - [`SurfaceModel::Mesh`]: the scene's triangles with their interpolated normals, exactly
//!   as the reference renderer shades them.
//! - [`SurfaceModel::Exact`]: the analytic surface the mesh was made from
//!   ([`specula_scene::ExactSurface`]: a bicubic patch, a sphere, a spherical cap), sampled
//!   over its own parameter square, so that points, normals and the rim are the surface's own.
//!   Where the eye's ray towards a sample meets the mirror's triangles clearly before it (by
//!   more than 1 % of the mirror's size: more than a tessellation's sag), the ray is intersected
//!   with the exact surface (Newton's method on a patch, closed form on a sphere), and the
//!   sample counts only where it is the ray's first crossing.
//! - [`SurfaceModel::Smooth`]: a smooth surface fitted to a mesh that has no exact one: on
//!   each triangle, the quadratic height field z = a x² + b xy + c y² + d x + e y + f (in the
//!   triangle's own frame) that fits, by least squares, its three corners' positions and
//!   normals and its neighbours' positions; points and normals are the fit's. How much a
//!   figure changes between `Mesh` and `Smooth` is the figure's surface uncertainty: what the
//!   tessellation alone may have moved it by.
//!
//! Each model is a set of cells (a mesh's triangles, or the exact surface's parameter square
//! cut into triangles) with barycentric coordinates within each: the analyses refine cells and
//! ask for the point and normals at a cell's barycentric coordinates.

use glam::{DVec2, DVec3, Vec2, Vec3};
use specula_scene::{ExactSurface, Mesh, Scene};

/// Which surface the samples lie on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceModel {
    Mesh,
    Exact,
    Smooth,
}

specula_params::choice!(SurfaceModel {
    Exact = "exact",
    Mesh = "mesh",
    Smooth = "smooth",
});

impl SurfaceModel {
    pub fn name(self) -> &'static str {
        match self {
            SurfaceModel::Mesh => "mesh",
            SurfaceModel::Exact => "exact",
            SurfaceModel::Smooth => "smooth",
        }
    }

    /// The best model `mesh` has as a mirror: its exact surface, else its triangles (a lens's
    /// exact surfaces are the lens analysis's: as a mirror it is its triangles).
    pub fn best_for(mesh: &Mesh) -> SurfaceModel {
        if mirror_exact(mesh).is_some() {
            SurfaceModel::Exact
        } else {
            SurfaceModel::Mesh
        }
    }
}

/// The exact surface a mirror analysis can sample: a patch's, a sphere's or a cap's.
pub fn mirror_exact(mesh: &Mesh) -> Option<&ExactSurface> {
    mesh.exact.as_ref().filter(|exact| exact.lens().is_none())
}

/// The exact surface's parameter square is cut into this many squares per side, each into two
/// triangles, before refinement starts.
const EXACT_CELLS: usize = 8;

/// A point of the mirror as a sample sees it.
#[derive(Clone, Copy, Debug)]
pub struct MirrorPoint {
    pub p: Vec3,
    /// The shading normal, facing the eye's side.
    pub ns: Vec3,
    /// The geometric normal, facing the eye's side.
    pub ng: Vec3,
}

/// A mirror in one model, ready to sample.
pub enum MirrorSurface<'a> {
    Mesh {
        scene: &'a Scene,
        mesh: usize,
    },
    Exact(&'a ExactSurface),
    Smooth {
        mesh: &'a Mesh,
        fits: Vec<LocalQuadric>,
    },
}

impl<'a> MirrorSurface<'a> {
    /// `scene`'s mesh `mesh` in `model` (None: the model asks for an exact surface the mesh
    /// does not have).
    pub fn new(scene: &'a Scene, mesh: usize, model: SurfaceModel) -> Option<MirrorSurface<'a>> {
        let m = &scene.meshes[mesh];
        Some(match model {
            SurfaceModel::Mesh => MirrorSurface::Mesh { scene, mesh },
            SurfaceModel::Exact => MirrorSurface::Exact(mirror_exact(m)?),
            SurfaceModel::Smooth => MirrorSurface::Smooth {
                mesh: m,
                fits: LocalQuadric::fit_mesh(m),
            },
        })
    }

    pub fn cells(&self) -> usize {
        match self {
            MirrorSurface::Mesh { scene, mesh } => scene.meshes[*mesh].triangles.len(),
            MirrorSurface::Exact(_) => 2 * EXACT_CELLS * EXACT_CELLS,
            MirrorSurface::Smooth { mesh, .. } => mesh.triangles.len(),
        }
    }

    /// The parameters of the exact surface at barycentric `b` of cell `cell`.
    pub(crate) fn exact_uv(cell: usize, b: Vec2) -> DVec2 {
        let square = cell / 2;
        let (i, j) = ((square % EXACT_CELLS) as f64, (square / EXACT_CELLS) as f64);
        let corners = if cell.is_multiple_of(2) {
            [
                DVec2::new(0.0, 0.0),
                DVec2::new(1.0, 0.0),
                DVec2::new(0.0, 1.0),
            ]
        } else {
            [
                DVec2::new(1.0, 0.0),
                DVec2::new(1.0, 1.0),
                DVec2::new(0.0, 1.0),
            ]
        };
        let (b1, b2) = (f64::from(b.x), f64::from(b.y));
        let local = corners[0] * (1.0 - b1 - b2) + corners[1] * b1 + corners[2] * b2;
        (DVec2::new(i, j) + local) / EXACT_CELLS as f64
    }

    /// The point at barycentric `b` of `cell`.
    pub fn position(&self, cell: usize, b: Vec2) -> Vec3 {
        match self {
            MirrorSurface::Mesh { scene, mesh } => triangle_point(&scene.meshes[*mesh], cell, b),
            MirrorSurface::Exact(exact) => exact.at(Self::exact_uv(cell, b)).p_world.as_vec3(),
            MirrorSurface::Smooth { mesh, fits } => fits[cell]
                .at(triangle_point(mesh, cell, b).as_dvec3())
                .0
                .as_vec3(),
        }
    }

    /// Corner `k` of `cell`: a mesh's own vertex (shared by its neighbours, so that the cells
    /// tile the surface without gaps), or the exact surface's point at the corner.
    pub fn corner(&self, cell: usize, k: usize) -> DVec3 {
        let b = [Vec2::ZERO, Vec2::X, Vec2::Y][k];
        match self {
            MirrorSurface::Exact(exact) => exact.at(Self::exact_uv(cell, b)).p_world,
            _ => {
                let mesh = self.mesh().expect("a mesh model");
                mesh.positions[mesh.triangles[cell][k] as usize].as_dvec3()
            }
        }
    }

    /// The mesh the model's cells are the triangles of (None: the exact surface's).
    pub fn mesh(&self) -> Option<&Mesh> {
        match self {
            MirrorSurface::Mesh { scene, mesh } => Some(&scene.meshes[*mesh]),
            MirrorSurface::Exact(_) => None,
            MirrorSurface::Smooth { mesh, .. } => Some(mesh),
        }
    }

    /// The point, its shading normal and its geometric normal at barycentric `b` of `cell`,
    /// the normals on the side the surface's normals face.
    pub(crate) fn raw(&self, cell: usize, b: Vec2) -> (DVec3, DVec3, DVec3) {
        match self {
            MirrorSurface::Mesh { scene, mesh } => {
                let m = &scene.meshes[*mesh];
                let [i0, i1, i2] = m.triangles[cell].map(|i| i as usize);
                let b0 = 1.0 - b.x - b.y;
                let p = triangle_point(m, cell, b).as_dvec3();
                let face = m.face_normal_scaled(cell).as_dvec3().normalize_or_zero();
                let ns = (m.normals[i0] * b0 + m.normals[i1] * b.x + m.normals[i2] * b.y)
                    .as_dvec3()
                    .try_normalize()
                    .unwrap_or(face);
                let ng = if face.dot(ns) < 0.0 { -face } else { face };
                (p, ns, ng)
            }
            MirrorSurface::Exact(exact) => {
                let at = exact.at(Self::exact_uv(cell, b));
                (at.p_world, at.n_world, at.n_world)
            }
            MirrorSurface::Smooth { mesh, fits } => {
                let (p, n) = fits[cell].at(triangle_point(mesh, cell, b).as_dvec3());
                (p, n, n)
            }
        }
    }

    /// The point at barycentric `b` of `cell` as the ray from `eye` sees it, its normals turned
    /// to face the eye (mirrors reflect on both sides, as the reference renders them).
    pub fn seen_from(&self, eye: Vec3, cell: usize, b: Vec2) -> Option<MirrorPoint> {
        let (p, ns, ng) = self.raw(cell, b);
        let p = p.as_vec3();
        let dir = (p - eye).try_normalize()?;
        let (ns, ng) = (ns.as_vec3(), ng.as_vec3());
        let (ns, ng) = if dir.dot(ng) > 0.0 {
            (-ns, -ng)
        } else {
            (ns, ng)
        };
        Some(MirrorPoint { p, ns, ng })
    }

    /// Whether the surface itself crosses the ray from `eye` to its point `p` before `p`: exact
    /// for the exact model (Newton's method on a patch, closed form on a sphere), the
    /// triangles' answer (`mesh_says`) for the others.
    pub fn crosses_before(&self, eye: Vec3, p: Vec3, mesh_says: bool) -> bool {
        match self {
            MirrorSurface::Exact(exact) => {
                let Some(dir) = (p - eye).try_normalize() else {
                    return false;
                };
                let distance = f64::from((p - eye).length());
                exact
                    .intersect(eye, dir)
                    .is_some_and(|(t, _)| t < distance * (1.0 - 1e-6) - 1e-7)
            }
            _ => mesh_says,
        }
    }

    /// Whether the scene's own triangles of the mirror stand for the surface (the mesh model):
    /// then they are what may hide a sample; the other models replace them.
    pub fn is_the_mesh(&self) -> bool {
        matches!(self, MirrorSurface::Mesh { .. })
    }
}

fn triangle_point(mesh: &Mesh, triangle: usize, b: Vec2) -> Vec3 {
    let [p0, p1, p2] = mesh.triangles[triangle].map(|i| mesh.positions[i as usize]);
    p0 * (1.0 - b.x - b.y) + p1 * b.x + p2 * b.y
}

/// A quadratic height field over one triangle's plane.
#[derive(Clone, Debug)]
pub struct LocalQuadric {
    origin: DVec3,
    /// Tangent axes and the normal of the triangle's frame.
    t: DVec3,
    s: DVec3,
    n: DVec3,
    /// z = c0 x² + c1 xy + c2 y² + c3 x + c4 y + c5.
    c: [f64; 6],
}

impl LocalQuadric {
    /// One fit per triangle of `mesh` (see the module's top).
    pub fn fit_mesh(mesh: &Mesh) -> Vec<LocalQuadric> {
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
        for t in &mesh.triangles {
            for &a in t {
                for &b in t {
                    if a != b && !neighbours[a as usize].contains(&b) {
                        neighbours[a as usize].push(b);
                    }
                }
            }
        }
        (0..mesh.triangles.len())
            .map(|k| {
                let corners = mesh.triangles[k];
                let mut ring: Vec<u32> = corners
                    .iter()
                    .flat_map(|&c| neighbours[c as usize].iter().copied())
                    .filter(|v| !corners.contains(v))
                    .collect();
                ring.sort_unstable();
                ring.dedup();
                LocalQuadric::fit(mesh, corners, &ring)
            })
            .collect()
    }

    fn fit(mesh: &Mesh, corners: [u32; 3], ring: &[u32]) -> LocalQuadric {
        let p = corners.map(|i| mesh.positions[i as usize].as_dvec3());
        let normals = corners.map(|i| mesh.normals[i as usize].as_dvec3());
        let origin = (p[0] + p[1] + p[2]) / 3.0;
        let face = (p[1] - p[0]).cross(p[2] - p[0]);
        let mut n = (normals[0] + normals[1] + normals[2])
            .try_normalize()
            .unwrap_or(DVec3::Z);
        if let Some(f) = face.try_normalize() {
            n = if f.dot(n) >= 0.0 { f } else { -f };
        }
        let t = (p[1] - p[0])
            .try_normalize()
            .unwrap_or_else(|| n.any_orthonormal_vector());
        let s = n.cross(t);
        let local = |q: DVec3| {
            let d = q - origin;
            (d.dot(t), d.dot(s), d.dot(n))
        };
        // Rows of the least-squares system A c = y: heights, then slopes from the normals.
        let mut rows: Vec<([f64; 6], f64)> = Vec::new();
        let mut height = |x: f64, y: f64, z: f64, w: f64| {
            rows.push(([x * x * w, x * y * w, y * y * w, x * w, y * w, w], z * w));
        };
        for q in &p {
            let (x, y, z) = local(*q);
            height(x, y, z, 4.0);
        }
        for &v in ring {
            let (x, y, z) = local(mesh.positions[v as usize].as_dvec3());
            height(x, y, z, 1.0);
        }
        let scale = (p[1] - p[0]).length().max((p[2] - p[0]).length()).max(1e-9);
        for (q, nq) in p.iter().zip(normals) {
            let (x, y, _) = local(*q);
            let nz = nq.dot(n);
            if nz.abs() < 1e-6 {
                continue;
            }
            // ∂z/∂x = −n_x / n_z, weighted by the triangle's size to match the heights' units.
            let w = 4.0 * scale;
            rows.push(([2.0 * x * w, y * w, 0.0, w, 0.0, 0.0], -nq.dot(t) / nz * w));
            rows.push(([0.0, x * w, 2.0 * y * w, 0.0, w, 0.0], -nq.dot(s) / nz * w));
        }
        LocalQuadric {
            origin,
            t,
            s,
            n,
            c: least_squares(&rows, scale),
        }
    }

    /// The fit's point over `q` (projected onto the triangle's plane) and its unit normal.
    pub fn at(&self, q: DVec3) -> (DVec3, DVec3) {
        let d = q - self.origin;
        let (x, y) = (d.dot(self.t), d.dot(self.s));
        let c = &self.c;
        let z = c[0] * x * x + c[1] * x * y + c[2] * y * y + c[3] * x + c[4] * y + c[5];
        let (zx, zy) = (
            2.0 * c[0] * x + c[1] * y + c[3],
            c[1] * x + 2.0 * c[2] * y + c[4],
        );
        let p = self.origin + self.t * x + self.s * y + self.n * z;
        let normal = (self.n - self.t * zx - self.s * zy).normalize();
        (p, normal)
    }
}

/// The least-squares solution of the rows' system, with a small ridge on the quadratic terms
/// (scaled to the triangle's size) so that a flat or under-determined neighbourhood gives the
/// plane rather than noise.
fn least_squares(rows: &[([f64; 6], f64)], scale: f64) -> [f64; 6] {
    let (mut ata, aty) = crate::spherometer::normal_equations(rows);
    let ridge = 1e-9 * scale.powi(4);
    for (i, row) in ata.iter_mut().enumerate().take(3) {
        row[i] += ridge;
    }
    for (i, row) in ata.iter_mut().enumerate().skip(3) {
        row[i] += 1e-12 * scale * scale;
    }
    // Gaussian elimination with partial pivoting.
    let mut m = ata;
    let mut y = aty;
    for col in 0..6 {
        let pivot = (col..6)
            .max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))
            .unwrap_or(col);
        m.swap(col, pivot);
        y.swap(col, pivot);
        if m[col][col].abs() < 1e-300 {
            continue;
        }
        let pivot_row = m[col];
        for r in col + 1..6 {
            let f = m[r][col] / pivot_row[col];
            for (entry, p) in m[r].iter_mut().zip(&pivot_row).skip(col) {
                *entry -= f * p;
            }
            y[r] -= f * y[col];
        }
    }
    let mut c = [0.0f64; 6];
    for r in (0..6).rev() {
        let rest: f64 = (r + 1..6).map(|k| m[r][k] * c[k]).sum();
        c[r] = if m[r][r].abs() < 1e-300 {
            0.0
        } else {
            (y[r] - rest) / m[r][r]
        };
    }
    c
}
