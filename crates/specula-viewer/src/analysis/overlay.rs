//! The analysis's overlay over the view and the camera that shows its result whole.
//! - Mirror view: where the ray reaches the ground plane with nothing nearer (1 mm of slack,
//!   as the analysis), the ground point's cell in a grid of how many eye points see it: cyan
//!   where some eye sees it (stronger where every one does); inside the required region or a
//!   regulation's fields, green where an eye sees it and red where none does (its blind part).
//! - Glare: where the first hit is the surface, that point as the chosen eye point sees it
//!   (projected into its glare image): where the glare's luminance factor is above the
//!   threshold, its luminance on a log scale from 1 cd/m² (dark blue) to 10⁹ cd/m² (yellow)
//!   (the factor's log from the threshold to 1 where no luminance is known); display pixels the
//!   glare washes out in red.
//! - Lens: where the first hit is the lens, the gaze through that point and the lens map's
//!   mean power or cylinder there, in false colour with contour lines ([`lens_overlay`]).
//!
//! An analysis the viewer draws nothing for has no overlay (its figures are in the panel).

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use specula_analyze::glare::analysis::GlareResult;
use specula_analyze::lens;
use specula_analyze::mirror_view::analysis::MirrorViewResult;
use specula_analyze::mirror_view::{MirrorView, Region};
use specula_methods::LiveScene;
use specula_scene::Camera;
use specula_trace::{Ray, SceneAccel};

use super::Analysis;

/// Cells along the longer side of the ground grid the mirror view's overlay reads.
const GROUND_GRID: usize = 1024;

/// How many eye points see each cell of the ground around the footprints.
pub struct GroundGrid {
    pub min: Vec2,
    pub max: Vec2,
    pub columns: usize,
    pub rows: usize,
    pub counts: Vec<u16>,
}

impl GroundGrid {
    /// How many eye points see ground point `p` (x, z); 0 outside the grid.
    pub fn count(&self, p: Vec2) -> u16 {
        let cell = (p - self.min) / (self.max - self.min)
            * Vec2::new(self.columns as f32, self.rows as f32);
        if !(cell.x >= 0.0 && cell.y >= 0.0) {
            return 0;
        }
        let (column, row) = (cell.x as usize, cell.y as usize);
        if column >= self.columns || row >= self.rows {
            return 0;
        }
        self.counts[row * self.columns + column]
    }
}

impl Analysis {
    /// A camera that shows the analysis's result whole: for a mirror view the regulation's
    /// fields or the required region (else the ground seen) from above, 60° down, from the
    /// eyes' side; for glare the shown eye point's own camera (the overlay is then exactly its
    /// glare image); for a lens the eye's, along the primary gaze.
    pub fn overview(&self, fov_y_deg: f32) -> Option<Camera> {
        let outcome = self.shown.as_ref()?;
        let report = &outcome.report;
        if let Some(m) = report.result::<MirrorViewResult>() {
            let view = &m.view.report;
            let ground = outcome.ground.as_ref()?;
            let (min, max) = match (outcome.fields.is_empty(), view.region) {
                (false, _) => outcome.fields.iter().flatten().fold(
                    (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
                    |(lo, hi), p| (lo.min(*p), hi.max(*p)),
                ),
                (true, Some(r)) => (Vec2::new(r.x0, r.z0), Vec2::new(r.x1, r.z1)),
                (true, None) => (ground.min, ground.max),
            };
            let centre = (min + max) * 0.5;
            let target = Vec3::new(centre.x, view.ground_y, centre.y);
            let eyes = outcome.eyes();
            let middle = eyes.iter().copied().sum::<Vec3>() / eyes.len().max(1) as f32;
            let towards_eye = Vec2::new(middle.x, middle.z) - centre;
            let side = towards_eye.try_normalize().unwrap_or(Vec2::Y);
            let distance = 0.6 * (max - min).length() / (fov_y_deg.to_radians() * 0.5).tan();
            let dir = Vec3::new(side.x * 0.5, 0.866, side.y * 0.5);
            return Some(Camera {
                eye: target + dir * distance,
                target,
                up: Vec3::Y,
                fov_y_deg,
                aspect: None,
            });
        }
        if let Some(g) = report.result::<GlareResult>() {
            let k = self.glare_eye().min(g.glare.images.len() - 1);
            return Some(g.glare.images[k].camera.clone());
        }
        let lens = report.result::<lens::Report>()?;
        let centre = Vec3::from_array(lens.rotation_centre.map(|c| c as f32));
        let forward = Vec3::from_array(lens.forward.map(|c| c as f32));
        Some(Camera {
            eye: centre,
            target: centre + forward,
            up: Vec3::from_array(lens.up.map(|c| c as f32)),
            fov_y_deg: 70.0,
            aspect: None,
        })
    }

    /// The overlay for `camera`'s view at `width` × `height` of `live` (see the module's doc);
    /// None where nothing is shown yet or the analysis draws nothing.
    pub fn overlay(
        &self,
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Option<Overlay> {
        let outcome = self.shown.as_ref()?;
        let report = &outcome.report;
        let accel = live.accel();
        if let Some(lens) = report.result::<lens::Report>() {
            let mesh = live
                .scene()
                .meshes
                .iter()
                .position(|m| m.name == lens.lens)?;
            return Some(lens_overlay(
                accel,
                camera,
                (width, height),
                mesh,
                lens,
                self.lens_map,
            ));
        }
        let glare_eye = self.glare_eye();
        let mirror = report.result::<MirrorViewResult>();
        let glare = report.result::<GlareResult>();
        if mirror.is_none() && glare.is_none() {
            return None;
        }
        let colour_of = |ray: &Ray| -> [u8; 4] {
            if let (Some(m), Some(ground)) = (mirror, outcome.ground.as_ref()) {
                return ground_colour(
                    accel,
                    ray,
                    m.view.report.ground_y,
                    m.view.report.region,
                    &outcome.fields,
                    ground,
                    outcome.eyes().len(),
                );
            }
            match glare {
                Some(g) => glare_colour(
                    accel,
                    ray,
                    g.surface,
                    &g.glare.images[glare_eye.min(g.glare.images.len() - 1)],
                    g.glare.report.width,
                    g.glare.report.height,
                    g.glare.report.threshold,
                ),
                None => CLEAR,
            }
        };
        let pixels = (0..width * height)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % width, i / width);
                let dir = camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
                colour_of(&Ray {
                    origin: camera.eye,
                    dir,
                })
            })
            .collect();
        Some(Overlay {
            width,
            height,
            pixels,
        })
    }
}

/// An image to draw over the view: sRGB colours with straight (not premultiplied) alpha.
pub struct Overlay {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[u8; 4]>,
}

pub(super) const CLEAR: [u8; 4] = [0, 0, 0, 0];

/// What the mirror view's overlay draws where `ray` meets the ground (see the module's doc).
fn ground_colour(
    accel: &SceneAccel,
    ray: &Ray,
    ground_y: f32,
    region: Option<Region>,
    fields: &[[Vec2; 4]],
    ground: &GroundGrid,
    eyes: usize,
) -> [u8; 4] {
    if ray.dir.y == 0.0 {
        return CLEAR;
    }
    let t = (ground_y - ray.origin.y) / ray.dir.y;
    if !(t > 0.0 && t.is_finite()) {
        return CLEAR;
    }
    if let Some(hit) = accel.intersect(ray, f32::INFINITY) {
        if hit.t < t - 1e-3f32.max(1e-4 * t) {
            return CLEAR;
        }
    }
    let p = ray.origin + ray.dir * t;
    let p = Vec2::new(p.x, p.z);
    let seen = ground.count(p);
    let in_field = |q: &[Vec2; 4]| {
        let sides = (0..4).map(|k| (q[(k + 1) % 4] - q[k]).perp_dot(p - q[k]));
        let signs: Vec<f32> = sides.collect();
        signs.iter().all(|s| *s >= 0.0) || signs.iter().all(|s| *s <= 0.0)
    };
    let in_region = region
        .is_some_and(|r| p.x >= r.x0 && p.x <= r.x1 && p.y >= r.z0 && p.y <= r.z1)
        || fields.iter().any(in_field);
    match (in_region, seen) {
        (true, 0) => with_alpha(BLIND, 150),
        (true, n) if usize::from(n) == eyes => with_alpha(REGION_SEEN, 130),
        (true, _) => with_alpha(REGION_SEEN, 80),
        (false, 0) => CLEAR,
        (false, n) if usize::from(n) == eyes => with_alpha(SEEN, 120),
        (false, _) => with_alpha(SEEN, 70),
    }
}

/// Where `camera` sees `p`, in pixels of a `width` × `height` image (None behind it).
pub fn project(camera: &Camera, p: Vec3, width: u32, height: u32) -> Option<Vec2> {
    let frame = camera.frame();
    let d = p - camera.eye;
    let depth = d.dot(frame.forward);
    if depth <= 0.0 {
        return None;
    }
    let tan_half = (camera.fov_y_deg.to_radians() * 0.5).tan();
    let aspect = width as f32 / height as f32;
    let ndc_x = d.dot(frame.right) / depth / (tan_half * aspect);
    let ndc_y = d.dot(frame.up) / depth / tan_half;
    Some(Vec2::new(
        (ndc_x + 1.0) * 0.5 * width as f32,
        (1.0 - ndc_y) * 0.5 * height as f32,
    ))
}

/// What the glare overlay draws where `ray` first hits the surface (see the module's doc).
fn glare_colour(
    accel: &SceneAccel,
    ray: &Ray,
    surface: usize,
    eye: &specula_analyze::glare::EyeImages,
    width: u32,
    height: u32,
    threshold: f64,
) -> [u8; 4] {
    let Some(hit) = accel.intersect(ray, f32::INFINITY) else {
        return CLEAR;
    };
    if hit.mesh as usize != surface {
        return CLEAR;
    }
    let p = ray.origin + ray.dir * hit.t;
    let Some(pixel) = project(&eye.camera, p, width, height) else {
        return CLEAR;
    };
    if !(pixel.x >= 0.0 && pixel.y >= 0.0) {
        return CLEAR;
    }
    let (x, y) = (pixel.x as u32, pixel.y as u32);
    if x >= width || y >= height {
        return CLEAR;
    }
    let i = (y * width + x) as usize;
    if eye.washed_out[i] {
        return WASHED_OUT;
    }
    let factor = eye.factor[i];
    if factor <= threshold {
        return CLEAR;
    }
    // In cd/m² where the source's luminance is known (1 to 10⁹ cd/m², log scale), else the
    // luminance factor's log from the threshold to 1.
    let t = if eye.glare_cd_m2[i] > 0.0 {
        eye.glare_cd_m2[i].log10() / 9.0
    } else {
        (factor.log10() - threshold.log10()) / -threshold.log10()
    };
    let [r, g, b] = specula_analyze::figure::scale_colour(t.clamp(0.0, 1.0));
    [r, g, b, 190]
}

/// Display pixels washed out by the glare.
pub(super) const WASHED_OUT: [u8; 4] = with_alpha(WASHED_OUT_RGB, 220);

/// The overlay's colours, which the panel's legend shows at full opacity: ground seen in the
/// mirror, a required region's or a field's seen and blind parts, washed-out display pixels.
pub const SEEN: [u8; 3] = [23, 190, 207];
pub const REGION_SEEN: [u8; 3] = [44, 190, 44];
pub const BLIND: [u8; 3] = [214, 39, 40];
pub const WASHED_OUT_RGB: [u8; 3] = [230, 20, 60];

const fn with_alpha([r, g, b]: [u8; 3], a: u8) -> [u8; 4] {
    [r, g, b, a]
}

/// What the lens overlay maps (the two: the wearer's mean power or cylinder).
pub type LensMap = specula_analyze::lens::plot::Map;

/// The lens overlay: per view pixel whose first hit is the lens, the gaze through that point
/// (its direction from the centre of rotation, on the gaze's tangent screen) and the map's
/// value there, interpolated over the grid, in false colour from the map's least (dark blue)
/// to its largest (yellow) value, with a dark line where the value crosses a contour level
/// between neighbouring pixels. The direction from the centre of rotation is the chief ray's
/// exactly at the eye-side surface; seen from the front, a point is mapped as if it were there.
fn lens_overlay(
    accel: &SceneAccel,
    camera: &Camera,
    (width, height): (u32, u32),
    lens_mesh: usize,
    report: &lens::Report,
    map: LensMap,
) -> Overlay {
    let values: Vec<Option<f64>> = report.grid.iter().map(|c| map.value(c)).collect();
    let (lo, hi) = values
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    let (lo, hi) = if lo.is_finite() && hi - lo > 1e-9 {
        (lo, hi)
    } else {
        (lo - 0.5, lo + 0.5)
    };
    let step = specula_analyze::lens::plot::map_interval(report, map, lo, hi);
    let centre = glam::DVec3::from_array(report.rotation_centre);
    let forward = glam::DVec3::from_array(report.forward);
    let up = glam::DVec3::from_array(report.up);
    let right = forward.cross(up).normalize();
    let field: Vec<Option<f64>> = (0..width * height)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let dir = camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
            let ray = Ray {
                origin: camera.eye,
                dir,
            };
            let hit = accel.intersect(&ray, f32::INFINITY)?;
            if hit.mesh as usize != lens_mesh {
                return None;
            }
            let d = (ray.origin + ray.dir * hit.t).as_dvec3() - centre;
            let along = d.dot(forward);
            if along <= 0.0 {
                return None;
            }
            let h = (d.dot(right) / along).atan().to_degrees();
            let v = (d.dot(up) / along).atan().to_degrees();
            specula_analyze::lens::plot::value_at(report, &values, h, v)
        })
        .collect();
    let band = |v: f64| (v / step).floor();
    let pixels = (0..width * height)
        .map(|i| {
            let Some(value) = field[i as usize] else {
                return CLEAR;
            };
            let (x, y) = (i % width, i / width);
            let neighbour = |dx: u32, dy: u32| {
                (x + dx < width && y + dy < height)
                    .then(|| field[((y + dy) * width + x + dx) as usize])
                    .flatten()
            };
            let on_line = [neighbour(1, 0), neighbour(0, 1)]
                .into_iter()
                .flatten()
                .any(|n| band(n) != band(value));
            if on_line {
                return [20, 20, 20, 230];
            }
            let [r, g, b] = specula_analyze::figure::scale_colour((value - lo) / (hi - lo));
            [r, g, b, 170]
        })
        .collect();
    Overlay {
        width,
        height,
        pixels,
    }
}

/// The ground grid over the footprints within range and the region.
pub(super) fn ground_grid(view: &MirrorView) -> GroundGrid {
    let range = view.report.range_m;
    let (mut min, mut max) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for (k, footprint) in view.footprints.iter().enumerate() {
        let [x, _, z] = view.report.eyes[k].position;
        let eye = Vec2::new(x, z);
        for p in footprint.iter().flatten() {
            let p = eye + (*p - eye).clamp_length_max(range);
            min = min.min(p);
            max = max.max(p);
        }
    }
    if let Some(r) = view.report.region {
        min = min.min(Vec2::new(r.x0, r.z0));
        max = max.max(Vec2::new(r.x1, r.z1));
    }
    if !(min.x < max.x && min.y < max.y) {
        return GroundGrid {
            min: Vec2::ZERO,
            max: Vec2::ONE,
            columns: 1,
            rows: 1,
            counts: vec![0],
        };
    }
    let size = max - min;
    let cell = size.max_element() / GROUND_GRID as f32;
    let columns = ((size.x / cell).ceil() as usize).clamp(1, GROUND_GRID);
    let rows = ((size.y / cell).ceil() as usize).clamp(1, GROUND_GRID);
    let max = min + Vec2::new(columns as f32, rows as f32) * cell;
    GroundGrid {
        counts: view.seen_counts(min, max, columns, rows),
        min,
        max,
        columns,
        rows,
    }
}
