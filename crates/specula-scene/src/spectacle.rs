//! A spectacle lens made from a prescription: a spherical front surface of the given base
//! curve and a toric back surface (minus-cylinder form), each principal meridian of the back
//! solved with the thick-lens formula so that the lens's back vertex power is the
//! prescription's in that meridian.
//!
//! **Frame** (the lens's own, before a scene places it): light travels +Z, from the object to
//! the eye, so the wearer looks along −Z with +Y up and +X on the wearer's right. The front
//! vertex is at the origin, the back vertex at (0, 0, `center_thickness`). An examiner facing
//! the wearer looks along +Z and has −X on the right: a TABO axis θ (degrees anticlockwise from
//! the examiner's right) is the meridian (−cos θ, sin θ, 0).
//!
//! **Powers.** The base curve is the front surface's power in the material's own index n_d:
//! F1 = (n_d − 1) / R1. In each principal meridian the back vertex power is
//! F_v = F1 / (1 − (t / n_d) F1) + F2, so F2 = F_v − F1 / (1 − (t / n_d) F1) and
//! R2 = (1 − n_d) / F2 (flat where F2 = 0). The axis meridian has F_v = sphere, the meridian
//! across it sphere + cylinder. A plus cylinder is transposed to minus form first.
//!
//! **Surfaces.** The back is a torus whose two principal meridians are circular arcs: along the
//! axis meridian (u) the radius R2 of the sphere's power, across it (v) that of sphere +
//! cylinder; it is the circle in the v-meridian swept about an axis parallel to v at distance
//! R_u from the vertex, z(u, v) = R_u − sgn(R_u) √((R_u − z_v(v))² − u²) with z_v the v-arc's
//! sag. Normals are the surfaces' exact normals at the vertices.
//!
//! **Tessellation.** `rings` rings from the centre to the rim and `segments` around, per
//! surface, and one band of quads for the edge. Interpolated normals reproduce a sphere's
//! normals exactly in direction (the normalised mix of (p_i − c) / R is the normal at the mixed
//! point), so a spherical surface's power is right at any tessellation; a torus's normals are
//! only approximated between the vertices, so a toric lens's cylinder converges as the
//! tessellation grows (docs/analyses/lens.md measures it).

use std::f64::consts::TAU;

use glam::{DVec2, DVec3, Vec2, Vec3};

use crate::exact_lens::{ExactLens, Face, LensSurface};
use crate::freeform::Freeform;
use crate::generators::{append_grid, empty, finish, Sample};
use crate::{ExactShape, ExactSurface};
use crate::{Mesh, SceneError};

/// A spectacle lens's prescription and blank. Lengths in metres, powers in dioptres.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Prescription {
    /// Back vertex power in the axis meridian.
    pub sphere: f64,
    /// Cylinder (minus form; a plus cylinder is transposed).
    pub cylinder: f64,
    /// Cylinder axis, TABO degrees.
    pub axis_deg: f64,
    /// n_d.
    pub index: f64,
    /// Abbe number V = (n_d − 1) / (n_F − n_C).
    pub abbe: f64,
    pub center_thickness: f64,
    /// Front surface power in the material's index, (n_d − 1) / R1.
    pub base_curve: f64,
    pub diameter: f64,
    /// A free-form front in place of the base curve's sphere (the base curve is then its
    /// power at the vertex, where the back is solved).
    pub front: Option<Freeform>,
    /// A free-form back in place of the solved torus: sphere, cylinder and axis are then what
    /// the lens was ordered as, not how it is made.
    pub back: Option<Freeform>,
    /// A progressive lens's ordered addition.
    pub add_d: Option<f64>,
    /// The distance and near reference points where the design sets them, metres in the lens
    /// frame (x right, y up).
    pub distance_reference: Option<DVec2>,
    pub near_reference: Option<DVec2>,
}

impl Prescription {
    /// The same prescription in minus-cylinder form, axis in [0, 180).
    pub fn minus_cylinder(&self) -> Prescription {
        let mut p = self.clone();
        if p.cylinder > 0.0 {
            p.sphere += p.cylinder;
            p.cylinder = -p.cylinder;
            p.axis_deg += 90.0;
        }
        p.axis_deg = p.axis_deg.rem_euclid(180.0);
        p
    }

    /// The glass's red, green and blue indices (n_C, n_d, n_F), as the reference uses them
    /// ([`crate::material::ior_from_abbe`]).
    pub fn indices(&self) -> Vec3 {
        crate::material::ior_from_abbe(self.index as f32, self.abbe as f32)
    }

    /// Back vertex power of the front surface alone, F1 / (1 − (t / n) F1).
    fn front_effective(&self) -> f64 {
        let f1 = self.base_curve;
        f1 / (1.0 - self.center_thickness / self.index * f1)
    }

    /// The back surface's curvature (1 / R2) for back vertex power `vertex_power`.
    fn back_curvature(&self, vertex_power: f64) -> f64 {
        let f2 = vertex_power - self.front_effective();
        f2 / (1.0 - self.index)
    }

    /// The front surface's curvature, 1 / R1.
    fn front_curvature(&self) -> f64 {
        self.base_curve / (self.index - 1.0)
    }

    fn check(&self) -> Result<(), SceneError> {
        let bad = |message: String| Err(SceneError::invalid("spectacle-lens", message));
        let values = [
            ("sphere", self.sphere),
            ("cylinder", self.cylinder),
            ("axis", self.axis_deg),
            ("index", self.index),
            ("abbe", self.abbe),
            ("center_thickness", self.center_thickness),
            ("base_curve", self.base_curve),
            ("diameter", self.diameter),
        ];
        for (name, value) in values {
            if !value.is_finite() {
                return bad(format!("{name} = {value} is not a number"));
            }
        }
        if self.index <= 1.0 {
            return bad(format!("index {} must exceed 1", self.index));
        }
        if self.abbe <= 0.0 {
            return bad(format!("abbe {} must be positive", self.abbe));
        }
        if self.center_thickness <= 0.0 || self.diameter <= 0.0 {
            return bad(format!(
                "center_thickness {} m and diameter {} m must be positive",
                self.center_thickness, self.diameter
            ));
        }
        let rim = 0.5 * self.diameter;
        for (side, surface) in [("front", &self.front), ("back", &self.back)] {
            if let Some([[x0, x1], [y0, y1]]) = surface.as_ref().and_then(Freeform::extent) {
                if x0 > -rim || x1 < rim || y0 > -rim || y1 < rim {
                    return bad(format!(
                        "the {side}'s {} spans x {:.1} to {:.1} mm and y {:.1} to {:.1} mm: it \
                         must cover the lens's {:.1} mm disc (±{:.1} mm)",
                        surface.as_ref().expect("a grid").describe(),
                        x0 * 1e3,
                        x1 * 1e3,
                        y0 * 1e3,
                        y1 * 1e3,
                        self.diameter * 1e3,
                        rim * 1e3
                    ));
                }
            }
        }
        if 1.0 - self.center_thickness / self.index * self.base_curve <= 0.0 {
            return bad(format!(
                "a base curve of {} D focuses inside a {} m thick lens: no back surface can make \
                 this power",
                self.base_curve, self.center_thickness
            ));
        }
        Ok(())
    }
}

impl Prescription {
    /// The lens's exact surfaces, in the lens frame (module doc).
    pub fn exact_lens(&self) -> ExactLens {
        let p = self.minus_cylinder();
        let front = match &p.front {
            Some(f) => LensSurface::freeform(f.clone(), 0.0),
            None => LensSurface::sphere(p.front_curvature(), 0.0),
        };
        let back = match &p.back {
            Some(f) => LensSurface::freeform(f.clone(), p.center_thickness),
            None => LensSurface::toric(
                p.back_curvature(p.sphere),
                p.back_curvature(p.sphere + p.cylinder),
                p.axis_deg,
                p.center_thickness,
            ),
        };
        ExactLens {
            front,
            back,
            diameter: p.diameter,
        }
    }
}

/// The lens of `prescription` with `rings` × `segments` per surface (module doc). Refused,
/// saying why: values that are not numbers, an index ≤ 1, and a prescription no lens of that
/// diameter can have (a surface that does not reach the rim, an edge thinner than nothing).
pub fn spectacle_lens(
    prescription: &Prescription,
    rings: u32,
    segments: u32,
) -> Result<Mesh, SceneError> {
    prescription.check()?;
    let p = prescription.minus_cylinder();
    let shape = p.exact_lens();
    let front = |x: f64, y: f64| shape.surface_point(Face::Front, x, y);
    let back = |x: f64, y: f64| shape.surface_point(Face::Back, x, y);
    let rim = p.diameter * 0.5;
    let segments = segments.max(8);
    let rings = rings.max(2);
    let bad = |message: String| SceneError::invalid("spectacle-lens", message);
    // Every rim point must exist on both surfaces, with glass between them.
    let mut thinnest = f64::INFINITY;
    let at = |u: f32, v: f32| {
        // The seam's columns coincide exactly (see generators::turn).
        let phi = if u >= 1.0 { 0.0 } else { f64::from(u) * TAU };
        let rho = f64::from(v) * rim;
        (rho * phi.cos(), rho * phi.sin())
    };
    // Every vertex the mesh places must lie on both surfaces (the grid's own coordinates, so
    // that building it cannot fail), and the rim, sampled finer, must hold glass.
    let reaches = (0..=segments).all(|i| {
        (0..=rings).all(|j| {
            let (x, y) = at(i as f32 / segments as f32, j as f32 / rings as f32);
            front(x, y).is_some() && back(x, y).is_some()
        })
    });
    let short_of_the_rim = || {
        bad(format!(
            "a surface of this prescription does not reach a {} mm rim: choose a smaller \
             diameter or a flatter base curve",
            p.diameter * 1e3
        ))
    };
    if !reaches {
        return Err(short_of_the_rim());
    }
    for k in 0..segments * 4 {
        let phi = TAU * f64::from(k) / f64::from(segments * 4);
        let (x, y) = (rim * phi.cos(), rim * phi.sin());
        let (Some((front, _)), Some((back, _))) = (front(x, y), back(x, y)) else {
            return Err(short_of_the_rim());
        };
        thinnest = thinnest.min(back.z - front.z);
    }
    if thinnest <= 0.0 {
        return Err(bad(format!(
            "the edge would be {:.2} mm thick at a {} mm diameter: no lens can have this \
             prescription there; make the centre thicker or the lens smaller",
            thinnest * 1e3,
            p.diameter * 1e3
        )));
    }
    let mut mesh = empty("spectacle lens");
    let to_sample = |(point, normal): (DVec3, DVec3), x: f64, y: f64| Sample {
        p: point.as_vec3(),
        n: normal.as_vec3(),
        uv: Vec2::new((0.5 + x / p.diameter) as f32, (0.5 - y / p.diameter) as f32),
    };
    append_grid(&mut mesh, segments, rings, |u, v| {
        let (x, y) = at(u, v);
        to_sample(front(x, y).expect("checked to the rim"), x, y)
    });
    append_grid(&mut mesh, segments, rings, |u, v| {
        let (x, y) = at(u, v);
        to_sample(back(x, y).expect("checked to the rim"), x, y)
    });
    append_grid(&mut mesh, segments, 1, |u, v| {
        let (x, y) = at(u, 1.0);
        let front = front(x, y).expect("checked").0;
        let back = back(x, y).expect("checked").0;
        let point = front.lerp(back, f64::from(v));
        Sample {
            p: point.as_vec3(),
            n: Vec3::new(x as f32, y as f32, 0.0).normalize(),
            uv: Vec2::new(u, v),
        }
    });
    let mut mesh = finish(mesh);
    mesh.exact = Some(ExactSurface::new(ExactShape::Lens(Box::new(shape))));
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prescription(sphere: f64, cylinder: f64, axis_deg: f64) -> Prescription {
        Prescription {
            sphere,
            cylinder,
            axis_deg,
            index: 1.6,
            abbe: 42.0,
            center_thickness: 0.002,
            base_curve: 4.0,
            diameter: 0.05,
            ..Prescription::default()
        }
    }

    #[test]
    fn each_meridian_s_back_curvature_gives_its_back_vertex_power() {
        let p = prescription(-2.0, -1.0, 30.0);
        let lens = p.exact_lens();
        // Thick-lens formula, forwards: F1 / (1 − t F1 / n) + (1 − n) / R2.
        let power = |c2: f64| p.front_effective() + (1.0 - p.index) * c2;
        let [along, across] = lens.back.vertex_curvatures();
        assert!((power(along) - -2.0).abs() < 1e-12);
        assert!((power(across) - -3.0).abs() < 1e-12);
        assert!((p.front_curvature() - 4.0 / 0.6).abs() < 1e-12);
    }

    #[test]
    fn a_plus_cylinder_is_transposed() {
        let p = prescription(-3.0, 1.0, 120.0).minus_cylinder();
        assert_eq!((p.sphere, p.cylinder, p.axis_deg), (-2.0, -1.0, 30.0));
    }

    #[test]
    fn impossible_prescriptions_are_refused_saying_why() {
        let thin_edge = Prescription {
            sphere: 6.0,
            center_thickness: 0.002,
            diameter: 0.07,
            ..prescription(6.0, 0.0, 0.0)
        };
        let e = spectacle_lens(&thin_edge, 8, 32).unwrap_err().to_string();
        assert!(e.contains("edge would be") && e.contains("mm thick"), "{e}");
        let steep = Prescription {
            base_curve: 30.0,
            ..prescription(-2.0, 0.0, 0.0)
        };
        let e = spectacle_lens(&steep, 8, 32).unwrap_err().to_string();
        assert!(e.contains("does not reach"), "{e}");
        let glass = Prescription {
            index: 0.9,
            ..prescription(-2.0, 0.0, 0.0)
        };
        let e = spectacle_lens(&glass, 8, 32).unwrap_err().to_string();
        assert!(e.contains("index 0.9 must exceed 1"), "{e}");
        let nan = Prescription {
            sphere: f64::NAN,
            ..prescription(-2.0, 0.0, 0.0)
        };
        let e = spectacle_lens(&nan, 8, 32).unwrap_err().to_string();
        assert!(e.contains("sphere = NaN"), "{e}");
    }

    #[test]
    fn the_mesh_is_closed_with_the_thickness_asked() {
        let p = prescription(-2.0, -1.0, 30.0);
        let mesh = spectacle_lens(&p, 12, 48).unwrap();
        mesh.check_topology("test").unwrap();
        let bounds = mesh.bounds();
        assert!((bounds.extent().x - 0.05).abs() < 1e-4);
        // The back vertex (the grid's centre) sits at the centre thickness.
        let centre = mesh
            .positions
            .iter()
            .filter(|q| q.x.abs() < 1e-9 && q.y.abs() < 1e-9)
            .map(|q| q.z)
            .fold(f32::NEG_INFINITY, f32::max);
        assert!((centre - 0.002).abs() < 1e-7, "{centre}");
    }
}
