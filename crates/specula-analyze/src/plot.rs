//! Plots of an analysis, as PNG (a raster of the figure) and SVG (the same raster embedded,
//! with axes, labels and a legend in vector text). Written by hand on the `image` crate, so that
//! plots cost no plotting library or system font to build; the PNG carries no text, the SVG
//! reads it.

use base64::Engine;
use glam::{Vec2, Vec3};
use image::{Rgb, RgbImage};
use specula_scene::{Camera, Scene};
use specula_trace::optics::reflect;
use specula_trace::reference::{offset_origin, render, surface_point, RenderSettings};
use specula_trace::{Ray, SceneAccel};

use crate::mirror_view::{MirrorView, Region};

/// Eye points' colours, in order (then again).
const PALETTE: [[u8; 3]; 6] = [
    [31, 119, 180],
    [44, 160, 44],
    [148, 103, 189],
    [255, 127, 14],
    [23, 190, 207],
    [140, 86, 75],
];

/// A plot: its raster and the SVG around it.
pub struct Plot {
    pub png: RgbImage,
    pub svg: String,
}

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

/// The ground map, `longest` pixels along its longer side: each eye point's footprint (within
/// range) in its colour, blended where several overlap; the region outlined; its blind part (no
/// eye sees it) in red.
pub fn ground_map(view: &MirrorView, longest: u32) -> Plot {
    let extent = ground_extent(view);
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
    let mut png = png;
    if let Some(r) = region {
        let to_pixel = |p: Vec2| {
            Vec2::new(
                (p.x - extent.min.x) / size.x * width as f32,
                (p.y - extent.min.y) / size.y * height as f32,
            )
        };
        let corners = [
            Vec2::new(r.x0, r.z0),
            Vec2::new(r.x1, r.z0),
            Vec2::new(r.x1, r.z1),
            Vec2::new(r.x0, r.z1),
        ]
        .map(to_pixel);
        for i in 0..4 {
            draw_line(&mut png, corners[i], corners[(i + 1) % 4], Rgb([0, 0, 0]));
        }
    }
    let mut legend: Vec<(String, [u8; 3])> = view
        .report
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
        .collect();
    if region.is_some() {
        legend.push(("blind: the region no eye sees".into(), [214, 39, 40]));
    }
    let title = format!(
        "{}: ground seen in '{}' from above (y = {} m, within {} m)",
        view.report.scene, view.report.mirror, view.report.ground_y, range
    );
    let svg = svg_around(
        &png,
        &title,
        ("x (m)", "z (m)"),
        Some((extent, true)),
        &legend,
    );
    Plot { png, svg }
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
    let title = format!(
        "'{}' from the eye at ({x:.3}, {y:.3}, {z:.3}): the ground's 1 m grid (5 m dark)",
        scene.meshes[mirror].name
    );
    let svg = svg_around(&png, &title, ("", ""), None, &[]);
    Plot { png, svg }
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

pub(crate) fn draw_line(png: &mut RgbImage, a: Vec2, b: Vec2, colour: Rgb<u8>) {
    let steps = (b - a).abs().max_element().ceil().max(1.0) as u32;
    for k in 0..=steps {
        let p = a + (b - a) * (k as f32 / steps as f32);
        let (x, y) = (p.x.round(), p.y.round());
        if x >= 0.0 && y >= 0.0 && (x as u32) < png.width() && (y as u32) < png.height() {
            png.put_pixel(x as u32, y as u32, colour);
        }
    }
}

/// PNG bytes of `png`.
pub fn png_bytes(png: &RgbImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    png.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .expect("a PNG encodes in memory");
    bytes
}

/// `text` safe in HTML and SVG.
pub fn html_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// An SVG page holding `png` with a title, axes with ticks over `extent` (metres) and a legend.
pub(crate) fn svg_around(
    png: &RgbImage,
    title: &str,
    labels: (&str, &str),
    extent: Option<(Extent, bool)>,
    legend: &[(String, [u8; 3])],
) -> String {
    let (w, h) = (png.width() as f32, png.height() as f32);
    let (left, top, bottom) = (60.0, 30.0, 45.0);
    let legend_height = 18.0 * legend.len() as f32;
    let (page_w, page_h) = (w + left + 20.0, h + top + bottom + legend_height);
    let data = base64::engine::general_purpose::STANDARD.encode(png_bytes(png));
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{page_w}\" height=\"{page_h}\" \
         font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" \
         fill=\"white\"/>\n<text x=\"{left}\" y=\"18\" font-size=\"14\">{}</text>\n<image \
         x=\"{left}\" y=\"{top}\" width=\"{w}\" height=\"{h}\" \
         href=\"data:image/png;base64,{data}\"/>\n<rect x=\"{left}\" y=\"{top}\" width=\"{w}\" \
         height=\"{h}\" fill=\"none\" stroke=\"black\"/>\n",
        html_escape(title)
    );
    if let Some((e, y_down)) = extent {
        let size = e.max - e.min;
        for (axis, span, from) in [(0, size.x, e.min.x), (1, size.y, e.min.y)] {
            let step = nice_step(span / 6.0);
            let mut v = (from / step).ceil() * step;
            while v <= from + span {
                let f = (v - from) / span;
                let (x1, y1, x2, y2, tx, ty, anchor) = if axis == 0 {
                    let x = left + f * w;
                    (x, top + h, x, top + h + 5.0, x, top + h + 18.0, "middle")
                } else {
                    let y = if y_down { top + f * h } else { top + h - f * h };
                    (left - 5.0, y, left, y, left - 8.0, y + 4.0, "end")
                };
                svg.push_str(&format!(
                    "<line x1=\"{x1}\" y1=\"{y1}\" x2=\"{x2}\" y2=\"{y2}\" stroke=\"black\"/>\
                     <text x=\"{tx}\" y=\"{ty}\" text-anchor=\"{anchor}\">{}</text>\n",
                    format_tick(v, step)
                ));
                v += step;
            }
        }
        svg.push_str(&format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n<text x=\"14\" y=\"{}\" \
             transform=\"rotate(-90 14 {})\" text-anchor=\"middle\">{}</text>\n",
            left + w * 0.5,
            top + h + 34.0,
            html_escape(labels.0),
            top + h * 0.5,
            top + h * 0.5,
            html_escape(labels.1)
        ));
    }
    for (k, (text, [r, g, b])) in legend.iter().enumerate() {
        let y = top + h + bottom + 18.0 * k as f32;
        svg.push_str(&format!(
            "<rect x=\"{left}\" y=\"{}\" width=\"12\" height=\"12\" fill=\"rgb({r},{g},{b})\"/>\
             <text x=\"{}\" y=\"{}\">{}</text>\n",
            y - 10.0,
            left + 18.0,
            y,
            html_escape(text)
        ));
    }
    svg.push_str("</svg>\n");
    svg
}

/// 1, 2 or 5 times a power of ten, near `raw`.
pub(crate) fn nice_step(raw: f32) -> f32 {
    let power = 10f32.powf(raw.max(1e-6).log10().floor());
    let m = raw / power;
    power
        * if m < 1.5 {
            1.0
        } else if m < 3.5 {
            2.0
        } else if m < 7.5 {
            5.0
        } else {
            10.0
        }
}

fn format_tick(v: f32, step: f32) -> String {
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    format!("{v:.decimals$}")
}

/// A colour from a scale of `t` in [0, 1]: dark blue through teal and green to yellow.
pub fn scale_colour(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    [0, 1, 2].map(|c| (STOPS[i][c] * (1.0 - f) + STOPS[i + 1][c] * f).round() as u8)
}

/// The eye points seen from the front, each a square coloured by how much of its view the glare
/// covers (its solid angle; grey: no glare), with its largest relative luminance written in it
/// (SVG).
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
    let mut png = RgbImage::from_pixel(width, height, Rgb([255, 255, 255]));
    let side = (spacing * scale * 0.9).max(2.0);
    let mut texts = String::new();
    for (e, p) in report.eyes.iter().zip(&at) {
        let centre = Vec2::new((p.x - lo.x) * scale, (hi.y - p.y) * scale);
        let colour = if e.glare {
            scale_colour(e.solid_angle_sr / widest)
        } else {
            [200, 200, 200]
        };
        let (x0, y0) = ((centre - side * 0.5).max(Vec2::ZERO)).into();
        for y in y0 as u32..((y0 + side) as u32).min(height) {
            for x in x0 as u32..((x0 + side) as u32).min(width) {
                png.put_pixel(x, y, Rgb(colour));
            }
        }
        texts.push_str(&format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"10\" fill=\"{}\">{}</text>\n",
            60.0 + centre.x,
            30.0 + centre.y + 4.0,
            if e.glare && e.solid_angle_sr / widest > 0.6 { "black" } else { "white" },
            if e.glare {
                format!("{:.4}", e.max_relative_luminance)
            } else {
                "none".into()
            }
        ));
    }
    let title = format!(
        "'{}' in '{}' per eye point (seen from behind the driver): the glare's solid angle (colour) and largest relative luminance",
        report.source, report.surface
    );
    let legend = vec![
        ("no glare".to_string(), [200, 200, 200]),
        (
            format!("the widest glare, {widest:.3e} sr"),
            scale_colour(1.0),
        ),
        ("a tenth of it".to_string(), scale_colour(0.1)),
    ];
    let extent = Extent { min: lo, max: hi };
    let mut svg = svg_around(
        &png,
        &title,
        ("right of the eye (m)", "up (m)"),
        Some((extent, false)),
        &legend,
    );
    svg.insert_str(svg.len() - "</svg>\n".len(), &texts);
    Plot { png, svg }
}

/// Eye point `k`'s image as the reference renders it, its glare pixels outlined in magenta.
pub fn glare_image(glare: &crate::glare::Glare, k: usize) -> Plot {
    let (width, height) = (glare.report.width, glare.report.height);
    let images = &glare.images[k];
    let mut image = specula_trace::Image::new(width, height);
    image.pixels.clone_from(&images.radiance);
    let mut png = image.to_srgb8();
    let threshold = glare.report.threshold;
    let lit = |x: u32, y: u32| images.relative[(y * width + x) as usize] > threshold;
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
                png.put_pixel(x, y, Rgb([255, 0, 255]));
            }
        }
    }
    let [x, y, z] = glare.report.eyes[k].position;
    let title = format!(
        "eye {} ({x:.3}, {y:.3}, {z:.3}): glare of '{}' in '{}' outlined",
        k + 1,
        glare.report.source,
        glare.report.surface
    );
    let svg = svg_around(&png, &title, ("", ""), None, &[]);
    Plot { png, svg }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round() {
        assert_eq!(nice_step(0.9), 1.0);
        assert_eq!(nice_step(23.0), 20.0);
        assert!((nice_step(0.04) - 0.05).abs() < 1e-7);
        assert_eq!(format_tick(2.5, 0.5), "2.5");
        assert_eq!(format_tick(20.0, 10.0), "20");
    }
}
