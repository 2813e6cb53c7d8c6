//! The sweep's pictures: a map of the sun positions (azimuth × elevation) coloured by the worst
//! eye point's glare luminance, washed-out positions crossed; and a polar plot of the sky seen
//! from above (the vehicle's forward axis up, the zenith in the centre) with the positions that
//! glare or wash out and, with a solar day, the sun's path through it.

use image::{Rgb, RgbImage};

use super::sweep::{SunEffect, SweepReport};
use crate::plot::{plot_around, scale_colour, Extent, Plot};

const NONE: [u8; 3] = [215, 215, 215];
const WASHED: [u8; 3] = [220, 20, 60];

/// A position's colour: the glare luminance on a log scale over the sweep's range (grey: none).
fn colour(effect: &SunEffect, range: (f64, f64)) -> [u8; 3] {
    if !effect.glare() {
        return NONE;
    }
    let (lo, hi) = range;
    let t = if hi > lo {
        (effect.max_luminance_cd_m2.max(lo).log10() - lo.log10()) / (hi.log10() - lo.log10())
    } else {
        1.0
    };
    scale_colour(t.clamp(0.0, 1.0))
}

fn luminance_range(sweep: &SweepReport) -> (f64, f64) {
    let lit = sweep
        .positions
        .iter()
        .filter(|p| p.glare() && p.max_luminance_cd_m2 > 0.0);
    let lo = lit
        .clone()
        .map(|p| p.max_luminance_cd_m2)
        .fold(f64::INFINITY, f64::min);
    let hi = lit.map(|p| p.max_luminance_cd_m2).fold(0.0, f64::max);
    if lo.is_finite() {
        (lo, hi)
    } else {
        (1.0, 1.0)
    }
}

fn legend(range: (f64, f64), display: bool) -> Vec<(String, [u8; 3])> {
    let mut legend = vec![
        ("no glare from any eye point".to_string(), NONE),
        (
            format!("glare, the worst eye point's {:.2e} cd/m²", range.0),
            scale_colour(0.0),
        ),
        (format!("glare, {:.2e} cd/m²", range.1), scale_colour(1.0)),
    ];
    if display {
        legend.push(("some of the display washed out (crossed)".into(), WASHED));
    }
    legend
}

fn cross(png: &mut RgbImage, x0: u32, y0: u32, side: u32) {
    for k in 0..side {
        for (x, y) in [(x0 + k, y0 + k), (x0 + side - 1 - k, y0 + k)] {
            if x < png.width() && y < png.height() {
                png.put_pixel(x, y, Rgb(WASHED));
            }
        }
    }
}

/// The sweep as a map: azimuth across, elevation up, one cell per position.
pub fn sweep_map(sweep: &SweepReport, title: &str) -> Plot {
    let step = sweep.step_deg;
    let columns = ((sweep.azimuth_deg[1] - sweep.azimuth_deg[0]) / step + 1e-9).floor() as u32 + 1;
    let rows = ((sweep.elevation_deg[1] - sweep.elevation_deg[0]) / step + 1e-9).floor() as u32 + 1;
    let cell = (640 / columns.max(rows)).clamp(3, 48);
    let mut png = RgbImage::from_pixel(columns * cell, rows * cell, Rgb([255, 255, 255]));
    let range = luminance_range(sweep);
    let display = sweep
        .positions
        .iter()
        .any(|p| p.max_washed_out_share.is_some());
    for (k, p) in sweep.positions.iter().enumerate() {
        let (i, j) = (k as u32 % columns, k as u32 / columns);
        let (x0, y0) = (i * cell, (rows - 1 - j) * cell);
        for y in y0..y0 + cell {
            for x in x0..x0 + cell {
                png.put_pixel(x, y, Rgb(colour(p, range)));
            }
        }
        if p.washed_out() {
            cross(&mut png, x0, y0, cell);
        }
    }
    let half = step as f32 * 0.5;
    let extent = Extent {
        min: glam::Vec2::new(
            sweep.azimuth_deg[0] as f32 - half,
            sweep.elevation_deg[0] as f32 - half,
        ),
        max: glam::Vec2::new(
            sweep.azimuth_deg[0] as f32 + (columns as f32 - 0.5) * step as f32,
            sweep.elevation_deg[0] as f32 + (rows as f32 - 0.5) * step as f32,
        ),
    };
    plot_around(
        png,
        title,
        (
            "sun azimuth from the vehicle's forward axis, right positive (°)",
            "sun elevation (°)",
        ),
        Some((extent, false)),
        &legend(range, display),
    )
}

/// The sky from above: forward up, right to the right, the zenith in the centre and the horizon
/// on the rim (radius ∝ 90° − elevation); rings every 30°; the day's path in black, a dot each
/// hour.
pub fn polar(sweep: &SweepReport, title: &str) -> Plot {
    let size = 480u32;
    let centre = size as f64 * 0.5;
    let radius = centre - 8.0;
    let mut png = RgbImage::from_pixel(size, size, Rgb([255, 255, 255]));
    let at = |az: f64, el: f64| {
        let r = radius * (90.0 - el) / 90.0;
        let a = az.to_radians();
        (centre + r * a.sin(), centre - r * a.cos())
    };
    let dot = |png: &mut RgbImage, (x, y): (f64, f64), half: i64, ink: [u8; 3]| {
        for dy in -half..=half {
            for dx in -half..=half {
                let (px, py) = (x.round() as i64 + dx, y.round() as i64 + dy);
                if px >= 0 && py >= 0 && (px as u32) < size && (py as u32) < size {
                    png.put_pixel(px as u32, py as u32, Rgb(ink));
                }
            }
        }
    };
    for ring in [0.0, 30.0, 60.0] {
        for k in 0..720 {
            dot(&mut png, at(f64::from(k) * 0.5, ring), 0, [160, 160, 160]);
        }
    }
    for k in 0..=90 {
        dot(&mut png, at(0.0, f64::from(k)), 0, [160, 160, 160]);
    }
    let range = luminance_range(sweep);
    let half = ((radius * sweep.step_deg / 90.0) * 0.35).clamp(1.0, 6.0) as i64;
    for p in &sweep.positions {
        let ink = if p.washed_out() {
            WASHED
        } else {
            colour(p, range)
        };
        if p.glare() || p.washed_out() {
            dot(&mut png, at(p.azimuth_deg, p.elevation_deg), half, ink);
        }
    }
    if let Some(day) = &sweep.day {
        for t in &day.times {
            let on_hour = (t.hours * 60.0).round() as i64 % 60 == 0;
            let ink = if t.effect.washed_out() {
                WASHED
            } else {
                [0, 0, 0]
            };
            dot(
                &mut png,
                at(t.effect.azimuth_deg, t.effect.elevation_deg),
                i64::from(on_hour) * 2,
                ink,
            );
        }
    }
    let display = sweep
        .positions
        .iter()
        .any(|p| p.max_washed_out_share.is_some());
    let mut legend = legend(range, display);
    legend.push((
        "rings: elevation 0°, 30°, 60°; the line to the top: ahead".into(),
        [160, 160, 160],
    ));
    if sweep.day.is_some() {
        legend.push((
            "the sun's path through the day, a larger dot each solar hour".into(),
            [0, 0, 0],
        ));
    }
    plot_around(png, title, ("", ""), None, &legend)
}
