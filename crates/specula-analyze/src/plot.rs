//! Plots of an analysis, as PNG and SVG: the figure's raster with its title, axes, ticks and
//! legend, drawn into the PNG with an 8 × 8 bitmap font compiled in (`font8x8`) and written as
//! vector text around the same raster in the SVG. Drawn by hand on the `image` crate, so that
//! plots cost no plotting library or system font to build.

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

/// A plot: its raster with its text (the PNG) and the SVG around the bare raster.
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
    plot_around(
        png,
        &title,
        ("x (m)", "z (m)"),
        Some((extent, true)),
        &legend,
    )
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
    plot_around(png, &title, ("", ""), None, &[])
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

/// The 8 × 8 glyph of `c` (rows top down, bit k = column k); a few typographic characters the
/// font lacks stand in for their ASCII look-alikes.
fn glyph(c: char) -> Option<[u8; 8]> {
    use font8x8::UnicodeFonts;
    let c = match c {
        '−' | '–' | '—' => '-',
        '′' | '’' => '\'',
        '×' => 'x',
        other => other,
    };
    font8x8::BASIC_FONTS
        .get(c)
        .or_else(|| font8x8::LATIN_FONTS.get(c))
        .or_else(|| font8x8::GREEK_FONTS.get(c))
}

/// Draws `text` with its top-left corner at (`x`, `y`), each glyph `scale` pixels per font
/// pixel; `vertical` writes it upwards (rotated a quarter turn anticlockwise). Returns its
/// length in pixels.
fn draw_text(
    png: &mut RgbImage,
    text: &str,
    (x, y): (i64, i64),
    scale: i64,
    colour: Rgb<u8>,
    vertical: bool,
) -> i64 {
    let mut advance = 0;
    for c in text.chars() {
        if let Some(rows) = glyph(c) {
            for (row, bits) in rows.iter().enumerate() {
                for column in 0..8 {
                    if bits & (1 << column) == 0 {
                        continue;
                    }
                    for dy in 0..scale {
                        for dx in 0..scale {
                            let (gx, gy) = (column as i64 * scale + dx, row as i64 * scale + dy);
                            let (px, py) = if vertical {
                                (x + gy, y - advance - gx)
                            } else {
                                (x + advance + gx, y + gy)
                            };
                            if px >= 0
                                && py >= 0
                                && (px as u32) < png.width()
                                && (py as u32) < png.height()
                            {
                                png.put_pixel(px as u32, py as u32, colour);
                            }
                        }
                    }
                }
            }
        }
        advance += 8 * scale;
    }
    advance
}

/// The PNG of a plot: `raster` with the title above, the axes' ticks and labels over `extent`
/// and the legend below, as [`svg_around`] writes them (the SVG's own text: numbers and words in
/// the same places).
fn png_around(
    raster: &RgbImage,
    title: &str,
    labels: (&str, &str),
    extent: Option<(Extent, bool)>,
    legend: &[(String, [u8; 3])],
) -> RgbImage {
    let (w, h) = (i64::from(raster.width()), i64::from(raster.height()));
    let (left, bottom, right) = (64i64, 40i64, 16i64);
    let line = 14i64;
    let width = (left + w + right).max(320);
    // The title wrapped at words to the page's width.
    let per_line = ((width - left - right) / 8).max(16) as usize;
    let mut title_lines: Vec<String> = vec![String::new()];
    for word in title.split(' ') {
        let current = title_lines.last_mut().expect("one line at least");
        if !current.is_empty() && current.chars().count() + 1 + word.chars().count() > per_line {
            title_lines.push(word.to_string());
        } else {
            if !current.is_empty() {
                current.push(' ');
            }
            current.push_str(word);
        }
    }
    let top = 10 + 12 * title_lines.len() as i64;
    let legend_height = line * legend.len() as i64 + 6;
    let height = top + h + bottom + legend_height;
    let ink = Rgb([0, 0, 0]);
    let mut png = RgbImage::from_pixel(width as u32, height as u32, Rgb([255, 255, 255]));
    image::imageops::overlay(&mut png, raster, left, top);
    for x in left - 1..=left + w {
        for y in [top - 1, top + h] {
            png.put_pixel(x as u32, y as u32, ink);
        }
    }
    for y in top - 1..=top + h {
        for x in [left - 1, left + w] {
            png.put_pixel(x as u32, y as u32, ink);
        }
    }
    for (k, text) in title_lines.iter().enumerate() {
        draw_text(&mut png, text, (left, 4 + 12 * k as i64), 1, ink, false);
    }
    if let Some((e, y_down)) = extent {
        let size = e.max - e.min;
        for (axis, span, from) in [(0, size.x, e.min.x), (1, size.y, e.min.y)] {
            let step = nice_step(span / 6.0);
            let mut v = (from / step).ceil() * step;
            while v <= from + span {
                let f = f64::from((v - from) / span);
                let text = format_tick(v, step);
                let chars = text.chars().count() as i64;
                if axis == 0 {
                    let x = left + (f * w as f64) as i64;
                    for dy in 0..5 {
                        png.put_pixel(x.clamp(0, width - 1) as u32, (top + h + dy) as u32, ink);
                    }
                    draw_text(&mut png, &text, (x - 4 * chars, top + h + 7), 1, ink, false);
                } else {
                    let y = if y_down {
                        top + (f * h as f64) as i64
                    } else {
                        top + h - (f * h as f64) as i64
                    };
                    for dx in 1..=5 {
                        png.put_pixel((left - dx) as u32, y.clamp(0, height - 1) as u32, ink);
                    }
                    draw_text(
                        &mut png,
                        &text,
                        (left - 8 - 8 * chars, y - 4),
                        1,
                        ink,
                        false,
                    );
                }
                v += step;
            }
        }
        let x_label = labels.0.chars().count() as i64 * 8;
        draw_text(
            &mut png,
            labels.0,
            (left + (w - x_label) / 2, top + h + 22),
            1,
            ink,
            false,
        );
        let y_label = labels.1.chars().count() as i64 * 8;
        draw_text(
            &mut png,
            labels.1,
            (2, top + (h + y_label) / 2),
            1,
            ink,
            true,
        );
    }
    for (k, (text, colour)) in legend.iter().enumerate() {
        let y = top + h + bottom + line * k as i64;
        for dy in 0..10 {
            for dx in 0..10 {
                png.put_pixel((left + dx) as u32, (y + dy) as u32, Rgb(*colour));
            }
        }
        draw_text(&mut png, text, (left + 16, y + 1), 1, ink, false);
    }
    png
}

/// A plot of `raster`: the PNG with its text drawn in, the SVG with it in vector text.
pub(crate) fn plot_around(
    raster: RgbImage,
    title: &str,
    labels: (&str, &str),
    extent: Option<(Extent, bool)>,
    legend: &[(String, [u8; 3])],
) -> Plot {
    Plot {
        png: png_around(&raster, title, labels, extent, legend),
        svg: svg_around(&raster, title, labels, extent, legend),
    }
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
    // A tick at zero reached by adding steps may be −1e-8: no "-0.0".
    let v = if (v / step).round() == 0.0 { 0.0 } else { v };
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
/// covers (its solid angle; grey: no glare), with its largest luminance factor written in it
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
        // The largest luminance factor, written in the square (the PNG's and the SVG's
        // raster alike).
        let text = if e.glare {
            format!("{:.4}", e.max_luminance_factor)
        } else {
            "none".into()
        };
        let ink = if e.glare && e.solid_angle_sr / widest > 0.6 {
            Rgb([0, 0, 0])
        } else {
            Rgb([255, 255, 255])
        };
        let half = 4 * text.chars().count() as i64;
        draw_text(
            &mut png,
            &text,
            (centre.x as i64 - half, centre.y as i64 - 4),
            1,
            ink,
            false,
        );
    }
    let title = format!(
        "'{}' in '{}' per eye point (seen from behind the driver): the glare's solid angle (colour) and largest luminance factor",
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
    plot_around(
        png,
        &title,
        ("right of the eye (m)", "up (m)"),
        Some((extent, false)),
        &legend,
    )
}

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
    plot_around(png, &title, ("", ""), None, &[])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_png_carries_the_text_in_a_compiled_in_font() {
        for c in "0123456789-.,:;()'%°² azAZ".chars() {
            assert!(glyph(c).is_some(), "{c:?} has a glyph");
        }
        assert!(glyph('Δ').is_some() && glyph('−').is_some() && glyph('′').is_some());
        let raster = RgbImage::from_pixel(100, 80, Rgb([200, 200, 200]));
        let extent = Extent {
            min: Vec2::ZERO,
            max: Vec2::new(10.0, 8.0),
        };
        let bare = png_around(&raster, "", ("", ""), None, &[]);
        let plot = plot_around(
            raster,
            "a title long enough to wrap onto a second line of the page, which is 320 wide",
            ("x (m)", "y (m)"),
            Some((extent, false)),
            &[("one".into(), [255, 0, 0])],
        );
        assert!(plot.png.height() > bare.height());
        let dark = |png: &RgbImage| png.pixels().filter(|p| p.0 == [0, 0, 0]).count();
        // The frame alone is dark in the bare plot; ticks, labels and title add ink.
        assert!(
            dark(&plot.png) > dark(&bare) + 500,
            "{} {}",
            dark(&plot.png),
            dark(&bare)
        );
    }

    #[test]
    fn ticks_are_round() {
        assert_eq!(nice_step(0.9), 1.0);
        assert_eq!(nice_step(23.0), 20.0);
        assert!((nice_step(0.04) - 0.05).abs() < 1e-7);
        assert_eq!(format_tick(2.5, 0.5), "2.5");
        assert_eq!(format_tick(20.0, 10.0), "20");
    }
}
