//! The mirror-view and glare plots: the ground map, the mirror from an eye point, the eye
//! points' glare and the worst eye point's view. Each is a [`Figure`]: its raster, with axes,
//! marks, colour bar and legend drawn by `plotters`.

use glam::{Vec2, Vec3};
use image::{Rgb, RgbImage};
use specula_scene::{Camera, Scene};
use specula_trace::optics::reflect;
use specula_trace::reference::{offset_origin, render, surface_point, RenderSettings};
use specula_trace::{Ray, SceneAccel};

pub use crate::figure::{png_bytes, scale_colour, Plot};
use crate::figure::{Axis, ColourBar, Figure, Mark};
use crate::mirror_view::{MirrorView, Region};
use crate::outcome::Outcome;

/// Eye points' colours, in order (then again): no green or red, which are the verdicts'.
const PALETTE: [[u8; 3]; 6] = [
    [31, 119, 180],
    [227, 119, 194],
    [148, 103, 189],
    [255, 127, 14],
    [23, 190, 207],
    [140, 86, 75],
];

/// Axis-aligned extent of a map, metres.
#[derive(Clone, Copy, Debug)]
pub struct Extent {
    pub min: Vec2,
    pub max: Vec2,
}

impl Extent {
    pub(crate) fn grow(self, by: f32) -> Extent {
        let pad = (self.max - self.min) * by;
        Extent {
            min: self.min - pad,
            max: self.max + pad,
        }
    }
}

/// What the ground map shows: around the region when there is one (its surroundings by half
/// its size), else the footprints within range.
pub fn ground_extent(view: &MirrorView) -> Extent {
    if let Some(region) = view.report.region {
        return Extent {
            min: Vec2::new(region.x0, region.z0),
            max: Vec2::new(region.x1, region.z1),
        }
        .grow(0.25);
    }
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
    if min.x >= max.x || min.y >= max.y {
        return Extent {
            min: Vec2::ZERO,
            max: Vec2::ONE,
        };
    }
    Extent { min, max }.grow(0.05)
}

/// A regulation's fields on the ground, for the ground map: each one's corners (x, z), its
/// verdict and the legend's words for it.
pub struct RegulationFields {
    pub fields: Vec<([Vec2; 4], Outcome, String)>,
}

impl RegulationFields {
    pub fn of(
        verdict: &crate::regulation::Verdict,
        regulation: &crate::regulation::Regulation,
        vehicle: &crate::regulation::Vehicle,
        range_m: f32,
    ) -> Result<RegulationFields, crate::AnalyzeError> {
        let mut fields = Vec::new();
        for (spec, f) in regulation.fields.iter().zip(&verdict.fields) {
            let g = &f.figures;
            let words = match g.verdict {
                Outcome::Pass => format!(
                    "{}: PASS, reaches {:.2} m farther",
                    f.name,
                    g.outer_margin_m.min(g.near_margin_m)
                ),
                outcome => format!(
                    "{}: {}, {:.2} % of it unseen",
                    f.name,
                    outcome.word(),
                    (1.0 - g.seen_share) * 100.0
                ),
            };
            fields.push((vehicle.field_corners(spec, range_m)?, g.verdict, words));
        }
        Ok(RegulationFields { fields })
    }
}

/// A verdict's colour on a plot.
pub fn outcome_colour(outcome: Outcome) -> [u8; 3] {
    match outcome {
        Outcome::Pass => [46, 125, 50],
        Outcome::Fail => [198, 40, 40],
        Outcome::Undecided => [183, 121, 31],
    }
}

/// The ground map's extent: the footprints' (or the region's) and the fields', no narrower than
/// 1 : 1.6 either way so that the legend below it has room.
fn map_extent(view: &MirrorView, fields: Option<&RegulationFields>) -> Extent {
    let mut extent = ground_extent(view);
    for (corners, ..) in fields.iter().flat_map(|f| &f.fields) {
        for c in corners {
            extent.min = extent.min.min(*c);
            extent.max = extent.max.max(*c);
        }
    }
    let size = extent.max - extent.min;
    let pad = Vec2::new(
        (size.y / 1.6 - size.x).max(0.0),
        (size.x / 1.6 - size.y).max(0.0),
    ) * 0.5;
    Extent {
        min: extent.min - pad,
        max: extent.max + pad,
    }
}

/// The eye points' legend: a colour each, or with many of them the count map's colours.
fn eyes_legend(view: &MirrorView) -> Vec<(String, [u8; 3])> {
    let n = view.footprints.len();
    if n > EYES_IN_COLOUR {
        return [1, n.div_ceil(2), n]
            .iter()
            .map(|&k| {
                let c = colorous::VIRIDIS.eval_rational(k, n);
                (format!("seen by {k} of {n} eye points"), [c.r, c.g, c.b])
            })
            .collect();
    }
    view.report
        .eyes
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let [x, y, z] = e.position;
            (
                format!("eye {} ({x:.3}, {y:.3}, {z:.3})", k + 1),
                PALETTE[k % PALETTE.len()],
            )
        })
        .collect()
}

/// More eye points than this are drawn as a count map (how many see each point) rather than
/// in a colour each.
const EYES_IN_COLOUR: usize = PALETTE.len();

/// The ground map, `longest` pixels along its longer side: each eye point's footprint (within
/// range) in its colour, blended where several overlap (with more eye points than the palette
/// has colours, how many eye points see each point); the region outlined; its blind part (no
/// eye sees it) in red; a regulation's fields outlined in their verdicts' colours.
pub fn ground_map(view: &MirrorView, fields: Option<&RegulationFields>, longest: u32) -> Plot {
    let extent = map_extent(view, fields);
    let size = extent.max - extent.min;
    let scale = longest as f32 / size.max_element();
    let width = ((size.x * scale).round() as u32).max(16);
    let height = ((size.y * scale).round() as u32).max(16);
    let to_ground = |x: u32, y: u32| {
        // Seen from above with x to the right (+Y up, right-handed), +z runs down the page.
        Vec2::new(
            extent.min.x + size.x * (x as f32 + 0.5) / width as f32,
            extent.min.y + size.y * (y as f32 + 0.5) / height as f32,
        )
    };
    let range = view.report.range_m;
    // Per eye, which pixels its footprint covers.
    let covered: Vec<Vec<bool>> = view
        .footprints
        .iter()
        .enumerate()
        .map(|(k, footprint)| {
            let [x, _, z] = view.report.eyes[k].position;
            let eye = Vec2::new(x, z);
            let mut mask = vec![false; (width * height) as usize];
            for t in footprint {
                fill_triangle(t, width, height, &extent, &mut mask, &|p| {
                    p.distance(eye) <= range
                });
            }
            mask
        })
        .collect();
    let region = view.report.region;
    let inside = |p: Vec2, r: &Region| p.x >= r.x0 && p.x <= r.x1 && p.y >= r.z0 && p.y <= r.z1;
    let png = RgbImage::from_fn(width, height, |x, y| {
        let i = (y * width + x) as usize;
        let p = to_ground(x, y);
        let eyes: Vec<usize> = (0..covered.len()).filter(|k| covered[*k][i]).collect();
        if eyes.is_empty() {
            return match region {
                Some(r) if inside(p, &r) => Rgb([214, 39, 40]),
                _ => Rgb([235, 235, 235]),
            };
        }
        if covered.len() > EYES_IN_COLOUR {
            let c = colorous::VIRIDIS.eval_rational(eyes.len(), covered.len());
            return Rgb([c.r, c.g, c.b]);
        }
        let mut sum = [0u32; 3];
        for k in &eyes {
            for (c, v) in sum.iter_mut().zip(PALETTE[k % PALETTE.len()]) {
                *c += u32::from(v);
            }
        }
        // Lighter outside the region, full colour inside it.
        let light = region.is_some_and(|r| !inside(p, &r));
        Rgb(sum.map(|c| {
            let c = c / eyes.len() as u32;
            if light {
                ((c + 2 * 255) / 3) as u8
            } else {
                c as u8
            }
        }))
    });
    let mut figure = Figure::new(String::new(), png);
    if let Some(r) = region {
        let (x0, x1, z0, z1) = (r.x0.into(), r.x1.into(), r.z0.into(), r.z1.into());
        figure.marks.push(Mark::Line {
            points: vec![(x0, z0), (x1, z0), (x1, z1), (x0, z1), (x0, z0)],
            colour: [0, 0, 0],
            width: 2,
        });
    }
    let mut legend = eyes_legend(view);
    for (corners, outcome, words) in fields.iter().flat_map(|f| &f.fields) {
        let mut points: Vec<(f64, f64)> = corners
            .iter()
            .map(|c| (f64::from(c.x), f64::from(c.y)))
            .collect();
        points.push(points[0]);
        figure.marks.push(Mark::Line {
            points,
            colour: outcome_colour(*outcome),
            width: 3,
        });
        legend.push((words.clone(), outcome_colour(*outcome)));
    }
    if region.is_some() {
        legend.push((
            "the required region (outlined): blind, no eye sees it".into(),
            [214, 39, 40],
        ));
    }
    figure.title = format!(
        "{}: ground seen in '{}' from above (y = {} m, within {} m)",
        view.report.scene, view.report.mirror, view.report.ground_y, range
    );
    // Seen from above, +z runs down the page.
    figure.axes = Some((
        Axis::new("x (m)", (extent.min.x.into(), extent.max.x.into())),
        Axis::new("z (m)", (extent.max.y.into(), extent.min.y.into())),
    ));
    figure.legend = legend;
    figure.plot()
}

/// The mirror seen from eye point `eye`, as the reference renders it, with the ground's
/// 1 m grid (5 m lines darker) drawn where the mirror shows the ground.
pub fn mirror_from_eye(
    scene: &Scene,
    accel: &SceneAccel,
    mirror: usize,
    eye: Vec3,
    ground_y: f32,
    width: u32,
) -> Plot {
    let height = (width * 3 / 4).max(1);
    // An eye at the mirror's very centre looks along −z: it has no direction to the mirror.
    let camera = crate::glare::eye_camera(scene, mirror, eye, width, height).unwrap_or(Camera {
        eye,
        target: eye + Vec3::NEG_Z,
        up: Vec3::Y,
        fov_y_deg: 90.0,
        aspect: None,
    });
    let mut view_scene = scene.clone();
    view_scene.camera = camera.clone();
    let settings = RenderSettings {
        width,
        height,
        spp: 1,
        max_depth: 8,
    };
    let image = render(&view_scene, accel, &settings, &|_, _| {});
    let mut png = image.to_srgb8();
    // Where each pixel's ray, reflected in the mirror, meets the ground (x, z).
    let ground: Vec<Option<Vec2>> = (0..width * height)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let dir = camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
            let ray = Ray { origin: eye, dir };
            let hit = crate::mirror_view::first_opaque_hit(scene, accel, &ray, f32::INFINITY)?;
            if hit.mesh as usize != mirror {
                return None;
            }
            let sp = surface_point(scene, &ray, &hit);
            let r = reflect(dir, sp.ns).normalize();
            let origin = offset_origin(sp.p, sp.ng, r);
            crate::mirror_view::ground_seen(scene, accel, origin, r, ground_y)
        })
        .collect();
    let cell = |g: Vec2, spacing: f32| (g / spacing).floor();
    for y in 0..height.saturating_sub(1) {
        for x in 0..width.saturating_sub(1) {
            let i = (y * width + x) as usize;
            let Some(g) = ground[i] else { continue };
            for (spacing, colour) in [(5.0, [20, 20, 20]), (1.0, [250, 250, 250])] {
                let crosses = [ground[i + 1], ground[i + width as usize]]
                    .iter()
                    .flatten()
                    .any(|n| cell(*n, spacing) != cell(g, spacing));
                if crosses {
                    png.put_pixel(x, y, Rgb(colour));
                    break;
                }
            }
        }
    }
    let [x, y, z] = eye.to_array();
    let mut figure = Figure::new(
        format!(
            "'{}' from the eye at ({x:.3}, {y:.3}, {z:.3}), with the ground's grid where it \
             shows the ground",
            scene.meshes[mirror].name
        ),
        png,
    );
    figure.legend = vec![
        ("the ground's grid, every 1 m".into(), [250, 250, 250]),
        ("every 5 m".into(), [20, 20, 20]),
    ];
    figure.plot()
}

/// Marks the pixels of a `width` × `height` map over `extent` whose centres lie in `t` (ground
/// x, z) and pass `keep`.
fn fill_triangle(
    t: &[Vec2; 3],
    width: u32,
    height: u32,
    extent: &Extent,
    mask: &mut [bool],
    keep: &impl Fn(Vec2) -> bool,
) {
    let size = extent.max - extent.min;
    let to_pixel = |p: Vec2| {
        Vec2::new(
            (p.x - extent.min.x) / size.x * width as f32,
            (p.y - extent.min.y) / size.y * height as f32,
        )
    };
    let [a, b, c] = t.map(to_pixel);
    let lo = a.min(b).min(c).floor().max(Vec2::ZERO);
    let hi = a
        .max(b)
        .max(c)
        .ceil()
        .min(Vec2::new(width as f32, height as f32));
    let edge = |p: Vec2, q: Vec2, s: Vec2| (q - p).perp_dot(s - p);
    let area = edge(a, b, c);
    if area == 0.0 || !area.is_finite() || lo.x >= hi.x || lo.y >= hi.y {
        return;
    }
    for y in lo.y as u32..hi.y as u32 {
        for x in lo.x as u32..hi.x as u32 {
            let s = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let inside = [edge(b, c, s), edge(c, a, s), edge(a, b, s)]
                .iter()
                .all(|w| w * area >= 0.0);
            if inside {
                let g = Vec2::new(
                    extent.min.x + size.x * s.x / width as f32,
                    extent.min.y + size.y * s.y / height as f32,
                );
                if keep(g) {
                    mask[(y * width + x) as usize] = true;
                }
            }
        }
    }
}

/// `text` safe in HTML and SVG.
pub fn html_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The eye points seen from behind the driver, each a square coloured by how much of its view
/// the glare covers (its solid angle, on the colour bar; grey: no glare), with its largest
/// luminance factor written in it.
pub fn glare_eyebox(report: &crate::glare::Report, frame: &crate::frame::VehicleFrame) -> Plot {
    let eyes: Vec<Vec3> = report
        .eyes
        .iter()
        .map(|e| Vec3::from_array(e.position))
        .collect();
    let mean = eyes.iter().copied().sum::<Vec3>() / eyes.len() as f32;
    let at: Vec<Vec2> = eyes
        .iter()
        .map(|e| Vec2::new((*e - mean).dot(frame.right), (*e - mean).dot(frame.up)))
        .collect();
    // The smallest spacing between eye points sets the squares' size.
    let mut spacing = f32::INFINITY;
    for (i, a) in at.iter().enumerate() {
        for b in &at[i + 1..] {
            let d = (*a - *b).abs().max_element();
            if d > 1e-6 {
                spacing = spacing.min(d);
            }
        }
    }
    if !spacing.is_finite() {
        spacing = 0.05;
    }
    let lo = at.iter().fold(Vec2::splat(f32::INFINITY), |m, p| m.min(*p)) - spacing * 0.5;
    let hi = at
        .iter()
        .fold(Vec2::splat(f32::NEG_INFINITY), |m, p| m.max(*p))
        + spacing * 0.5;
    let scale = 480.0 / (hi - lo).max_element();
    let (width, height) = (
        (((hi - lo).x * scale).round() as u32).max(8),
        (((hi - lo).y * scale).round() as u32).max(8),
    );
    let widest = report
        .eyes
        .iter()
        .map(|e| e.solid_angle_sr)
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let bar = ColourBar {
        label: "the glare's solid angle seen from the eye point (sr)".into(),
        range: (0.0, widest),
        log: false,
    };
    let mut figure = Figure::new(
        format!(
            "'{}' in '{}' per eye point (seen from behind the driver): the glare's solid angle \
             (colour) and largest luminance factor (figure)",
            report.source, report.surface
        ),
        RgbImage::from_pixel(width, height, Rgb([255, 255, 255])),
    );
    let half = f64::from(spacing) * 0.45;
    for (e, p) in report.eyes.iter().zip(&at) {
        let (x, y) = (f64::from(p.x), f64::from(p.y));
        let colour = if e.glare {
            bar.colour(e.solid_angle_sr)
        } else {
            NO_GLARE
        };
        figure.marks.push(Mark::Box {
            corners: [(x - half, y - half), (x + half, y + half)],
            colour,
        });
        figure.marks.push(Mark::Text {
            at: (x, y),
            text: if e.glare {
                format!("{:.4}", e.max_luminance_factor)
            } else {
                "none".into()
            },
            colour: [0, 0, 0],
            halo: [255, 255, 255],
        });
    }
    figure.axes = Some((
        Axis::new("right of the eye (m)", (lo.x.into(), hi.x.into())),
        Axis::new("up (m)", (lo.y.into(), hi.y.into())),
    ));
    figure.colour_bar = Some(bar);
    figure.legend = vec![("no glare".to_string(), NO_GLARE)];
    figure.plot()
}

const NO_GLARE: [u8; 3] = [200, 200, 200];
const GLARE_OUTLINE: [u8; 3] = [255, 0, 255];

/// Eye point `k`'s image as the reference renders it, its glare pixels outlined in magenta.
pub fn glare_image(glare: &crate::glare::Glare, k: usize) -> Plot {
    let (width, height) = (glare.report.width, glare.report.height);
    let images = &glare.images[k];
    let mut image = specula_trace::Image::new(width, height);
    image.pixels.clone_from(&images.radiance);
    let mut png = image.to_srgb8();
    let threshold = glare.report.threshold;
    let lit = |x: u32, y: u32| images.factor[(y * width + x) as usize] > threshold;
    for y in 0..height {
        for x in 0..width {
            if !lit(x, y) {
                continue;
            }
            let edge = x == 0
                || y == 0
                || x + 1 == width
                || y + 1 == height
                || !lit(x - 1, y)
                || !lit(x + 1, y)
                || !lit(x, y - 1)
                || !lit(x, y + 1);
            if edge {
                png.put_pixel(x, y, Rgb(GLARE_OUTLINE));
            }
        }
    }
    let [x, y, z] = glare.report.eyes[k].position;
    let mut figure = Figure::new(
        format!(
            "eye {} ({x:.3}, {y:.3}, {z:.3}): the glare of '{}' in '{}'",
            k + 1,
            glare.report.source,
            glare.report.surface
        ),
        png,
    );
    figure.legend = vec![(
        format!("where the luminance factor exceeds {threshold} (outline)"),
        GLARE_OUTLINE,
    )];
    figure.plot()
}
