//! Sun sweeps and solar days without tracing per sun position. A path that ends on the sky does
//! not depend on where the sun is: each eye point is traced once ([`super::trace_eyes`]), each
//! pixel keeping its sky exits' directions, footprints and throughputs, and every sun position
//! is then a lookup: the exits are binned by elevation (bands of [`BAND_DEG`], each exit in
//! every band its reach touches), the sun's band gives the candidates, and each candidate's
//! disc coverage is computed as for a single sun ([`super::sun_glare`], which tests every exit:
//! the two agree exactly, a test holds them to it).
//!
//! A sweep covers azimuths AZ0..=AZ1 and elevations EL0..=EL1 in steps of STEP degrees
//! (vehicle frame, [`super::sun`]). Per position: how many eye points see glare, the worst
//! eye point's glare luminance and washed-out share. With a latitude, the vehicle's compass
//! heading and a date, the sun's path through that day (apparent solar time, every
//! `step_min` minutes while it is above the horizon) is looked up the same way, and the solar
//! times when glare or a washed-out display happen are reported as intervals.

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use specula_scene::Scene;
use specula_trace::SceneAccel;

use super::{
    eye_figures, eye_images, report_header, sun, sun_in_pixel, sun_report, trace_eyes, with_eyes,
    EyeGlare, EyeTrace, Glare, Options, PixelGlare, Source, Sun,
};
use crate::frame::VehicleFrame;
use crate::AnalyzeError;

/// The elevation bands' width, degrees.
pub const BAND_DEG: f64 = 0.5;

/// A grid of sun positions, vehicle frame, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepSpec {
    pub azimuth: [f64; 2],
    pub elevation: [f64; 2],
    pub step_deg: f64,
}

impl SweepSpec {
    pub fn validate(&self) -> Result<(), AnalyzeError> {
        let bad = |reason: String| AnalyzeError::BadOption {
            option: "sun_sweep",
            reason,
        };
        let [az0, az1] = self.azimuth;
        let [el0, el1] = self.elevation;
        if ![az0, az1, el0, el1, self.step_deg]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(bad("every value must be a finite number of degrees".into()));
        }
        if self.step_deg <= 0.0 {
            return Err(bad(format!(
                "step {}°: a sweep needs a positive step",
                self.step_deg
            )));
        }
        if az1 < az0 || az1 - az0 > 360.0 {
            return Err(bad(format!(
                "azimuths {az0}..{az1}°: AZ1 must not be below AZ0, nor more than 360° beyond it"
            )));
        }
        if el1 < el0 {
            return Err(bad(format!(
                "elevations {el0}..{el1}°: EL1 must not be below EL0"
            )));
        }
        sun::validate_elevation("sun_sweep", el0)?;
        sun::validate_elevation("sun_sweep", el1)?;
        let count = self.steps(self.azimuth) * self.steps(self.elevation);
        if count > 1_000_000 {
            return Err(bad(format!(
                "{count} sun positions: at most 1,000,000 (take a larger step)"
            )));
        }
        Ok(())
    }

    fn steps(&self, [lo, hi]: [f64; 2]) -> usize {
        ((hi - lo) / self.step_deg + 1e-9).floor() as usize + 1
    }

    /// The positions (azimuth, elevation), azimuth fastest.
    pub fn positions(&self) -> Vec<(f64, f64)> {
        let (na, ne) = (self.steps(self.azimuth), self.steps(self.elevation));
        (0..ne)
            .flat_map(|j| {
                (0..na).map(move |i| {
                    (
                        self.azimuth[0] + i as f64 * self.step_deg,
                        self.elevation[0] + j as f64 * self.step_deg,
                    )
                })
            })
            .collect()
    }
}

/// A day of the sun's path: where, which way the vehicle heads, when.
#[derive(Clone, Debug, PartialEq)]
pub struct Day {
    /// Degrees, north positive.
    pub latitude_deg: f64,
    /// The vehicle's forward axis as a compass bearing, degrees clockwise from north.
    pub heading_deg: f64,
    /// YYYY-MM-DD.
    pub date: String,
    /// Minutes between the looked-up times.
    pub step_min: f64,
}

impl Day {
    pub fn validate(&self) -> Result<u32, AnalyzeError> {
        if !(self.latitude_deg.is_finite() && self.latitude_deg.abs() <= 90.0) {
            return Err(AnalyzeError::BadOption {
                option: "latitude",
                reason: format!("{}°: a latitude in [−90°, 90°]", self.latitude_deg),
            });
        }
        if !self.heading_deg.is_finite() {
            return Err(AnalyzeError::BadOption {
                option: "heading",
                reason: format!("{}°: a finite compass bearing", self.heading_deg),
            });
        }
        if !(self.step_min.is_finite() && self.step_min > 0.0 && self.step_min <= 240.0) {
            return Err(AnalyzeError::BadOption {
                option: "time_step",
                reason: format!("{} min: in (0, 240]", self.step_min),
            });
        }
        sun::day_of_year(&self.date)
    }
}

/// What one sun position does over the eye points.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SunEffect {
    /// Vehicle frame, degrees.
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
    pub eyes_with_glare: usize,
    /// The worst eye point's glare luminance (the image's), cd/m²; 0 without glare.
    pub max_luminance_cd_m2: f64,
    /// The largest washed-out share of the display (null without one).
    pub max_washed_out_share: Option<f64>,
}

impl SunEffect {
    /// What the sun at (azimuth, elevation) does, from every eye point's figures.
    pub fn of(azimuth_deg: f64, elevation_deg: f64, eyes: &[EyeGlare]) -> SunEffect {
        SunEffect {
            azimuth_deg,
            elevation_deg,
            eyes_with_glare: eyes.iter().filter(|e| e.glare).count(),
            max_luminance_cd_m2: eyes
                .iter()
                .filter_map(|e| e.max_luminance_cd_m2)
                .fold(0.0, f64::max),
            max_washed_out_share: eyes
                .iter()
                .filter_map(|e| e.display.as_ref().map(|d| d.washed_out_share))
                .reduce(f64::max),
        }
    }

    pub fn glare(&self) -> bool {
        self.eyes_with_glare > 0
    }

    pub fn washed_out(&self) -> bool {
        self.max_washed_out_share.is_some_and(|s| s > 0.0)
    }
}

/// One looked-up time of the solar day.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SolarTime {
    /// Apparent solar time, hours (12 = solar noon).
    pub hours: f64,
    /// The sun's compass azimuth, degrees clockwise from north.
    pub compass_azimuth_deg: f64,
    #[serde(flatten)]
    pub effect: SunEffect,
}

#[derive(Clone, Debug, Serialize)]
pub struct DayReport {
    pub latitude_deg: f64,
    pub heading_deg: f64,
    pub date: String,
    pub day_of_year: u32,
    pub step_min: f64,
    /// The times with the sun above the horizon.
    pub times: Vec<SolarTime>,
    /// [first, last] solar hours of each run of times with glare.
    pub glare_hours: Vec<[f64; 2]>,
    /// ... and with some of the display washed out.
    pub washed_out_hours: Vec<[f64; 2]>,
}

#[derive(Clone, Debug, Serialize)]
pub struct SweepReport {
    pub azimuth_deg: [f64; 2],
    pub elevation_deg: [f64; 2],
    pub step_deg: f64,
    pub illuminance_lx: f64,
    /// Azimuth fastest.
    pub positions: Vec<SunEffect>,
    /// The position whose figures the report's eyes hold: the largest washed-out share, then
    /// the most eye points with glare, then the brightest glare.
    pub worst_position: usize,
    /// Wall-clock seconds tracing the eye points once, and looking every position up.
    pub trace_s: f64,
    pub lookup_s: f64,
    pub day: Option<DayReport>,
}

/// One eye point's sky exits binned by elevation.
pub struct SkyIndex {
    /// Band k holds (pixel, exit) pairs, in pixel order, whose reach touches elevations
    /// [−90 + k·BAND_DEG, −90 + (k + 1)·BAND_DEG).
    bands: Vec<Vec<(u32, u32)>>,
}

fn band_of(elevation_deg: f64) -> usize {
    (((elevation_deg + 90.0) / BAND_DEG).floor().max(0.0) as usize).min(band_count() - 1)
}

fn band_count() -> usize {
    (180.0 / BAND_DEG).ceil() as usize + 1
}

impl SkyIndex {
    pub fn new(trace: &EyeTrace, frame: &VehicleFrame) -> SkyIndex {
        let mut bands = vec![Vec::new(); band_count()];
        for (i, pixel) in trace.pixels.iter().enumerate() {
            for (k, exit) in pixel.sky.iter().enumerate() {
                let elevation = frame.elevation_deg(exit.dir);
                let reach = sun::reach(exit).to_degrees();
                let touched = band_of(elevation - reach)..=band_of(elevation + reach);
                for band in &mut bands[touched] {
                    band.push((i as u32, k as u32));
                }
            }
        }
        SkyIndex { bands }
    }

    /// The sun's glare in every pixel, from the candidates of the sun's band.
    pub fn sun_glare(
        &self,
        trace: &EyeTrace,
        frame: &VehicleFrame,
        sun_dir: glam::Vec3,
        sun_luminance: f64,
    ) -> Vec<(usize, PixelGlare)> {
        let band = &self.bands[band_of(frame.elevation_deg(sun_dir))];
        let mut glare = Vec::new();
        for run in band.chunk_by(|a, b| a.0 == b.0) {
            let pixel = &trace.pixels[run[0].0 as usize];
            let exits = run.iter().map(|(_, k)| &pixel.sky[*k as usize]);
            if let Some(g) = sun_in_pixel(exits, sun_dir, sun_luminance) {
                glare.push((run[0].0 as usize, g));
            }
        }
        glare
    }
}

/// Every eye point's figures with the sun at `sun`, by lookup.
fn look_up(
    traces: &[EyeTrace],
    indexes: &[SkyIndex],
    frame: &VehicleFrame,
    options: &Options,
    sun: &Sun,
) -> Vec<EyeGlare> {
    let dir = sun.direction(frame);
    traces
        .iter()
        .zip(indexes)
        .map(|(trace, index)| {
            let glare = index.sun_glare(trace, frame, dir, sun.luminance_cd_m2());
            eye_figures(trace, &glare, options.threshold, options.display.as_ref()).0
        })
        .collect()
}

/// Runs a sweep: `options.source` must be the sun (its illuminance is the sweep's; its position
/// is replaced by each of `spec`'s), calling `progress` after each eye point is traced.
#[allow(clippy::too_many_arguments)]
pub fn sweep(
    scene: &Scene,
    accel: &SceneAccel,
    eyes: &[glam::Vec3],
    frame: &VehicleFrame,
    options: &Options,
    spec: &SweepSpec,
    day: Option<&Day>,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Glare, AnalyzeError> {
    let Source::Sun(base) = options.source else {
        return Err(AnalyzeError::BadOption {
            option: "sun_sweep",
            reason: "a sweep moves the sun: it takes no `source`".into(),
        });
    };
    spec.validate()?;
    let day_of_year = day.map(Day::validate).transpose()?;
    let started = Instant::now();
    let traces = trace_eyes(scene, accel, eyes, options, progress)?;
    let trace_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let indexes: Vec<SkyIndex> = traces.iter().map(|t| SkyIndex::new(t, frame)).collect();
    let at = |azimuth_deg: f64, elevation_deg: f64| Sun {
        azimuth_deg,
        elevation_deg,
        ..base
    };
    let positions: Vec<SunEffect> = spec
        .positions()
        .par_iter()
        .map(|&(az, el)| {
            SunEffect::of(
                az,
                el,
                &look_up(&traces, &indexes, frame, options, &at(az, el)),
            )
        })
        .collect();
    let lookup_s = started.elapsed().as_secs_f64();
    let day = match (day, day_of_year) {
        (Some(day), Some(n)) => Some(solar_day(&traces, &indexes, frame, options, &base, day, n)),
        _ => None,
    };
    let worst_position = worst(&positions);
    let worst_sun = at(
        positions[worst_position].azimuth_deg,
        positions[worst_position].elevation_deg,
    );
    let mut figures = Vec::with_capacity(traces.len());
    let mut images = Vec::with_capacity(traces.len());
    for (trace, index) in traces.iter().zip(&indexes) {
        let dir = worst_sun.direction(frame);
        let glare = index.sun_glare(trace, frame, dir, worst_sun.luminance_cd_m2());
        let (eye, washed) = eye_figures(trace, &glare, options.threshold, options.display.as_ref());
        images.push(eye_images(trace, &glare, &washed));
        figures.push(eye);
    }
    let mut report = with_eyes(report_header(scene, options, frame), figures);
    report.sun = Some(sun_report(&worst_sun, frame));
    report.sweep = Some(SweepReport {
        azimuth_deg: spec.azimuth,
        elevation_deg: spec.elevation,
        step_deg: spec.step_deg,
        illuminance_lx: base.illuminance_lx,
        positions,
        worst_position,
        trace_s,
        lookup_s,
        day,
    });
    Ok(Glare { report, images })
}

/// The largest washed-out share, then the most eye points with glare, then the brightest.
fn worst(positions: &[SunEffect]) -> usize {
    positions
        .iter()
        .enumerate()
        .max_by(|a, b| {
            let washed = |e: &SunEffect| e.max_washed_out_share.unwrap_or(0.0);
            washed(a.1)
                .total_cmp(&washed(b.1))
                .then(a.1.eyes_with_glare.cmp(&b.1.eyes_with_glare))
                .then(a.1.max_luminance_cd_m2.total_cmp(&b.1.max_luminance_cd_m2))
                .then(b.0.cmp(&a.0))
        })
        .map_or(0, |(k, _)| k)
}

fn solar_day(
    traces: &[EyeTrace],
    indexes: &[SkyIndex],
    frame: &VehicleFrame,
    options: &Options,
    base: &Sun,
    day: &Day,
    day_of_year: u32,
) -> DayReport {
    let steps = (24.0 * 60.0 / day.step_min).floor() as usize;
    let times: Vec<SolarTime> = (0..=steps)
        .into_par_iter()
        .filter_map(|k| {
            let hours = k as f64 * day.step_min / 60.0;
            let (compass, elevation) = sun::solar_position(day.latitude_deg, day_of_year, hours);
            if elevation <= 0.0 {
                return None;
            }
            let azimuth = (compass - day.heading_deg + 180.0).rem_euclid(360.0) - 180.0;
            let sun = Sun {
                azimuth_deg: azimuth,
                elevation_deg: elevation,
                ..*base
            };
            let eyes = look_up(traces, indexes, frame, options, &sun);
            Some(SolarTime {
                hours,
                compass_azimuth_deg: compass,
                effect: SunEffect::of(azimuth, elevation, &eyes),
            })
        })
        .collect();
    let runs = |flag: fn(&SunEffect) -> bool| {
        let mut runs: Vec<[f64; 2]> = Vec::new();
        let mut previous: Option<f64> = None;
        for t in times.iter().filter(|t| flag(&t.effect)) {
            match (runs.last_mut(), previous) {
                (Some(run), Some(p)) if (t.hours - p - day.step_min / 60.0).abs() < 1e-9 => {
                    run[1] = t.hours
                }
                _ => runs.push([t.hours, t.hours]),
            }
            previous = Some(t.hours);
        }
        runs
    };
    DayReport {
        latitude_deg: day.latitude_deg,
        heading_deg: day.heading_deg,
        date: day.date.clone(),
        day_of_year,
        step_min: day.step_min,
        glare_hours: runs(SunEffect::glare),
        washed_out_hours: runs(SunEffect::washed_out),
        times,
    }
}
