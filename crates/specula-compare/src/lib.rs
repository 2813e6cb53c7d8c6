//! `specula compare`: renders the reference and each technique from the same camera at the same
//! resolution and reports, per technique, its error on the reflector/refractor pixels (a mask
//! from the primary hits, as the G-buffer's IDs) split by surface class: a technique's figures
//! are over the surfaces it shades itself, and those it hands to another method
//! ([`MethodInfo::delegates`]: c3rc's refractors are envmap's) are reported apart, naming that
//! method, since their figure is the delegate's; an error heat-map, its time per stage and its
//! speed-up over the reference; written as a self-contained HTML page and as JSON (schema:
//! docs/compare.schema.json).
//!
//! Like with like: every method, the reference included, is timed the same way. It is prepared
//! (the reference's BVH is built: `build_ms`), renders a first frame that is timed apart (it
//! pays for shader compilation and first use: `first_frame_ms`), then `frames` warm frames;
//! a method's `total_ms` is their median (with the spread), and each speed-up is a warm median
//! over a warm median. Where there is a GPU, each technique's time is also put beside
//! `gpu-trace`'s (the exact answer on the same GPU; timed the same way even when not among the
//! methods compared). A method that fails to prepare or render is a row holding its error
//! (`failed`); the others still run and report.

pub mod metrics;
pub mod suite;
pub mod timing;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use base64::Engine;
use serde::Serialize;
use specula_gpu::TimingSource;
use specula_methods::{
    apply_parameters, apply_setting, by_name, check_settings, Context, Frame, Label, LiveScene,
    MethodInfo, SurfaceClass, Technique, TechniqueError,
};
use specula_scene::Scene;
use specula_trace::reference::primary_hits;
use specula_trace::Image;
pub use timing::Spread;

pub use metrics::Metrics;

/// The version of [`Report`]'s JSON (docs/compare.schema.json). 2: a method's `metrics` is
/// over the surfaces it shades itself (null when none) and `delegated` holds the others;
/// `mirror_pixels` and `refractor_pixels` split the mask. 3: methods are keyed by `label`
/// (`c3rc`, `c3rc:paper`), with the `preset` it runs (null for the defaults). 4: `failed`
/// lists the methods that could not be measured, each with its error. 5: the reference is timed
/// as the methods are, warm (`total_ms` the median of `frames` warm frames, its BVH build and
/// first frame apart, `build_ms` and `first_frame_ms`); every time has its spread (`frame`),
/// every method its `prepare_ms` and `first_frame_ms`, and gpu-trace, the second base, its own
/// (`gpu_trace`).
pub const SCHEMA_VERSION: u32 = 5;

#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Technique(#[from] TechniqueError),
    #[error(transparent)]
    Gpu(#[from] specula_gpu::GpuError),
    #[error("{path}: {message}")]
    Write { path: String, message: String },
    /// Nothing to measure the methods on; `hint` says why (the mirrors and glass are out of
    /// view, or there are none and how to make one: the option `material`, which front ends
    /// show in their own words).
    #[error("the scene has no mirror or dielectric surface in view: nothing to compare; {hint}")]
    EmptyMask { hint: String },
    #[error("{folder}: the folder holds no .toml scene file")]
    NoScenes { folder: String },
}

/// [`CompareError::EmptyMask`] for `scene`: its mirrors and glass are out of view, or it has
/// none and the error says how to make one.
fn empty_mask(scene: &Scene) -> CompareError {
    let mut specular: Vec<&str> = Vec::new();
    for mesh in &scene.meshes {
        if scene.materials[mesh.material].is_specular() && !specular.contains(&&*mesh.name) {
            specular.push(&mesh.name);
        }
    }
    let hint = match specular.as_slice() {
        [] => format!(
            "it has none: make an object one with `material` NAME=mirror (or NAME=glass:IOR); \
             its objects are: {}",
            scene.object_names_listed()
        ),
        names => format!(
            "its mirrors and glass ({}) are out of the camera's view",
            specula_scene::material_override::names_listed(names.iter().copied())
        ),
    };
    CompareError::EmptyMask { hint }
}

#[derive(Clone, Debug)]
pub struct Options {
    pub width: u32,
    pub height: u32,
    /// Labels: a method's name, or the name, a colon and a preset (`c3rc:paper`).
    pub methods: Vec<String>,
    /// Samples per pixel of the reference (1 = pixel centres, as the techniques).
    pub spp: u32,
    pub max_depth: u32,
    /// `NAME=VALUE` technique parameters, applied after the presets to every method that has
    /// them; `LABEL.NAME=VALUE` to that label's only.
    pub parameters: Vec<String>,
    /// Warm frames timed per method, the reference's included (at least 1; the CLI's default
    /// is [`DEFAULT_FRAMES`]).
    pub frames: u32,
}

/// `compare --frames`' default.
pub const DEFAULT_FRAMES: u32 = 3;

/// GPU objects a frame created.
#[derive(Clone, Debug, Serialize)]
pub struct CreatedReport {
    pub textures: u64,
    pub buffers: u64,
    pub bind_groups: u64,
}

#[derive(Clone, Debug, Serialize)]
pub struct StageReport {
    pub stage: String,
    pub ms: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct ReferenceReport {
    pub spp: u32,
    pub max_depth: u32,
    /// The median of its warm frames (BVH kept), as every method's `total_ms`.
    pub total_ms: f64,
    pub frame: Spread,
    /// The scene's BVH build, which every CPU ray query of the run then shares.
    pub build_ms: f64,
    /// Its first frame after the build (wall clock).
    pub first_frame_ms: f64,
    pub image: String,
}

/// How gpu-trace, the second speed-up's base, was timed where it was not among the methods.
#[derive(Clone, Debug, Serialize)]
pub struct BaseReport {
    pub prepare_ms: f64,
    pub first_frame_ms: f64,
    pub frame: Spread,
}

#[derive(Clone, Debug, Serialize)]
pub struct MethodReport {
    /// What the row, its images and the suite's cells are keyed by: `method` or
    /// `method:preset`.
    pub label: String,
    pub method: String,
    /// The preset it runs (null: the method's defaults); `parameters` are the values in force.
    pub preset: Option<String>,
    pub parameters: BTreeMap<String, String>,
    /// "gpu-timestamps" or "cpu-wall-clock".
    pub timing: String,
    /// Each stage's median over the warm frames.
    pub stages: Vec<StageReport>,
    /// The median of its warm frames.
    pub total_ms: f64,
    pub frame: Spread,
    /// `prepare` (scene-only work, wall clock) and its first frame (wall clock: shader
    /// compilation and first use), apart from the warm frames.
    pub prepare_ms: f64,
    pub first_frame_ms: f64,
    /// The reference's warm median over this method's.
    pub speedup_over_reference: f64,
    /// gpu-trace's frame time over this method's (null without a GPU).
    pub speedup_over_gpu_trace: Option<f64>,
    pub counters: BTreeMap<String, u64>,
    /// Its figures on the masked pixels of the surfaces it shades itself (those of the classes
    /// it does not delegate); None (null) when it delegates every masked pixel, e.g. c3rc on a
    /// scene whose only specular surfaces are glass.
    pub metrics: Option<Metrics>,
    /// Per surface class it hands to another method and that is in view: its figures there,
    /// apart (they are the delegate's, not its own).
    pub delegated: Vec<DelegatedReport>,
    pub image: String,
    pub heat_map: String,
    /// Fallbacks the technique reported for this frame.
    pub warnings: Vec<String>,
    /// GPU objects the timed frame created (0 in a steady state).
    pub created: CreatedReport,
}

/// A method's figures on the masked pixels of one surface class it delegates
/// ([`MethodInfo::delegates`]).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DelegatedReport {
    pub material: SurfaceClass,
    /// The method those surfaces are handed to.
    pub delegate: String,
    /// The method's image measured on those pixels: the delegate's figure there, as long as
    /// the delegation is what the method declares (the suite test checks it).
    pub metrics: Metrics,
}

/// A method that failed to prepare or render: its row holds the error instead of figures.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FailedMethod {
    pub label: String,
    pub method: String,
    /// The error and its causes, outermost first.
    pub error: String,
}

/// `error` with its causes, as `anyhow` writes `{:#}`: "outer: inner: innermost".
pub fn error_chain(error: &(dyn std::error::Error + 'static)) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        let cause_text = cause.to_string();
        if !text.ends_with(&cause_text) {
            text.push_str(": ");
            text.push_str(&cause_text);
        }
        source = cause.source();
    }
    text
}

#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub schema_version: u32,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub adapter: String,
    /// Pixels whose primary visible surface (G-buffer ID) is a mirror or dielectric.
    pub mask_pixels: usize,
    /// Of those, the mirror pixels and the dielectric (refractor) pixels.
    pub mirror_pixels: usize,
    pub refractor_pixels: usize,
    pub reference: ReferenceReport,
    /// Warm frames timed per method.
    pub frames: u32,
    /// gpu-trace's warm median frame time on this run's GPU (null without a GPU).
    pub gpu_trace_ms: Option<f64>,
    /// How gpu-trace was timed, where it was timed as the base only (null where it is among
    /// the methods, whose row says it, or without a GPU).
    pub gpu_trace: Option<BaseReport>,
    pub methods: Vec<MethodReport>,
    /// The methods asked for that failed (and gpu-trace where its timing, the second
    /// speed-up's base, failed), in the order asked.
    pub failed: Vec<FailedMethod>,
}

/// The report plus the images it refers to.
pub struct Comparison {
    pub report: Report,
    pub reference: Image,
    /// (image, heat-map) per method, in report order.
    pub method_images: Vec<(Image, image::RgbImage)>,
    /// Per pixel (row-major), the class of the specular surface its primary ray meets; None
    /// off the mask.
    pub classes: Vec<Option<SurfaceClass>>,
}

/// A method's figures from its `image`: on the masked pixels of the classes it shades itself
/// (None where there are none), and apart on those of each class it delegates that is in
/// view. `flip` is the FLIP map of the whole image against `reference`; `classes` the class of
/// each pixel's primary surface.
pub fn method_figures(
    info: &MethodInfo,
    reference: &Image,
    image: &Image,
    flip: &[f32],
    classes: &[Option<SurfaceClass>],
) -> (Option<Metrics>, Vec<DelegatedReport>) {
    let own = metrics::class_mask(classes, |c| info.delegate_for(c).is_none());
    let metrics = own
        .contains(&true)
        .then(|| metrics::measure(reference, image, flip, &own));
    let delegated = info
        .delegates
        .iter()
        .filter_map(|d| {
            let mask = metrics::class_mask(classes, |c| c == d.material);
            mask.contains(&true).then(|| DelegatedReport {
                material: d.material,
                delegate: d.to.to_string(),
                metrics: metrics::measure(reference, image, flip, &mask),
            })
        })
        .collect();
    (metrics, delegated)
}

fn timing_name(t: TimingSource) -> &'static str {
    match t {
        TimingSource::GpuTimestamps => "gpu-timestamps",
        TimingSource::CpuWallClock => "cpu-wall-clock",
    }
}

/// Runs the comparison: the registry's exact method against each of `options.methods`.
pub fn compare(
    scene: &Scene,
    ctx: &Context,
    options: &Options,
    progress: &dyn Fn(&str),
) -> Result<Comparison, CompareError> {
    let (width, height) = (options.width, options.height);
    // Build every technique first so an unknown name or setting fails before any long work.
    let mut techniques = techniques_for(options)?;
    let specular = |mesh: &specula_scene::Mesh| scene.materials[mesh.material].is_specular();
    if !scene.meshes.iter().any(specular) {
        return Err(empty_mask(scene));
    }
    progress("reference");
    let build_start = Instant::now();
    let live = LiveScene::new(scene.clone());
    let build_ms = build_start.elapsed().as_secs_f64() * 1e3;
    let mut reference_method = (specula_methods::exact_method().create)();
    apply_parameters(
        reference_method.as_mut(),
        &[
            format!("spp={}", options.spp),
            format!("max_depth={}", options.max_depth),
        ],
    )?;
    let timed_reference = time_frames(reference_method.as_mut(), ctx, &live, options)?;
    let reference = timed_reference.frame.image(ctx)?;
    let reference_ms = timed_reference.frame_times.median_ms;

    progress("mask");
    // The class of the mirror or dielectric each pixel's primary ray (through the pixel
    // centre, as the G-buffer's) sees; the mask is where there is one.
    let classes = pixel_classes(scene, &live, width, height);
    let count = |class: SurfaceClass| classes.iter().filter(|&&c| c == Some(class)).count();
    let (mirror_pixels, refractor_pixels) =
        (count(SurfaceClass::Mirror), count(SurfaceClass::Refractor));
    let mask_pixels = mirror_pixels + refractor_pixels;
    if mask_pixels == 0 {
        return Err(empty_mask(scene));
    }

    let mut methods = Vec::new();
    let mut method_images = Vec::new();
    let mut failed = Vec::new();
    for (label, technique) in techniques.iter_mut() {
        progress(&label.to_string());
        let measured = (|| {
            let timed = time_frames(technique.as_mut(), ctx, &live, options)?;
            let image = timed.frame.image(ctx)?;
            Ok::<_, TechniqueError>((timed, image))
        })();
        let (timed, image) = match measured {
            Ok(measured) => measured,
            Err(error) => {
                failed.push(FailedMethod {
                    label: label.to_string(),
                    method: technique.name().to_string(),
                    error: error_chain(&error),
                });
                continue;
            }
        };
        let (report, images) = method_report(
            label,
            technique.as_ref(),
            &timed,
            image,
            &reference,
            &classes,
            reference_ms,
        );
        methods.push(report);
        method_images.push(images);
    }
    let (gpu_trace, gpu_trace_ms) =
        gpu_trace_base(&methods, ctx, &live, options, progress, &mut failed)?;
    for m in &mut methods {
        m.speedup_over_gpu_trace = gpu_trace_ms.map(|g| timing::speedup(g, m.total_ms));
    }
    Ok(Comparison {
        report: Report {
            schema_version: SCHEMA_VERSION,
            scene: scene.name.clone(),
            width,
            height,
            adapter: ctx.describe(),
            mask_pixels,
            mirror_pixels,
            refractor_pixels,
            reference: ReferenceReport {
                spp: options.spp,
                max_depth: options.max_depth,
                total_ms: reference_ms,
                frame: timed_reference.frame_times,
                build_ms,
                first_frame_ms: timed_reference.first_frame_ms,
                image: "reference.png".into(),
            },
            frames: options.frames,
            gpu_trace_ms,
            gpu_trace,
            methods,
            failed,
        },
        reference,
        method_images,
        classes,
    })
}

/// The methods of a run, each made with its label's preset and settings.
type Techniques = Vec<(Label, Box<dyn Technique>)>;

/// Every method of the run, made with its preset and settings (an unknown name or setting
/// fails here, before any long work).
fn techniques_for(options: &Options) -> Result<Techniques, CompareError> {
    let labels = Label::parse_list(&options.methods)?;
    check_settings(&labels, &options.parameters)?;
    let techniques = labels
        .iter()
        .map(|label| {
            let mut technique = label.create()?;
            if label.info.name == specula_methods::gpu_trace::INFO.name {
                apply_parameters(
                    technique.as_mut(),
                    &[format!("max_depth={}", options.max_depth)],
                )?;
            }
            for setting in label.settings_for(&options.parameters) {
                apply_setting(technique.as_mut(), setting)?;
            }
            Ok((*label, technique))
        })
        .collect::<Result<Vec<_>, TechniqueError>>()?;
    Ok(techniques)
}

/// The class of the mirror or dielectric each pixel's primary ray (through the pixel centre,
/// as the G-buffer's) sees; the mask is where there is one.
fn pixel_classes(
    scene: &Scene,
    live: &LiveScene,
    width: u32,
    height: u32,
) -> Vec<Option<SurfaceClass>> {
    primary_hits(scene, live.accel(), width, height)
        .iter()
        .map(|hit| {
            hit.and_then(|h| {
                SurfaceClass::of(&scene.materials[scene.meshes[h.mesh as usize].material])
            })
        })
        .collect()
}

/// One method's report and its image and FLIP heat map.
fn method_report(
    label: &Label,
    technique: &dyn Technique,
    timed: &Timed,
    image: Image,
    reference: &Image,
    classes: &[Option<SurfaceClass>],
    reference_ms: f64,
) -> (MethodReport, (Image, image::RgbImage)) {
    let (width, height) = (image.width, image.height);
    let frame = &timed.frame;
    let flip = metrics::flip_map(reference, &image);
    let (metrics, delegated) = method_figures(technique.info(), reference, &image, &flip, classes);
    let total_ms = timed.frame_times.median_ms;
    let report = MethodReport {
        label: label.to_string(),
        method: technique.name().to_string(),
        preset: label.preset.map(|p| p.name.to_string()),
        parameters: technique.parameters().into_iter().collect(),
        timing: timing_name(frame.timing).to_string(),
        stages: timed.stages.clone(),
        total_ms,
        frame: timed.frame_times,
        prepare_ms: timed.prepare_ms,
        first_frame_ms: timed.first_frame_ms,
        speedup_over_reference: timing::speedup(reference_ms, total_ms),
        speedup_over_gpu_trace: None,
        counters: frame.counters.iter().cloned().collect(),
        metrics,
        delegated,
        image: format!("{}.png", label.file_stem()),
        heat_map: format!("{}-flip.png", label.file_stem()),
        warnings: frame.warnings.clone(),
        created: CreatedReport {
            textures: frame.created().textures,
            buffers: frame.created().buffers,
            bind_groups: frame.created().bind_groups,
        },
    };
    (report, (image, metrics::heat_map(&flip, width, height)))
}

/// The second speed-up's base, gpu-trace's frame time: from the run where it is one of the
/// methods, else timed apart where the run has a GPU.
fn gpu_trace_base(
    methods: &[MethodReport],
    ctx: &Context,
    live: &LiveScene,
    options: &Options,
    progress: &dyn Fn(&str),
    failed: &mut Vec<FailedMethod>,
) -> Result<(Option<BaseReport>, Option<f64>), CompareError> {
    let mut gpu_trace = None;
    let gpu_trace_ms = match methods
        .iter()
        .find(|m| m.label == specula_methods::gpu_trace::INFO.name)
    {
        Some(m) => Some(m.total_ms),
        None if ctx.gpu.is_some() => {
            progress(specula_methods::gpu_trace::INFO.name);
            let mut base = by_name(specula_methods::gpu_trace::INFO.name)?;
            apply_parameters(base.as_mut(), &[format!("max_depth={}", options.max_depth)])?;
            match time_frames(base.as_mut(), ctx, live, options) {
                Ok(timed) => {
                    gpu_trace = Some(BaseReport {
                        prepare_ms: timed.prepare_ms,
                        first_frame_ms: timed.first_frame_ms,
                        frame: timed.frame_times,
                    });
                    Some(timed.frame_times.median_ms)
                }
                Err(error) => {
                    failed.push(FailedMethod {
                        label: specula_methods::gpu_trace::INFO.name.to_string(),
                        method: specula_methods::gpu_trace::INFO.name.to_string(),
                        error: format!(
                            "timing the second speed-up's base: {}",
                            error_chain(&error)
                        ),
                    });
                    None
                }
            }
        }
        None => None,
    };
    Ok((gpu_trace, gpu_trace_ms))
}

/// A method timed as [`compare`] times every method: prepared, a first frame, then
/// `options.frames` warm frames.
struct Timed {
    prepare_ms: f64,
    first_frame_ms: f64,
    frame_times: Spread,
    /// Each stage's median over the warm frames, in the frames' order.
    stages: Vec<StageReport>,
    /// The last warm frame: its image, counters and warnings are reported.
    frame: Frame,
}

fn time_frames(
    technique: &mut dyn Technique,
    ctx: &Context,
    live: &LiveScene,
    options: &Options,
) -> Result<Timed, TechniqueError> {
    let camera = &live.scene().camera;
    let (width, height) = (options.width, options.height);
    let wall_ms = |start: Instant| start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    technique.prepare(ctx, live)?;
    let prepare_ms = wall_ms(start);
    let start = Instant::now();
    let first = technique.render(ctx, live, camera, width, height)?;
    // A GPU frame is done once its pixels can be read: wait for them, as a warm frame's
    // timestamps do.
    first.image(ctx)?;
    let first_frame_ms = wall_ms(start);
    let mut totals = Vec::new();
    let mut stages: Vec<(String, Vec<f64>)> = Vec::new();
    let mut last = first;
    for _ in 0..options.frames.max(1) {
        last = technique.render(ctx, live, camera, width, height)?;
        totals.push(last.total_milliseconds());
        for s in &last.stages {
            match stages.iter_mut().find(|(name, _)| *name == s.stage) {
                Some((_, times)) => times.push(s.milliseconds),
                None => stages.push((s.stage.clone(), vec![s.milliseconds])),
            }
        }
    }
    Ok(Timed {
        prepare_ms,
        first_frame_ms,
        frame_times: Spread::of(totals),
        stages: stages
            .into_iter()
            .map(|(stage, times)| StageReport {
                stage,
                ms: Spread::of(times).median_ms,
            })
            .collect(),
        frame: last,
    })
}

pub(crate) fn write_error(path: &Path, e: impl std::fmt::Display) -> CompareError {
    CompareError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

fn png_bytes(img: &image::RgbImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .expect("PNG encodes in memory");
    bytes
}

fn data_uri(img: &image::RgbImage) -> String {
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png_bytes(img))
    )
}

/// RMSE, PSNR, mean FLIP and the share over 0.1, as four table cells.
fn metric_cells(m: &Metrics) -> String {
    format!(
        "<td>{:.4}</td><td>{}</td><td>{:.4}</td><td>{:.1} %</td>",
        m.rmse,
        m.psnr_db
            .map(|p| format!("{p:.1}"))
            .unwrap_or_else(|| "∞".into()),
        m.mean_flip,
        m.share_flip_over_0_1 * 100.0
    )
}

pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

impl Comparison {
    /// Writes `report.html` (self-contained: images embedded), `report.json` and the PNGs into
    /// `dir`; returns the HTML's path.
    pub fn write_report(&self, dir: &Path) -> Result<PathBuf, CompareError> {
        std::fs::create_dir_all(dir).map_err(|e| write_error(dir, e))?;
        let save = |name: &str, img: &image::RgbImage| {
            let path = dir.join(name);
            img.save(&path).map_err(|e| write_error(&path, e))
        };
        let reference = self.reference.to_srgb8();
        save(&self.report.reference.image, &reference)?;
        for (m, (img, heat)) in self.report.methods.iter().zip(&self.method_images) {
            save(&m.image, &img.to_srgb8())?;
            save(&m.heat_map, heat)?;
        }
        self.write_json(&dir.join("report.json"))?;
        let path = dir.join("report.html");
        std::fs::write(&path, self.html()).map_err(|e| write_error(&path, e))?;
        Ok(path)
    }

    pub fn write_json(&self, path: &Path) -> Result<(), CompareError> {
        let text = serde_json::to_string_pretty(&self.report).map_err(|e| write_error(path, e))?;
        std::fs::write(path, text).map_err(|e| write_error(path, e))
    }

    pub fn html(&self) -> String {
        let r = &self.report;
        let rows = self.table_rows();
        let figures = self.figures();
        format!(
            r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>specula compare: {scene}</title>
<style>
body {{ font-family: sans-serif; margin: 2em; background: #fafafa; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
td, th {{ border: 1px solid #bbb; padding: 4px 8px; text-align: right; vertical-align: top; }}
td:first-child, th:first-child {{ text-align: left; }}
tr.delegated td {{ color: #666; font-style: italic; }}
tr.failed td {{ color: #a00; text-align: left; }}
#figures {{ display: flex; flex-wrap: wrap; gap: 1em; align-items: flex-start; }}
#figures > div {{ width: {display_width}px; }}
#figures small {{ overflow-wrap: anywhere; }}
img {{ image-rendering: pixelated; width: {display_width}px; display: block; margin: 0.3em 0; }}
</style></head><body>
<h1>specula compare: {scene}</h1>
<p>{width}×{height} pixels on {adapter}. Errors are measured on the {mask} pixels whose visible surface is a mirror or
dielectric ({mirrors} mirror, {refractors} refractor; from the primary hits, as the G-buffer's IDs): RMSE and PSNR on
linear radiance clamped to [0, 1]; FLIP on the sRGB images. A method's row counts the surfaces it shades itself; the
surfaces it hands to another method (c3rc's refractors are envmap's) are on a row of their own below it, naming that
method: that figure is the other method's. A method that failed is a row with its error.
Times compare like with like: every method, the CPU reference included, is prepared and renders a first frame
(timed apart), then {frames} warm frames; "frame" is their median (min–max below it), and each stage its median.
Speed-up is the reference's warm median ({reference:.1} ms; its BVH build, {build:.1} ms, and first frame,
{first:.1} ms, are not in it) over the method's; the next column is gpu-trace's warm median on the same GPU over
the method's ({gpu_trace}).</p>
<table>
<tr><th>method</th><th>RMSE</th><th>PSNR (dB)</th><th>mean FLIP</th><th>FLIP &gt; 0.1</th><th>frame (ms)</th><th>prepare (ms)</th><th>speed-up over reference (warm / warm)</th><th>vs gpu-trace (warm / warm)</th><th>stages (ms)</th><th>timing</th></tr>
{rows}</table>
<div id="figures">
{figures}</div>
</body></html>
"#,
            scene = escape(&r.scene),
            width = r.width,
            height = r.height,
            adapter = escape(&r.adapter),
            mask = r.mask_pixels,
            mirrors = r.mirror_pixels,
            refractors = r.refractor_pixels,
            display_width = r.width.clamp(256, 512),
            frames = r.frames,
            reference = r.reference.total_ms,
            build = r.reference.build_ms,
            first = r.reference.first_frame_ms,
            gpu_trace = r
                .gpu_trace_ms
                .map(|g| format!("gpu-trace {g:.1} ms warm"))
                .unwrap_or_else(|| "no GPU in this run".into()),
        )
    }
    /// The table's rows: per method its figures (warnings above, the surfaces it delegates
    /// below), then the methods that failed.
    fn table_rows(&self) -> String {
        let r = &self.report;
        let mut rows = String::new();
        for m in &r.methods {
            let stages: Vec<String> = m
                .stages
                .iter()
                .map(|s| format!("{} {:.2}", escape(&s.stage), s.ms))
                .collect();
            for warning in &m.warnings {
                rows.push_str(&format!(
                    "<tr><td colspan=\"11\">⚠ {}</td></tr>\n",
                    escape(warning)
                ));
            }
            let own = match &m.metrics {
                Some(metrics) => metric_cells(metrics),
                None => "<td colspan=\"4\">none of its own: every pixel delegated (below)</td>"
                    .to_string(),
            };
            rows.push_str(&format!(
                "<tr><td>{}</td>{own}<td>{:.2}<br><small>{:.2}–{:.2}</small></td><td>{:.2}<br><small>first {:.1}</small></td><td>{:.2}×</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                escape(&m.label),
                m.total_ms,
                m.frame.min_ms,
                m.frame.max_ms,
                m.prepare_ms,
                m.first_frame_ms,
                m.speedup_over_reference,
                m.speedup_over_gpu_trace.map(|v| format!("{v:.2}×")).unwrap_or_else(|| "–".into()),
                stages.join("<br>"),
                escape(&m.timing),
            ));
            for d in &m.delegated {
                rows.push_str(&format!(
                    "<tr class=\"delegated\"><td>↳ {} {} pixels</td>{}<td colspan=\"6\">shaded by {}: its figure, not {}'s own</td></tr>\n",
                    d.metrics.mask_pixels,
                    d.material,
                    metric_cells(&d.metrics),
                    escape(&d.delegate),
                    escape(&m.label),
                ));
            }
        }
        for f in &r.failed {
            rows.push_str(&format!(
                "<tr class=\"failed\"><td>{}</td><td colspan=\"10\">failed: {}</td></tr>\n",
                escape(&f.label),
                escape(&f.error)
            ));
        }
        rows
    }

    /// The reference, then each method's image and its FLIP heat map.
    fn figures(&self) -> String {
        let r = &self.report;
        // One column each: the reference, then each method's image above its FLIP map.
        let mut figures = format!(
            "<div><b>reference</b><img src=\"{}\"><small>{} spp, depth {}; warm frame {:.1} ms, BVH build {:.1} ms, first frame {:.1} ms</small></div>\n",
            data_uri(&self.reference.to_srgb8()),
            r.reference.spp,
            r.reference.max_depth,
            r.reference.total_ms,
            r.reference.build_ms,
            r.reference.first_frame_ms
        );
        for (m, (img, heat)) in r.methods.iter().zip(&self.method_images) {
            let params: Vec<String> = m
                .parameters
                .iter()
                .map(|(k, v)| format!("{}={}", escape(k), escape(v)))
                .collect();
            figures.push_str(&format!(
                "<div><b>{}</b><img src=\"{}\"><img src=\"{}\"><small>above: its FLIP error (black = none, yellow = large)</small><details><summary><small>parameters</small></summary><small>{}</small></details></div>\n",
                escape(&m.label),
                data_uri(&img.to_srgb8()),
                data_uri(heat),
                params.join(", "),
            ));
        }
        figures
    }
}
