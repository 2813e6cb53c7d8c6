//! `specula analyze lens`: a spectacle lens's power, cylinder, prism, lateral colour and
//! distortion as the wearer gets them at each gaze direction, from exact rays; its focimeter
//! reading ([`focimeter`]) against a standard's tolerances ([`standard`]); the lens as the frame
//! tilts and wraps it and the compensated prescription ([`wear`]). Rays go through the lens's
//! exact surfaces where the scene made it from a shape, else its triangles ([`tracer`]).
//!
//! **The eye.** It rotates about its centre of rotation C, from the primary gaze `forward`
//! (with `up`), by Listing's law: the rotation taking `forward` to the gaze g turns about an
//! axis perpendicular to `forward` (the shortest arc), and carries the eye's right and up along
//! (its own frame at that gaze). A gaze (h, v) in degrees points along forward + tan h · right +
//! tan v · up (a tangent screen's coordinates: (30, 0) is 30° to the wearer's right).
//!
//! **The chief ray** leaves C along g, is refracted into the lens and out of it by Snell's law
//! at each surface ([`tracer`]: the exact surfaces, or the triangles with their interpolated
//! normals), and leaves into object space along g', in double precision. A gaze whose chief ray
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
//! evenly spaced (the distortion picture) has none. `rotating_eye_magnification` is 1 / |J e|
//! along the horizontal and the vertical (the gaze's tangent per the object's);
//! `spectacle_magnification` the same with J taken from the entrance pupil, 3 mm behind the
//! cornea ([1 / (1 − (t/n) F1)] · [1 / (1 − h Fv)] for a thick lens).

pub mod analysis;
pub use analysis::INFO;
pub mod focimeter;
pub mod near;
mod options;
pub mod plot;
mod prescription;
mod progressive;
pub mod report;
pub mod standard;
mod summary;
pub mod tracer;
mod uncertainty;
pub mod wear;
pub mod zones;

use glam::{DQuat, DVec3};
use rayon::prelude::*;
use serde::Serialize;
use specula_scene::{Camera, MaterialKind, Mesh, Scene};

use crate::mirror_surface::SurfaceModel;
use crate::AnalyzeError;
use focimeter::{Focimeter, LensFrame};
pub use standard::Verdict;
pub use tracer::{Failure, LensTracer, Traced};
pub use wear::{Compensated, Rx, Wear};

pub use options::*;
use prescription::*;
use progressive::*;
pub use uncertainty::*;

/// The version of [`Report`]'s JSON (docs/analyze-lens.schema.json).
pub const SCHEMA_VERSION: u32 = 3;

/// The default vertex distance: from the cornea to the lens's back surface along the primary
/// line of sight.
pub const DEFAULT_VERTEX_DISTANCE_M: f64 = 0.012;

/// The default depth of the eye's centre of rotation behind the cornea.
pub const DEFAULT_ROTATION_BEHIND_CORNEA_M: f64 = 0.015;

/// The entrance pupil's depth behind the cornea, for spectacle magnification.
pub const ENTRANCE_PUPIL_BEHIND_CORNEA_M: f64 = 0.003;

/// The index labs quote base curves in.
pub const TOOLING_INDEX: f64 = 1.53;

/// The lens map's default spacing, millimetres.
pub const DEFAULT_LENS_STEP_MM: f64 = 1.0;

/// The gaze angle at which the central magnification (J) is taken.
const CENTRAL_GAZE_DEG: f64 = 0.1;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Eye {
    Right,
    Left,
}

specula_params::choice!(Eye {
    Right = "right",
    Left = "left",
});

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
    /// From the cornea to the centre of rotation (the entrance pupil lies
    /// [`ENTRANCE_PUPIL_BEHIND_CORNEA_M`] behind the cornea).
    pub rotation_behind_cornea_m: f64,
    /// The primary gaze and up (unit, perpendicular).
    pub forward: DVec3,
    pub up: DVec3,
    pub gaze: Gaze,
    /// None: an object at infinity.
    pub object_distance_m: Option<f64>,
    /// The bundle's half-width at the lens, metres.
    pub step_m: f64,
    /// The lens's surface: exact where the scene made it from a shape.
    pub surface: SurfaceModel,
    pub wear: Wear,
    /// What the wearer was prescribed (and the ordered prism).
    pub prescription: Option<Rx>,
    /// The vertex distance the prescription was refracted at (None: the lens's own).
    pub refraction_vertex_m: Option<f64>,
    /// Solve the ordered prescription that gives the prescription as worn (module doc of
    /// [`wear`]).
    pub compensate: bool,
    pub standard: Option<&'static standard::Table>,
    /// The distance and prism reference points, millimetres from the back vertex along the
    /// lens's right and up.
    pub reference_points_mm: [[f64; 2]; 2],
    /// A progressive lens's near reference point, millimetres like the others.
    pub near_reference_mm: Option<[f64; 2]>,
    /// A progressive lens's ordered addition: asks for its progressive figures.
    pub add_d: Option<f64>,
    /// Where the eyes look at near, if they do.
    pub near: Option<near::Near>,
    /// The lens map's spacing, millimetres (None: no lens map and no clear zones).
    pub lens_step_mm: Option<f64>,
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
            role: "lens",
            name: mesh.name.clone(),
            kind: match kind {
                MaterialKind::Dielectric { .. } => "a thin-walled sheet (no power)".into(),
                other => format!("{other:?}").to_lowercase(),
            },
            expected: "a refractor (a solid dielectric)",
            wanted: crate::Wanted::SolidGlass,
        }),
    }
}

/// The mesh named `name`, for `--lens`: an unknown name lists the scene's refractors (solid
/// dielectrics), the objects a lens analysis takes.
pub fn find_lens(scene: &Scene, name: &str) -> Result<usize, AnalyzeError> {
    crate::object(scene, "lens", name).map_err(|e| match e {
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

/// The surface a lens is best analysed on: its exact one where the scene made it from a
/// shape, else its triangles.
pub fn best_surface(mesh: &Mesh) -> SurfaceModel {
    if mesh.exact.as_ref().is_some_and(|e| e.lens().is_some()) {
        SurfaceModel::Exact
    } else {
        SurfaceModel::Mesh
    }
}

/// The back vertex: where the camera's view axis first meets the lens (the camera is taken as
/// the wearer's eye, on the lens's eye side), on its best surface.
pub fn back_vertex(scene: &Scene, lens: usize, camera: &Camera) -> Result<DVec3, AnalyzeError> {
    let mesh = &scene.meshes[lens];
    let tracer = tracer(mesh, best_surface(mesh))?;
    let eye = camera.eye.as_dvec3();
    let forward = (camera.target - camera.eye).as_dvec3().normalize();
    tracer
        .next_hit(eye - forward * 1e-6, forward)
        .map(|(p, _)| p)
        .ok_or_else(|| AnalyzeError::BadOption {
            option: "rotation_centre",
            reason: format!(
                "the camera's view axis misses '{}', so its back vertex (and the centre of \
                 rotation behind it) is unknown: give `rotation_centre` X,Y,Z",
                mesh.name
            ),
        })
}

/// The centre of rotation `vertex_distance_m` + `behind_cornea_m` behind the lens's back
/// vertex on the camera's view axis.
pub fn rotation_centre_behind(
    scene: &Scene,
    lens: usize,
    vertex_distance_m: f64,
    behind_cornea_m: f64,
) -> Result<DVec3, AnalyzeError> {
    for (option, value) in [
        ("vertex_distance", vertex_distance_m),
        ("rotation_behind_cornea", behind_cornea_m),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(AnalyzeError::BadOption {
                option,
                reason: format!(
                    "{} mm: the distance must be positive (the cornea cannot touch the lens, \
                     and the centre of rotation lies behind the cornea)",
                    value * 1e3
                ),
            });
        }
    }
    let (forward, _) = primary_frame(&scene.camera)?;
    Ok(back_vertex(scene, lens, &scene.camera)? - forward * (vertex_distance_m + behind_cornea_m))
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
            // + 0.0: no −0.
            axis_deg: if axis >= 180.0 - 1e-9 {
                0.0
            } else {
                axis + 0.0
            },
            mean_power_d: mean,
        }
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

impl Cell {
    /// A gaze outside the lens: no figures.
    pub fn outside(gaze_deg: [f64; 2]) -> Cell {
        Cell {
            gaze_deg,
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
        }
    }
}

/// The base curve: the front surface's power in the lens's index and in the 1.53 tooling index
/// labs quote.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct BaseCurve {
    pub lens_index_d: f64,
    pub tooling_index_d: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub schema_version: u32,
    pub scene: String,
    pub lens: String,
    pub eye: Eye,
    /// The surface traced: "exact" (the lens's own), "mesh" or "smooth".
    pub surface: SurfaceModel,
    /// For a mesh: the largest change of a sphere, cylinder or mean power over the grid and
    /// the focimeter's readings when the triangles are replaced by their smooth fit (the
    /// other of mesh and smooth), dioptres; None on the exact surface.
    pub surface_uncertainty_d: Option<f64>,
    /// A lens with a sag-grid surface: how far its power may be off where the grid is coarse
    /// for the surface's curvature (None: no sag grid).
    pub sag_grid: Option<SagGridUncertainty>,
    pub rotation_centre: [f64; 3],
    pub forward: [f64; 3],
    pub up: [f64; 3],
    pub wear: Wear,
    /// The fitting point: where the primary line of sight meets the back surface as worn.
    pub fitting_point: [f64; 3],
    /// The vertex sphere's radius: from the rotation centre to the fitting point.
    pub vertex_sphere_radius_m: f64,
    /// The cornea's distance from the fitting point: the vertex sphere's radius less the
    /// centre of rotation's depth behind the cornea, millimetres.
    pub vertex_distance_mm: f64,
    pub rotation_behind_cornea_mm: f64,
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
    /// Spectacle magnification, horizontally and vertically: the angular magnification seen
    /// from the entrance pupil (3 mm behind the cornea); for a thick lens
    /// [1 / (1 − (t/n) F1)] · [1 / (1 − h Fv)], h from the back vertex to the pupil.
    pub spectacle_magnification: [f64; 2],
    /// The same from the centre of rotation: the rotating eye's field magnification.
    pub rotating_eye_magnification: [f64; 2],
    /// An exact lens's base curve.
    pub base_curve: Option<BaseCurve>,
    /// The focimeter at the distance and the prism reference points (the lens off the face).
    pub focimeter: Vec<focimeter::Reading>,
    /// The prescription given (minus-cylinder form).
    pub prescription: Option<Rx>,
    pub refraction_vertex_mm: Option<f64>,
    /// What the wearer should get at the vertex sphere: the prescription re-referenced from
    /// the refraction's vertex distance to the lens's. The power error and the unwanted
    /// cylinder are taken against it.
    pub target: Option<Rx>,
    pub compensated: Option<Compensated>,
    pub verdict: Option<Verdict>,
    /// The lens map over the lens's own coordinates.
    pub lens_map: Option<zones::LensMap>,
    /// The fitting point in the lens map's coordinates, mm.
    pub fitting_point_mm: [f64; 2],
    pub clear_zones: Vec<zones::ClearZone>,
    /// The focimeter on the progressive surface's side, at the distance and near reference
    /// points.
    pub add_focimeter: Vec<focimeter::Reading>,
    pub progressive: Option<zones::Progressive>,
    pub near: Option<near::NearFigures>,
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
    /// The primary line of sight's chief ray.
    primary: Traced,
    vertex_sphere_radius: f64,
}

impl<'a> Setup<'a> {
    /// The analysis of the lens `tracer` traces, refused where the eye does not look through
    /// it or the object lies at or behind it.
    fn new(
        tracer: LensTracer<'a>,
        options: &'a Options,
        indices: DVec3,
        name: &str,
    ) -> Result<Setup<'a>, AnalyzeError> {
        let primary = primary_trace(&tracer, options, indices.y, name)?;
        let vertex_sphere_radius = (primary.points[0] - options.rotation_centre).length();
        if let Some(distance) = options.object_distance_m {
            let front = (primary.points[1] - options.rotation_centre).length();
            if distance < front + 0.01 {
                return Err(AnalyzeError::BadOption {
                    option: "object_distance",
                    reason: format!(
                        "{distance} m from the centre of rotation puts the object at or behind \
                         the lens, whose front is {front:.4} m away: give more than {:.3} m",
                        front + 0.01
                    ),
                });
            }
        }
        Ok(Setup {
            tracer,
            options,
            right: options.forward.cross(options.up).normalize(),
            indices,
            primary,
            vertex_sphere_radius,
        })
    }

    /// Every gaze's figures: the centre's, and the grid's row by row.
    fn grid(
        &self,
        central: &Central,
        target: Option<&Rx>,
        progress: &(dyn Fn(usize) + Sync),
    ) -> (Cell, Vec<Cell>) {
        let o = self.options;
        let cell = |h: f64, v: f64| figures(self, h, v, central, target);
        let (horizontal, vertical) = (o.gaze.horizontal(), o.gaze.vertical());
        let done = std::sync::atomic::AtomicUsize::new(0);
        let rows: Vec<Vec<Cell>> = vertical
            .par_iter()
            .map(|&v| {
                let row = horizontal.iter().map(|&h| cell(h, v)).collect();
                progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                row
            })
            .collect();
        (cell(0.0, 0.0), rows.into_iter().flatten().collect())
    }

    /// An object-space direction's tangents over the primary gaze (right / forward,
    /// up / forward).
    fn tangent_of(&self, out: DVec3) -> [f64; 2] {
        let o = self.options;
        let along = out.dot(o.forward);
        [out.dot(self.right) / along, out.dot(o.up) / along]
    }

    /// The derivative of the object's tangents by the gaze's for rays from `origin` about the
    /// primary gaze (2 × 2: a toric lens magnifies its meridians differently), by central
    /// differences at ±0.1° of gaze.
    fn tangent_derivative(&self, origin: DVec3, name: &str) -> Result<[[f64; 2]; 2], AnalyzeError> {
        let o = self.options;
        let delta = CENTRAL_GAZE_DEG.to_radians().tan();
        let mut j = [[0.0; 2]; 2];
        for (k, axis) in [self.right, o.up].into_iter().enumerate() {
            let at = |sign: f64| {
                let dir = (o.forward + axis * (sign * delta)).normalize();
                self.tracer
                    .trace(origin, dir, self.indices.y)
                    .map(|c| self.tangent_of(c.dir))
            };
            let (plus, minus) = at(1.0)
                .and_then(|p| Ok((p, at(-1.0)?)))
                .map_err(|failure| AnalyzeError::BadOption {
                    option: "rotation_centre",
                    reason: format!(
                        "the primary gaze meets the edge of '{name}' ({failure:?}): the \
                         centre of rotation must look through the lens"
                    ),
                })?;
            for (row, column) in j.iter_mut().enumerate() {
                column[k] = (plus[row] - minus[row]) / (2.0 * delta);
            }
        }
        Ok(j)
    }

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
        let out = chief.dir;
        // A basis across the object-space chief ray.
        let a = (frame.right - out * frame.right.dot(out)).normalize();
        let b = out.cross(a);
        let front = chief.points[1];
        let object = self.object_point(chief);
        let launch = |s1: f64, s2: f64| match object {
            None => (front + out * 0.01 + (a * s1 + b * s2) * step, -out),
            Some(object) => {
                let dir = (-out + (a * s1 + b * s2) * step).normalize();
                // Started on its own line 10 mm before the lens, so that a far object's
                // distance never reaches the single-precision BVH.
                let t = (front + out * 0.01 - object).dot(out) / dir.dot(out);
                (object + dir * t, dir)
            }
        };
        let vertex_point = self.options.rotation_centre + frame.gaze * self.vertex_sphere_radius;
        bundle_vergence(
            &self.tracer,
            self.indices.y,
            launch,
            vertex_point,
            -frame.gaze,
            [frame.right, frame.up],
        )
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

/// The vergence matrix [L_rr, L_ru, L_uu] (dioptres, converging positive) of the bundle of four
/// rays `launch(s1, s2)` at (±1, 0) and (0, ±1), traced through the lens and measured in the
/// plane through `at` across `light` (the light's direction there), in the basis `axes`
/// (right, up): L = −(∂u/∂s)(∂x/∂s)⁻¹ from the rays' positions x and slopes u, symmetrised.
pub(crate) fn bundle_vergence(
    tracer: &LensTracer,
    ior: f64,
    launch: impl Fn(f64, f64) -> (DVec3, DVec3),
    at: DVec3,
    light: DVec3,
    axes: [DVec3; 2],
) -> Result<[f64; 3], Failure> {
    let [right, up] = axes;
    let measure = |s1: f64, s2: f64| -> Result<([f64; 2], [f64; 2]), Failure> {
        let (origin, dir) = launch(s1, s2);
        let traced = tracer.trace(origin, dir, ior)?;
        let (q, d) = (traced.points[1], traced.dir);
        let t = (at - q).dot(light) / d.dot(light);
        let x = q + d * t - at;
        let along = d.dot(light);
        Ok((
            [x.dot(right), x.dot(up)],
            [d.dot(right) / along, d.dot(up) / along],
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
    let placed = tracer(lens, options.surface)?;
    let fitting_point = primary_trace(&placed, options, indices.y, &lens.name)?.points[0];
    let world_from_placed =
        options
            .wear
            .world_from_placed(fitting_point, options.forward, options.up, options.eye);
    let worn = wear::moved(lens, world_from_placed);
    let worn_tracer = tracer(&worn, options.surface)?;
    let setup = Setup::new(worn_tracer, options, indices, &lens.name)?;
    let rotating = setup.tangent_derivative(options.rotation_centre, &lens.name)?;
    let pupil = options.rotation_centre
        + options.forward * (options.rotation_behind_cornea_m - ENTRANCE_PUPIL_BEHIND_CORNEA_M);
    let magnification =
        |j: [[f64; 2]; 2]| [1.0 / j[0][0].hypot(j[1][0]), 1.0 / j[0][1].hypot(j[1][1])];
    let spectacle = setup.tangent_derivative(pupil, &lens.name)?;
    let central = Central {
        j: rotating,
        object_tangent: setup.tangent_of(setup.primary.dir),
    };
    let target = options.prescription.map(|rx| {
        let vertex_distance = setup.vertex_sphere_radius - options.rotation_behind_cornea_m;
        options
            .refraction_vertex_m
            .map_or(rx, |d| rx.moved_towards_eye(d - vertex_distance))
    });
    let (centre, grid) = setup.grid(&central, target.as_ref(), progress);
    let mut focimeter = read_focimeter(&placed, lens, options, indices.y, fitting_point)?;
    let frame = worn_frame(&worn, &setup);
    let fitting_mm = frame.mm_of(setup.primary.points[0]);
    let reference = target.unwrap_or_else(|| own_power(&centre));
    let lens_map = lens_map_of(&setup, &frame, &worn, &central, &reference)?;
    let clear_zones = lens_map.as_ref().map_or_else(Vec::new, |map| {
        zones::clear_zones(map, &grid, options.gaze.step_deg, fitting_mm)
    });
    let (mut add_focimeter, progressive) = progressive_figures(
        &placed,
        lens,
        options,
        indices.y,
        lens_map.as_ref(),
        fitting_mm,
    )?;
    let near = near_of(&setup, &worn, &frame, fitting_mm, &central, target)?;
    let surface_uncertainty_d = surface_uncertainty(
        &setup,
        lens,
        &worn,
        &central,
        target.as_ref(),
        (&centre, &grid),
        &mut focimeter,
        fitting_point,
    )?;
    let sag_grid = sag_grid_uncertainty(
        lens,
        indices.y,
        [&mut focimeter, &mut add_focimeter],
        lens_map.as_ref(),
    );
    let compensated = compensated_of(scene, &setup, &worn, target)?;
    let verdict = verdict_of(
        options,
        compensated,
        &focimeter,
        &add_focimeter,
        progressive.as_ref(),
    )?;
    let finite_difference_change_d = largest_fd_change(&centre, &grid);
    Ok(Report {
        schema_version: SCHEMA_VERSION,
        scene: scene.name.clone(),
        lens: lens.name.clone(),
        eye: options.eye,
        surface: options.surface,
        surface_uncertainty_d,
        sag_grid,
        rotation_centre: options.rotation_centre.to_array(),
        forward: options.forward.to_array(),
        up: options.up.to_array(),
        wear: options.wear,
        fitting_point: setup.primary.points[0].to_array(),
        vertex_sphere_radius_m: setup.vertex_sphere_radius,
        vertex_distance_mm: (setup.vertex_sphere_radius - options.rotation_behind_cornea_m) * 1e3,
        rotation_behind_cornea_mm: options.rotation_behind_cornea_m * 1e3,
        object_distance_m: options.object_distance_m,
        indices: indices.to_array(),
        gaze: options.gaze,
        columns: options.gaze.horizontal().len(),
        rows: options.gaze.vertical().len(),
        step_mm: options.step_m * 1e3,
        finite_difference_change_d,
        spectacle_magnification: magnification(spectacle),
        rotating_eye_magnification: magnification(rotating),
        base_curve: base_curve(lens, indices.y),
        focimeter,
        prescription: options.prescription.map(Rx::minus_cylinder),
        refraction_vertex_mm: options.refraction_vertex_m.map(|d| d * 1e3),
        target,
        compensated,
        verdict,
        lens_map,
        fitting_point_mm: fitting_mm.to_array(),
        clear_zones,
        add_focimeter,
        progressive,
        near,
        centre,
        grid,
    })
}

/// The lens in `model`, refused where it asks for an exact surface the lens lacks.
fn tracer(mesh: &Mesh, model: SurfaceModel) -> Result<LensTracer<'_>, AnalyzeError> {
    LensTracer::with_model(mesh, model).ok_or_else(|| AnalyzeError::BadOption {
        option: "surface",
        reason: format!(
            "'{}' has no exact surfaces (only `lens` and `spectacle-lens` shapes and the \
             built-in lenses do); use `surface` mesh or smooth",
            mesh.name
        ),
    })
}

/// The primary line of sight through the lens, refused where the eye is not behind it.
fn primary_trace(
    tracer: &LensTracer,
    options: &Options,
    ior: f64,
    name: &str,
) -> Result<Traced, AnalyzeError> {
    if tracer.contains(options.rotation_centre) {
        return Err(AnalyzeError::BadOption {
            option: "rotation_centre",
            reason: format!(
                "{} lies inside '{name}': the eye's centre of rotation must be behind the lens",
                options.rotation_centre
            ),
        });
    }
    tracer
        .trace(options.rotation_centre, options.forward, ior)
        .map_err(|failure| AnalyzeError::BadOption {
            option: "rotation_centre",
            reason: format!(
                "looking straight ahead from {} the eye does not see through '{name}' \
                 ({failure:?}): put the centre of rotation behind the lens",
                options.rotation_centre
            ),
        })
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
fn figures(setup: &Setup, h: f64, v: f64, central: &Central, target: Option<&Rx>) -> Cell {
    let outside = Cell::outside([h, v]);
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
    let (power_error_d, unwanted_cylinder_d) = match target {
        Some(rx) => {
            let rx = rx.power_vector();
            let got = Rx::new(power.sphere_d, power.cylinder_d, power.axis_deg).power_vector();
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
