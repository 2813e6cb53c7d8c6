//! `specula analyze lens`: a spectacle lens's power, cylinder, prism, lateral colour and
//! distortion as the wearer gets them at each gaze direction, from exact rays.
//!
//! **The eye.** It rotates about its centre of rotation C, from the primary gaze `forward`
//! (with `up`), by Listing's law: the rotation taking `forward` to the gaze g turns about an
//! axis perpendicular to `forward` (the shortest arc), and carries the eye's right and up along
//! (its own frame at that gaze). A gaze (h, v) in degrees points along forward + tan h · right +
//! tan v · up (a tangent screen's coordinates: (30, 0) is 30° to the wearer's right).
//!
//! **The chief ray** leaves C along g, is refracted into the lens and out of it by Snell's law
//! at each surface with the lens's own interpolated normals, and leaves into object space along
//! g'. Rays are traced in double precision: the lens's BVH finds each triangle, its plane gives
//! the exact point, its vertex normals interpolated there the normal. A gaze whose chief ray
//! misses the lens, meets its edge (incidence beyond 75°) or crosses it other than in and out
//! once, or whose bundle does, is **outside the lens**.
//!
//! **Power.** From the object point on the chief ray (at infinity, or `object_distance` from C
//! in a straight line; at least 1 cm before the lens) a narrow bundle around the chief ray is traced through the lens to the
//! vertex sphere (about C, through the back vertex), where the chief ray meets it at P. In the
//! plane through P across the chief ray, in the eye's own (right, up), each ray's position x and
//! slope u are measured; the bundle's vergence matrix is L = −(∂u/∂s)(∂x/∂s)⁻¹ (central
//! differences over the bundle's two offsets s; dioptres, converging positive). Its eigenvalues
//! are the principal vergences: sphere = the larger, cylinder = the smaller minus the larger
//! (minus form), the axis the larger's meridian in TABO degrees (anticlockwise from the right of
//! an examiner facing the wearer), mean power = sphere + cylinder / 2. At infinity these are the
//! as-worn powers referred to the vertex sphere (at the centre, the back vertex power); for a
//! finite object they are the exit vergences. The bundle's half-width is `step` at the lens (an
//! angle of step / distance for a near object); each figure is taken at step and step / 2, and
//! the largest change over the grid is reported as the finite differences' convergence.
//!
//! **Against a prescription** (given, or the one a spectacle-lens shape was made from): the
//! power-vector difference (M, J0, J45) with M = S + C/2, J0 = −(C/2) cos 2A,
//! J45 = −(C/2) sin 2A: the power error ΔM and the unwanted cylinder 2 √(ΔJ0² + ΔJ45²). For a
//! near object, ΔM is taken against the prescription plus the object's own vergence at the
//! vertex sphere (what the wearer should get).
//!
//! **Prism:** the chief ray's deviation, 100 × the tangent of g' from g along the eye's right and
//! up: horizontal positive base out (towards the temple of the chosen eye), vertical positive
//! base up. **Lateral colour:** the angle between g' traced with the glass's red and blue indices
//! (n_C and n_F), arcminutes. **Distortion**, as lens design reports it (negative: barrel): on
//! tangent screens (tangents along the primary right and up over forward), the gaze g_t against
//! the paraxial image of the object's offset from the central chief ray's,
//! 100 (|g_t| / |J⁻¹ (o_t − o_t₀)| − 1), where J is the derivative of the object's tangents by
//! the gaze's at the centre (central differences at ±0.1°; a 2 × 2 matrix, since a toric lens
//! magnifies its meridians differently). A view whose straight object lines stay straight and
//! evenly spaced (the distortion picture) has none. The report's `spectacle_magnification` is
//! 1 / |J e| along the horizontal and the vertical: the gaze's tangent per the object's.

use glam::{DQuat, DVec3};
use rayon::prelude::*;
use serde::Serialize;
use specula_scene::{Camera, MaterialKind, Mesh, Prescription, Scene};
use specula_trace::{Ray, SceneAccel};

use crate::AnalyzeError;

/// The version of [`Report`]'s JSON (docs/analyze-lens.schema.json).
pub const SCHEMA_VERSION: u32 = 1;

/// The default distance from the back vertex to the eye's centre of rotation: 12 mm vertex
/// distance and 15 mm from the cornea to the centre of rotation.
pub const ROTATION_CENTRE_BEHIND_VERTEX_M: f64 = 0.027;

/// A surface met beyond this incidence is the lens's edge, not an optical surface.
const EDGE_INCIDENCE_DEG: f64 = 75.0;

/// The gaze angle at which the central magnification (J) is taken.
const CENTRAL_GAZE_DEG: f64 = 0.1;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Eye {
    Right,
    Left,
}

/// The gaze grid: h in [−h_max, h_max], v in [−v_max, v_max], every `step` degrees from 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Gaze {
    pub h_max_deg: f64,
    pub v_max_deg: f64,
    pub step_deg: f64,
}

impl Gaze {
    /// The grid's values along one axis, ascending, 0 included (0 alone for a grid
    /// [`analyze`] refuses: a step that is not positive, too many cells).
    fn values(max: f64, step: f64) -> Vec<f64> {
        // A relative slack: 30 / 0.1 is 299.99999999999994 in floating point.
        let n = (max / step * (1.0 + 1e-9) + 1e-9).floor();
        if !(step > 0.0 && (0.0..=1e6).contains(&n)) {
            return vec![0.0];
        }
        let n = n as i64;
        (-n..=n).map(|k| k as f64 * step).collect()
    }

    pub fn horizontal(&self) -> Vec<f64> {
        Gaze::values(self.h_max_deg, self.step_deg)
    }

    pub fn vertical(&self) -> Vec<f64> {
        Gaze::values(self.v_max_deg, self.step_deg)
    }
}

#[derive(Clone, Debug)]
pub struct Options {
    pub lens: usize,
    pub eye: Eye,
    pub rotation_centre: DVec3,
    /// The primary gaze and up (unit, perpendicular).
    pub forward: DVec3,
    pub up: DVec3,
    pub gaze: Gaze,
    /// None: an object at infinity.
    pub object_distance_m: Option<f64>,
    /// The bundle's half-width at the lens, metres.
    pub step_m: f64,
    pub prescription: Option<Prescription>,
}

/// The lens's material's red, green and blue indices; the lens must be a solid refractor.
fn indices(scene: &Scene, lens: usize) -> Result<DVec3, AnalyzeError> {
    let mesh = &scene.meshes[lens];
    match scene.materials[mesh.material].kind {
        MaterialKind::Dielectric {
            ior,
            thin_walled: false,
        } => Ok(ior.as_dvec3()),
        ref kind => Err(AnalyzeError::WrongMaterial {
            role: "--lens",
            name: mesh.name.clone(),
            kind: match kind {
                MaterialKind::Dielectric { .. } => "a thin-walled sheet (no power)".into(),
                other => format!("{other:?}").to_lowercase(),
            },
            expected: "a refractor (a solid dielectric)",
        }),
    }
}

/// The lens's triangles alone, in a BVH of their own: the analysis sees nothing else.
pub struct LensTracer<'a> {
    mesh: &'a Mesh,
    accel: SceneAccel,
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
    pub fn new(mesh: &'a Mesh) -> LensTracer<'a> {
        let triangles = mesh
            .triangles
            .iter()
            .map(|t| t.map(|i| mesh.positions[i as usize]))
            .collect();
        let ids = (0..mesh.triangles.len() as u32).map(|t| (0, t)).collect();
        LensTracer {
            mesh,
            accel: SceneAccel::from_triangles(triangles, ids),
        }
    }

    /// The next surface point of the ray from `origin` along `dir`: the point, the interpolated
    /// normal (as stored: outward), in double precision.
    fn next_hit(&self, origin: DVec3, dir: DVec3) -> Option<(DVec3, DVec3)> {
        // Past the surface the ray starts on (by more than single precision's step there); the
        // exact point is found again below.
        let nudge = 1e-6 * (1.0 + origin.abs().max_element());
        let ray = Ray {
            origin: (origin + dir * nudge).as_vec3(),
            dir: dir.as_vec3(),
        };
        let hit = self.accel.intersect(&ray, f32::INFINITY)?;
        let [i0, i1, i2] = self.mesh.triangles[hit.triangle as usize].map(|i| i as usize);
        let p = [i0, i1, i2].map(|i| self.mesh.positions[i].as_dvec3());
        let n = [i0, i1, i2].map(|i| self.mesh.normals[i].as_dvec3());
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
        // A sliver the single-precision test accepted but double precision cannot solve: its
        // own hit, as the BVH found it.
        let (point, b1, b2) = if point.is_finite() && b1.is_finite() && b2.is_finite() {
            (point, b1, b2)
        } else {
            (
                (ray.origin + ray.dir * hit.t).as_dvec3(),
                f64::from(hit.b1),
                f64::from(hit.b2),
            )
        };
        // Within the triangle (a point on its edge may fall a rounding outside): no
        // extrapolated normals.
        let weights = DVec3::new(1.0 - b1 - b2, b1, b2).max(DVec3::ZERO);
        let weights = weights / weights.element_sum().max(1e-300);
        let normal = (n[0] * weights.x + n[1] * weights.y + n[2] * weights.z).try_normalize()?;
        Some((point, normal))
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

    /// Whether `p` lies inside the lens: an odd number of crossings along at least two of three
    /// directions (a ray grazing an edge could miscount one).
    pub fn contains(&self, p: DVec3) -> bool {
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

/// The mesh named `name`, for `--lens`: an unknown name lists the scene's refractors (solid
/// dielectrics), the objects a lens analysis takes.
pub fn find_lens(scene: &Scene, name: &str) -> Result<usize, AnalyzeError> {
    crate::object(scene, "--lens", name).map_err(|e| match e {
        AnalyzeError::UnknownObject { role, name, .. } => {
            let mut lenses: Vec<&str> = scene
                .meshes
                .iter()
                .filter(|m| {
                    matches!(
                        scene.materials[m.material].kind,
                        MaterialKind::Dielectric {
                            thin_walled: false,
                            ..
                        }
                    )
                })
                .map(|m| m.name.as_str())
                .collect();
            lenses.dedup();
            AnalyzeError::UnknownObject {
                role,
                name,
                valid: if lenses.is_empty() {
                    "none (no object of this scene is a solid glass)".into()
                } else {
                    format!("(its lenses) {}", lenses.join(", "))
                },
            }
        }
        other => other,
    })
}

/// The back vertex: where the camera's view axis first meets the lens (the camera is taken as
/// the wearer's eye, on the lens's eye side).
pub fn back_vertex(scene: &Scene, lens: usize, camera: &Camera) -> Result<DVec3, AnalyzeError> {
    let tracer = LensTracer::new(&scene.meshes[lens]);
    let eye = camera.eye.as_dvec3();
    let forward = (camera.target - camera.eye).as_dvec3().normalize();
    tracer
        .next_hit(eye - forward * 1e-6, forward)
        .map(|(p, _)| p)
        .ok_or_else(|| AnalyzeError::BadOption {
            option: "--rotation-centre",
            reason: format!(
                "the camera's view axis misses '{}', so its back vertex (and the default centre \
                 of rotation 27 mm behind it) is unknown: give --rotation-centre X,Y,Z",
                scene.meshes[lens].name
            ),
        })
}

/// A bundle's principal figures at one gaze.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Power {
    pub sphere_d: f64,
    pub cylinder_d: f64,
    pub axis_deg: f64,
    pub mean_power_d: f64,
}

impl Power {
    /// Sphere, cylinder (minus form) and TABO axis of a symmetric vergence matrix
    /// [[a, b], [b, c]] in the eye's (right, up).
    fn from_matrix(a: f64, b: f64, c: f64) -> Power {
        let mean = 0.5 * (a + c);
        let spread = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        // The larger eigenvalue's direction (cos φ, sin φ) in (right, up); an examiner facing
        // the wearer has the wearer's left on the right.
        let phi = 0.5 * (2.0 * b).atan2(a - c);
        let axis = phi.sin().atan2(-phi.cos()).to_degrees().rem_euclid(180.0);
        Power {
            sphere_d: mean + spread,
            cylinder_d: -2.0 * spread,
            axis_deg: if axis >= 180.0 - 1e-9 { 0.0 } else { axis },
            mean_power_d: mean,
        }
    }

    /// The power vector (M, J0, J45).
    pub fn power_vector(sphere: f64, cylinder: f64, axis_deg: f64) -> [f64; 3] {
        let a = 2.0 * axis_deg.to_radians();
        [
            sphere + 0.5 * cylinder,
            -0.5 * cylinder * a.cos(),
            -0.5 * cylinder * a.sin(),
        ]
    }
}

/// One gaze direction's figures; all None outside the lens.
#[derive(Clone, Debug, Serialize)]
pub struct Cell {
    pub gaze_deg: [f64; 2],
    pub outside: bool,
    pub sphere_d: Option<f64>,
    pub cylinder_d: Option<f64>,
    pub axis_deg: Option<f64>,
    pub mean_power_d: Option<f64>,
    /// [horizontal, vertical]: base out and base up positive.
    pub prism_d: Option<[f64; 2]>,
    pub lateral_colour_arcmin: Option<f64>,
    pub distortion_percent: Option<f64>,
    /// Against the prescription: M − M_Rx.
    pub power_error_d: Option<f64>,
    /// Against the prescription: 2 √(ΔJ0² + ΔJ45²).
    pub unwanted_cylinder_d: Option<f64>,
    /// Where the chief ray crosses the eye-side surface, from the back vertex along the eye's
    /// primary right and up, millimetres.
    pub back_point_mm: Option<[f64; 2]>,
    /// The object-space direction g' in the primary frame's tangent coordinates
    /// (right / forward, up / forward): where the wearer sees through this gaze.
    pub object_tangent: Option<[f64; 2]>,
    /// The largest change of a vergence between the bundle's step and half of it, dioptres.
    #[serde(skip)]
    pub fd_change_d: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct PrescriptionReport {
    pub sphere_d: f64,
    pub cylinder_d: f64,
    pub axis_deg: f64,
    pub index: f64,
    pub abbe: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub schema_version: u32,
    pub scene: String,
    pub lens: String,
    pub eye: Eye,
    pub rotation_centre: [f64; 3],
    pub forward: [f64; 3],
    pub up: [f64; 3],
    /// The vertex sphere's radius: from the rotation centre to the back vertex along forward.
    pub vertex_sphere_radius_m: f64,
    /// None: infinity.
    pub object_distance_m: Option<f64>,
    /// The glass's red, green (the figures') and blue indices.
    pub indices: [f64; 3],
    pub gaze: Gaze,
    pub columns: usize,
    pub rows: usize,
    pub step_mm: f64,
    /// The largest change of any vergence between the bundle's step and half of it, over the
    /// grid, dioptres.
    pub finite_difference_change_d: f64,
    /// At the centre, the gaze's tangent per the object's, horizontally and vertically (below 1
    /// a minus lens minifies).
    pub spectacle_magnification: [f64; 2],
    pub prescription: Option<PrescriptionReport>,
    pub centre: Cell,
    /// Row by row from the lowest v, each from the smallest h.
    pub grid: Vec<Cell>,
}

/// The eye's frame at one gaze.
struct EyeFrame {
    gaze: DVec3,
    right: DVec3,
    up: DVec3,
}

struct Setup<'a> {
    tracer: LensTracer<'a>,
    options: &'a Options,
    right: DVec3,
    indices: DVec3,
    vertex_sphere_radius: f64,
}

impl Setup<'_> {
    fn frame(&self, h_deg: f64, v_deg: f64) -> EyeFrame {
        let o = self.options;
        let gaze =
            (o.forward + self.right * h_deg.to_radians().tan() + o.up * v_deg.to_radians().tan())
                .normalize();
        let turn = DQuat::from_rotation_arc(o.forward, gaze);
        EyeFrame {
            gaze,
            right: turn * self.right,
            up: turn * o.up,
        }
    }

    /// The vergence matrix at the vertex sphere of the bundle around `chief` with half-width
    /// `step` (metres at the lens, or its angle at a near object), in `frame`'s (right, up).
    fn vergence(&self, frame: &EyeFrame, chief: &Traced, step: f64) -> Result<[f64; 3], Failure> {
        let o = self.options;
        let ior = self.indices.y;
        let out = chief.dir;
        // A basis across the object-space chief ray.
        let a = (frame.right - out * frame.right.dot(out)).normalize();
        let b = out.cross(a);
        let front = chief.points[1];
        let p = o.rotation_centre + frame.gaze * self.vertex_sphere_radius;
        let object = self.object_point(chief);
        let measure = |s1: f64, s2: f64| -> Result<([f64; 2], [f64; 2]), Failure> {
            let (origin, dir) = match object {
                None => (front + out * 0.01 + (a * s1 + b * s2) * step, -out),
                Some(object) => {
                    let dir = (-out + (a * s1 + b * s2) * step).normalize();
                    // Started on its own line 10 mm before the lens, so that a far object's
                    // distance never reaches the single-precision BVH.
                    let t = (front + out * 0.01 - object).dot(out) / dir.dot(out);
                    (object + dir * t, dir)
                }
            };
            let traced = self.tracer.trace(origin, dir, ior)?;
            let (q, d) = (traced.points[1], traced.dir);
            let t = (p - q).dot(frame.gaze) / d.dot(frame.gaze);
            let x = q + d * t - p;
            let along = d.dot(-frame.gaze);
            Ok((
                [x.dot(frame.right), x.dot(frame.up)],
                [d.dot(frame.right) / along, d.dot(frame.up) / along],
            ))
        };
        let (xp1, up1) = measure(1.0, 0.0)?;
        let (xm1, um1) = measure(-1.0, 0.0)?;
        let (xp2, up2) = measure(0.0, 1.0)?;
        let (xm2, um2) = measure(0.0, -1.0)?;
        // Columns: derivatives along s1 and s2.
        let jx = [
            [xp1[0] - xm1[0], xp2[0] - xm2[0]],
            [xp1[1] - xm1[1], xp2[1] - xm2[1]],
        ];
        let ju = [
            [up1[0] - um1[0], up2[0] - um2[0]],
            [up1[1] - um1[1], up2[1] - um2[1]],
        ];
        let det = jx[0][0] * jx[1][1] - jx[0][1] * jx[1][0];
        if det.abs() < 1e-30 {
            return Err(Failure::Edge);
        }
        let inverse = [
            [jx[1][1] / det, -jx[0][1] / det],
            [-jx[1][0] / det, jx[0][0] / det],
        ];
        let mut l = [[0.0; 2]; 2];
        for (i, row) in l.iter_mut().enumerate() {
            for (j, value) in row.iter_mut().enumerate() {
                *value = -(ju[i][0] * inverse[0][j] + ju[i][1] * inverse[1][j]);
            }
        }
        Ok([l[0][0], 0.5 * (l[0][1] + l[1][0]), l[1][1]])
    }

    /// The object point on the chief ray's object-space line, `object_distance` from the centre
    /// of rotation (None: at infinity).
    fn object_point(&self, chief: &Traced) -> Option<DVec3> {
        let distance = self.options.object_distance_m?;
        let from_centre = chief.points[1] - self.options.rotation_centre;
        let along = from_centre.dot(chief.dir);
        let reach = along * along - from_centre.length_squared() + distance * distance;
        Some(chief.points[1] + chief.dir * (-along + reach.max(0.0).sqrt()))
    }

    /// The chief ray at a gaze, traced out of the eye with index `ior`.
    fn chief(&self, frame: &EyeFrame, ior: f64) -> Result<Traced, Failure> {
        self.tracer
            .trace(self.options.rotation_centre, frame.gaze, ior)
    }
}

/// The angle between two unit directions, accurate when small.
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Runs the analysis; `progress` is told how many grid rows are done.
pub fn analyze(
    scene: &Scene,
    options: &Options,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Report, AnalyzeError> {
    let lens = &scene.meshes[options.lens];
    let indices = indices(scene, options.lens)?;
    validate(options)?;
    let tracer = LensTracer::new(lens);
    if tracer.contains(options.rotation_centre) {
        return Err(AnalyzeError::BadOption {
            option: "--rotation-centre",
            reason: format!(
                "{} lies inside '{}': the eye's centre of rotation must be behind the lens",
                options.rotation_centre, lens.name
            ),
        });
    }
    let right = options.forward.cross(options.up).normalize();
    let primary = tracer
        .trace(options.rotation_centre, options.forward, indices.y)
        .map_err(|failure| AnalyzeError::BadOption {
            option: "--rotation-centre",
            reason: format!(
                "looking straight ahead from {} the eye does not see through '{}' ({failure:?}): \
                 put the centre of rotation behind the lens",
                options.rotation_centre, lens.name
            ),
        })?;
    let vertex_sphere_radius = (primary.points[0] - options.rotation_centre).length();
    if let Some(distance) = options.object_distance_m {
        let front = (primary.points[1] - options.rotation_centre).length();
        if distance < front + 0.01 {
            return Err(AnalyzeError::BadOption {
                option: "--object-distance",
                reason: format!(
                    "{distance} m from the centre of rotation puts the object at or behind the \
                     lens, whose front is {front:.4} m away: give more than {:.3} m",
                    front + 0.01
                ),
            });
        }
    }
    let setup = Setup {
        tracer,
        options,
        right,
        indices,
        vertex_sphere_radius,
    };
    // The central magnification, per direction: the derivative of the object's tangent
    // coordinates by the gaze's at the centre (2 × 2: a toric lens magnifies its meridians
    // differently), by central differences at ±0.1° of gaze.
    let tangent_of = |out: DVec3| {
        let along = out.dot(options.forward);
        [out.dot(right) / along, out.dot(options.up) / along]
    };
    let delta = CENTRAL_GAZE_DEG.to_radians().tan();
    let mut j = [[0.0; 2]; 2];
    for (k, (h, v)) in [(1.0, 0.0), (0.0, 1.0)].into_iter().enumerate() {
        let at = |sign: f64| {
            let frame = setup.frame(sign * h * CENTRAL_GAZE_DEG, sign * v * CENTRAL_GAZE_DEG);
            setup.chief(&frame, indices.y).map(|c| tangent_of(c.dir))
        };
        let (plus, minus) = at(1.0)
            .and_then(|p| Ok((p, at(-1.0)?)))
            .map_err(|failure| AnalyzeError::BadOption {
                option: "--rotation-centre",
                reason: format!(
                    "the primary gaze meets the edge of '{}' ({failure:?}): the centre of \
                     rotation must look through the lens",
                    lens.name
                ),
            })?;
        for (row, column) in j.iter_mut().enumerate() {
            column[k] = (plus[row] - minus[row]) / (2.0 * delta);
        }
    }
    let central = Central {
        j,
        object_tangent: tangent_of(primary.dir),
    };
    let spectacle_magnification = [1.0 / j[0][0].hypot(j[1][0]), 1.0 / j[0][1].hypot(j[1][1])];
    let cell = |h: f64, v: f64| figures(&setup, h, v, &central, options.prescription.as_ref());
    let (horizontal, vertical) = (options.gaze.horizontal(), options.gaze.vertical());
    let done = std::sync::atomic::AtomicUsize::new(0);
    let rows: Vec<Vec<Cell>> = vertical
        .par_iter()
        .map(|&v| {
            let row = horizontal.iter().map(|&h| cell(h, v)).collect();
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            row
        })
        .collect();
    let grid: Vec<Cell> = rows.into_iter().flatten().collect();
    let centre = cell(0.0, 0.0);
    let finite_difference_change_d = grid
        .iter()
        .chain(std::iter::once(&centre))
        .map(|c| c.fd_change_d)
        .fold(0.0, f64::max);
    Ok(Report {
        schema_version: SCHEMA_VERSION,
        scene: scene.name.clone(),
        lens: lens.name.clone(),
        eye: options.eye,
        rotation_centre: options.rotation_centre.to_array(),
        forward: options.forward.to_array(),
        up: options.up.to_array(),
        vertex_sphere_radius_m: vertex_sphere_radius,
        object_distance_m: options.object_distance_m,
        indices: indices.to_array(),
        gaze: options.gaze,
        columns: horizontal.len(),
        rows: vertical.len(),
        step_mm: options.step_m * 1e3,
        finite_difference_change_d,
        spectacle_magnification,
        prescription: options.prescription.map(|p| {
            let p = p.minus_cylinder();
            PrescriptionReport {
                sphere_d: p.sphere,
                cylinder_d: p.cylinder,
                axis_deg: p.axis_deg,
                index: p.index,
                abbe: p.abbe,
            }
        }),
        centre,
        grid,
    })
}

fn validate(options: &Options) -> Result<(), AnalyzeError> {
    let g = options.gaze;
    let fine = |v: f64| v.is_finite() && v >= 0.0;
    if !(fine(g.h_max_deg) && fine(g.v_max_deg) && g.step_deg.is_finite() && g.step_deg > 0.0)
        || g.h_max_deg >= 89.0
        || g.v_max_deg >= 89.0
    {
        return Err(AnalyzeError::BadOption {
            option: "--gaze",
            reason: format!(
                "H_MAX,V_MAX,STEP = {},{},{}: the maxima must be between 0 and 89 degrees and \
                 the step positive",
                g.h_max_deg, g.v_max_deg, g.step_deg
            ),
        });
    }
    let cells = g.horizontal().len() as f64 * g.vertical().len() as f64;
    if cells > 1e6 {
        return Err(AnalyzeError::BadOption {
            option: "--gaze",
            reason: format!("{cells} gaze directions: take a larger step"),
        });
    }
    if let Some(d) = options.object_distance_m {
        if !(d.is_finite() && d > 0.0) {
            return Err(AnalyzeError::BadOption {
                option: "--object-distance",
                reason: format!("{d} m: give a positive distance (or leave it out: infinity)"),
            });
        }
    }
    let (f, u) = (options.forward, options.up);
    let unit = |v: DVec3| v.is_finite() && (v.length() - 1.0).abs() < 1e-6;
    if !(unit(f) && unit(u) && f.dot(u).abs() < 1e-6) {
        return Err(AnalyzeError::BadOption {
            option: "forward and up",
            reason: format!("{f} and {u} must be perpendicular unit vectors"),
        });
    }
    if !(options.step_m.is_finite() && options.step_m > 0.0) {
        return Err(AnalyzeError::BadOption {
            option: "--step-mm",
            reason: format!("{} m: the bundle needs a positive width", options.step_m),
        });
    }
    if !options.rotation_centre.is_finite() {
        return Err(AnalyzeError::BadOption {
            option: "--rotation-centre",
            reason: "not a point".into(),
        });
    }
    Ok(())
}

/// The central chief ray's object tangents and the derivative J of the object's tangents by
/// the gaze's there.
struct Central {
    j: [[f64; 2]; 2],
    object_tangent: [f64; 2],
}

impl Central {
    /// The distortion at gaze (`h`, `v`) degrees whose chief ray leaves along the object
    /// tangents `object` (module doc); 0 at the centre, None where J cannot be inverted.
    fn distortion(&self, h: f64, v: f64, object: [f64; 2]) -> Option<f64> {
        let gaze = [h.to_radians().tan(), v.to_radians().tan()];
        let length = gaze[0].hypot(gaze[1]);
        if length < 1e-12 {
            return Some(0.0);
        }
        let j = self.j;
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det.abs() < 1e-12 {
            return None;
        }
        let offset = [
            object[0] - self.object_tangent[0],
            object[1] - self.object_tangent[1],
        ];
        let paraxial = [
            (j[1][1] * offset[0] - j[0][1] * offset[1]) / det,
            (-j[1][0] * offset[0] + j[0][0] * offset[1]) / det,
        ];
        Some(100.0 * (length / paraxial[0].hypot(paraxial[1]) - 1.0))
    }
}

/// One gaze direction's figures (see the module doc).
fn figures(
    setup: &Setup,
    h: f64,
    v: f64,
    central: &Central,
    prescription: Option<&Prescription>,
) -> Cell {
    let outside = Cell {
        gaze_deg: [h, v],
        outside: true,
        sphere_d: None,
        cylinder_d: None,
        axis_deg: None,
        mean_power_d: None,
        prism_d: None,
        lateral_colour_arcmin: None,
        distortion_percent: None,
        power_error_d: None,
        unwanted_cylinder_d: None,
        back_point_mm: None,
        object_tangent: None,
        fd_change_d: 0.0,
    };
    let o = setup.options;
    let frame = setup.frame(h, v);
    let Ok(chief) = setup.chief(&frame, setup.indices.y) else {
        return outside;
    };
    let step = match o.object_distance_m {
        None => o.step_m,
        Some(distance) => o.step_m / distance,
    };
    let (Ok(coarse), Ok(fine)) = (
        setup.vergence(&frame, &chief, step),
        setup.vergence(&frame, &chief, step * 0.5),
    ) else {
        return outside;
    };
    let fd_change_d = coarse
        .iter()
        .zip(&fine)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let power = Power::from_matrix(fine[0], fine[1], fine[2]);
    let out = chief.dir;
    let along = out.dot(frame.gaze);
    let side = match o.eye {
        Eye::Right => 1.0,
        Eye::Left => -1.0,
    };
    let prism = [
        side * 100.0 * out.dot(frame.right) / along,
        100.0 * out.dot(frame.up) / along,
    ];
    let colour = match (
        setup.chief(&frame, setup.indices.x),
        setup.chief(&frame, setup.indices.z),
    ) {
        (Ok(red), Ok(blue)) => Some(angle_between(red.dir, blue.dir).to_degrees() * 60.0),
        _ => None,
    };
    let forward_part = out.dot(o.forward);
    let object_tangent = [
        out.dot(setup.right) / forward_part,
        out.dot(o.up) / forward_part,
    ];
    let distortion = central.distortion(h, v, object_tangent);
    let (power_error_d, unwanted_cylinder_d) = match prescription {
        Some(p) => {
            let p = p.minus_cylinder();
            let rx = Power::power_vector(p.sphere, p.cylinder, p.axis_deg);
            let got = Power::power_vector(power.sphere_d, power.cylinder_d, power.axis_deg);
            // From a near object the wearer should get its own vergence at the vertex sphere
            // plus the prescription.
            let vertex_point = o.rotation_centre + frame.gaze * setup.vertex_sphere_radius;
            let object_vergence = setup
                .object_point(&chief)
                .map_or(0.0, |object| -1.0 / (object - vertex_point).length());
            let (dm, dj0, dj45) = (
                got[0] - rx[0] - object_vergence,
                got[1] - rx[1],
                got[2] - rx[2],
            );
            (Some(dm), Some(2.0 * dj0.hypot(dj45)))
        }
        None => (None, None),
    };
    let back = chief.points[0] - (o.rotation_centre + o.forward * setup.vertex_sphere_radius);
    Cell {
        gaze_deg: [h, v],
        outside: false,
        sphere_d: Some(power.sphere_d),
        cylinder_d: Some(power.cylinder_d),
        axis_deg: Some(power.axis_deg),
        mean_power_d: Some(power.mean_power_d),
        prism_d: Some(prism),
        lateral_colour_arcmin: colour,
        distortion_percent: distortion,
        power_error_d,
        unwanted_cylinder_d,
        back_point_mm: Some([back.dot(setup.right) * 1e3, back.dot(o.up) * 1e3]),
        object_tangent: Some(object_tangent),
        fd_change_d,
    }
}

/// The primary gaze and up of `camera`: its view direction, and its up made perpendicular
/// (refused where they are parallel: the axes and prisms would have no orientation).
pub fn primary_frame(camera: &Camera) -> Result<(DVec3, DVec3), AnalyzeError> {
    let forward = (camera.target - camera.eye).as_dvec3().normalize();
    let up = camera.up.as_dvec3();
    let up = (up - forward * up.dot(forward))
        .try_normalize()
        .filter(|_| forward.is_finite())
        .ok_or_else(|| AnalyzeError::BadOption {
            option: "camera",
            reason: format!(
                "the camera's up {} is parallel to its view direction: the wearer's up (for \
                 the axis and the prism) is undefined",
                camera.up
            ),
        })?;
    Ok((forward, up))
}

/// The default options for `lens` in `scene`: the right eye, its centre of rotation 27 mm
/// behind the back vertex on the camera's view axis, a 30° × 30° grid every 2.5°, an object at
/// infinity, a 0.5 mm bundle, and the prescription the lens was made from, if any.
pub fn default_options(scene: &Scene, lens: usize) -> Result<Options, AnalyzeError> {
    default_options_with(scene, lens, true)
}

/// [`default_options`], finding the back vertex only where `find_centre` (else the rotation
/// centre is the camera's eye, for the caller to replace).
pub fn default_options_with(
    scene: &Scene,
    lens: usize,
    find_centre: bool,
) -> Result<Options, AnalyzeError> {
    indices(scene, lens)?;
    let (forward, up) = primary_frame(&scene.camera)?;
    let rotation_centre = if find_centre {
        back_vertex(scene, lens, &scene.camera)? - forward * ROTATION_CENTRE_BEHIND_VERTEX_M
    } else {
        scene.camera.eye.as_dvec3()
    };
    Ok(Options {
        lens,
        eye: Eye::Right,
        rotation_centre,
        forward,
        up,
        gaze: Gaze {
            h_max_deg: 30.0,
            v_max_deg: 30.0,
            step_deg: 2.5,
        },
        object_distance_m: None,
        step_m: 5e-4,
        prescription: scene
            .prescriptions
            .iter()
            .find(|(name, _)| *name == scene.meshes[lens].name)
            .map(|(_, p)| *p),
    })
}
