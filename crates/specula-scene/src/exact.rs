//! Exact surfaces: the analytic shape a generator tessellated, kept on its mesh
//! ([`crate::Mesh::exact`]) so that an analysis can place its samples on the surface itself,
//! with its exact normal, instead of on the triangles that approximate it.
//!
//! Each shape is a map from a parameter square (u, v) ∈ [0, 1]² onto the surface, the same
//! parameters its generator's grid used: a bicubic Bézier patch's own (u, v); a sphere's and a
//! spherical cap's azimuth (u) and polar angle (v); a solid lens ([`crate::exact_lens`]), which
//! the lens analysis traces through, is its front surface's azimuth (u) and radius (v). Sampling the square samples the whole
//! surface, its rim included (a tessellation's rim is a polygon inside the true one). A sample
//! at (u, v) is where the ray from any eye towards that point meets the surface, so no
//! intersection has to be searched for; [`ExactSurface::intersect`] is there for rays that
//! are not aimed at a known point (Newton's method on a patch, closed form on a sphere).
//!
//! Points are computed in double precision in object space and taken to world space by
//! `world_from_object`, normals by its inverse transpose (an ellipsoid is a scaled sphere).
//! Moving the mesh moves its exact surface with it ([`crate::Mesh::transform`]); anything that
//! changes the triangles otherwise (flat shading, merging, splitting) drops it.

use glam::{DMat3, DMat4, DVec2, DVec3, Mat4, Vec3};
use std::f64::consts::{PI, TAU};

use crate::exact_lens::{ExactLens, Face};

/// An analytic shape in object space.
#[derive(Clone, Debug, PartialEq)]
pub enum ExactShape {
    /// A bicubic Bézier patch, `control[row][column]`: u along a row, v down the columns; its
    /// normal is Pu × Pv.
    BicubicPatch { control: Box<[[DVec3; 4]; 4]> },
    /// A sphere of `radius` about the origin: u turns about +Y from +Z towards +X, v runs from
    /// the +Y pole (0) to the −Y pole (1); the normal points out.
    Sphere { radius: f64 },
    /// [`crate::generators::spherical_cap`]'s cap: apex at the origin, reflecting side facing
    /// +Z; u turns about Z, v runs from the apex (0) to the rim (1).
    SphericalCap {
        radius_of_curvature: f64,
        aperture: f64,
        concave: bool,
    },
    /// A solid lens ([`crate::exact_lens`]): what the lens analysis traces. As a parameter
    /// square it is its front surface (u turns about Z from +X, v runs from the axis to the
    /// rim); the mirror analyses take a lens's triangles.
    Lens(Box<ExactLens>),
}

/// A point of an exact surface, world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub p_world: DVec3,
    /// Unit normal on the side the generator's mesh faces.
    pub n_world: DVec3,
}

/// An exact shape placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct ExactSurface {
    pub shape: ExactShape,
    pub world_from_object: DMat4,
}

impl ExactSurface {
    pub fn new(shape: ExactShape) -> ExactSurface {
        ExactSurface {
            shape,
            world_from_object: DMat4::IDENTITY,
        }
    }

    /// Moves the surface by `world_from_before` (applied after its present placement).
    pub fn transform(&mut self, world_from_before: Mat4) {
        self.world_from_object = world_from_before.as_dmat4() * self.world_from_object;
    }

    /// The surface's point and normal at parameters `uv` (clamped to the unit square).
    pub fn at(&self, uv: DVec2) -> SurfacePoint {
        let uv = uv.clamp(DVec2::ZERO, DVec2::ONE);
        let (p_object, n_object) = match &self.shape {
            ExactShape::BicubicPatch { control } => {
                let (p, _, _) = bezier_patch(control, uv.x, uv.y);
                (p, bezier_patch_normal(control, uv.x, uv.y))
            }
            ExactShape::Sphere { radius } => {
                let (phi, theta) = (TAU * uv.x, PI * uv.y);
                let n = DVec3::new(
                    theta.sin() * phi.sin(),
                    theta.cos(),
                    theta.sin() * phi.cos(),
                );
                (n * *radius, n)
            }
            ExactShape::SphericalCap {
                radius_of_curvature: r,
                aperture,
                concave,
            } => {
                let theta_max = (aperture * 0.5 / r).clamp(-1.0, 1.0).asin();
                let (phi, theta) = (TAU * uv.x, uv.y * theta_max);
                let radial = DVec3::new(phi.cos(), phi.sin(), 0.0) * theta.sin();
                if *concave {
                    let centre = DVec3::new(0.0, 0.0, *r);
                    let p = centre + *r * (radial - DVec3::Z * theta.cos());
                    (p, (centre - p) / *r)
                } else {
                    let centre = DVec3::new(0.0, 0.0, -*r);
                    let p = centre + *r * (radial + DVec3::Z * theta.cos());
                    (p, (p - centre) / *r)
                }
            }
            ExactShape::Lens(lens) => {
                let (phi, rho) = (TAU * uv.x, uv.y * lens.rim());
                lens.surface_point(Face::Front, rho * phi.cos(), rho * phi.sin())
                    .unwrap_or((DVec3::ZERO, -DVec3::Z))
            }
        };
        let normal_from_object = DMat3::from_mat4(self.world_from_object)
            .inverse()
            .transpose();
        SurfacePoint {
            p_world: self.world_from_object.transform_point3(p_object),
            n_world: (normal_from_object * n_object)
                .try_normalize()
                .unwrap_or(n_object),
        }
    }

    /// The lens this surface is, if it is one.
    pub fn lens(&self) -> Option<&ExactLens> {
        match &self.shape {
            ExactShape::Lens(lens) => Some(lens),
            _ => None,
        }
    }

    /// The first point along the ray `origin + t dir` (t > 0) where it meets the surface, with
    /// its parameters: closed form on a sphere or cap (in object space, where it is a sphere),
    /// Newton's method on a patch or a lens's surfaces, started from each cell of a coarse grid of (u, v) so that a
    /// wavy patch's nearer crossing is not missed.
    pub fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<(f64, DVec2)> {
        let object_from_world = self.world_from_object.inverse();
        let o = object_from_world.transform_point3(origin.as_dvec3());
        let d = object_from_world.transform_vector3(dir.as_dvec3());
        match &self.shape {
            ExactShape::BicubicPatch { control } => patch_intersect(control, o, d),
            ExactShape::Sphere { radius } => {
                let t = sphere_roots(o, d, DVec3::ZERO, *radius)
                    .into_iter()
                    .flatten()
                    .find(|t| *t > 1e-9)?;
                let n = (o + d * t) / *radius;
                let phi = n.x.atan2(n.z).rem_euclid(TAU);
                Some((t, DVec2::new(phi / TAU, n.y.clamp(-1.0, 1.0).acos() / PI)))
            }
            ExactShape::SphericalCap {
                radius_of_curvature: r,
                aperture,
                concave,
            } => {
                let centre = DVec3::new(0.0, 0.0, if *concave { *r } else { -*r });
                let theta_max = (aperture * 0.5 / r).clamp(-1.0, 1.0).asin();
                sphere_roots(o, d, centre, *r)
                    .into_iter()
                    .flatten()
                    .filter(|t| *t > 1e-9)
                    .find_map(|t| {
                        let p = o + d * t;
                        // The cap is the part of the sphere on the apex's side, within θ_max of it.
                        let towards_apex = if *concave { -(p - centre) } else { p - centre };
                        let theta = (towards_apex.z / r).clamp(-1.0, 1.0).acos();
                        (theta <= theta_max + 1e-12).then(|| {
                            let phi = p.y.atan2(p.x).rem_euclid(TAU);
                            let v = if theta_max > 0.0 {
                                theta / theta_max
                            } else {
                                0.0
                            };
                            (t, DVec2::new(phi / TAU, v.min(1.0)))
                        })
                    })
            }
            ExactShape::Lens(lens) => {
                let hit = lens.next_hit(o, d, 1e-12)?;
                let phi = hit.p.y.atan2(hit.p.x).rem_euclid(TAU);
                let v = (hit.p.truncate().length() / lens.rim()).min(1.0);
                Some((hit.t, DVec2::new(phi / TAU, v)))
            }
        }
    }
}

/// The two roots of |o + t d − c|² = r², nearer first.
fn sphere_roots(o: DVec3, d: DVec3, c: DVec3, r: f64) -> [Option<f64>; 2] {
    let oc = o - c;
    let (a, b, k) = (d.dot(d), oc.dot(d), oc.dot(oc) - r * r);
    let disc = b * b - a * k;
    if disc < 0.0 || a == 0.0 {
        return [None, None];
    }
    let s = disc.sqrt();
    [Some((-b - s) / a), Some((-b + s) / a)]
}

fn bernstein3(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t]
}

fn bernstein3_derivative(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        -3.0 * s * s,
        3.0 * s * s - 6.0 * s * t,
        6.0 * s * t - 3.0 * t * t,
        3.0 * t * t,
    ]
}

/// Point and partial derivatives of a bicubic Bézier patch.
pub fn bezier_patch(control: &[[DVec3; 4]; 4], u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let (bu, bv) = (bernstein3(u), bernstein3(v));
    let (du, dv) = (bernstein3_derivative(u), bernstein3_derivative(v));
    let (mut p, mut pu, mut pv) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for (j, row) in control.iter().enumerate() {
        for (i, &c) in row.iter().enumerate() {
            p += c * bu[i] * bv[j];
            pu += c * du[i] * bv[j];
            pv += c * bu[i] * dv[j];
        }
    }
    (p, pu, pv)
}

/// Exact patch normal, Pu × Pv; where the patch collapses (Pu or Pv vanishes, as at the
/// teapot's poles) the limit is taken by stepping a little inside the parameter square.
pub fn bezier_patch_normal(control: &[[DVec3; 4]; 4], u: f64, v: f64) -> DVec3 {
    let (_, pu, pv) = bezier_patch(control, u, v);
    let n = pu.cross(pv);
    if n.length_squared() > 1e-24 {
        return n.normalize();
    }
    let eps = 1e-3;
    let (_, pu, pv) = bezier_patch(control, u.clamp(eps, 1.0 - eps), v.clamp(eps, 1.0 - eps));
    pu.cross(pv).try_normalize().unwrap_or(DVec3::Z)
}

/// A patch's control points in double precision.
pub fn control_points(control: &[[Vec3; 4]; 4]) -> [[DVec3; 4]; 4] {
    control.map(|row| row.map(|p| p.as_dvec3()))
}

/// Newton's method on F(t, u, v) = o + t d − P(u, v) = 0 from each start of a 4 × 4 grid of
/// (u, v); the nearest root with (u, v) in the square and t > 0.
fn patch_intersect(control: &[[DVec3; 4]; 4], o: DVec3, d: DVec3) -> Option<(f64, DVec2)> {
    let mut best: Option<(f64, DVec2)> = None;
    for start in 0..16 {
        let mut uv = DVec2::new(
            (start % 4) as f64 / 3.0 * 0.9 + 0.05,
            (start / 4) as f64 / 3.0 * 0.9 + 0.05,
        );
        let (p, _, _) = bezier_patch(control, uv.x, uv.y);
        let mut t = (p - o).dot(d) / d.length_squared();
        for _ in 0..40 {
            let (p, pu, pv) = bezier_patch(control, uv.x, uv.y);
            let f = o + d * t - p;
            if f.length() < 1e-12 * (1.0 + p.length()) {
                break;
            }
            // J = [d, −Pu, −Pv]; solve J Δ = −F.
            let j = DMat3::from_cols(d, -pu, -pv);
            if j.determinant().abs() < 1e-300 {
                break;
            }
            let step = j.inverse() * -f;
            t += step.x;
            uv += DVec2::new(step.y, step.z);
            if !(uv.x.is_finite() && uv.y.is_finite()) || uv.abs().max_element() > 4.0 {
                break;
            }
        }
        let (p, _, _) = bezier_patch(control, uv.x, uv.y);
        let inside =
            uv.cmpge(DVec2::splat(-1e-9)).all() && uv.cmple(DVec2::splat(1.0 + 1e-9)).all();
        let converged = (o + d * t - p).length() < 1e-9 * (1.0 + p.length());
        if inside && converged && t > 1e-9 && best.is_none_or(|(b, _)| t < b) {
            best = Some((t, uv.clamp(DVec2::ZERO, DVec2::ONE)));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_aimed_at_a_sample_meets_the_surface_there() {
        let control = control_points(&crate::generators::door_mirror_control_points());
        let mut patch = ExactSurface::new(ExactShape::BicubicPatch {
            control: Box::new(control),
        });
        patch.transform(Mat4::from_translation(Vec3::new(0.3, -0.2, 0.1)));
        let eye = Vec3::new(0.28, 0.1, 0.9);
        for uv in [
            DVec2::new(0.3, 0.7),
            DVec2::new(0.9, 0.1),
            DVec2::new(0.5, 0.5),
        ] {
            let target = patch.at(uv).p_world;
            let dir = (target - eye.as_dvec3()).normalize().as_vec3();
            let (_, found) = patch.intersect(eye, dir).expect("the ray meets the patch");
            assert!(found.distance(uv) < 1e-5, "{found} for {uv}");
        }
        let cap = ExactSurface::new(ExactShape::SphericalCap {
            radius_of_curvature: 1.2,
            aperture: 0.2,
            concave: false,
        });
        let target = cap.at(DVec2::new(0.2, 0.6));
        assert!((target.p_world - DVec3::new(0.0, 0.0, -1.2)).length() - 1.2 < 1e-12);
        let dir = (target.p_world - DVec3::new(0.0, 0.0, 2.0))
            .normalize()
            .as_vec3();
        let (_, uv) = cap.intersect(Vec3::new(0.0, 0.0, 2.0), dir).unwrap();
        assert!(uv.distance(DVec2::new(0.2, 0.6)) < 1e-5, "{uv}");
        // Beside the cap's rim: no hit.
        assert!(cap
            .intersect(Vec3::new(0.2, 0.0, 2.0), Vec3::NEG_Z)
            .is_none());
    }
}
