//! The glare plots: the eye points' glare map and the worst eye point's view with its glare
//! outlined; and the sweep's pictures: a map of the sun positions (azimuth × elevation) coloured by the worst
//! eye point's glare luminance on a log colour bar, washed-out positions crossed; and a polar
//! plot of the sky seen from above (the vehicle's forward axis up, the zenith in the centre)
//! with the positions that glare or wash out and, with a solar day, the sun's path through it.

use image::{Rgb, RgbImage};

use super::sweep::{SunEffect, SweepReport};
use crate::figure::{Axis, ColourBar, Figure, Mark, Plot};
use glam::{Vec2, Vec3};

const NONE: [u8; 3] = [215, 215, 215];
const WASHED: [u8; 3] = [220, 20, 60];
const GUIDE: [u8; 3] = [150, 150, 150];

/// The glare luminance's scale: logarithmic over the sweep's range.
fn luminance_bar(sweep: &SweepReport) -> ColourBar {
    let lit = sweep
        .positions
        .iter()
        .filter(|p| p.glare() && p.max_luminance_cd_m2 > 0.0);
    let lo = lit
        .clone()
        .map(|p| p.max_luminance_cd_m2)
        .fold(f64::INFINITY, f64::min);
    let hi = lit.map(|p| p.max_luminance_cd_m2).fold(0.0, f64::max);
    let range = match lo.is_finite() {
        true if hi > lo => (lo, hi),
        true => (lo * 0.5, lo * 2.0),
        false => (1.0, 10.0),
    };
    ColourBar {
        label: "the worst eye point's glare luminance (cd/m², log scale)".into(),
        range,
        log: true,
    }
}

/// A position's colour on `bar` (grey: no glare).
fn colour(effect: &SunEffect, bar: &ColourBar) -> [u8; 3] {
    if effect.glare() {
        bar.colour(effect.max_luminance_cd_m2)
    } else {
        NONE
    }
}

fn legend(sweep: &SweepReport) -> Vec<(String, [u8; 3])> {
    let mut legend = vec![("no glare from any eye point".to_string(), NONE)];
    let display = sweep
        .positions
        .iter()
        .any(|p| p.max_washed_out_share.is_some());
    if display {
        legend.push(("some of the display washed out (crossed)".into(), WASHED));
    }
    legend
}

/// The sweep as a map: azimuth across, elevation up, one cell per position.
pub fn sweep_map(sweep: &SweepReport, title: &str) -> Plot {
    let step = sweep.step_deg;
    let columns = ((sweep.azimuth_deg[1] - sweep.azimuth_deg[0]) / step + 1e-9).floor() as u32 + 1;
    let rows = ((sweep.elevation_deg[1] - sweep.elevation_deg[0]) / step + 1e-9).floor() as u32 + 1;
    let cell = (640 / columns.max(rows)).clamp(3, 48);
    let bar = luminance_bar(sweep);
    let mut png = RgbImage::from_pixel(columns * cell, rows * cell, Rgb([255, 255, 255]));
    let mut crosses = Vec::new();
    let half = step * 0.5;
    for (k, p) in sweep.positions.iter().enumerate() {
        let (i, j) = (k as u32 % columns, k as u32 / columns);
        let (x0, y0) = (i * cell, (rows - 1 - j) * cell);
        for y in y0..y0 + cell {
            for x in x0..x0 + cell {
                png.put_pixel(x, y, Rgb(colour(p, &bar)));
            }
        }
        if p.washed_out() {
            let (az, el) = (p.azimuth_deg, p.elevation_deg);
            for (from, to) in [
                ((-half, -half), (half, half)),
                ((-half, half), (half, -half)),
            ] {
                crosses.push(Mark::Line {
                    points: vec![(az + from.0, el + from.1), (az + to.0, el + to.1)],
                    colour: WASHED,
                    width: 2,
                });
            }
        }
    }
    let mut figure = Figure::new(title, png);
    figure.axes = Some((
        Axis::new(
            "sun azimuth from the vehicle's forward axis, right positive (°)",
            (
                sweep.azimuth_deg[0] - half,
                sweep.azimuth_deg[0] + (f64::from(columns) - 0.5) * step,
            ),
        ),
        Axis::new(
            "sun elevation (°)",
            (
                sweep.elevation_deg[0] - half,
                sweep.elevation_deg[0] + (f64::from(rows) - 0.5) * step,
            ),
        ),
    ));
    figure.marks = crosses;
    figure.legend = legend(sweep);
    figure.colour_bar = Some(bar);
    figure.plot()
}

/// The sky from above: forward up, right to the right, the zenith in the centre and the horizon
/// on the rim (radius ∝ 90° − elevation); rings every 30°; the day's path in black, a larger
/// dot each solar hour.
pub fn polar(sweep: &SweepReport, title: &str) -> Plot {
    let size = 480u32;
    let centre = f64::from(size) * 0.5;
    let radius = centre - 24.0;
    // Raster pixels, y down.
    let at = |az: f64, el: f64| {
        let r = radius * (90.0 - el) / 90.0;
        let a = az.to_radians();
        (centre + r * a.sin(), centre - r * a.cos())
    };
    let mut marks = Vec::new();
    for ring in [0.0, 30.0, 60.0] {
        marks.push(Mark::Line {
            points: (0..=360).map(|k| at(f64::from(k), ring)).collect(),
            colour: GUIDE,
            width: 1,
        });
        marks.push(Mark::Text {
            at: at(45.0, ring + 4.0),
            text: format!("{ring}°"),
            colour: [90, 90, 90],
            halo: [255, 255, 255],
        });
    }
    marks.push(Mark::Line {
        points: vec![at(0.0, 90.0), at(0.0, 0.0)],
        colour: GUIDE,
        width: 1,
    });
    for (az, word) in [
        (0.0, "ahead"),
        (90.0, "right"),
        (180.0, "behind"),
        (270.0, "left"),
    ] {
        marks.push(Mark::Text {
            at: at(az, -9.0),
            text: word.into(),
            colour: [0, 0, 0],
            halo: [255, 255, 255],
        });
    }
    let bar = luminance_bar(sweep);
    let half = ((radius * sweep.step_deg / 90.0) * 0.35).clamp(1.5, 6.0);
    for p in &sweep.positions {
        if !(p.glare() || p.washed_out()) {
            continue;
        }
        let ink = if p.washed_out() {
            WASHED
        } else {
            colour(p, &bar)
        };
        let (x, y) = at(p.azimuth_deg, p.elevation_deg);
        marks.push(Mark::Box {
            corners: [(x - half, y - half), (x + half, y + half)],
            colour: ink,
        });
    }
    if let Some(day) = &sweep.day {
        marks.push(Mark::Line {
            points: day
                .times
                .iter()
                .map(|t| at(t.effect.azimuth_deg, t.effect.elevation_deg))
                .collect(),
            colour: [0, 0, 0],
            width: 1,
        });
        for t in &day.times {
            let on_hour = (t.hours * 60.0).round() as i64 % 60 == 0;
            if !(on_hour || t.effect.washed_out()) {
                continue;
            }
            let ink = if t.effect.washed_out() {
                WASHED
            } else {
                [0, 0, 0]
            };
            let (x, y) = at(t.effect.azimuth_deg, t.effect.elevation_deg);
            let r = if on_hour { 3.0 } else { 1.5 };
            marks.push(Mark::Box {
                corners: [(x - r, y - r), (x + r, y + r)],
                colour: ink,
            });
        }
    }
    let mut figure = Figure::new(
        title,
        RgbImage::from_pixel(size, size, Rgb([255, 255, 255])),
    );
    figure.marks = marks;
    let mut legend = legend(sweep);
    legend.push((
        "rings: elevation 0°, 30°, 60°; the line to the top: ahead".into(),
        GUIDE,
    ));
    if sweep.day.is_some() {
        legend.push((
            "the sun's path through the day, a larger dot each solar hour".into(),
            [0, 0, 0],
        ));
    }
    figure.legend = legend;
    figure.colour_bar = Some(bar);
    figure.plot()
}

/// The eye points seen from behind the driver, each a square coloured by how much of its view
/// the glare covers (its solid angle, on the colour bar; grey: no glare), with its largest
/// luminance factor written in it.
pub fn glare_eyebox(report: &super::Report, frame: &crate::frame::VehicleFrame) -> Plot {
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
pub fn glare_image(glare: &super::Glare, k: usize) -> Plot {
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
