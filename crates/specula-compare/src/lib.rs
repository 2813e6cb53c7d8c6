//! `specula compare`: renders the reference and each technique from the same camera at the same
//! resolution and reports, per technique, its error on the reflector/refractor pixels (a mask
//! from the primary hits, as the G-buffer's IDs) split by surface class: a technique's figures
//! are over the surfaces it shades itself, and those it hands to another method
//! ([`MethodInfo::delegates`]: c3rc's refractors are envmap's) are reported apart, naming that
//! method, since their figure is the delegate's; an error heat-map, its time per stage and its
//! speed-up over the reference; written as a self-contained HTML page and as JSON (schema:
//! docs/compare.schema.json). A technique's time is that of its second frame (the first pays
//! for shader compilation); the reference's is its CPU render time, BVH build included. Where
//! there is a GPU, each technique's time is also put beside `gpu-trace`'s (the exact answer on
//! the same GPU; timed even when not among the methods compared). A method that fails to
//! prepare or render is a row holding its error (`failed`); the others still run and report.

pub mod metrics;
pub mod suite;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use base64::Engine;
use serde::Serialize;
use specula_gpu::TimingSource;
use specula_methods::{
    apply_parameters, apply_setting, by_name, check_settings, Context, Label, LiveScene,
    MethodInfo, SurfaceClass, TechniqueError,
};
use specula_scene::Scene;
use specula_trace::reference::primary_hits;
use specula_trace::Image;

pub use metrics::Metrics;

/// The version of [`Report`]'s JSON (docs/compare.schema.json). 2: a method's `metrics` is
/// over the surfaces it shades itself (null when none) and `delegated` holds the others;
/// `mirror_pixels` and `refractor_pixels` split the mask. 3: methods are keyed by `label`
/// (`c3rc`, `c3rc:paper`), with the `preset` it runs (null for the defaults). 4: `failed`
/// lists the methods that could not be measured, each with its error.
pub const SCHEMA_VERSION: u32 = 4;

#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Technique(#[from] TechniqueError),
    #[error(transparent)]
    Gpu(#[from] specula_gpu::GpuError),
    #[error("{path}: {message}")]
    Write { path: String, message: String },
    #[error("the scene has no mirror or dielectric surface in view: nothing to compare")]
    EmptyMask,
    #[error("{folder}: the folder holds no .toml scene file")]
    NoScenes { folder: String },
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
}

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
    pub total_ms: f64,
    pub image: String,
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
    pub stages: Vec<StageReport>,
    pub total_ms: f64,
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
    /// gpu-trace's frame time on this run's GPU (null without a GPU).
    pub gpu_trace_ms: Option<f64>,
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
    let labels = Label::parse_list(&options.methods)?;
    check_settings(&labels, &options.parameters)?;
    let mut techniques = labels
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

    progress("reference");
    let start = Instant::now();
    let live = LiveScene::new(scene.clone());
    let mut reference_method = (specula_methods::exact_method().create)();
    apply_parameters(
        reference_method.as_mut(),
        &[
            format!("spp={}", options.spp),
            format!("max_depth={}", options.max_depth),
        ],
    )?;
    let reference = reference_method
        .render(ctx, &live, &scene.camera, width, height)?
        .image(ctx)?;
    let reference_ms = start.elapsed().as_secs_f64() * 1e3;

    progress("mask");
    // The class of the mirror or dielectric each pixel's primary ray (through the pixel
    // centre, as the G-buffer's) sees; the mask is where there is one.
    let classes: Vec<Option<SurfaceClass>> = primary_hits(scene, live.accel(), width, height)
        .iter()
        .map(|hit| {
            hit.and_then(|h| {
                SurfaceClass::of(&scene.materials[scene.meshes[h.mesh as usize].material])
            })
        })
        .collect();
    let count = |class: SurfaceClass| classes.iter().filter(|&&c| c == Some(class)).count();
    let (mirror_pixels, refractor_pixels) =
        (count(SurfaceClass::Mirror), count(SurfaceClass::Refractor));
    let mask_pixels = mirror_pixels + refractor_pixels;
    if mask_pixels == 0 {
        return Err(CompareError::EmptyMask);
    }

    let mut methods = Vec::new();
    let mut method_images = Vec::new();
    let mut failed = Vec::new();
    for (label, technique) in techniques.iter_mut() {
        progress(&label.to_string());
        let measured = (|| {
            technique.prepare(ctx, &live)?;
            // One untimed frame first: the first frame pays for shader compilation and first
            // use.
            technique.render(ctx, &live, &scene.camera, width, height)?;
            let frame = technique.render(ctx, &live, &scene.camera, width, height)?;
            let image = frame.image(ctx)?;
            Ok::<_, TechniqueError>((frame, image))
        })();
        let (frame, image) = match measured {
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
        let flip = metrics::flip_map(&reference, &image);
        let (metrics, delegated) =
            method_figures(technique.info(), &reference, &image, &flip, &classes);
        let total_ms = frame.total_milliseconds();
        methods.push(MethodReport {
            label: label.to_string(),
            method: technique.name().to_string(),
            preset: label.preset.map(|p| p.name.to_string()),
            parameters: technique.parameters().into_iter().collect(),
            timing: timing_name(frame.timing).to_string(),
            stages: frame
                .stages
                .iter()
                .map(|s| StageReport {
                    stage: s.stage.clone(),
                    ms: s.milliseconds,
                })
                .collect(),
            total_ms,
            speedup_over_reference: reference_ms / total_ms.max(1e-9),
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
        });
        method_images.push((image, metrics::heat_map(&flip, width, height)));
    }
    let gpu_trace_ms = match methods
        .iter()
        .find(|m| m.label == specula_methods::gpu_trace::INFO.name)
    {
        Some(m) => Some(m.total_ms),
        None if ctx.gpu.is_some() => {
            progress(specula_methods::gpu_trace::INFO.name);
            let mut gpu_trace = by_name(specula_methods::gpu_trace::INFO.name)?;
            apply_parameters(
                gpu_trace.as_mut(),
                &[format!("max_depth={}", options.max_depth)],
            )?;
            let timed = (|| {
                gpu_trace.prepare(ctx, &live)?;
                gpu_trace.render(ctx, &live, &scene.camera, width, height)?;
                let frame = gpu_trace.render(ctx, &live, &scene.camera, width, height)?;
                Ok::<_, TechniqueError>(frame.total_milliseconds())
            })();
            match timed {
                Ok(ms) => Some(ms),
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
    for m in &mut methods {
        m.speedup_over_gpu_trace = gpu_trace_ms.map(|g| g / m.total_ms.max(1e-9));
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
                image: "reference.png".into(),
            },
            gpu_trace_ms,
            methods,
            failed,
        },
        reference,
        method_images,
        classes,
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
        let mut rows = String::new();
        for m in &r.methods {
            let stages: Vec<String> = m
                .stages
                .iter()
                .map(|s| format!("{} {:.2}", escape(&s.stage), s.ms))
                .collect();
            for warning in &m.warnings {
                rows.push_str(&format!(
                    "<tr><td colspan=\"10\">⚠ {}</td></tr>\n",
                    escape(warning)
                ));
            }
            let own = match &m.metrics {
                Some(metrics) => metric_cells(metrics),
                None => "<td colspan=\"4\">none of its own: every pixel delegated (below)</td>"
                    .to_string(),
            };
            rows.push_str(&format!(
                "<tr><td>{}</td>{own}<td>{:.2}</td><td>{:.1}×</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                escape(&m.label),
                m.total_ms,
                m.speedup_over_reference,
                m.speedup_over_gpu_trace.map(|v| format!("{v:.2}×")).unwrap_or_else(|| "–".into()),
                stages.join("<br>"),
                escape(&m.timing),
            ));
            for d in &m.delegated {
                rows.push_str(&format!(
                    "<tr class=\"delegated\"><td>↳ {} {} pixels</td>{}<td colspan=\"5\">shaded by {}: its figure, not {}'s own</td></tr>\n",
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
                "<tr class=\"failed\"><td>{}</td><td colspan=\"9\">failed: {}</td></tr>\n",
                escape(&f.label),
                escape(&f.error)
            ));
        }
        let mut figures = format!(
            "<figure><img src=\"{}\"><figcaption>reference ({} spp, depth {}, {:.1} ms)</figcaption></figure>\n",
            data_uri(&self.reference.to_srgb8()),
            r.reference.spp,
            r.reference.max_depth,
            r.reference.total_ms
        );
        for (m, (img, heat)) in r.methods.iter().zip(&self.method_images) {
            let params: Vec<String> = m
                .parameters
                .iter()
                .map(|(k, v)| format!("{}={}", escape(k), escape(v)))
                .collect();
            figures.push_str(&format!(
                "<figure><img src=\"{}\"><figcaption>{} ({})</figcaption></figure>\n<figure><img src=\"{}\"><figcaption>{}: FLIP error (black = none, yellow = large)</figcaption></figure>\n",
                data_uri(&img.to_srgb8()),
                escape(&m.label),
                params.join(", "),
                data_uri(heat),
                escape(&m.label)
            ));
        }
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
figure {{ display: inline-block; margin: 0.5em; }}
img {{ image-rendering: pixelated; width: {display_width}px; }}
</style></head><body>
<h1>specula compare: {scene}</h1>
<p>{width}×{height} pixels on {adapter}. Errors are measured on the {mask} pixels whose visible surface is a mirror or
dielectric ({mirrors} mirror, {refractors} refractor; from the primary hits, as the G-buffer's IDs): RMSE and PSNR on
linear radiance clamped to [0, 1]; FLIP on the sRGB images. A method's row counts the surfaces it shades itself; the
surfaces it hands to another method (c3rc's refractors are envmap's) are on a row of their own below it, naming that
method: that figure is the other method's. A method that failed is a row with its error.
Speed-up is the CPU reference's render time over the technique's frame time; the next column is gpu-trace's frame
time on the same GPU over the technique's ({gpu_trace}).</p>
<table>
<tr><th>method</th><th>RMSE</th><th>PSNR (dB)</th><th>mean FLIP</th><th>FLIP &gt; 0.1</th><th>frame (ms)</th><th>speed-up</th><th>vs gpu-trace</th><th>stages (ms)</th><th>timing</th></tr>
{rows}</table>
{figures}
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
            gpu_trace = r
                .gpu_trace_ms
                .map(|g| format!("gpu-trace {g:.1} ms"))
                .unwrap_or_else(|| "no GPU in this run".into()),
        )
    }
}
