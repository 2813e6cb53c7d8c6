//! `specula analyze glare`: whether, where and how brightly a light source is seen reflected in
//! a surface (a truck's instrument cover reflecting the side window over the dial), from each
//! eye point.
//!
//! Per eye point a camera at the eye is aimed at the surface's bounding-sphere centre, its field
//! of view fitted to that sphere. Each pixel's path is followed as the reference follows it
//! (the same Fresnel factors: a mirror's Schlick term or constant F0; a dielectric's exact
//! unpolarised reflectance R, R × the reflected branch plus (1 − R) × the refracted one, total
//! internal reflection sending everything to the reflected branch, one path per colour
//! channel where the indices differ; a thin sheet's 2R / (1 + R) and the rest straight
//! through), and split: a path's **glare** is the radiance it brings from the source after at
//! least one specular reflection on the surface (its front or, inside a glass, its back face).
//!
//! Figures are dimensionless ratios of luminance Y (Rec. 709 weights of linear RGB): a pixel's
//! **relative luminance** is its glare's Y over the Y of the source's own radiance at the point
//! the path reached; its **veiling ratio** is the glare's Y over the Y of what the pixel shows
//! without the glare (the dial it veils; the reference's radiance minus the glare). A pixel
//! shows glare where its relative luminance exceeds `threshold`. Per eye point: whether glare is
//! seen, the largest relative luminance and veiling ratio, the glare's solid angle and its
//! centroid in the image; over the eye points: the share that see glare and the worst one (the
//! largest veiling ratio).

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use specula_scene::{Camera, MaterialKind, Scene};
use specula_trace::optics::{
    fresnel_dielectric, fresnel_schlick, reflect, refract, thin_sheet_reflectance,
};
use specula_trace::reference::{offset_origin, surface_point, SurfacePoint, Tracer};
use specula_trace::{Ray, SceneAccel};

use crate::AnalyzeError;

/// The version of [`Report`]'s JSON (docs/analyze-glare.schema.json).
pub const SCHEMA_VERSION: u32 = 1;

/// Veiling ratios are capped here where the pixel shows (nearly) nothing but the glare.
pub const MAX_VEILING_RATIO: f64 = 1e6;

/// A veiling ratio as reports print it: "over black" where the glare veils (nearly) nothing.
pub fn veiling_text(ratio: f64) -> String {
    if ratio >= MAX_VEILING_RATIO {
        "over black".into()
    } else {
        format!("{ratio:.4}")
    }
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(c: Vec3) -> f64 {
    f64::from(0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z)
}

#[derive(Clone, Debug)]
pub struct Options {
    pub surface: usize,
    pub source: usize,
    pub width: u32,
    pub height: u32,
    /// Specular bounces a path may take (the reference's `max_depth`).
    pub max_depth: u32,
    /// Relative luminance above which a pixel shows glare.
    pub threshold: f64,
}

impl Options {
    /// The surface must be a mirror or a glass, the source neither (it emits or is lit).
    pub fn validate(&self, scene: &Scene) -> Result<(), AnalyzeError> {
        let kind = |mesh: usize| &scene.materials[scene.meshes[mesh].material].kind;
        let name = |mesh: usize| scene.meshes[mesh].name.clone();
        let describe = |kind: &MaterialKind| format!("{kind:?}").to_lowercase();
        if matches!(
            kind(self.surface),
            MaterialKind::Unlit | MaterialKind::Diffuse
        ) {
            return Err(AnalyzeError::WrongMaterial {
                role: "--surface",
                name: name(self.surface),
                kind: describe(kind(self.surface)),
                expected: "a mirror or a glass (a surface that reflects specularly)",
            });
        }
        if !matches!(
            kind(self.source),
            MaterialKind::Unlit | MaterialKind::Diffuse
        ) {
            return Err(AnalyzeError::WrongMaterial {
                role: "--source",
                name: name(self.source),
                kind: describe(kind(self.source)),
                expected: "an emitting or lit surface (unlit or diffuse)",
            });
        }
        if !(self.threshold.is_finite() && self.threshold >= 0.0) {
            return Err(AnalyzeError::BadOption {
                option: "--threshold",
                reason: format!(
                    "{}: a relative luminance, finite and not negative",
                    self.threshold
                ),
            });
        }
        if self.width == 0 || self.height == 0 {
            return Err(AnalyzeError::BadOption {
                option: "--size",
                reason: format!("{}x{}: the image needs pixels", self.width, self.height),
            });
        }
        Ok(())
    }
}

/// One eye point's figures.
#[derive(Clone, Debug, Serialize)]
pub struct EyeGlare {
    pub position: [f32; 3],
    /// Whether any pixel shows glare.
    pub glare: bool,
    pub max_relative_luminance: f64,
    pub max_veiling_ratio: f64,
    /// Solid angle of the pixels that show glare, sr.
    pub solid_angle_sr: f64,
    /// The glare's centroid in this eye's image (pixels from the top-left corner, weighted by
    /// the glare's luminance); null without glare.
    pub centroid_px: Option<[f32; 2]>,
    /// Pixels that show glare.
    pub glare_pixels: usize,
}

/// What `specula analyze glare` reports (docs/analyze-glare.schema.json).
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub schema_version: u32,
    pub scene: String,
    pub surface: String,
    pub source: String,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub threshold: f64,
    pub eyes: Vec<EyeGlare>,
    /// Share of the eye points that see glare.
    pub share_with_glare: f64,
    /// The eye point with the largest veiling ratio (index into `eyes`; among equal ratios, the
    /// one whose glare covers the largest solid angle); null when none sees glare.
    pub worst_eye: Option<usize>,
}

/// One eye point's images: the reference's radiance, the glare and the relative luminance per
/// pixel (row-major), and the camera they were taken with.
pub struct EyeImages {
    pub camera: Camera,
    pub radiance: Vec<Vec3>,
    pub glare: Vec<Vec3>,
    pub relative: Vec<f64>,
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

/// What a path brings from the source after reflecting on the surface, and the source's own
/// radiance where the strongest such path reached it.
#[derive(Clone, Copy, Default)]
struct Split {
    glare: Vec3,
    /// (weight's luminance, the source's radiance there) of the strongest glare path.
    strongest: Option<(f64, Vec3)>,
}

impl Split {
    fn scaled(self, factor: Vec3) -> Split {
        Split {
            glare: self.glare * factor,
            strongest: self
                .strongest
                .map(|(w, radiance)| (w * luminance(factor), radiance)),
        }
    }

    fn plus(self, other: Split) -> Split {
        let strongest = match (self.strongest, other.strongest) {
            (Some(a), Some(b)) => Some(if a.0 >= b.0 { a } else { b }),
            (a, b) => a.or(b),
        };
        Split {
            glare: self.glare + other.glare,
            strongest,
        }
    }

    fn channel(self, c: usize) -> Split {
        let mut glare = Vec3::ZERO;
        glare[c] = self.glare[c];
        Split { glare, ..self }
    }
}

struct GlareTracer<'a> {
    tracer: Tracer<'a>,
    surface: usize,
    source: usize,
}

impl GlareTracer<'_> {
    fn spawn(
        &self,
        sp: &SurfacePoint,
        dir: Vec3,
        depth: u32,
        via: bool,
        channel: Option<usize>,
    ) -> Split {
        let ray = Ray {
            origin: offset_origin(sp.p, sp.ng, dir),
            dir,
        };
        self.trace(&ray, depth + 1, via, channel)
    }

    /// The glare along `ray`; `via`: the path has reflected on the surface already.
    fn trace(&self, ray: &Ray, depth: u32, via: bool, channel: Option<usize>) -> Split {
        let scene = self.tracer.scene;
        let Some(hit) = self.tracer.accel.intersect(ray, f32::INFINITY) else {
            return Split::default();
        };
        let sp = surface_point(scene, ray, &hit);
        let material = &scene.materials[sp.material];
        let on_surface = hit.mesh as usize == self.surface;
        match material.kind {
            MaterialKind::Unlit | MaterialKind::Diffuse => {
                if !(via && hit.mesh as usize == self.source) {
                    return Split::default();
                }
                let base = material.color
                    * material
                        .texture
                        .map(|t| scene.textures[t].sample(sp.uv))
                        .unwrap_or(Vec3::ONE);
                let radiance = match material.kind {
                    MaterialKind::Unlit => base,
                    _ => self.tracer.diffuse(&sp, base),
                };
                Split {
                    glare: radiance,
                    strongest: Some((1.0, radiance)),
                }
            }
            MaterialKind::Mirror { fresnel } => {
                if depth >= self.tracer.max_depth {
                    return Split::default();
                }
                let cos_i = -ray.dir.dot(sp.ns);
                let f = if fresnel {
                    fresnel_schlick(material.color, cos_i)
                } else {
                    material.color
                };
                let reflected = reflect(ray.dir, sp.ns);
                self.spawn(&sp, reflected, depth, via || on_surface, channel)
                    .scaled(f)
            }
            MaterialKind::Dielectric { ior, thin_walled } => {
                if depth >= self.tracer.max_depth {
                    return Split::default();
                }
                let at = |ior: f32, channel| {
                    self.dielectric(ray, &sp, ior, thin_walled, depth, via, on_surface, channel)
                };
                match channel {
                    None if material.is_dispersive() => (0..3)
                        .map(|c| at(ior[c], Some(c)).channel(c))
                        .fold(Split::default(), Split::plus),
                    None => at(ior.x, None),
                    Some(c) => at(ior[c], Some(c)),
                }
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn dielectric(
        &self,
        ray: &Ray,
        sp: &SurfacePoint,
        ior: f32,
        thin: bool,
        depth: u32,
        via: bool,
        on_surface: bool,
        channel: Option<usize>,
    ) -> Split {
        let cos_i = (-ray.dir.dot(sp.ns)).clamp(0.0, 1.0);
        let reflected = reflect(ray.dir, sp.ns);
        let via_reflected = via || on_surface;
        if thin {
            let r = thin_sheet_reflectance(cos_i, ior);
            return self
                .spawn(sp, reflected, depth, via_reflected, channel)
                .scaled(Vec3::splat(r))
                .plus(
                    self.spawn(sp, ray.dir, depth, via, channel)
                        .scaled(Vec3::splat(1.0 - r)),
                );
        }
        let eta = if sp.backface { ior } else { 1.0 / ior };
        let r = fresnel_dielectric(cos_i, eta);
        match refract(ray.dir, sp.ns, eta) {
            Some(transmitted) if r < 1.0 => {
                let t = self
                    .spawn(sp, transmitted.normalize(), depth, via, channel)
                    .scaled(Vec3::splat(1.0 - r));
                if r > 0.0 {
                    t.plus(
                        self.spawn(sp, reflected, depth, via_reflected, channel)
                            .scaled(Vec3::splat(r)),
                    )
                } else {
                    t
                }
            }
            _ => self.spawn(sp, reflected, depth, via_reflected, channel),
        }
    }
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

/// Runs the analysis from `eyes`, calling `progress` after each eye point.
pub fn analyze(
    scene: &Scene,
    accel: &SceneAccel,
    eyes: &[Vec3],
    options: &Options,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Glare, AnalyzeError> {
    options.validate(scene)?;
    let glare_tracer = GlareTracer {
        tracer: Tracer {
            scene,
            accel,
            max_depth: options.max_depth,
        },
        surface: options.surface,
        source: options.source,
    };
    let (width, height) = (options.width, options.height);
    let mut eye_reports = Vec::with_capacity(eyes.len());
    let mut images = Vec::with_capacity(eyes.len());
    for (k, eye) in eyes.iter().enumerate() {
        let camera = eye_camera(scene, options.surface, *eye, width, height).ok_or_else(|| {
            AnalyzeError::BadOption {
                option: "--eye",
                reason: format!(
                    "{eye} is the centre of '{}': an eye point there has no direction to look",
                    scene.meshes[options.surface].name
                ),
            }
        })?;
        let pixels: Vec<(Vec3, Split)> = (0..width * height)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % width, i / width);
                let dir = camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
                let ray = Ray { origin: *eye, dir };
                (
                    glare_tracer.tracer.radiance(&ray, 0, None),
                    glare_tracer.trace(&ray, 0, false, None),
                )
            })
            .collect();
        let relative: Vec<f64> = pixels
            .iter()
            .map(|(_, split)| match split.strongest {
                Some((_, source)) if luminance(source) > 0.0 => {
                    luminance(split.glare) / luminance(source)
                }
                _ => 0.0,
            })
            .collect();
        let mut figures = EyeGlare {
            position: eye.to_array(),
            glare: false,
            max_relative_luminance: 0.0,
            max_veiling_ratio: 0.0,
            solid_angle_sr: 0.0,
            centroid_px: None,
            glare_pixels: 0,
        };
        let (mut centroid, mut weight) = (Vec2::ZERO, 0.0f64);
        for (i, ((radiance, split), rel)) in pixels.iter().zip(&relative).enumerate() {
            if *rel <= options.threshold {
                continue;
            }
            let (x, y) = (i as u32 % width, i as u32 / width);
            let glare_y = luminance(split.glare);
            let without = (luminance(*radiance) - glare_y).max(0.0);
            let veiling = if without * MAX_VEILING_RATIO > glare_y {
                glare_y / without
            } else {
                MAX_VEILING_RATIO
            };
            figures.glare = true;
            figures.glare_pixels += 1;
            figures.max_relative_luminance = figures.max_relative_luminance.max(*rel);
            figures.max_veiling_ratio = figures.max_veiling_ratio.max(veiling);
            figures.solid_angle_sr += pixel_solid_angle(&camera, x, y, width, height);
            centroid += Vec2::new(x as f32 + 0.5, y as f32 + 0.5) * glare_y as f32;
            weight += glare_y;
        }
        if weight > 0.0 {
            figures.centroid_px = Some((centroid / weight as f32).to_array());
        }
        eye_reports.push(figures);
        images.push(EyeImages {
            camera,
            radiance: pixels.iter().map(|p| p.0).collect(),
            glare: pixels.iter().map(|p| p.1.glare).collect(),
            relative,
        });
        progress(k + 1);
    }
    let with_glare = eye_reports.iter().filter(|e| e.glare).count();
    // The largest veiling ratio; among equals (several "over black"), the widest glare.
    let worst_eye = eye_reports
        .iter()
        .enumerate()
        .filter(|(_, e)| e.glare)
        .max_by(|a, b| {
            a.1.max_veiling_ratio
                .total_cmp(&b.1.max_veiling_ratio)
                .then(a.1.solid_angle_sr.total_cmp(&b.1.solid_angle_sr))
        })
        .map(|(k, _)| k);
    Ok(Glare {
        report: Report {
            schema_version: SCHEMA_VERSION,
            scene: scene.name.clone(),
            surface: scene.meshes[options.surface].name.clone(),
            source: scene.meshes[options.source].name.clone(),
            width,
            height,
            max_depth: options.max_depth,
            threshold: options.threshold,
            share_with_glare: with_glare as f64 / eyes.len().max(1) as f64,
            worst_eye,
            eyes: eye_reports,
        },
        images,
    })
}
