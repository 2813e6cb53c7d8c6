//! A lens's exact surfaces: what [`crate::generators::lens`] and
//! [`crate::spectacle::spectacle_lens`] tessellate, kept so that `specula analyze lens` traces
//! the surfaces themselves (the rule mirrors follow, [`crate::exact`]).
//!
//! **Frame** (the lens's own): light travels +Z; the front vertex is at the origin, the back
//! vertex at (0, 0, centre thickness); +X is the wearer's right, +Y up. Each optical surface is
//! a height field z = vertex_z + s(x, y) over the disc of the lens's diameter; the rim between
//! them is the cylinder x² + y² = (diameter / 2)².
//!
//! **Surfaces.** Each is a torus whose principal meridians are circular arcs (a sphere when
//! both curvatures agree): curvature c_u along the `axis` meridian (u) and c_v across it (v),
//! the circle of the v-meridian swept about an axis parallel to v at distance 1 / c_u from the
//! vertex: s(u, v) = R_u − sgn(R_u) √((R_u − s_v(v))² − u²), s_v the v-arc's sag. Curvatures
//! are positive when the centre of curvature lies on the +Z side.
//!
//! **Intersection** is Newton's method on the ray's height above the surface, started where
//! the ray crosses the vertex plane (the surfaces are shallow over a lens's disc), to a
//! root within 1e-15 of the ray's length; normals are the height field's exact normals.

use glam::{DVec2, DVec3};

use crate::freeform::Freeform;

/// One optical surface of a lens: z = `vertex_z` + s(x, y) (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct LensSurface {
    pub vertex_z: f64,
    pub shape: SurfaceShape,
}

/// What a lens surface's sag s(x, y) is.
#[derive(Clone, Debug, PartialEq)]
pub enum SurfaceShape {
    /// A torus (a sphere when both curvatures agree), module doc.
    Toric {
        /// Curvature along the `axis` meridian, 1 / metres.
        curvature_axis: f64,
        /// Curvature across it.
        curvature_across: f64,
        /// The axis meridian's unit direction in the (x, y) plane.
        axis: DVec2,
    },
    Freeform(Freeform),
}

/// Which part of the lens a ray met.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Face {
    Front,
    Back,
    Rim,
}

/// A crossing of the lens's boundary, in its own frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensHit {
    pub t: f64,
    pub p: DVec3,
    /// Unit, pointing out of the glass.
    pub n_outward: DVec3,
    pub face: Face,
}

/// A lens's two optical surfaces and its round rim, in its own frame (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct ExactLens {
    pub front: LensSurface,
    pub back: LensSurface,
    pub diameter: f64,
}

/// Sag of a circular arc of curvature `c` at distance `r` from its vertex (None beyond the
/// arc's reach).
pub fn arc_sag(c: f64, r: f64) -> Option<f64> {
    let k = 1.0 - c * c * r * r;
    // Short of the arc's end, where its slope is infinite.
    (k > 1e-12).then(|| c * r * r / (1.0 + k.sqrt()))
}

/// d(sag)/dr of the arc.
fn arc_slope(c: f64, r: f64) -> f64 {
    c * r / (1.0 - c * c * r * r).max(1e-300).sqrt()
}

/// A torus with curvature `cu` along u and `cv` along v at its vertex: its sag and gradient
/// (∂z/∂u, ∂z/∂v) at (u, v); None where (u, v) lies beyond the surface.
pub fn toric_sag(cu: f64, cv: f64, u: f64, v: f64) -> Option<(f64, f64, f64)> {
    let zv = arc_sag(cv, v)?;
    let dzv = arc_slope(cv, v);
    if cu == 0.0 {
        return Some((zv, 0.0, dzv));
    }
    let radius = 1.0 / cu;
    let d = radius - zv;
    let k = d * d - u * u;
    if k <= 1e-12 * d * d || d * radius <= 0.0 {
        return None;
    }
    let s = k.sqrt();
    let sign = radius.signum();
    Some((radius - sign * s, sign * u / s, sign * d * dzv / s))
}

impl LensSurface {
    /// How far the surface's curvature at (x, y) may be off, 1 / metres: a sag grid's
    /// interpolation error there, 0 for a surface in closed form.
    pub fn curvature_uncertainty(&self, x: f64, y: f64) -> f64 {
        match &self.shape {
            SurfaceShape::Freeform(f) => f.curvature_uncertainty(x, y),
            SurfaceShape::Toric { .. } => 0.0,
        }
    }

    pub fn sphere(curvature: f64, vertex_z: f64) -> LensSurface {
        LensSurface {
            vertex_z,
            shape: SurfaceShape::Toric {
                curvature_axis: curvature,
                curvature_across: curvature,
                axis: DVec2::X,
            },
        }
    }

    pub fn freeform(shape: Freeform, vertex_z: f64) -> LensSurface {
        LensSurface {
            vertex_z,
            shape: SurfaceShape::Freeform(shape),
        }
    }

    /// The principal curvatures at the vertex (larger first for a free-form surface; along
    /// and across the axis for a torus), 1 / metres.
    pub fn vertex_curvatures(&self) -> [f64; 2] {
        match &self.shape {
            SurfaceShape::Toric {
                curvature_axis,
                curvature_across,
                ..
            } => [*curvature_axis, *curvature_across],
            SurfaceShape::Freeform(f) => f
                .local(0.0, 0.0)
                .map_or([f64::NAN; 2], |l| l.principal_curvatures()),
        }
    }

    /// A torus whose `curvature_axis` meridian runs along TABO `axis_deg` (anticlockwise from
    /// the right of an examiner facing the wearer, who has the wearer's left, −X, on the right).
    pub fn toric(
        curvature_axis: f64,
        curvature_across: f64,
        axis_deg: f64,
        vertex_z: f64,
    ) -> LensSurface {
        let theta = axis_deg.to_radians();
        LensSurface {
            vertex_z,
            shape: SurfaceShape::Toric {
                curvature_axis,
                curvature_across,
                axis: DVec2::new(-theta.cos(), theta.sin()),
            },
        }
    }

    /// The surface's height z and gradient (∂z/∂x, ∂z/∂y) at (x, y).
    pub fn height(&self, x: f64, y: f64) -> Option<(f64, DVec2)> {
        let (curvature_axis, curvature_across, axis) = match &self.shape {
            SurfaceShape::Toric {
                curvature_axis,
                curvature_across,
                axis,
            } => (*curvature_axis, *curvature_across, *axis),
            SurfaceShape::Freeform(f) => {
                let local = f.local(x, y)?;
                return Some((self.vertex_z + local.sag, local.gradient));
            }
        };
        let across = axis.perp();
        let q = DVec2::new(x, y);
        let (u, v) = (q.dot(axis), q.dot(across));
        let (s, dsu, dsv) = if curvature_axis == curvature_across {
            let r = q.length();
            let s = arc_sag(curvature_axis, r)?;
            let slope = arc_slope(curvature_axis, r);
            if r > 0.0 {
                (s, slope * u / r, slope * v / r)
            } else {
                (s, 0.0, 0.0)
            }
        } else {
            toric_sag(curvature_axis, curvature_across, u, v)?
        };
        Some((self.vertex_z + s, axis * dsu + across * dsv))
    }

    /// Where the ray o + t d first crosses the surface with t > `t_min`: Newton's method on
    /// its height above the surface, from its crossing of the vertex plane.
    fn intersect(&self, o: DVec3, d: DVec3, t_min: f64) -> Option<f64> {
        if d.z.abs() < 1e-12 * d.length() {
            return None;
        }
        let mut t = (self.vertex_z - o.z) / d.z;
        for _ in 0..60 {
            let p = o + d * t;
            let (z, gradient) = self.height(p.x, p.y)?;
            let slope = d.z - gradient.dot(d.truncate());
            if slope.abs() < 1e-300 {
                return None;
            }
            let step = (p.z - z) / slope;
            t -= step;
            if step.abs() <= 1e-15 * (1.0 + t.abs()) {
                let p = o + d * t;
                let (z, _) = self.height(p.x, p.y)?;
                return ((p.z - z).abs() < 1e-12 && t > t_min).then_some(t);
            }
        }
        None
    }
}

impl ExactLens {
    /// How far the lens's power through (x, y) may be off for its surfaces' uncertain
    /// curvatures, dioptres: (n − 1) times the sum of the two surfaces' (each surface's power is
    /// (n − 1) times its curvature, to first order).
    pub fn power_uncertainty_d(&self, x: f64, y: f64, ior: f64) -> f64 {
        (ior - 1.0)
            * (self.front.curvature_uncertainty(x, y) + self.back.curvature_uncertainty(x, y))
    }

    pub fn rim(&self) -> f64 {
        self.diameter * 0.5
    }

    /// The point of `face` (front or back) at (x, y) and its outward normal.
    pub fn surface_point(&self, face: Face, x: f64, y: f64) -> Option<(DVec3, DVec3)> {
        let (surface, outward_z) = match face {
            Face::Front => (&self.front, -1.0),
            Face::Back => (&self.back, 1.0),
            Face::Rim => return None,
        };
        let (z, g) = surface.height(x, y)?;
        let n = DVec3::new(-g.x, -g.y, 1.0) * outward_z;
        Some((DVec3::new(x, y, z), n.normalize()))
    }

    /// The first crossing of the lens's boundary by the ray o + t d with t > `t_min`
    /// (lens frame; `d` need not be unit, `t` is in its units).
    pub fn next_hit(&self, o: DVec3, d: DVec3, t_min: f64) -> Option<LensHit> {
        let rim = self.rim();
        let within = |t: f64| (o + d * t).truncate().length() <= rim * (1.0 + 1e-12);
        let faces = [Face::Front, Face::Back].into_iter().filter_map(|face| {
            let surface = if face == Face::Front {
                &self.front
            } else {
                &self.back
            };
            let t = surface.intersect(o, d, t_min).filter(|&t| within(t))?;
            let p = o + d * t;
            let (p, n_outward) = self.surface_point(face, p.x, p.y)?;
            Some(LensHit {
                t,
                p,
                n_outward,
                face,
            })
        });
        let rim_hits = self.rim_roots(o, d).into_iter().flatten().filter_map(|t| {
            let p = o + d * t;
            let (front, _) = self.front.height(p.x, p.y)?;
            let (back, _) = self.back.height(p.x, p.y)?;
            (t > t_min && (front..=back).contains(&p.z)).then(|| LensHit {
                t,
                p,
                n_outward: DVec3::new(p.x, p.y, 0.0).normalize(),
                face: Face::Rim,
            })
        });
        faces.chain(rim_hits).min_by(|a, b| a.t.total_cmp(&b.t))
    }

    /// The ray's crossings of the rim's cylinder.
    fn rim_roots(&self, o: DVec3, d: DVec3) -> [Option<f64>; 2] {
        let (o2, d2) = (o.truncate(), d.truncate());
        let a = d2.length_squared();
        let b = o2.dot(d2);
        let c = o2.length_squared() - self.rim() * self.rim();
        let disc = b * b - a * c;
        if a < 1e-300 || disc < 0.0 {
            return [None, None];
        }
        let s = disc.sqrt();
        [Some((-b - s) / a), Some((-b + s) / a)]
    }

    /// Whether `p` (lens frame) lies in the glass.
    pub fn contains(&self, p: DVec3) -> bool {
        if p.truncate().length() > self.rim() {
            return false;
        }
        match (self.front.height(p.x, p.y), self.back.height(p.x, p.y)) {
            (Some((front, _)), Some((back, _))) => (front..=back).contains(&p.z),
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_meets_a_sphere_where_the_closed_form_puts_it() {
        let lens = ExactLens {
            front: LensSurface::sphere(1.0 / 0.12, 0.0),
            back: LensSurface::sphere(1.0 / 0.075, 0.002),
            diameter: 0.05,
        };
        let (o, d) = (
            DVec3::new(0.011, -0.004, -0.05),
            DVec3::new(0.1, 0.05, 1.0).normalize(),
        );
        let hit = lens.next_hit(o, d, 1e-12).unwrap();
        assert_eq!(hit.face, Face::Front);
        // The sphere about (0, 0, R) of radius R.
        let centre = DVec3::new(0.0, 0.0, 0.12);
        assert!(((hit.p - centre).length() - 0.12).abs() < 1e-14);
        // The front faces the object (−Z), away from its centre of curvature.
        assert!(hit.n_outward.dot((hit.p - centre).normalize()) > 1.0 - 1e-12);
        let out = lens.next_hit(hit.p, d, 1e-12).unwrap();
        assert_eq!(out.face, Face::Back);
        let centre = DVec3::new(0.0, 0.0, 0.077);
        assert!(((out.p - centre).length() - 0.075).abs() < 1e-14);
        assert!(out.n_outward.dot((centre - out.p).normalize()) > 1.0 - 1e-12);
        assert!(lens.contains(hit.p.lerp(out.p, 0.5)));
        // Beside the rim, through the glass's edge only.
        let edge = lens
            .next_hit(DVec3::new(-0.03, 0.0, 0.004), DVec3::X, 1e-12)
            .unwrap();
        assert_eq!(edge.face, Face::Rim);
        assert!((edge.p.x + 0.025).abs() < 1e-15);
    }

    #[test]
    fn a_torus_has_its_curvatures_along_its_meridians_and_its_gradient() {
        let (cu, cv) = (1.0 / 0.08, 1.0 / 0.12);
        let surface = LensSurface::toric(cu, cv, 30.0, 0.0);
        let h = 1e-4;
        let along = |dir: DVec2| surface.height(dir.x * h, dir.y * h).unwrap().0 * 2.0 / (h * h);
        let SurfaceShape::Toric { axis, .. } = surface.shape else {
            panic!("a torus")
        };
        assert!((along(axis) - cu).abs() < 1e-4 * cu);
        assert!((along(axis.perp()) - cv).abs() < 1e-4 * cv);
        let (x, y) = (0.01, -0.015);
        let (z, g) = surface.height(x, y).unwrap();
        let e = 1e-7;
        let gx = (surface.height(x + e, y).unwrap().0 - z) / e;
        let gy = (surface.height(x, y + e).unwrap().0 - z) / e;
        assert!((g.x - gx).abs() < 1e-5 && (g.y - gy).abs() < 1e-5);
        // A ray aimed at a point of the torus meets it there.
        let target = DVec3::new(x, y, z);
        let o = DVec3::new(0.0, 0.0, -0.04);
        let t = surface.intersect(o, target - o, 1e-12).unwrap();
        assert!((t - 1.0).abs() < 1e-12, "{t}");
    }
}
