//! `specula analyze glare`: whether, where and how brightly a light source, a named surface (a
//! truck's side window) or the sun, is seen reflected in a surface (the instrument cover over
//! the dial), in cd/m², from each eye point, and whether the display behind the cover stays
//! readable under it.
//!
//! Per eye point a camera at the eye is aimed at the surface's bounding-sphere centre, its field
//! of view fitted to that sphere. Each pixel's paths are followed as the reference follows them
//! (a mirror's Schlick term or constant F0; a dielectric's exact Fresnel reflectance, here per
//! polarisation: s and p carried apart along the path, so that a slab's two faces and a thin
//! sheet sum each polarisation's bounces on its own, [`paths`]; total internal reflection sends
//! everything to the reflected branch; one path per colour channel where the indices differ), and
//! split: a path's **glare** is what it brings from the source after at least one specular
//! reflection on the surface (its front or, inside a glass, its back face).
//!
//! Units. A pixel's **luminance factor** is its glare's luminance over the source's own (Y of
//! Rec. 709 linear RGB): the paths' throughput as the eye sees the source's image. With the
//! source's luminance (`--source-luminance`, or the sun's E/Ω, [`sun`]) the glare is in cd/m²:
//! the image's luminance (factor × source luminance), and per pixel the glare's mean luminance
//! over the pixel (the same, where the image covers the whole pixel; the sun's image is often
//! smaller than a pixel, and its share of each pixel is found from the paths' footprints, so it
//! is never missed). A pixel shows glare where its luminance factor exceeds `threshold` (a
//! luminance factor, dimensionless). The **veiling ratio** (named sources) is the glare's Y over
//! the Y of what the pixel shows without it.
//!
//! The display: pixels whose paths reach the display mesh through the surface without reflecting
//! on it see the display with transmittance τ (the Y of those paths' throughput); there the
//! contrast ratio is (τ L_bright + L_glare) / (τ L_dark + L_glare), L_bright and L_dark the larger
//! and smaller of the symbol and background luminances (either polarity), L_glare the pixel's
//! mean glare luminance. A display pixel whose contrast falls below `min_contrast` is washed out.
//! The sun lights nothing but the paths that meet it (the display's luminances are the user's;
//! the scene's other surfaces keep their own lighting).
//!
//! Per eye point: whether glare is seen, the largest luminance factor and luminance, the glare's
//! mean luminance over its solid angle, the veiling ratio, the solid angle and centroid; over the
//! display: mean τ, the veiling luminance (the glare's mean over the display's pixels), the worst
//! contrast and the washed-out share. Over the eye points: the share that see glare (and that
//! see the display washed out) and the worst one. Sun sweeps and solar days: [`sweep`].

pub mod analysis;
pub use analysis::INFO;
pub mod paths;
pub mod plots;
pub mod report;
mod summary;
pub mod sun;
pub mod sweep;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use specula_scene::{Camera, MaterialKind, Scene};
use specula_trace::reference::Tracer;
use specula_trace::SceneAccel;

use crate::frame::VehicleFrame;
use crate::AnalyzeError;
use paths::{PathTracer, PixelPaths, Roles};
pub use sun::Sun;

/// The version of [`Report`]'s JSON (docs/analyze-glare.schema.json).
pub const SCHEMA_VERSION: u32 = 2;

/// Veiling ratios are capped here where the pixel shows (nearly) nothing but the glare.
pub const MAX_VEILING_RATIO: f64 = 1e6;

/// Contrast ratios are capped here (a display whose dark level is 0, without glare).
pub const MAX_CONTRAST: f64 = 1e6;

/// What a veiling ratio means, said once under each table that prints one.
pub const VEILING_MEANS: &str = "veiling: the glare's luminance over the luminance of what it \
     veils at the same pixel (the largest over the eye point's glare); \"over black\" where what \
     it veils is (nearly) black, so the ratio has no finite value";

/// The washed-out share of the display per eye point and over them, in words: the largest
/// (and which eye point), the mean over all eye points, and how many see any of it washed out.
pub fn washed_out_text(r: &Report) -> Option<String> {
    r.display.as_ref()?;
    let shares: Vec<f64> = r
        .eyes
        .iter()
        .map(|e| e.display.as_ref().map_or(0.0, |d| d.washed_out_share))
        .collect();
    let (worst, largest) =
        shares
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |a, (k, s)| if *s > a.1 { (k, *s) } else { a });
    let mean = shares.iter().sum::<f64>() / shares.len().max(1) as f64;
    let some = shares.iter().filter(|s| **s > 0.0).count();
    Some(format!(
        "the display is washed out over {:.1} % of its area on average over the {} eye points, \
         at most {:.1} % (eye {}); {some} of the {} eye points see some of it washed out",
        mean * 100.0,
        shares.len(),
        largest * 100.0,
        worst + 1,
        shares.len()
    ))
}

/// A veiling ratio as reports print it: "over black" where the glare veils (nearly) nothing,
/// "–" where there is none (the sun's).
pub fn veiling_text(ratio: Option<f64>) -> String {
    match ratio {
        None => "–".into(),
        Some(ratio) if ratio >= MAX_VEILING_RATIO => "over black".into(),
        Some(ratio) => crate::verdict_page::number(ratio, ""),
    }
}

/// A luminance in cd/m² as reports print it (4 significant figures, plain decimals), "–"
/// where not known.
pub fn luminance_text(value: Option<f64>) -> String {
    value.map_or_else(|| "–".into(), |v| crate::verdict_page::number(v, ""))
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(c: Vec3) -> f64 {
    f64::from(0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z)
}

/// What is seen reflected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Source {
    /// A mesh of the scene (unlit or lit).
    Named(usize),
    /// The sun, where paths leave the scene.
    Sun(Sun),
}

/// A display behind the surface and its luminances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Display {
    pub mesh: usize,
    pub symbol_cd_m2: f64,
    pub background_cd_m2: f64,
    /// Contrast ratio below which a display pixel is washed out.
    pub min_contrast: f64,
}

impl Display {
    fn bright_dark(&self) -> (f64, f64) {
        (
            self.symbol_cd_m2.max(self.background_cd_m2),
            self.symbol_cd_m2.min(self.background_cd_m2),
        )
    }

    /// (τ L_bright + L_glare) / (τ L_dark + L_glare), capped at [`MAX_CONTRAST`].
    pub fn contrast(&self, transmittance: f64, glare_cd_m2: f64) -> f64 {
        let (bright, dark) = self.bright_dark();
        let (high, low) = (
            transmittance * bright + glare_cd_m2,
            transmittance * dark + glare_cd_m2,
        );
        if low * MAX_CONTRAST > high {
            high / low
        } else {
            MAX_CONTRAST
        }
    }
}

/// Each eye point's image by default, pixels (the command's `--size`, the viewer's).
pub const DEFAULT_SIZE: (u32, u32) = (320, 240);
/// The luminance factor above which a pixel counts as glare by default (`--threshold`).
pub const DEFAULT_THRESHOLD: f64 = 1e-3;
/// Specular bounces a glare path may take by default (the reference's).
pub const DEFAULT_MAX_DEPTH: u32 = 8;

#[derive(Clone, Debug)]
pub struct Options {
    pub surface: usize,
    pub source: Source,
    /// The named source's luminance, cd/m² (its radiance scaled so that its Y equals it).
    pub source_luminance: Option<f64>,
    pub display: Option<Display>,
    pub width: u32,
    pub height: u32,
    /// Specular bounces a path may take (the reference's `max_depth`).
    pub max_depth: u32,
    /// Luminance factor above which a pixel shows glare.
    pub threshold: f64,
}

fn positive_luminance(option: &'static str, value: f64, zero: bool) -> Result<(), AnalyzeError> {
    if value.is_finite() && (value > 0.0 || (zero && value == 0.0)) {
        return Ok(());
    }
    Err(AnalyzeError::BadOption {
        option,
        reason: format!(
            "{value} cd/m²: a luminance must be a finite number {}",
            if zero { "not below 0" } else { "above 0" }
        ),
    })
}

impl Options {
    /// The defaults for `surface` glaring with `source`: no luminance in cd/m², no display,
    /// [`DEFAULT_SIZE`], [`DEFAULT_MAX_DEPTH`] and [`DEFAULT_THRESHOLD`].
    pub fn new(surface: usize, source: Source) -> Options {
        Options {
            surface,
            source,
            source_luminance: None,
            display: None,
            width: DEFAULT_SIZE.0,
            height: DEFAULT_SIZE.1,
            max_depth: DEFAULT_MAX_DEPTH,
            threshold: DEFAULT_THRESHOLD,
        }
    }

    /// The surface must be a mirror or a glass; a named source and the display neither (they
    /// emit or are lit); luminances finite and not negative.
    pub fn validate(&self, scene: &Scene) -> Result<(), AnalyzeError> {
        let kind = |mesh: usize| &scene.materials[scene.meshes[mesh].material].kind;
        let name = |mesh: usize| scene.meshes[mesh].name.clone();
        let describe = |kind: &MaterialKind| format!("{kind:?}").to_lowercase();
        let emits = |mesh: usize| matches!(kind(mesh), MaterialKind::Unlit | MaterialKind::Diffuse);
        if emits(self.surface) {
            return Err(AnalyzeError::WrongMaterial {
                role: "surface",
                name: name(self.surface),
                kind: describe(kind(self.surface)),
                expected: "a mirror or a glass (a surface that reflects specularly)",
                wanted: crate::Wanted::MirrorOrGlass,
            });
        }
        match self.source {
            Source::Named(source) if !emits(source) => {
                return Err(AnalyzeError::WrongMaterial {
                    role: "source",
                    name: name(source),
                    kind: describe(kind(source)),
                    expected: "an emitting or lit surface (unlit or diffuse)",
                    wanted: crate::Wanted::Emitting,
                })
            }
            Source::Named(_) => {}
            Source::Sun(sun) => {
                sun.validate()?;
                if self.source_luminance.is_some() {
                    return Err(AnalyzeError::BadOption {
                        option: "source_luminance",
                        reason: "the sun's luminance is E/Ω, from `sun_illuminance`".into(),
                    });
                }
            }
        }
        if let Some(l) = self.source_luminance {
            positive_luminance("source_luminance", l, false)?;
        }
        if let Some(display) = &self.display {
            self.validate_display(scene, display)?;
        }
        if !(self.threshold.is_finite() && self.threshold >= 0.0) {
            return Err(AnalyzeError::BadOption {
                option: "threshold",
                reason: format!(
                    "{}: a luminance factor (glare over source luminance), finite and not negative",
                    self.threshold
                ),
            });
        }
        if self.width == 0 || self.height == 0 {
            return Err(AnalyzeError::BadOption {
                option: "size",
                reason: format!("{}x{}: the image needs pixels", self.width, self.height),
            });
        }
        Ok(())
    }

    fn validate_display(&self, scene: &Scene, display: &Display) -> Result<(), AnalyzeError> {
        let mesh = &scene.meshes[display.mesh];
        let kind = &scene.materials[mesh.material].kind;
        if display.mesh == self.surface
            || !matches!(kind, MaterialKind::Unlit | MaterialKind::Diffuse)
        {
            return Err(AnalyzeError::WrongMaterial {
                role: "display",
                name: mesh.name.clone(),
                kind: format!("{kind:?}").to_lowercase(),
                expected: "an emitting or lit surface behind the cover (unlit or diffuse)",
                wanted: crate::Wanted::Emitting,
            });
        }
        positive_luminance("symbol_luminance", display.symbol_cd_m2, true)?;
        positive_luminance("background_luminance", display.background_cd_m2, true)?;
        if display.symbol_cd_m2 == display.background_cd_m2 {
            return Err(AnalyzeError::BadOption {
                option: "symbol_luminance",
                reason: format!(
                    "{} cd/m², the background's too: a display with no contrast to keep",
                    display.symbol_cd_m2
                ),
            });
        }
        if !(display.min_contrast.is_finite() && display.min_contrast > 1.0) {
            return Err(AnalyzeError::BadOption {
                option: "min_contrast",
                reason: format!("{}: a contrast ratio above 1", display.min_contrast),
            });
        }
        if matches!(self.source, Source::Named(_)) && self.source_luminance.is_none() {
            return Err(AnalyzeError::BadOption {
                option: "display",
                reason: "the contrast under a named source's glare needs the source's luminance \
                         in cd/m² (`source_luminance`)"
                    .into(),
            });
        }
        Ok(())
    }

    fn roles(&self) -> Roles {
        Roles {
            surface: self.surface,
            source: match self.source {
                Source::Named(mesh) => Some(mesh),
                Source::Sun(_) => None,
            },
            display: self.display.map(|d| d.mesh),
        }
    }
}

/// The display's figures from one eye point.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct EyeDisplay {
    /// Pixels that see the display through the surface.
    pub pixels: usize,
    /// The cover's mean transmittance τ over them.
    pub transmittance: f64,
    /// The glare's mean luminance over them, cd/m².
    pub veiling_luminance_cd_m2: f64,
    /// The lowest contrast ratio among them.
    pub min_contrast: f64,
    /// The contrast ratio without glare, L_bright / L_dark.
    pub contrast_without_glare: f64,
    /// Share of them whose contrast is below the threshold.
    pub washed_out_share: f64,
}

/// One eye point's figures.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct EyeGlare {
    pub position: [f32; 3],
    /// Whether any pixel shows glare.
    pub glare: bool,
    /// The largest luminance factor of the glare's image (its luminance over the source's).
    pub max_luminance_factor: f64,
    /// The largest luminance of the glare's image, cd/m² (null without the source's luminance).
    pub max_luminance_cd_m2: Option<f64>,
    /// The glare's luminance averaged over the solid angle it covers, cd/m².
    pub mean_luminance_cd_m2: Option<f64>,
    /// The largest veiling ratio (a named source's glare over the rest of the pixel; null for
    /// the sun, whose sky is not in the scene's units).
    pub max_veiling_ratio: Option<f64>,
    /// Solid angle the glare covers, sr.
    pub solid_angle_sr: f64,
    /// The glare's centroid in this eye's image (pixels from the top-left corner, weighted by
    /// the glare's luminance); null without glare.
    pub centroid_px: Option<[f32; 2]>,
    /// Pixels that show glare.
    pub glare_pixels: usize,
    /// The display's figures (null without --display).
    pub display: Option<EyeDisplay>,
}

#[derive(Clone, Debug, Serialize)]
pub struct SunReport {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
    pub illuminance_lx: f64,
    /// E/Ω, cd/m².
    pub luminance_cd_m2: f64,
    /// Towards the sun, world space.
    pub direction: [f32; 3],
}

#[derive(Clone, Debug, Serialize)]
pub struct DisplayReport {
    pub name: String,
    pub symbol_luminance_cd_m2: f64,
    pub background_luminance_cd_m2: f64,
    pub min_contrast: f64,
}

/// What `specula analyze glare` reports (docs/analyze-glare.schema.json).
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub schema_version: u32,
    pub scene: String,
    pub surface: String,
    /// The named source, or "sun".
    pub source: String,
    pub source_luminance_cd_m2: Option<f64>,
    /// The sun's position (with a sweep: the worst position's).
    pub sun: Option<SunReport>,
    pub display: Option<DisplayReport>,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    /// A luminance factor.
    pub threshold: f64,
    pub eyes: Vec<EyeGlare>,
    /// Share of the eye points that see glare.
    pub share_with_glare: f64,
    /// Share of the eye points that see some of the display washed out (null without one).
    pub share_washed_out: Option<f64>,
    /// The worst eye point (index into `eyes`): with a display the largest washed-out share
    /// (then the lowest contrast); else the largest veiling ratio for a named source, the
    /// largest luminance factor for the sun; among equals the widest glare. Null when none
    /// sees glare.
    pub worst_eye: Option<usize>,
    /// The sun sweep (null without one).
    pub sweep: Option<sweep::SweepReport>,
}

/// One eye point's images (row-major): what it sees (the sun left out), a named source's glare
/// (scene units; 0 for the sun), the glare's luminance factor and mean luminance (cd/m², 0 where
/// not known), the washed-out display pixels, and the camera.
pub struct EyeImages {
    pub camera: Camera,
    pub radiance: Vec<Vec3>,
    pub glare: Vec<Vec3>,
    pub factor: Vec<f64>,
    pub glare_cd_m2: Vec<f64>,
    pub washed_out: Vec<bool>,
}

pub struct Glare {
    pub report: Report,
    pub images: Vec<EyeImages>,
}

/// The camera of an eye point: at the eye, aimed at the surface's bounding-sphere centre, the
/// sphere filling the frame's narrower side with a tenth to spare (170° at most, where the eye is
/// inside the sphere). None for an eye at the centre itself, which has no direction to look.
pub fn eye_camera(
    scene: &Scene,
    surface: usize,
    eye: Vec3,
    width: u32,
    height: u32,
) -> Option<Camera> {
    let bounds = scene.meshes[surface].bounds();
    let (centre, radius) = (bounds.center(), bounds.radius().max(1e-4));
    if eye.distance(centre) < 1e-6 * (1.0 + radius) {
        return None;
    }
    let distance = eye.distance(centre).max(radius * 1.01);
    let fitted = (2.0 * (radius / distance).asin() * 1.1).min(170f32.to_radians());
    // The field of view is vertical: widen it where the frame is narrower than tall.
    let aspect = width as f32 / height.max(1) as f32;
    let fov_y = if aspect < 1.0 {
        2.0 * ((fitted * 0.5).tan() / aspect).atan()
    } else {
        fitted
    };
    Some(Camera {
        eye,
        target: centre,
        up: Vec3::Y,
        fov_y_deg: fov_y.to_degrees().clamp(0.5, 170.0),
        aspect: None,
    })
}

/// Solid angle of pixel (x, y) of a pinhole camera: its area on the image plane at unit
/// distance times cos³ of its ray's angle to the view axis.
fn pixel_solid_angle(camera: &Camera, x: u32, y: u32, width: u32, height: u32) -> f64 {
    let tan_half = f64::from((camera.fov_y_deg.to_radians() * 0.5).tan());
    let pixel = 2.0 * tan_half / f64::from(height);
    let forward = camera.frame().forward;
    let dir = camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
    let cos = f64::from(dir.dot(forward));
    pixel * pixel * cos * cos * cos
}

/// One eye point's paths, traced once: what every sun position and threshold is judged from.
pub struct EyeTrace {
    pub eye: Vec3,
    pub camera: Camera,
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<PixelPaths>,
    /// Each pixel's solid angle, sr.
    pub solid_angle: Vec<f64>,
}

impl EyeTrace {
    /// Pixels that see the display through the surface.
    fn display_pixels(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.pixels
            .iter()
            .enumerate()
            .filter(|(_, p)| p.display_transmittance > 0.0)
            .map(|(i, p)| (i, p.display_transmittance))
    }
}

/// Traces every eye point's pixels, calling `progress` after each.
pub fn trace_eyes(
    scene: &Scene,
    accel: &SceneAccel,
    eyes: &[Vec3],
    options: &Options,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<EyeTrace>, AnalyzeError> {
    options.validate(scene)?;
    let tracer = PathTracer {
        tracer: Tracer {
            scene,
            accel,
            max_depth: options.max_depth,
        },
        roles: options.roles(),
    };
    let (width, height) = (options.width, options.height);
    let mut traces = Vec::with_capacity(eyes.len());
    for (k, eye) in eyes.iter().enumerate() {
        let camera = eye_camera(scene, options.surface, *eye, width, height).ok_or_else(|| {
            AnalyzeError::BadOption {
                option: "eye",
                reason: format!(
                    "{eye} is the centre of '{}': an eye point there has no direction to look",
                    scene.meshes[options.surface].name
                ),
            }
        })?;
        let pixels: Vec<PixelPaths> = (0..width * height)
            .into_par_iter()
            .map(|i| tracer.pixel(&camera, i % width, i / width, width, height))
            .collect();
        let solid_angle = (0..width * height)
            .map(|i| pixel_solid_angle(&camera, i % width, i / width, width, height))
            .collect();
        traces.push(EyeTrace {
            eye: *eye,
            camera,
            width,
            height,
            pixels,
            solid_angle,
        });
        progress(k + 1);
    }
    if let Some(display) = &options.display {
        if traces.iter().all(|t| t.display_pixels().next().is_none()) {
            return Err(AnalyzeError::BadOption {
                option: "display",
                reason: format!(
                    "'{}' is not behind '{}': no eye point sees it through the surface",
                    scene.meshes[display.mesh].name, scene.meshes[options.surface].name
                ),
            });
        }
    }
    Ok(traces)
}

/// The glare in one pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelGlare {
    /// Luminance factor of the glare's image in the pixel.
    pub factor: f64,
    /// Share of the pixel the image covers.
    pub covered: f64,
    /// The glare's mean luminance over the pixel, cd/m² (null without the source's luminance).
    pub luminance_cd_m2: Option<f64>,
    /// The named source's glare, scene units (the veiling ratio's numerator).
    pub scene_glare: Option<Vec3>,
}

/// A named source's glare in every pixel that has some, in pixel order.
fn named_glare(trace: &EyeTrace, luminance_cd_m2: Option<f64>) -> Vec<(usize, PixelGlare)> {
    trace
        .pixels
        .iter()
        .enumerate()
        .filter(|(_, p)| p.source_factor > 0.0)
        .map(|(i, p)| {
            let glare = PixelGlare {
                factor: p.source_factor,
                covered: 1.0,
                luminance_cd_m2: luminance_cd_m2.map(|l| l * p.source_factor),
                scene_glare: Some(p.glare),
            };
            (i, glare)
        })
        .collect()
}

/// The sun's glare in a pixel, from its sky exits (all of them, or the candidates an index
/// found: those further from the sun add nothing).
pub fn sun_in_pixel<'a>(
    exits: impl Iterator<Item = &'a paths::SkyExit>,
    sun_dir: Vec3,
    sun_luminance: f64,
) -> Option<PixelGlare> {
    let mut glare = PixelGlare::default();
    let mut luminance = 0.0;
    for exit in exits {
        let coverage = sun::disc_coverage(exit, sun_dir);
        if coverage > 0.0 {
            glare.factor += exit.factor;
            glare.covered += coverage;
            luminance += coverage * exit.factor * sun_luminance;
        }
    }
    (glare.covered > 0.0).then_some(PixelGlare {
        covered: glare.covered.min(1.0),
        luminance_cd_m2: Some(luminance),
        ..glare
    })
}

/// The sun's glare in every pixel of `trace`, tracing nothing: each pixel's sky exits tested.
pub fn sun_glare(trace: &EyeTrace, sun_dir: Vec3, sun_luminance: f64) -> Vec<(usize, PixelGlare)> {
    trace
        .pixels
        .iter()
        .enumerate()
        .filter_map(|(i, p)| sun_in_pixel(p.sky.iter(), sun_dir, sun_luminance).map(|g| (i, g)))
        .collect()
}

/// One eye point's figures from the glare of its pixels (`glare`, in pixel order; the rest
/// have none), and the washed-out pixels.
pub fn eye_figures(
    trace: &EyeTrace,
    glare: &[(usize, PixelGlare)],
    threshold: f64,
    display: Option<&Display>,
) -> (EyeGlare, Vec<usize>) {
    let mut figures = EyeGlare {
        position: trace.eye.to_array(),
        glare: false,
        max_luminance_factor: 0.0,
        max_luminance_cd_m2: None,
        mean_luminance_cd_m2: None,
        max_veiling_ratio: None,
        solid_angle_sr: 0.0,
        centroid_px: None,
        glare_pixels: 0,
        display: None,
    };
    let (mut centroid, mut weight) = (Vec2::ZERO, 0.0f64);
    let (mut luminous, mut covered_sr) = (0.0, 0.0);
    let image_luminance = |g: &PixelGlare| g.luminance_cd_m2.map(|l| l / g.covered);
    for (i, g) in glare {
        if g.factor <= threshold {
            continue;
        }
        let (x, y) = ((*i as u32) % trace.width, (*i as u32) / trace.width);
        figures.glare = true;
        figures.glare_pixels += 1;
        figures.max_luminance_factor = figures.max_luminance_factor.max(g.factor);
        if let Some(l) = image_luminance(g) {
            let max = figures.max_luminance_cd_m2.unwrap_or(0.0);
            figures.max_luminance_cd_m2 = Some(max.max(l));
            luminous += g.luminance_cd_m2.unwrap_or(0.0) * trace.solid_angle[*i];
        }
        if let Some(scene_glare) = g.scene_glare {
            let ratio = veiling_ratio(&trace.pixels[*i], scene_glare);
            figures.max_veiling_ratio = Some(figures.max_veiling_ratio.unwrap_or(0.0).max(ratio));
        }
        covered_sr += g.covered * trace.solid_angle[*i];
        let w = g.factor * g.covered;
        centroid += Vec2::new(x as f32 + 0.5, y as f32 + 0.5) * w as f32;
        weight += w;
    }
    figures.solid_angle_sr = covered_sr;
    if figures.max_luminance_cd_m2.is_some() && covered_sr > 0.0 {
        figures.mean_luminance_cd_m2 = Some(luminous / covered_sr);
    }
    if weight > 0.0 {
        figures.centroid_px = Some((centroid / weight as f32).to_array());
    }
    let mut washed = Vec::new();
    if let Some(display) = display {
        let (d, w) = display_figures(trace, glare, display);
        figures.display = Some(d);
        washed = w;
    }
    (figures, washed)
}

/// A named source's glare over what the pixel shows without it.
fn veiling_ratio(pixel: &PixelPaths, scene_glare: Vec3) -> f64 {
    let glare_y = luminance(scene_glare);
    let without = (luminance(pixel.radiance) - glare_y).max(0.0);
    if without * MAX_VEILING_RATIO > glare_y {
        glare_y / without
    } else {
        MAX_VEILING_RATIO
    }
}

/// The display's figures: pixels without glare all have the contrast without glare.
fn display_figures(
    trace: &EyeTrace,
    glare: &[(usize, PixelGlare)],
    display: &Display,
) -> (EyeDisplay, Vec<usize>) {
    let (bright, dark) = display.bright_dark();
    let clear = display.contrast(1.0, 0.0);
    let (mut pixels, mut transmittance) = (0usize, 0.0);
    let mut washed = Vec::new();
    for (i, tau) in trace.display_pixels() {
        pixels += 1;
        transmittance += tau;
        if clear < display.min_contrast {
            washed.push(i);
        }
    }
    let (mut veiling, mut lowest) = (0.0, if pixels > 0 { clear } else { 0.0 });
    for (i, g) in glare {
        let tau = trace.pixels[*i].display_transmittance;
        if tau <= 0.0 {
            continue;
        }
        let lg = g.luminance_cd_m2.unwrap_or(0.0);
        veiling += lg;
        let contrast = display.contrast(tau, lg);
        lowest = lowest.min(contrast);
        if contrast < display.min_contrast && clear >= display.min_contrast {
            washed.push(*i);
        }
    }
    washed.sort_unstable();
    let share = |n: usize| {
        if pixels > 0 {
            n as f64 / pixels as f64
        } else {
            0.0
        }
    };
    let figures = EyeDisplay {
        pixels,
        transmittance: share(1) * transmittance,
        veiling_luminance_cd_m2: share(1) * veiling,
        min_contrast: lowest,
        contrast_without_glare: if dark > 0.0 {
            (bright / dark).min(MAX_CONTRAST)
        } else {
            MAX_CONTRAST
        },
        washed_out_share: share(washed.len()),
    };
    (figures, washed)
}

/// The worst eye point, as [`Report::worst_eye`] defines it.
pub fn worst_eye(eyes: &[EyeGlare]) -> Option<usize> {
    let washed = |e: &EyeGlare| e.display.as_ref().map_or(0.0, |d| d.washed_out_share);
    let contrast = |e: &EyeGlare| e.display.as_ref().map_or(0.0, |d| -d.min_contrast);
    let strength = |e: &EyeGlare| e.max_veiling_ratio.unwrap_or(e.max_luminance_factor);
    eyes.iter()
        .enumerate()
        .filter(|(_, e)| e.glare || washed(e) > 0.0)
        .max_by(|a, b| {
            washed(a.1)
                .total_cmp(&washed(b.1))
                .then(contrast(a.1).total_cmp(&contrast(b.1)))
                .then(strength(a.1).total_cmp(&strength(b.1)))
                .then(a.1.solid_angle_sr.total_cmp(&b.1.solid_angle_sr))
        })
        .map(|(k, _)| k)
}

/// The glare in every pixel of `trace` from `options`' source (a named one, or the sun).
fn glare_of(trace: &EyeTrace, options: &Options, frame: &VehicleFrame) -> Vec<(usize, PixelGlare)> {
    match options.source {
        Source::Named(_) => named_glare(trace, options.source_luminance),
        Source::Sun(sun) => sun_glare(trace, sun.direction(frame), sun.luminance_cd_m2()),
    }
}

/// One eye point's images.
fn eye_images(trace: &EyeTrace, glare: &[(usize, PixelGlare)], washed: &[usize]) -> EyeImages {
    let n = trace.pixels.len();
    let (mut factor, mut glare_cd_m2) = (vec![0.0; n], vec![0.0; n]);
    for (i, g) in glare {
        factor[*i] = g.factor;
        glare_cd_m2[*i] = g.luminance_cd_m2.unwrap_or(0.0);
    }
    let mut washed_out = vec![false; n];
    for i in washed {
        washed_out[*i] = true;
    }
    EyeImages {
        camera: trace.camera.clone(),
        radiance: trace.pixels.iter().map(|p| p.radiance).collect(),
        glare: trace.pixels.iter().map(|p| p.glare).collect(),
        factor,
        glare_cd_m2,
        washed_out,
    }
}

/// The report's header for `options` (its eyes and the shares left to fill).
fn report_header(scene: &Scene, options: &Options, frame: &VehicleFrame) -> Report {
    let sun = match options.source {
        Source::Sun(sun) => Some(sun_report(&sun, frame)),
        Source::Named(_) => None,
    };
    Report {
        schema_version: SCHEMA_VERSION,
        scene: scene.name.clone(),
        surface: scene.meshes[options.surface].name.clone(),
        source: match options.source {
            Source::Named(mesh) => scene.meshes[mesh].name.clone(),
            Source::Sun(_) => "sun".into(),
        },
        source_luminance_cd_m2: options.source_luminance,
        sun,
        display: options.display.map(|d| DisplayReport {
            name: scene.meshes[d.mesh].name.clone(),
            symbol_luminance_cd_m2: d.symbol_cd_m2,
            background_luminance_cd_m2: d.background_cd_m2,
            min_contrast: d.min_contrast,
        }),
        width: options.width,
        height: options.height,
        max_depth: options.max_depth,
        threshold: options.threshold,
        eyes: Vec::new(),
        share_with_glare: 0.0,
        share_washed_out: None,
        worst_eye: None,
        sweep: None,
    }
}

pub fn sun_report(sun: &Sun, frame: &VehicleFrame) -> SunReport {
    SunReport {
        azimuth_deg: sun.azimuth_deg,
        elevation_deg: sun.elevation_deg,
        illuminance_lx: sun.illuminance_lx,
        luminance_cd_m2: sun.luminance_cd_m2(),
        direction: sun.direction(frame).to_array(),
    }
}

/// Fills the report's eyes, shares and worst eye.
fn with_eyes(mut report: Report, eyes: Vec<EyeGlare>) -> Report {
    let count = eyes.len().max(1) as f64;
    report.share_with_glare = eyes.iter().filter(|e| e.glare).count() as f64 / count;
    if report.display.is_some() {
        let washed = eyes
            .iter()
            .filter(|e| e.display.as_ref().is_some_and(|d| d.washed_out_share > 0.0))
            .count();
        report.share_washed_out = Some(washed as f64 / count);
    }
    report.worst_eye = worst_eye(&eyes);
    report.eyes = eyes;
    report
}

/// Runs the analysis from `eyes` (the sun placed in `frame`), calling `progress` after each
/// eye point.
pub fn analyze(
    scene: &Scene,
    accel: &SceneAccel,
    eyes: &[Vec3],
    frame: &VehicleFrame,
    options: &Options,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Glare, AnalyzeError> {
    let traces = trace_eyes(scene, accel, eyes, options, progress)?;
    let mut figures = Vec::with_capacity(traces.len());
    let mut images = Vec::with_capacity(traces.len());
    for trace in &traces {
        let glare = glare_of(trace, options, frame);
        let (eye, washed) = eye_figures(trace, &glare, options.threshold, options.display.as_ref());
        images.push(eye_images(trace, &glare, &washed));
        figures.push(eye);
    }
    Ok(Glare {
        report: with_eyes(report_header(scene, options, frame), figures),
        images,
    })
}
