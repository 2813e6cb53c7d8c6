//! The sun: its direction in the vehicle frame, its disc and luminance, how much of a pixel its
//! reflected image covers, and where it stands at a solar time of a date and latitude.
//!
//! Vehicle-frame angles (docs/conventions.md, [`crate::frame`]): the azimuth is measured in the
//! ground plane from the vehicle's forward axis, positive towards its right (clockwise seen from
//! above, as a compass bearing relative to the heading: 0° ahead, 90° right, 180° behind,
//! −90° or 270° left); the elevation is the angle above the ground plane.
//!
//! The disc is 0.53° across (angular radius 0.265°, solid angle Ω = 2π(1 − cos 0.265°) =
//! 6.72 × 10⁻⁵ sr), of uniform luminance E/Ω (limb darkening is not modelled), E being the
//! direct-normal illuminance: 100,000 lx by default, an upper bound that the clear-sky sun comes
//! near only high in the sky (air mass is not modelled: give a lower E for a low sun).

use glam::Vec3;

use super::paths::{gnomonic, SkyExit};
use crate::frame::VehicleFrame;
use crate::AnalyzeError;

/// The sun disc's angular radius, degrees.
pub const SUN_RADIUS_DEG: f64 = 0.265;

/// The default direct-normal illuminance, lux.
pub const DEFAULT_ILLUMINANCE_LX: f64 = 100_000.0;

/// The sun disc's solid angle, sr.
pub fn disc_solid_angle() -> f64 {
    2.0 * std::f64::consts::PI * (1.0 - SUN_RADIUS_DEG.to_radians().cos())
}

/// The sun at one position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
    /// Direct-normal illuminance, lux.
    pub illuminance_lx: f64,
}

impl Sun {
    /// The disc's luminance E/Ω, cd/m².
    pub fn luminance_cd_m2(&self) -> f64 {
        self.illuminance_lx / disc_solid_angle()
    }

    /// The unit direction towards the sun, world space.
    pub fn direction(&self, frame: &VehicleFrame) -> Vec3 {
        direction(frame, self.azimuth_deg, self.elevation_deg)
    }

    pub fn validate(&self) -> Result<(), AnalyzeError> {
        let bad = |reason: String| AnalyzeError::BadOption {
            option: "sun",
            reason,
        };
        if !(self.azimuth_deg.is_finite() && self.elevation_deg.is_finite()) {
            return Err(bad(format!(
                "{},{}: azimuth and elevation must be finite degrees",
                self.azimuth_deg, self.elevation_deg
            )));
        }
        validate_elevation("sun", self.elevation_deg)?;
        if !(self.illuminance_lx.is_finite() && self.illuminance_lx > 0.0) {
            return Err(AnalyzeError::BadOption {
                option: "sun_illuminance",
                reason: format!(
                    "{} lx: the sun's direct-normal illuminance must be a positive number of lux",
                    self.illuminance_lx
                ),
            });
        }
        Ok(())
    }
}

/// An elevation the sun can have and still light the cab: above the horizon, at most 90°.
pub fn validate_elevation(option: &'static str, elevation_deg: f64) -> Result<(), AnalyzeError> {
    if elevation_deg <= 0.0 {
        return Err(AnalyzeError::BadOption {
            option,
            reason: format!(
                "elevation {elevation_deg}°: the sun is below the horizon (or on it); glare needs \
                 it above, at an elevation in (0°, 90°]"
            ),
        });
    }
    if elevation_deg > 90.0 {
        return Err(AnalyzeError::BadOption {
            option,
            reason: format!("elevation {elevation_deg}°: at most 90° (the zenith)"),
        });
    }
    Ok(())
}

/// The unit direction at vehicle-frame azimuth and elevation (degrees).
pub fn direction(frame: &VehicleFrame, azimuth_deg: f64, elevation_deg: f64) -> Vec3 {
    let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    let horizontal = frame.forward.as_dvec3() * az.cos() + frame.right.as_dvec3() * az.sin();
    (horizontal * el.cos() + frame.up.as_dvec3() * el.sin())
        .normalize()
        .as_vec3()
}

/// The share of a pixel (0..=1) over which `exit` sees the sun disc centred on `sun` (a unit
/// direction): the pixel's square mapped by the exit's footprint onto the sky, intersected with
/// the disc. Where the disc's image is smaller than the pixel the disc is sampled (its image
/// lies wholly or partly in the pixel), else the pixel is; 256 points either way, so no disc
/// however small is missed and the share is good to about 1/256 of the smaller of the two.
pub fn disc_coverage(exit: &SkyExit, sun: Vec3) -> f64 {
    let radius = SUN_RADIUS_DEG.to_radians().tan();
    let [[a, c], [b, d]] = exit.footprint; // columns: ∂/∂x = (a, c), ∂/∂y = (b, d)
    let cos = f64::from(exit.dir.dot(sun));
    if cos <= 0.0 || cos.clamp(-1.0, 1.0).acos() > reach(exit) {
        return 0.0;
    }
    let t = gnomonic(exit, sun);
    let det = a * d - b * c;
    let to_sky = |[u, v]: [f64; 2]| [a * u + b * v, c * u + d * v];
    let in_disc = |q: [f64; 2]| {
        let [x, y] = to_sky(q);
        (x - t[0]).hypot(y - t[1]) <= radius
    };
    let ellipse_area = std::f64::consts::PI * radius * radius / det.abs().max(1e-300);
    const N: usize = 16;
    if ellipse_area <= 1.0 && det.abs() > 0.0 {
        // Sample the disc (sunflower pattern) and count the points whose pixel position lies in
        // the pixel's square.
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let inside = (0..N * N)
            .filter(|k| {
                let r = radius * ((*k as f64 + 0.5) / (N * N) as f64).sqrt();
                let phi = golden * *k as f64;
                let (x, y) = (t[0] + r * phi.cos(), t[1] + r * phi.sin());
                let u = (d * x - b * y) / det;
                let v = (-c * x + a * y) / det;
                u.abs() <= 0.5 && v.abs() <= 0.5
            })
            .count();
        ellipse_area * inside as f64 / (N * N) as f64
    } else {
        let inside = (0..N * N)
            .filter(|k| {
                let u = ((k % N) as f64 + 0.5) / N as f64 - 0.5;
                let v = ((k / N) as f64 + 0.5) / N as f64 - 0.5;
                in_disc([u, v])
            })
            .count();
        inside as f64 / (N * N) as f64
    }
}

/// The largest angle (radians) from `exit`'s direction at which the sun disc can still touch
/// its pixel: the footprint's corner plus the disc's radius, with a margin.
pub fn reach(exit: &SkyExit) -> f64 {
    let [[a, c], [b, d]] = exit.footprint;
    let corner = 0.5 * (a.hypot(c) + b.hypot(d));
    (corner + SUN_RADIUS_DEG.to_radians().tan()).atan() * 1.01 + 1e-6
}

/// The sun's declination on day `day_of_year` (1 = 1 January), radians (Spencer, "Fourier
/// series representation of the position of the sun", 1971; within about 0.03°).
pub fn declination(day_of_year: u32) -> f64 {
    let g = 2.0 * std::f64::consts::PI * (f64::from(day_of_year) - 1.0) / 365.0;
    0.006918 - 0.399912 * g.cos() + 0.070257 * g.sin() - 0.006758 * (2.0 * g).cos()
        + 0.000907 * (2.0 * g).sin()
        - 0.002697 * (3.0 * g).cos()
        + 0.00148 * (3.0 * g).sin()
}

/// The sun's compass azimuth (degrees from north, clockwise) and elevation (degrees) at
/// apparent solar time `hours` (12 = solar noon) on `day_of_year` at `latitude_deg` (north
/// positive). Refraction by the atmosphere is not modelled.
pub fn solar_position(latitude_deg: f64, day_of_year: u32, hours: f64) -> (f64, f64) {
    let (phi, delta) = (latitude_deg.to_radians(), declination(day_of_year));
    let h = (15.0 * (hours - 12.0)).to_radians();
    let east = -delta.cos() * h.sin();
    let north = delta.sin() * phi.cos() - delta.cos() * h.cos() * phi.sin();
    let up = delta.sin() * phi.sin() + delta.cos() * h.cos() * phi.cos();
    let azimuth = east.atan2(north).to_degrees().rem_euclid(360.0);
    (azimuth, up.clamp(-1.0, 1.0).asin().to_degrees())
}

/// Day of the year (1..=366) of a date `YYYY-MM-DD`.
pub fn day_of_year(date: &str) -> Result<u32, AnalyzeError> {
    let bad = |reason: String| AnalyzeError::BadOption {
        option: "date",
        reason: format!("'{date}': {reason}"),
    };
    let parts: Vec<&str> = date.split('-').collect();
    let [year, month, day] = parts.as_slice() else {
        return Err(bad("expected YYYY-MM-DD".into()));
    };
    let number = |s: &str, what: &str| {
        s.parse::<u32>()
            .map_err(|_| bad(format!("the {what} '{s}' is not a number")))
    };
    let (year, month, day) = (
        number(year, "year")?,
        number(month, "month")?,
        number(day, "day")?,
    );
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    let lengths = [
        31,
        if leap { 29 } else { 28 },
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    if !(1..=12).contains(&month) {
        return Err(bad(format!("month {month} is not 1 to 12")));
    }
    if day == 0 || day > lengths[month as usize - 1] {
        return Err(bad(format!(
            "day {day} is not in month {month} (1 to {})",
            lengths[month as usize - 1]
        )));
    }
    Ok(lengths[..month as usize - 1].iter().sum::<u32>() + day)
}
