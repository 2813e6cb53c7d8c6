//! `specula analyze mirror-view`: what is seen in a mirror, from each eye point and from all
//! together (ambinocular, as UN ECE R46 judges: a point counts when any eye sees it).
//!
//! Steps, per eye point:
//! 1. Each mirror triangle is cut into n × n sub-triangles; at each of their corners S the
//!    exact ray from the eye towards S is traced through the whole scene. S is seen when nothing
//!    lies before it (the car body may hide part of the mirror; a window pane, thin-walled
//!    glass, hides nothing; solid glass, which would bend the ray, is taken as hiding).
//! 2. At the hit the ray is reflected about the mirror's shading normal (as the reference
//!    reflects it) and followed to its first hit. Its direction is a sample of the field of
//!    view; where it meets the ground plane (`ground_y`) before any object (window panes
//!    passed, as above), the point it meets is a sample of the footprint (objects occlude the
//!    road).
//! 3. Figures: the horizontal and vertical extent of the seen directions in the vehicle frame;
//!    their solid angle, summed exactly over the sub-triangles whose three corners are seen
//!    (each a spherical triangle of reflected directions); the ground seen, the sub-triangles
//!    whose three corners meet the ground, rasterised on a grid and clipped to `range_m` of the
//!    eye (horizontally); the share of a required region the footprint covers.
//! 4. n doubles until each figure changes by less than its tolerance (relative for the solid
//!    angle and the areas, in degrees for the extents), or the sample budget is spent (then the
//!    report says the figures did not converge).
//!
//! Ambinocular figures: the extents over every eye's directions, and the solid angle and the
//! areas of the union of the eyes' sub-triangles, rasterised (the solid angle on a grid of
//! horizontal angle × elevation, each cell weighted by its solid angle). `region_seen_by_all` is
//! the share every eye sees; the blind part is the region no eye sees.
//!
//! Exactness: a flat mirror maps its triangles to the ground and to directions projectively
//! (through the eye's mirror image), so its sub-triangles tile the footprint and the spherical
//! image exactly at any n; a curved mirror converges as n grows. The grids' cells are stated in
//! the report (`ground_cell_m`, `direction_cell_deg`): a footprint's area is exact to about
//! its perimeter × half a cell.

pub mod analysis;
pub mod plot;
pub mod report;
pub use analysis::INFO;
pub(crate) mod summary;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use specula_scene::{MaterialKind, Scene};
use specula_trace::optics::reflect;
use specula_trace::reference::offset_origin;
use specula_trace::{Ray, SceneAccel};

use crate::frame::VehicleFrame;
use crate::mirror_surface::{MirrorSurface, SurfaceModel};
use crate::AnalyzeError;

/// The version of [`Report`]'s JSON (docs/analyze-mirror-view.schema.json).
pub const SCHEMA_VERSION: u32 = 3;

/// The most levels a sub-triangle on an edge of what is seen is cut in four.
const MAX_DEPTH: u32 = 16;

/// Cells per side of the grids areas and solid angles of unions are counted on.
const GRID: usize = 2048;

/// A required region on the ground: x and z bounds, metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Region {
    pub x0: f32,
    pub z0: f32,
    pub x1: f32,
    pub z1: f32,
}

impl Region {
    /// The region between two corners, in either order; it must have an area.
    pub fn new(x0: f32, z0: f32, x1: f32, z1: f32) -> Result<Region, AnalyzeError> {
        let region = Region {
            x0: x0.min(x1),
            z0: z0.min(z1),
            x1: x0.max(x1),
            z1: z0.max(z1),
        };
        if ![x0, z0, x1, z1].iter().all(|v| v.is_finite()) || region.area() <= 0.0 {
            return Err(AnalyzeError::BadOption {
                option: "region",
                reason: format!(
                    "X0,Z0,X1,Z1 = {x0},{z0},{x1},{z1} has no area: the corners must differ in \
                     x and in z"
                ),
            });
        }
        Ok(region)
    }

    pub fn area(&self) -> f64 {
        f64::from(self.x1 - self.x0) * f64::from(self.z1 - self.z0)
    }
}

/// What the analysis is asked.
#[derive(Clone, Debug)]
pub struct Options {
    /// The mirror's mesh.
    pub mirror: usize,
    pub frame: VehicleFrame,
    /// The ground plane's height (world y).
    pub ground_y: f32,
    /// Ground farther than this from the eye, horizontally, is not counted.
    pub range_m: f32,
    pub region: Option<Region>,
    /// Refinement stops when the solid angle and the areas change by less than this share.
    pub tolerance: f64,
    /// ... and the extents by less than this many degrees.
    pub tolerance_deg: f64,
    /// The most ray samples one eye point may take.
    pub max_samples: usize,
    /// The surface the samples lie on (default: the mirror's exact surface where it has one).
    pub surface: SurfaceModel,
    /// What hides the mirror and the ground.
    pub obstacles: Obstacles,
}

/// How finely a mirror view is refined: it stops when the solid angle and the areas change by
/// less than `tolerance` (a share) and the extents by less than `tolerance_deg`, or at
/// `max_samples` ray samples an eye point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Precision {
    pub tolerance: f64,
    pub tolerance_deg: f64,
    pub max_samples: usize,
}

impl Precision {
    /// A report's figures: what `specula analyze mirror-view` refines to by default.
    pub const REPORT: Precision = Precision {
        tolerance: 0.005,
        tolerance_deg: 0.05,
        max_samples: 4_000_000,
    };
    /// The viewer's, rerun while the mirror is dragged (about 150 ms an eye point on 2 cores).
    pub const INTERACTIVE: Precision = Precision {
        tolerance: 0.02,
        tolerance_deg: 0.1,
        max_samples: 1_000_000,
    };
}

/// Ground farther than this from the eye, horizontally, is not counted by default (metres).
pub const DEFAULT_RANGE_M: f32 = 100.0;

impl Options {
    /// The defaults for `mirror` in `frame`, refined to `precision`: the ground at the scene's
    /// lowest point, [`DEFAULT_RANGE_M`], no required region, the mirror's own surface model
    /// ([`SurfaceModel::best_for`]) and every object of the scene in the way.
    pub fn new(scene: &Scene, mirror: usize, frame: VehicleFrame, precision: Precision) -> Options {
        Options {
            mirror,
            frame,
            ground_y: lowest_point(scene),
            range_m: DEFAULT_RANGE_M,
            region: None,
            tolerance: precision.tolerance,
            tolerance_deg: precision.tolerance_deg,
            max_samples: precision.max_samples,
            surface: SurfaceModel::best_for(&scene.meshes[mirror]),
            obstacles: Obstacles::Scene,
        }
    }
}

/// What may stand between the eye, the mirror and the ground.
#[derive(Clone, Debug, PartialEq)]
pub enum Obstacles {
    /// Every opaque object of the scene (thin-walled glass passes light).
    Scene,
    /// Only these meshes, the vehicle's own body and fittings: the rest of the scene is not
    /// there (a regulation's field lies on an empty, flat road). What they hide is counted
    /// apart ([`MirrorView::clear_footprints`]).
    Vehicle(Vec<usize>),
}

impl Obstacles {
    /// Whether mesh `mesh` may hide anything.
    fn hides(&self, mesh: usize) -> bool {
        match self {
            Obstacles::Scene => true,
            Obstacles::Vehicle(parts) => parts.contains(&mesh),
        }
    }

    fn is_vehicle(&self, mesh: usize) -> bool {
        matches!(self, Obstacles::Vehicle(parts) if parts.contains(&mesh))
    }
}

impl Options {
    /// Checks the options against `scene`: the mesh is a mirror, the range positive.
    pub fn validate(&self, scene: &Scene) -> Result<(), AnalyzeError> {
        let mesh = &scene.meshes[self.mirror];
        let material = &scene.materials[mesh.material];
        if !matches!(material.kind, MaterialKind::Mirror { .. }) {
            return Err(AnalyzeError::WrongMaterial {
                role: "mirror",
                name: mesh.name.clone(),
                kind: format!("{:?}", material.kind).to_lowercase(),
                expected: "a mirror",
                wanted: crate::Wanted::Mirror,
            });
        }
        if !(self.range_m.is_finite() && self.range_m > 0.0) {
            return Err(AnalyzeError::BadOption {
                option: "range",
                reason: format!("{} m: the range must be a positive distance", self.range_m),
            });
        }
        for (option, value) in [
            ("tolerance", self.tolerance),
            ("tolerance_deg", self.tolerance_deg),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(AnalyzeError::BadOption {
                    option,
                    reason: format!("{value}: a tolerance must be a positive number"),
                });
            }
        }
        if self.surface == SurfaceModel::Exact
            && crate::mirror_surface::mirror_exact(mesh).is_none()
        {
            return Err(AnalyzeError::BadOption {
                option: "surface",
                reason: format!(
                    "'{}' has no exact surface (only generated patches, spheres and caps do); \
                     use `surface` mesh or smooth",
                    mesh.name
                ),
            });
        }
        if let Obstacles::Vehicle(parts) = &self.obstacles {
            if parts.contains(&self.mirror) {
                return Err(AnalyzeError::BadOption {
                    option: "vehicle",
                    reason: format!("'{}' is the mirror, not a part of the body", mesh.name),
                });
            }
        }
        if !self.ground_y.is_finite() {
            return Err(AnalyzeError::BadOption {
                option: "ground",
                reason: format!("{} is not a height", self.ground_y),
            });
        }
        Ok(())
    }
}

/// The lowest point of the scene's objects: the default ground.
pub fn lowest_point(scene: &Scene) -> f32 {
    scene.bounds().min.y
}

/// One corner of a sub-triangle, as the eye sees it in the mirror.
#[derive(Clone, Copy, Debug)]
struct Sample {
    /// The reflected direction (unit), where the mirror is seen at this point.
    reflected: Option<Vec3>,
    /// Where the reflected ray meets the ground before any object (x, z).
    ground: Option<Vec2>,
    /// Where it would meet the ground with the vehicle's body taken away (the mirror seen
    /// through it too); with [`Obstacles::Scene`], `ground`.
    clear_ground: Option<Vec2>,
}

/// What one eye sees at one subdivision.
struct Sampled {
    samples: usize,
    seen: usize,
    /// Spherical triangles of reflected directions whose three corners are seen.
    directions: Vec<[Vec3; 3]>,
    /// Ground triangles (x, z) whose three corners meet the ground.
    ground: Vec<[Vec2; 3]>,
    /// ... and those that would with the vehicle's body taken away.
    clear_ground: Vec<[Vec2; 3]>,
    solid_angle_sr: f64,
}

/// Solid angle of the spherical triangle of unit vectors `a`, `b`, `c` (Van Oosterom and
/// Strackee 1983).
pub fn spherical_triangle_solid_angle(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let numerator = a.dot(b.cross(c)).abs();
    let denominator = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    2.0 * numerator.atan2(denominator)
}

/// Where corner (i, j) of a triangle cut `n` times per side starts its row: the corners
/// (i, j) with i + j ≤ n at barycentric (1 − i/n − j/n, i/n, j/n) are stored row by row, row i
/// holding n + 1 − i of them.
fn row_start(n: usize, i: usize) -> usize {
    i * (n + 1) - i * i.saturating_sub(1) / 2
}

/// One eye's samples: each mirror triangle cut `n` times per side, and each sub-triangle whose
/// corners disagree (seen or hidden, meeting the ground or not) cut in four again, `depth`
/// times more, so that the edges of what is seen (the car body's outline, the buildings' on
/// the road) are followed at a fraction of a uniform grid's cost.
fn sample_eye(
    scene: &Scene,
    accel: &SceneAccel,
    eye: Vec3,
    surface: &MirrorSurface,
    options: &Options,
    n: usize,
    depth: u32,
) -> Sampled {
    let parts: Vec<Sampled> = (0..surface.cells())
        .into_par_iter()
        .map(|cell| {
            let sample = |b: Vec2| sample_point(scene, accel, eye, surface, cell, b, options);
            let bary = |i: usize, j: usize| Vec2::new(i as f32 / n as f32, j as f32 / n as f32);
            let mut grid = Vec::with_capacity((n + 1) * (n + 2) / 2);
            for i in 0..=n {
                for j in 0..=n - i {
                    grid.push(sample(bary(i, j)));
                }
            }
            let mut part = Sampled::empty();
            part.samples = grid.len();
            part.seen = grid.iter().filter(|s| s.reflected.is_some()).count();
            let at = |i: usize, j: usize| (bary(i, j), grid[row_start(n, i) + j]);
            for i in 0..n {
                for j in 0..n - i {
                    descend(
                        &sample,
                        [at(i, j), at(i + 1, j), at(i, j + 1)],
                        depth,
                        &mut part,
                    );
                    if j + 1 < n - i {
                        let cell = [at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                        descend(&sample, cell, depth, &mut part);
                    }
                }
            }
            part
        })
        .collect();
    let mut sampled = Sampled::empty();
    for part in parts {
        sampled.samples += part.samples;
        sampled.seen += part.seen;
        sampled.solid_angle_sr += part.solid_angle_sr;
        sampled.directions.extend(part.directions);
        sampled.ground.extend(part.ground);
        sampled.clear_ground.extend(part.clear_ground);
    }
    sampled
}

impl Sampled {
    fn empty() -> Sampled {
        Sampled {
            samples: 0,
            seen: 0,
            directions: Vec::new(),
            ground: Vec::new(),
            clear_ground: Vec::new(),
            solid_angle_sr: 0.0,
        }
    }
}

/// Adds a sub-triangle (barycentric corners with their samples) to `part`: whole where its
/// corners agree or `depth` is spent, else cut in four at its edges' midpoints.
fn descend(
    sample: &impl Fn(Vec2) -> Sample,
    corners: [(Vec2, Sample); 3],
    depth: u32,
    part: &mut Sampled,
) {
    let status = |s: &Sample| {
        (
            s.reflected.is_some(),
            s.ground.is_some(),
            s.clear_ground.is_some(),
        )
    };
    let agree = status(&corners[0].1) == status(&corners[1].1)
        && status(&corners[1].1) == status(&corners[2].1);
    if depth == 0 || agree {
        let samples = corners.map(|c| c.1);
        if let [Some(a), Some(b), Some(c)] = samples.map(|s| s.reflected) {
            part.solid_angle_sr += spherical_triangle_solid_angle(a, b, c);
            part.directions.push([a, b, c]);
        }
        if let [Some(a), Some(b), Some(c)] = samples.map(|s| s.ground) {
            part.ground.push([a, b, c]);
        }
        if let [Some(a), Some(b), Some(c)] = samples.map(|s| s.clear_ground) {
            part.clear_ground.push([a, b, c]);
        }
        return;
    }
    let mut midpoint = |a: usize, b: usize| {
        let m = (corners[a].0 + corners[b].0) * 0.5;
        let s = sample(m);
        part.samples += 1;
        part.seen += usize::from(s.reflected.is_some());
        (m, s)
    };
    let (m01, m12, m20) = (midpoint(0, 1), midpoint(1, 2), midpoint(2, 0));
    for child in [
        [corners[0], m01, m20],
        [m01, corners[1], m12],
        [m20, m12, corners[2]],
        [m01, m12, m20],
    ] {
        descend(sample, child, depth - 1, part);
    }
}

/// The first hit along `ray` within `t_max` that hides what lies behind it: thin-walled sheets
/// (a side window the driver looks through, a glazed shelter) pass light straight through and
/// are passed; solid glass, which bends rays, hides (a limit of these analyses).
pub fn first_opaque_hit(
    scene: &Scene,
    accel: &SceneAccel,
    ray: &Ray,
    t_max: f32,
) -> Option<specula_trace::Hit> {
    first_hit_where(scene, accel, ray, t_max, &|_| true)
}

/// As [`first_opaque_hit`], among the meshes `may_hide` accepts (the others are passed).
fn first_hit_where(
    scene: &Scene,
    accel: &SceneAccel,
    ray: &Ray,
    t_max: f32,
    may_hide: &dyn Fn(usize) -> bool,
) -> Option<specula_trace::Hit> {
    let mut origin = ray.origin;
    let mut travelled = 0.0;
    for _ in 0..64 {
        let hit = accel.intersect(
            &Ray {
                origin,
                dir: ray.dir,
            },
            t_max - travelled,
        )?;
        let material = &scene.materials[scene.meshes[hit.mesh as usize].material];
        let thin_glass = matches!(
            material.kind,
            MaterialKind::Dielectric {
                thin_walled: true,
                ..
            }
        );
        if !thin_glass && may_hide(hit.mesh as usize) {
            return Some(specula_trace::Hit {
                t: travelled + hit.t,
                ..hit
            });
        }
        let p = origin + ray.dir * hit.t;
        let step = hit.t + 2e-5 * (1.0 + p.abs().max_element());
        origin += ray.dir * step;
        travelled += step;
        if travelled >= t_max {
            return None;
        }
    }
    None
}

/// The eye's ray towards the mirror's point at barycentric `b` of `cell`: whether nothing
/// hides it, and where its reflection goes. The point is on the mirror by construction, so only
/// what lies before it is looked for (a ray aimed exactly at a mirror's outer edge could
/// otherwise slip past it); a model other than the mesh replaces the mirror's own triangles,
/// which then hide nothing.
fn sample_point(
    scene: &Scene,
    accel: &SceneAccel,
    eye: Vec3,
    surface: &MirrorSurface,
    cell: usize,
    b: Vec2,
    options: &Options,
) -> Sample {
    let unseen = Sample {
        reflected: None,
        ground: None,
        clear_ground: None,
    };
    let Some(at) = surface.seen_from(eye, cell, b) else {
        return unseen;
    };
    let to_point = at.p - eye;
    let distance = to_point.length();
    let Some(dir) = to_point.try_normalize() else {
        return unseen;
    };
    let obstacles = &options.obstacles;
    let mirror = options.mirror;
    let hides = |m: usize| {
        if m == mirror {
            surface.is_the_mesh()
        } else {
            obstacles.hides(m)
        }
    };
    let ray = Ray { origin: eye, dir };
    let slack = 1e-3 * distance + 1e-4;
    if !surface.is_the_mesh() {
        // The triangles stand in for the surface: a crossing of them well before the point
        // (beyond their sag) asks the surface itself.
        let sag = 0.01 * scene.meshes[mirror].bounds().extent().length();
        let only_mirror = |m: usize| m == mirror;
        let before = first_hit_where(scene, accel, &ray, distance - sag, &only_mirror);
        if before.is_some() && surface.crosses_before(eye, at.p, true) {
            return unseen;
        }
    }
    let mut behind_vehicle = false;
    if let Some(hit) = first_hit_where(scene, accel, &ray, distance - slack, &hides) {
        if !obstacles.is_vehicle(hit.mesh as usize) {
            return unseen;
        }
        // Hidden by the body: only what nothing but the body hides counts as its share.
        let not_vehicle = |m: usize| hides(m) && !obstacles.is_vehicle(m);
        if first_hit_where(scene, accel, &ray, distance - slack, &not_vehicle).is_some() {
            return unseen;
        }
        behind_vehicle = true;
    }
    let reflected = reflect(dir, at.ns).normalize();
    // Interpolated normals can send a grazing reflection into the mirror: not a view.
    if reflected.dot(at.ng) <= 0.0 {
        return unseen;
    }
    let origin = offset_origin(at.p, at.ng, reflected);
    let (ground, clear_ground) = match obstacles {
        Obstacles::Scene => {
            let g = ground_where(scene, accel, origin, reflected, options.ground_y, &hides);
            (g, g)
        }
        Obstacles::Vehicle(_) => {
            let not_vehicle = |m: usize| hides(m) && !obstacles.is_vehicle(m);
            let clear = ground_where(
                scene,
                accel,
                origin,
                reflected,
                options.ground_y,
                &not_vehicle,
            );
            let ground = clear.filter(|_| !behind_vehicle).and_then(|_| {
                ground_where(scene, accel, origin, reflected, options.ground_y, &hides)
            });
            (ground, clear)
        }
    };
    Sample {
        reflected: (!behind_vehicle).then_some(reflected),
        ground,
        clear_ground,
    }
}

/// Where the ray from `origin` along `dir` meets the ground plane y = `ground_y` (x, z), when it
/// goes down and nothing opaque lies before it.
pub(crate) fn ground_seen(
    scene: &Scene,
    accel: &SceneAccel,
    origin: Vec3,
    dir: Vec3,
    ground_y: f32,
) -> Option<Vec2> {
    ground_where(scene, accel, origin, dir, ground_y, &|_| true)
}

/// As [`ground_seen`], among the meshes `may_hide` accepts.
fn ground_where(
    scene: &Scene,
    accel: &SceneAccel,
    origin: Vec3,
    dir: Vec3,
    ground_y: f32,
    may_hide: &dyn Fn(usize) -> bool,
) -> Option<Vec2> {
    let t = (dir.y < 0.0)
        .then(|| (ground_y - origin.y) / dir.y)
        .filter(|t| *t > 0.0)?;
    let blocked = first_hit_where(
        scene,
        accel,
        &Ray { origin, dir },
        t * (1.0 - 1e-4) - 1e-4,
        may_hide,
    );
    blocked.is_none().then(|| {
        let g = origin + dir * t;
        Vec2::new(g.x, g.z)
    })
}

/// A grid of cells over a rectangle, marking what is covered.
struct Raster {
    min: Vec2,
    cell: Vec2,
    columns: usize,
    rows: usize,
    covered: Vec<bool>,
}

impl Raster {
    fn new(min: Vec2, max: Vec2, columns: usize, rows: usize) -> Raster {
        Raster {
            min,
            cell: (max - min) / Vec2::new(columns as f32, rows as f32),
            columns,
            rows,
            covered: vec![false; columns * rows],
        }
    }

    fn centre(&self, column: usize, row: usize) -> Vec2 {
        self.min + self.cell * Vec2::new(column as f32 + 0.5, row as f32 + 0.5)
    }

    /// Marks the cells whose centres lie in triangle `t` and pass `keep`.
    fn fill(&mut self, t: &[Vec2; 3], keep: &impl Fn(Vec2) -> bool) {
        let lo = t[0].min(t[1]).min(t[2]);
        let hi = t[0].max(t[1]).max(t[2]);
        let first = ((lo - self.min) / self.cell).floor().max(Vec2::ZERO);
        let last = ((hi - self.min) / self.cell).ceil();
        let (c0, r0) = (first.x as usize, first.y as usize);
        let c1 = (last.x.max(0.0) as usize).min(self.columns);
        let r1 = (last.y.max(0.0) as usize).min(self.rows);
        let edge = |a: Vec2, b: Vec2, p: Vec2| (b - a).perp_dot(p - a);
        let area = edge(t[0], t[1], t[2]);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        for row in r0..r1 {
            for column in c0..c1 {
                let p = self.centre(column, row);
                let w = [
                    edge(t[1], t[2], p),
                    edge(t[2], t[0], p),
                    edge(t[0], t[1], p),
                ];
                let inside = w.iter().all(|w| w * area >= 0.0);
                if inside && keep(p) {
                    self.covered[row * self.columns + column] = true;
                }
            }
        }
    }

    fn cell_area(&self) -> f64 {
        f64::from(self.cell.x) * f64::from(self.cell.y)
    }

    fn count(&self) -> usize {
        self.covered.iter().filter(|c| **c).count()
    }
}

/// Figures of one eye point, or of all together.
#[derive(Clone, Debug, Serialize)]
pub struct Figures {
    pub horizontal_deg: f64,
    pub vertical_deg: f64,
    pub solid_angle_sr: f64,
    pub ground_area_m2: f64,
    /// Share of the region seen by any eye point (for one eye point: by it). Null without a
    /// region.
    pub region_seen_by_any: Option<f64>,
    /// Share seen by every eye point (for one eye point: by it).
    pub region_seen_by_all: Option<f64>,
    /// The region's area no eye point sees, m².
    pub blind_area_m2: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct EyeReport {
    pub position: [f32; 3],
    #[serde(flatten)]
    pub figures: Figures,
    /// Cuts per side of each mirror triangle at the last refinement, and the levels of cutting
    /// in four on the edges of what is seen beyond that.
    pub subdivision: u32,
    pub edge_depth: u32,
    /// Ray samples on the mirror, and of those, the ones that see it.
    pub samples: usize,
    pub seen_samples: usize,
    /// Samples per m² of mirror surface.
    pub density_per_m2: f64,
    /// Whether every figure changed by less than its tolerance at the last doubling.
    pub converged: bool,
}

/// What `specula analyze mirror-view` reports (docs/analyze-mirror-view.schema.json).
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub schema_version: u32,
    pub scene: String,
    pub mirror: String,
    /// The surface the samples lay on.
    pub surface: SurfaceModel,
    pub forward: [f32; 3],
    pub up: [f32; 3],
    pub ground_y: f32,
    pub range_m: f32,
    pub region: Option<Region>,
    pub tolerance: f64,
    pub tolerance_deg: f64,
    /// The longer cell side of the ground grid the union's area is counted on, m (each eye's
    /// own grid spans only its footprint, so its cells are finer), and of the direction grid
    /// of the ambinocular solid angle, degrees.
    pub ground_cell_m: f64,
    pub direction_cell_deg: f64,
    /// All eye points together: a point counts when any eye sees it.
    #[serde(flatten)]
    pub figures: Figures,
    pub eyes: Vec<EyeReport>,
    /// What the figures cannot show: an eye point that sees nothing of the mirror, named.
    pub warnings: Vec<String>,
}

/// The analysis's outcome: the report, and the footprints for plots.
pub struct MirrorView {
    pub report: Report,
    /// Per eye point, its ground triangles (x, z), unclipped.
    pub footprints: Vec<Vec<[Vec2; 3]>>,
    /// ... those it would see with the vehicle's body taken away ([`Obstacles::Vehicle`]; else
    /// the footprints again).
    pub clear_footprints: Vec<Vec<[Vec2; 3]>>,
    /// ... its footprint at the refinement before the last (how much the last one moved it).
    pub previous_footprints: Vec<Vec<[Vec2; 3]>>,
    /// ... its spherical triangles of reflected directions.
    pub directions: Vec<Vec<[Vec3; 3]>>,
}

impl MirrorView {
    /// How many eye points see each cell of a `columns` × `rows` grid over the ground from
    /// `min` to `max` (x, z), within their range: a cell counts for an eye point when its
    /// centre lies in one of that eye's footprint triangles, as the figures count it. Row-major,
    /// row 0 at `min.y`.
    pub fn seen_counts(&self, min: Vec2, max: Vec2, columns: usize, rows: usize) -> Vec<u16> {
        let mut counts = vec![0u16; columns * rows];
        let range = self.report.range_m;
        for (k, footprint) in self.footprints.iter().enumerate() {
            let [x, _, z] = self.report.eyes[k].position;
            let eye = Vec2::new(x, z);
            let mut raster = Raster::new(min, max, columns, rows);
            for t in footprint {
                raster.fill(t, &|p| p.distance(eye) <= range);
            }
            for (count, covered) in counts.iter_mut().zip(&raster.covered) {
                *count += u16::from(*covered);
            }
        }
        counts
    }
}

/// One eye's sampling, refined until its figures hold.
struct Refined {
    sampled: Sampled,
    /// The ground triangles of the refinement before the last (None: there was none).
    previous: Option<Vec<[Vec2; 3]>>,
    /// Levels of cutting on the edges of what is seen, beyond the grid.
    depth: u32,
    /// The ground seen within range, m² ([`clipped_area`]).
    ground_area_m2: f64,
    subdivision: usize,
    converged: bool,
}

fn extents(frame: &VehicleFrame, reference: Vec3, directions: &[[Vec3; 3]]) -> (f64, f64) {
    let mut h = (f64::INFINITY, f64::NEG_INFINITY);
    let mut v = (f64::INFINITY, f64::NEG_INFINITY);
    for d in directions.iter().flatten() {
        let (x, y) = (frame.horizontal_deg(*d, reference), frame.elevation_deg(*d));
        h = (h.0.min(x), h.1.max(x));
        v = (v.0.min(y), v.1.max(y));
    }
    if h.0 > h.1 {
        return (0.0, 0.0);
    }
    (h.1 - h.0, v.1 - v.0)
}

/// The horizontal reference of a set of directions: their mean's horizontal part.
fn reference_of<'a>(frame: &VehicleFrame, directions: impl Iterator<Item = &'a [Vec3; 3]>) -> Vec3 {
    let sum: Vec3 = directions.flat_map(|t| t.iter()).copied().sum();
    frame.horizontal(sum).unwrap_or(frame.forward)
}

/// The ground `eye` sees within `range` (x, z), m²: its triangles rasterised on a grid over
/// their bounds clipped to the range's square, each cell counted when its centre is in a
/// triangle and within range.
fn clipped_area(ground: &[[Vec2; 3]], eye: Vec2, range: f32) -> f64 {
    let (mut lo, mut hi) = (eye - range, eye + range);
    let (mut t_lo, mut t_hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for p in ground.iter().flatten() {
        t_lo = t_lo.min(*p);
        t_hi = t_hi.max(*p);
    }
    lo = lo.max(t_lo);
    hi = hi.min(t_hi);
    if !(lo.x < hi.x && lo.y < hi.y) {
        return 0.0;
    }
    let mut raster = Raster::new(lo, hi, GRID, GRID);
    let keep = |p: Vec2| p.distance(eye) <= range;
    for t in ground {
        raster.fill(t, &keep);
    }
    raster.count() as f64 * raster.cell_area()
}

/// Samples one eye point ever finer until its figures hold: the grid doubles while the extents
/// move (they follow the mirror's curvature), then the sub-triangles on the edges of what is
/// seen are cut further, a level at a time, until the solid angle and the ground area hold;
/// then the grid is doubled once more at that depth, and the figures must hold there too (else
/// refinement goes on from that grid), so that a curvature the straight sub-triangles cannot
/// follow is measured, not assumed away.
fn refine(
    scene: &Scene,
    accel: &SceneAccel,
    eye: Vec3,
    surface: &MirrorSurface,
    options: &Options,
) -> Refined {
    let triangles = surface.cells().max(1);
    let samples_at = |n: usize| triangles * (n + 1) * (n + 2) / 2;
    let eye_xz = Vec2::new(eye.x, eye.z);
    let area = |s: &Sampled| clipped_area(&s.ground, eye_xz, options.range_m);
    let (mut n, mut depth) = (1, 0);
    while samples_at(n * 2) <= 1000 {
        n *= 2;
    }
    let mut current = sample_eye(scene, accel, eye, surface, options, n, depth);
    let mut current_area = area(&current);
    let mut extents_hold = false;
    let done = |sampled, previous, ground_area_m2, n, depth, converged| Refined {
        sampled,
        previous,
        ground_area_m2,
        subdivision: n,
        depth,
        converged,
    };
    let mut previous = None;
    // Whether `b`'s figures are within tolerance of `a`'s: (extents, all of them).
    let compare = |a: &Sampled, a_area: f64, b: &Sampled, b_area: f64| {
        let reference = reference_of(&options.frame, b.directions.iter());
        let (h0, v0) = extents(&options.frame, reference, &a.directions);
        let (h1, v1) = extents(&options.frame, reference, &b.directions);
        let close = |x: f64, y: f64| (x - y).abs() <= options.tolerance * y.abs().max(1e-9);
        let extents_close =
            (h0 - h1).abs() <= options.tolerance_deg && (v0 - v1).abs() <= options.tolerance_deg;
        // Seen points but no whole sub-triangle yet: nothing to compare, so nothing holds.
        let measured = b.seen == 0 || !b.directions.is_empty();
        let all = measured
            && extents_close
            && close(a.solid_angle_sr, b.solid_angle_sr)
            && close(a_area, b_area);
        (extents_close, all)
    };
    loop {
        let (next_n, next_depth) = if extents_hold {
            (n, depth + 1)
        } else {
            (n * 2, depth)
        };
        // A deeper level at most doubles the samples on the edges; a finer grid quadruples all.
        let estimate = if extents_hold {
            2 * current.samples
        } else {
            4 * current.samples
        };
        if estimate > options.max_samples || next_depth > MAX_DEPTH {
            return done(current, previous, current_area, n, depth, false);
        }
        let next = sample_eye(scene, accel, eye, surface, options, next_n, next_depth);
        let next_area = area(&next);
        let (extents_close, converged) = compare(&current, current_area, &next, next_area);
        let deepened = extents_hold;
        extents_hold |= extents_close;
        (n, depth) = (next_n, next_depth);
        previous = Some(std::mem::replace(&mut current, next).ground);
        current_area = next_area;
        if !converged {
            continue;
        }
        if !deepened {
            // Converged as the grid doubled: the grid has been checked.
            return done(current, previous, current_area, n, depth, true);
        }
        // Converged as the edges were cut further: check a finer grid at this depth.
        if 4 * current.samples > options.max_samples {
            return done(current, previous, current_area, n, depth, false);
        }
        let finer = sample_eye(scene, accel, eye, surface, options, n * 2, depth);
        let finer_area = area(&finer);
        let (_, holds) = compare(&current, current_area, &finer, finer_area);
        n *= 2;
        previous = Some(std::mem::replace(&mut current, finer).ground);
        current_area = finer_area;
        if holds {
            return done(current, previous, current_area, n, depth, true);
        }
        extents_hold = false;
    }
}

/// Runs the analysis from `eyes`, calling `progress` after each eye point: each eye point's
/// footprint and directions refined, then the union over the eye points on a ground grid and
/// a direction grid, the required region seen by any and by all.
pub fn analyze(
    scene: &Scene,
    accel: &SceneAccel,
    eyes: &[Vec3],
    options: &Options,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<MirrorView, AnalyzeError> {
    options.validate(scene)?;
    let surface = MirrorSurface::new(scene, options.mirror, options.surface)
        .expect("validate checked the mirror has the surface asked for");
    let mirror = &scene.meshes[options.mirror];
    // Eye points in parallel (a flat mirror has two triangles: too few to share out alone).
    let done = std::sync::atomic::AtomicUsize::new(0);
    let refined: Vec<Refined> = eyes
        .par_iter()
        .map(|eye| {
            let r = refine(scene, accel, *eye, &surface, options);
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            r
        })
        .collect();
    let frame = &options.frame;
    let union_ground = union_ground(&refined, eyes, options);
    let directions = DirectionGrid::new(frame, &refined);
    let (eye_reports, all_region) = eye_reports(mirror, &refined, eyes, options);
    let any_share = region_grid(&refined, eyes, options, None)
        .as_ref()
        .map(region_share);
    let all_share =
        all_region.map(|all| all.iter().filter(|c| **c).count() as f64 / all.len() as f64);
    let (horizontal_deg, vertical_deg) = extents(
        frame,
        directions.reference,
        &refined
            .iter()
            .flat_map(|r| r.sampled.directions.iter().copied())
            .collect::<Vec<_>>(),
    );
    let report = Report {
        schema_version: SCHEMA_VERSION,
        scene: scene.name.clone(),
        mirror: mirror.name.clone(),
        surface: options.surface,
        forward: frame.forward.to_array(),
        up: frame.up.to_array(),
        ground_y: options.ground_y,
        range_m: options.range_m,
        region: options.region,
        tolerance: options.tolerance,
        tolerance_deg: options.tolerance_deg,
        ground_cell_m: union_ground
            .as_ref()
            .map_or(0.0, |g| f64::from(g.cell.max_element())),
        direction_cell_deg: directions.cell_deg(),
        figures: Figures {
            horizontal_deg,
            vertical_deg,
            solid_angle_sr: directions.union_solid_angle(&refined),
            ground_area_m2: union_ground
                .as_ref()
                .map_or(0.0, |g| g.count() as f64 * g.cell_area()),
            region_seen_by_any: any_share,
            region_seen_by_all: all_share,
            blind_area_m2: options
                .region
                .zip(any_share)
                .map(|(region, share)| region.area() * (1.0 - share)),
        },
        warnings: blind_eye_warnings(&mirror.name, &eye_reports),
        eyes: eye_reports,
    };
    let mut view = MirrorView {
        report,
        footprints: Vec::new(),
        clear_footprints: Vec::new(),
        previous_footprints: Vec::new(),
        directions: Vec::new(),
    };
    for r in refined {
        view.previous_footprints
            .push(r.previous.unwrap_or_else(|| r.sampled.ground.clone()));
        view.footprints.push(r.sampled.ground);
        view.clear_footprints.push(r.sampled.clear_ground);
        view.directions.push(r.sampled.directions);
    }
    Ok(view)
}

/// The union of the eyes' footprints, each clipped to its own range, on a grid over them all
/// within the range square of every eye; None where no eye sees the ground.
fn union_ground(refined: &[Refined], eyes: &[Vec3], options: &Options) -> Option<Raster> {
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for t in refined.iter().flat_map(|r| &r.sampled.ground) {
        for p in t {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
    }
    let (mut range_lo, mut range_hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for e in eyes {
        let e = Vec2::new(e.x, e.z);
        range_lo = range_lo.min(e - options.range_m);
        range_hi = range_hi.max(e + options.range_m);
    }
    let (lo, hi) = (lo.max(range_lo), hi.min(range_hi));
    if !(lo.x < hi.x && lo.y < hi.y) {
        return None;
    }
    let mut union = Raster::new(lo, hi, GRID, GRID);
    for (k, r) in refined.iter().enumerate() {
        let e = Vec2::new(eyes[k].x, eyes[k].z);
        let keep = |p: Vec2| p.distance(e) <= options.range_m;
        for t in &r.sampled.ground {
            union.fill(t, &keep);
        }
    }
    Some(union)
}

/// The required region's grid, covered where eye point `k` (or, for None, any eye point) sees
/// the ground within its range.
fn region_grid(
    refined: &[Refined],
    eyes: &[Vec3],
    options: &Options,
    k: Option<usize>,
) -> Option<Raster> {
    options.region.map(|region| {
        let mut raster = Raster::new(
            Vec2::new(region.x0, region.z0),
            Vec2::new(region.x1, region.z1),
            512,
            512,
        );
        for (i, r) in refined.iter().enumerate() {
            if k.is_some_and(|k| k != i) {
                continue;
            }
            let e = Vec2::new(eyes[i].x, eyes[i].z);
            let keep = |p: Vec2| p.distance(e) <= options.range_m;
            for t in &r.sampled.ground {
                raster.fill(t, &keep);
            }
        }
        raster
    })
}

fn region_share(raster: &Raster) -> f64 {
    raster.count() as f64 / raster.covered.len() as f64
}

/// Each eye point's figures, and the region's cells every eye point sees (None without a
/// region).
/// A warning for each eye point that sees nothing of the mirror: its figures are zeros, which
/// no one should read as a measured field of view.
fn blind_eye_warnings(mirror: &str, eyes: &[EyeReport]) -> Vec<String> {
    eyes.iter()
        .filter(|e| e.seen_samples == 0)
        .map(|e| {
            let [x, y, z] = e.position;
            format!(
                "eye point ({x:.3}, {y:.3}, {z:.3}) sees nothing of the mirror '{mirror}': no ray \
                 from it reaches the mirror's reflecting side (it is behind the mirror, or the \
                 mirror faces away from it), so its figures are zero"
            )
        })
        .collect()
}

fn eye_reports(
    mirror: &specula_scene::Mesh,
    refined: &[Refined],
    eyes: &[Vec3],
    options: &Options,
) -> (Vec<EyeReport>, Option<Vec<bool>>) {
    let frame = &options.frame;
    let mirror_area: f64 = (0..mirror.triangles.len())
        .map(|t| 0.5 * f64::from(mirror.face_normal_scaled(t).length()))
        .sum();
    let mut reports = Vec::with_capacity(eyes.len());
    let mut all_region: Option<Vec<bool>> = None;
    for (k, r) in refined.iter().enumerate() {
        let own_reference = reference_of(frame, r.sampled.directions.iter());
        let (horizontal_deg, vertical_deg) = extents(frame, own_reference, &r.sampled.directions);
        let region = region_grid(refined, eyes, options, Some(k));
        let share = region.as_ref().map(region_share);
        if let Some(region) = &region {
            all_region = Some(match all_region {
                None => region.covered.clone(),
                Some(all) => all
                    .iter()
                    .zip(&region.covered)
                    .map(|(a, b)| *a && *b)
                    .collect(),
            });
        }
        reports.push(EyeReport {
            position: eyes[k].to_array(),
            figures: Figures {
                horizontal_deg,
                vertical_deg,
                solid_angle_sr: r.sampled.solid_angle_sr,
                ground_area_m2: r.ground_area_m2,
                region_seen_by_any: share,
                region_seen_by_all: share,
                blind_area_m2: options
                    .region
                    .zip(share)
                    .map(|(region, share)| region.area() * (1.0 - share)),
            },
            subdivision: r.subdivision as u32,
            edge_depth: r.depth,
            samples: r.sampled.samples,
            seen_samples: r.sampled.seen,
            density_per_m2: r.sampled.samples as f64 / mirror_area.max(1e-12),
            converged: r.converged,
        });
    }
    (reports, all_region)
}

/// The grid of reflected directions, in degrees (horizontal from a reference direction,
/// elevation), over every eye point's: the ambinocular solid angle's.
struct DirectionGrid<'a> {
    frame: &'a VehicleFrame,
    reference: Vec3,
    lo: Vec2,
    side: f32,
    /// Any direction at all.
    any: bool,
}

impl<'a> DirectionGrid<'a> {
    fn new(frame: &'a VehicleFrame, refined: &[Refined]) -> DirectionGrid<'a> {
        let reference = reference_of(frame, refined.iter().flat_map(|r| &r.sampled.directions));
        let mut grid = DirectionGrid {
            frame,
            reference,
            lo: Vec2::ZERO,
            side: 1.0,
            any: false,
        };
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for d in refined.iter().flat_map(|r| &r.sampled.directions).flatten() {
            let a = grid.angles(*d);
            lo = lo.min(a);
            hi = hi.max(a);
        }
        grid.any = lo.x <= hi.x;
        if !grid.any {
            (lo, hi) = (Vec2::ZERO, Vec2::ONE);
        }
        grid.lo = lo;
        grid.side = (hi - lo).max_element().max(1e-6);
        grid
    }

    fn angles(&self, d: Vec3) -> Vec2 {
        Vec2::new(
            self.frame.horizontal_deg(d, self.reference) as f32,
            self.frame.elevation_deg(d) as f32,
        )
    }

    fn cell_deg(&self) -> f64 {
        if self.any {
            f64::from(self.side) / GRID as f64
        } else {
            0.0
        }
    }

    /// The solid angle the eye points' directions cover together.
    fn union_solid_angle(&self, refined: &[Refined]) -> f64 {
        let mut directions = Raster::new(self.lo, self.lo + Vec2::splat(self.side), GRID, GRID);
        for t in refined.iter().flat_map(|r| &r.sampled.directions) {
            directions.fill(&t.map(|d| self.angles(d)), &|_| true);
        }
        let cell_sr = |row: usize| {
            let elevation = (directions.centre(0, row).y as f64).to_radians();
            elevation.cos()
                * f64::from(directions.cell.x).to_radians()
                * f64::from(directions.cell.y).to_radians()
        };
        (0..directions.rows)
            .map(|row| {
                let covered = directions.covered[row * directions.columns..][..directions.columns]
                    .iter()
                    .filter(|c| **c)
                    .count();
                covered as f64 * cell_sr(row)
            })
            .sum()
    }
}
