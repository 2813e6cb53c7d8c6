//! What a focimeter reads at a point of the lens: the back surface on the lens rest, the
//! instrument's axis along the back surface's normal at the point, a narrow beam.
//!
//! **Prism.** The ray that leaves the back surface at the point along the instrument's axis
//! (found by tracing it backwards, from the eye's side along −normal, out of the front) came in
//! along w; the prism is 100 × tan of w's deviation, along the lens's right and up across the
//! axis, base out (towards the temple of the chosen eye) and base up positive.
//!
//! **Power.** A parallel beam along w, of half-width `step` around that ray, is traced through
//! the lens; in the plane through the point across the axis, in the lens's right and up, its
//! vergence matrix L = −(∂u/∂s)(∂x/∂s)⁻¹ gives the back vertex sphere, cylinder (minus form)
//! and axis (TABO) at the point, as the instrument reads them. Each is taken at `step` and
//! `step / 2`; their change is the reading's finite-difference uncertainty.
//!
//! **The lens's frame**: for an exact lens its own (back vertex, +Z towards the eye, +X the
//! wearer's right, +Y up); for a mesh the fitting point, the primary gaze and up. A
//! progressive lens's add is read on its progressive surface's side ([`LensFrame::from_front`]
//! for a front surface: the lens turned over on the rest).

use glam::{DMat4, DVec3};
use serde::Serialize;

use super::tracer::{Failure, LensTracer};
use super::wear::Rx;
use super::{bundle_vergence, Eye, Power};

/// A lens's own frame, world space.
#[derive(Clone, Copy, Debug)]
pub struct LensFrame {
    pub back_vertex: DVec3,
    /// Along the lens's axis, towards the eye (unit).
    pub towards_eye: DVec3,
    pub right: DVec3,
    pub up: DVec3,
}

impl LensFrame {
    /// An exact lens's frame: `world_from_lens` applied to its own axes, the back vertex at
    /// (0, 0, `back_vertex_z`).
    pub fn of_exact(world_from_lens: DMat4, back_vertex_z: f64) -> LensFrame {
        let axis = |v: DVec3| world_from_lens.transform_vector3(v).normalize();
        LensFrame {
            back_vertex: world_from_lens.transform_point3(DVec3::new(0.0, 0.0, back_vertex_z)),
            towards_eye: axis(DVec3::Z),
            right: axis(DVec3::X),
            up: axis(DVec3::Y),
        }
    }

    /// The same lens seen from its front: the instrument's reference at the front vertex
    /// (`front_vertex_z` along the lens's axis from the back vertex's origin) and its axis
    /// pointing away from the eye, right and up kept.
    pub fn from_front(world_from_lens: DMat4, front_vertex_z: f64) -> LensFrame {
        let frame = LensFrame::of_exact(world_from_lens, front_vertex_z);
        LensFrame {
            towards_eye: -frame.towards_eye,
            ..frame
        }
    }

    /// A point's coordinates across the lens's axis, mm from the vertex.
    pub fn mm_of(&self, p: DVec3) -> glam::DVec2 {
        let q = p - self.back_vertex;
        glam::DVec2::new(q.dot(self.right), q.dot(self.up)) * 1e3
    }
}

/// One focimeter reading.
#[derive(Clone, Debug, Serialize)]
pub struct Reading {
    /// "distance reference point" or "prism reference point".
    pub point: &'static str,
    /// Where, from the back vertex along the lens's right and up, millimetres.
    pub at_mm: [f64; 2],
    pub sphere_d: f64,
    pub cylinder_d: f64,
    pub axis_deg: f64,
    /// Base out and base up positive, Δ.
    pub prism_d: [f64; 2],
    /// How far the powers may be off: the change from the beam to half of it, plus the
    /// surface's uncertainty for a mesh, dioptres.
    pub uncertainty_d: f64,
    pub axis_uncertainty_deg: f64,
    /// How far the prism may be off: its change when the central ray starts elsewhere (the
    /// trace's numerical error), plus the surface's change for a mesh, Δ.
    pub prism_uncertainty_d: f64,
    /// ∂prism / ∂position (Δ per mm; columns: right, up): where the ordered prism lies.
    #[serde(skip)]
    pub prism_per_mm: [[f64; 2]; 2],
}

impl Reading {
    pub fn rx(&self) -> Rx {
        Rx {
            sphere_d: self.sphere_d,
            cylinder_d: self.cylinder_d,
            axis_deg: self.axis_deg,
            prism_d: self.prism_d,
        }
    }

    /// How far from this point the lens has the prism `ordered`, millimetres (by its prism
    /// gradient; None where the lens has no power to move its prism).
    pub fn ordered_prism_offset_mm(&self, ordered: [f64; 2]) -> Option<f64> {
        let j = self.prism_per_mm;
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det.abs() < 1e-12 {
            return None;
        }
        let e = [ordered[0] - self.prism_d[0], ordered[1] - self.prism_d[1]];
        let dx = (j[1][1] * e[0] - j[0][1] * e[1]) / det;
        let dy = (-j[1][0] * e[0] + j[0][0] * e[1]) / det;
        Some(dx.hypot(dy))
    }
}

/// The instrument's settings.
pub struct Focimeter<'a> {
    pub tracer: &'a LensTracer<'a>,
    pub frame: LensFrame,
    pub ior: f64,
    pub step_m: f64,
    pub eye: Eye,
}

/// How far before the back vertex's plane the central ray starts, metres; the prism's
/// uncertainty is its change when the ray starts [`STANDOFF_CHECK_M`] before it instead (the
/// trace's own numerical error: the prism of one ray does not depend on where it starts).
const STANDOFF_M: f64 = 0.05;
const STANDOFF_CHECK_M: f64 = 0.08;

/// The central ray at a reading point.
struct CentralRay {
    point: DVec3,
    normal: DVec3,
    right: DVec3,
    up: DVec3,
    front: DVec3,
    out: DVec3,
    prism: [f64; 2],
}

/// The prism and the beam's vergence matrices (beam, half beam) at one point.
struct Raw {
    prism: [f64; 2],
    coarse: [f64; 3],
    fine: [f64; 3],
}

impl Focimeter<'_> {
    /// The reading at `at_mm` from the back vertex (module doc).
    pub fn read(&self, point: &'static str, at_mm: [f64; 2]) -> Result<Reading, Failure> {
        let raw = self.raw(at_mm)?;
        // The prism's gradient, by central differences over ±0.5 mm.
        let mut prism_per_mm = [[0.0; 2]; 2];
        for k in 0..2 {
            let shifted = |sign: f64| {
                let mut at = at_mm;
                at[k] += sign * 0.5;
                self.raw(at).map(|r| r.prism)
            };
            let (plus, minus) = (shifted(1.0)?, shifted(-1.0)?);
            for (row, column) in prism_per_mm.iter_mut().enumerate() {
                column[k] = plus[row] - minus[row];
            }
        }
        let again = self.central(at_mm, STANDOFF_CHECK_M)?.prism;
        let prism_uncertainty = (raw.prism[0] - again[0])
            .abs()
            .max((raw.prism[1] - again[1]).abs());
        let power = Power::from_matrix(raw.fine[0], raw.fine[1], raw.fine[2]);
        let coarse = Power::from_matrix(raw.coarse[0], raw.coarse[1], raw.coarse[2]);
        let change = (0..3)
            .map(|k| (raw.fine[k] - raw.coarse[k]).abs())
            .fold(0.0, f64::max);
        let axis_change = if power.cylinder_d.abs() > 1e-6 {
            let d = (power.axis_deg - coarse.axis_deg).rem_euclid(180.0);
            d.min(180.0 - d)
        } else {
            0.0
        };
        Ok(Reading {
            point,
            at_mm,
            sphere_d: power.sphere_d,
            cylinder_d: power.cylinder_d,
            axis_deg: power.axis_deg,
            prism_d: raw.prism,
            uncertainty_d: change,
            axis_uncertainty_deg: axis_change,
            prism_uncertainty_d: prism_uncertainty,
            prism_per_mm,
        })
    }

    /// The central ray at `at_mm`, launched `standoff` metres before the back vertex's plane:
    /// where it meets the back surface, the lens's right and up across the instrument's axis
    /// there, and the ray through the lens.
    fn central(&self, at_mm: [f64; 2], standoff: f64) -> Result<CentralRay, Failure> {
        let f = &self.frame;
        let start = f.back_vertex
            + f.right * (at_mm[0] * 1e-3)
            + f.up * (at_mm[1] * 1e-3)
            + f.towards_eye * standoff;
        let (point, normal) = self
            .tracer
            .next_hit(start, -f.towards_eye)
            .ok_or(Failure::Missed)?;
        if normal.dot(f.towards_eye) <= 0.0 {
            return Err(Failure::Edge);
        }
        // The lens's right and up across the instrument's axis.
        // Up from the lens's up, not normal × right: read from the front, the instrument's
        // axis is reversed but the wearer's right and up (and so the TABO axis) are not.
        let right = (f.right - normal * f.right.dot(normal)).normalize();
        let up = (f.up - normal * f.up.dot(normal) - right * f.up.dot(right)).normalize();
        let back = self
            .tracer
            .trace(point + normal * 0.01, -normal, self.ior)?;
        let out = back.dir;
        let along = out.dot(-normal);
        let side = match self.eye {
            Eye::Right => 1.0,
            Eye::Left => -1.0,
        };
        Ok(CentralRay {
            point,
            normal,
            right,
            up,
            front: back.points[1],
            out,
            prism: [
                side * 100.0 * out.dot(right) / along,
                100.0 * out.dot(up) / along,
            ],
        })
    }

    fn raw(&self, at_mm: [f64; 2]) -> Result<Raw, Failure> {
        let CentralRay {
            point,
            normal,
            right,
            up,
            front,
            out,
            prism,
        } = self.central(at_mm, STANDOFF_M)?;
        let light = -out;
        let a = (right - light * right.dot(light)).normalize();
        let b = light.cross(a);
        let vergence = |step: f64| {
            let launch = |s1: f64, s2: f64| (front + out * 0.01 + (a * s1 + b * s2) * step, light);
            bundle_vergence(self.tracer, self.ior, launch, point, normal, [right, up])
        };
        Ok(Raw {
            prism,
            coarse: vergence(self.step_m)?,
            fine: vergence(self.step_m * 0.5)?,
        })
    }
}
