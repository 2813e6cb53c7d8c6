//! Rays through a lens in double precision, on one of three surfaces
//! ([`SurfaceModel`], as the mirror analyses name them):
//!
//! - `Exact`: the lens's own surfaces ([`specula_scene::ExactLens`]: spheres and torics,
//!   Newton's method on their height fields, exact normals) where the scene made the lens from
//!   a shape (`lens`, `spectacle-lens`).
//! - `Mesh`: its triangles in a BVH of their own; a hit's point is on the triangle's plane, its
//!   normal the vertex normals interpolated there (as the reference renderer shades it).
//! - `Smooth`: the triangles' hits moved onto each triangle's quadric fit
//!   ([`crate::mirror_surface::LocalQuadric`]) with its normal; how far a figure moves between
//!   `Mesh` and `Smooth` is a mesh lens's surface uncertainty.

use glam::{DMat3, DMat4, DVec3};
use specula_scene::{ExactLens, Mesh};
use specula_trace::{Ray, SceneAccel};

use crate::mirror_surface::{LocalQuadric, SurfaceModel};

/// A surface met beyond this incidence is the lens's edge, not an optical surface.
const EDGE_INCIDENCE_DEG: f64 = 75.0;

/// The lens alone: the analysis sees nothing else.
pub struct LensTracer<'a> {
    surface: Surface<'a>,
}

enum Surface<'a> {
    Triangles {
        mesh: &'a Mesh,
        accel: SceneAccel,
        /// Present for [`SurfaceModel::Smooth`].
        fits: Option<Vec<LocalQuadric>>,
        /// How far past its start a ray's next hit must lie: for the smooth fit, past the
        /// fit's distance from the triangles (a hit moved onto the fit may lie that far off
        /// its triangle's plane).
        skip_m: f64,
    },
    Exact(Box<PlacedLens>),
}

/// An exact lens and its placement.
struct PlacedLens {
    lens: ExactLens,
    world_from_lens: DMat4,
    lens_from_world: DMat4,
    normal_to_world: DMat3,
}

/// Why a ray did not pass through the lens.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    Missed,
    Edge,
    TotalInternalReflection,
}

/// A ray through the lens: its points on the surfaces in order, and its direction out.
pub struct Traced {
    pub points: [DVec3; 2],
    pub dir: DVec3,
}

fn refract(d: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| eta * d + (eta * cos_i - k.sqrt()) * n)
}

impl<'a> LensTracer<'a> {
    /// The lens's triangles (the `Mesh` model).
    pub fn new(mesh: &'a Mesh) -> LensTracer<'a> {
        LensTracer::triangles(mesh, None)
    }

    /// `mesh` in `model`; None where the model is `Exact` and the mesh has no exact lens.
    pub fn with_model(mesh: &'a Mesh, model: SurfaceModel) -> Option<LensTracer<'a>> {
        match model {
            SurfaceModel::Mesh => Some(LensTracer::new(mesh)),
            SurfaceModel::Smooth => Some(LensTracer::triangles(
                mesh,
                Some(LocalQuadric::fit_mesh(mesh)),
            )),
            SurfaceModel::Exact => {
                let exact = mesh.exact.as_ref()?;
                Some(LensTracer::exact(
                    exact.lens()?.clone(),
                    exact.world_from_object,
                ))
            }
        }
    }

    /// An exact lens placed by `world_from_lens`.
    pub fn exact(lens: ExactLens, world_from_lens: DMat4) -> LensTracer<'static> {
        LensTracer {
            surface: Surface::Exact(Box::new(PlacedLens {
                lens,
                world_from_lens,
                lens_from_world: world_from_lens.inverse(),
                normal_to_world: DMat3::from_mat4(world_from_lens).inverse().transpose(),
            })),
        }
    }

    fn triangles(mesh: &'a Mesh, fits: Option<Vec<LocalQuadric>>) -> LensTracer<'a> {
        let skip_m = fits.as_ref().map_or(0.0, |fits| {
            let off_plane = (0..mesh.triangles.len()).map(|t| {
                let centroid = mesh.triangles[t]
                    .iter()
                    .map(|&i| mesh.positions[i as usize].as_dvec3())
                    .sum::<DVec3>()
                    / 3.0;
                (fits[t].at(centroid).0 - centroid).length()
            });
            4.0 * off_plane.fold(0.0, f64::max)
        });
        let triangles = mesh
            .triangles
            .iter()
            .map(|t| t.map(|i| mesh.positions[i as usize]))
            .collect();
        let ids = (0..mesh.triangles.len() as u32).map(|t| (0, t)).collect();
        LensTracer {
            surface: Surface::Triangles {
                mesh,
                accel: SceneAccel::from_triangles(triangles, ids),
                fits,
                skip_m,
            },
        }
    }

    /// The next surface point of the ray from `origin` along `dir` (unit) and its outward
    /// normal, in double precision.
    pub fn next_hit(&self, origin: DVec3, dir: DVec3) -> Option<(DVec3, DVec3)> {
        match &self.surface {
            Surface::Triangles {
                mesh,
                accel,
                fits,
                skip_m,
            } => {
                let (tri, point, normal) = triangle_hit(mesh, accel, origin, dir, *skip_m)?;
                match fits {
                    None => Some((point, normal)),
                    Some(fits) => Some(onto_fit(&fits[tri], point, dir, normal)),
                }
            }
            Surface::Exact(placed) => {
                let o = placed.lens_from_world.transform_point3(origin);
                let d = placed.lens_from_world.transform_vector3(dir);
                // Past the surface the ray starts on (Newton's roots are good to 1e-15 m).
                let hit = placed.lens.next_hit(o, d, 1e-10 / d.length())?;
                Some((
                    placed.world_from_lens.transform_point3(hit.p),
                    (placed.normal_to_world * hit.n_outward).normalize(),
                ))
            }
        }
    }

    /// The ray from `origin` along `dir` (unit) through the lens of index `ior`: in through one
    /// surface and out through another, each refraction by Snell's law.
    pub fn trace(&self, origin: DVec3, dir: DVec3, ior: f64) -> Result<Traced, Failure> {
        let (mut o, mut d) = (origin, dir);
        let mut points = [DVec3::ZERO; 2];
        let edge = EDGE_INCIDENCE_DEG.to_radians().cos();
        for (k, point) in points.iter_mut().enumerate() {
            let (p, normal) = self.next_hit(o, d).ok_or(Failure::Missed)?;
            let cos = d.dot(normal);
            let entering = cos < 0.0;
            if entering != (k == 0) || cos.abs() < edge {
                return Err(Failure::Edge);
            }
            let (facing, eta) = if entering {
                (normal, 1.0 / ior)
            } else {
                (-normal, ior)
            };
            d = refract(d, facing, eta)
                .ok_or(Failure::TotalInternalReflection)?
                .normalize();
            o = p;
            *point = p;
        }
        // Out of the glass, nothing more of the lens may lie ahead.
        if self.next_hit(o, d).is_some() {
            return Err(Failure::Edge);
        }
        Ok(Traced { points, dir: d })
    }

    /// Whether `p` lies inside the lens: for an exact lens, between its surfaces within its
    /// rim; for triangles, an odd number of crossings along at least two of three directions
    /// (a ray grazing an edge could miscount one).
    pub fn contains(&self, p: DVec3) -> bool {
        if let Surface::Exact(placed) = &self.surface {
            return placed
                .lens
                .contains(placed.lens_from_world.transform_point3(p));
        }
        let crossings = |dir: DVec3| {
            let mut count = 0;
            let mut o = p;
            while let Some((q, _)) = self.next_hit(o, dir) {
                count += 1;
                o = q;
                if count > 64 {
                    break;
                }
            }
            count
        };
        let odd = [
            DVec3::new(0.31, 0.52, 0.79),
            DVec3::new(-0.64, 0.18, -0.75),
            DVec3::new(0.12, -0.97, 0.21),
        ]
        .map(|d| crossings(d.normalize()) % 2 == 1);
        odd.iter().filter(|o| **o).count() >= 2
    }
}

/// The triangle the ray from `origin` along `dir` meets next, the point on its plane and the
/// interpolated normal there (as stored: outward).
fn triangle_hit(
    mesh: &Mesh,
    accel: &SceneAccel,
    origin: DVec3,
    dir: DVec3,
    skip_m: f64,
) -> Option<(usize, DVec3, DVec3)> {
    // Past the surface the ray starts on (by more than single precision's step there); the
    // exact point is found again below.
    let nudge = (1e-6 * (1.0 + origin.abs().max_element())).max(skip_m);
    let ray = Ray {
        origin: (origin + dir * nudge).as_vec3(),
        dir: dir.as_vec3(),
    };
    let hit = accel.intersect(&ray, f32::INFINITY)?;
    let [i0, i1, i2] = mesh.triangles[hit.triangle as usize].map(|i| i as usize);
    let p = [i0, i1, i2].map(|i| mesh.positions[i].as_dvec3());
    let n = [i0, i1, i2].map(|i| mesh.normals[i].as_dvec3());
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let plane = e1.cross(e2);
    let t = (p[0] - origin).dot(plane) / dir.dot(plane);
    let point = origin + dir * t;
    let q = point - p[0];
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (q.dot(e1), q.dot(e2));
    let denominator = d00 * d11 - d01 * d01;
    let b1 = (d11 * d20 - d01 * d21) / denominator;
    let b2 = (d00 * d21 - d01 * d20) / denominator;
    // A sliver the single-precision test accepted but double precision cannot solve: its own
    // hit, as the BVH found it.
    let (point, b1, b2) = if point.is_finite() && b1.is_finite() && b2.is_finite() {
        (point, b1, b2)
    } else {
        (
            (ray.origin + ray.dir * hit.t).as_dvec3(),
            f64::from(hit.b1),
            f64::from(hit.b2),
        )
    };
    // Within the triangle (a point on its edge may fall a rounding outside): no extrapolated
    // normals.
    let weights = DVec3::new(1.0 - b1 - b2, b1, b2).max(DVec3::ZERO);
    let weights = weights / weights.element_sum().max(1e-300);
    let normal = (n[0] * weights.x + n[1] * weights.y + n[2] * weights.z).try_normalize()?;
    Some((hit.triangle as usize, point, normal))
}

/// The ray's crossing of a triangle's quadric fit, from its crossing `on_plane` of the
/// triangle's plane: a few steps of intersecting the ray with the fit's tangent plane (the
/// fit is within a tessellation's sag of the plane), its normal turned to the side
/// `outward` faces.
fn onto_fit(fit: &LocalQuadric, on_plane: DVec3, dir: DVec3, outward: DVec3) -> (DVec3, DVec3) {
    let mut point = on_plane;
    let (mut q, mut n) = fit.at(point);
    for _ in 0..4 {
        let along = dir.dot(n);
        if along.abs() < 1e-9 {
            break;
        }
        point += dir * ((q - point).dot(n) / along);
        (q, n) = fit.at(point);
    }
    let n = if n.dot(outward) < 0.0 { -n } else { n };
    (point, n)
}
