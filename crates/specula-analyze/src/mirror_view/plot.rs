//! The mirror-view plots: the ground map (with a regulation's fields) and the mirror seen from
//! an eye point. Each is a [`Figure`]: its raster, with axes, marks, colour bar and legend drawn
//! by `plotters`.

use glam::{Vec2, Vec3};
use image::{Rgb, RgbImage};
use specula_scene::{Camera, Scene};
use specula_trace::optics::reflect;
use specula_trace::reference::{offset_origin, render, surface_point, RenderSettings};
use specula_trace::{Ray, SceneAccel};

use super::{MirrorView, Region};
use crate::figure::Plot;
use crate::figure::{Axis, Figure, Mark};
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
