//! `reference`: the exact Whitted-style ray tracer (specula-trace) as a technique: the ground
//! truth every other method is judged against. CPU only (rayon); it needs no GPU.
//!
//! Paper: none (Whitted 1980; the semantics are DESIGN.md's "scene semantics").
//!
//! Steps: for each pixel, `spp` rays (one through the centre, or stratified jittered samples)
//! traced through the scene's shared BVH ([`LiveScene::accel`]), both branches at dielectrics,
//! to `max_depth` bounces. A whole image (no budget) is traced in parallel bands of rows
//! written in place, each row's and column's image-plane coordinate computed once
//! ([`specula_trace::reference::trace_image`]).
//!
//! Progressive mode (`budget_ms` > 0; the viewer's): each `render` call works for about
//! `budget_ms` and returns what it has. The image is refined coarse to fine: first every 8th
//! pixel in x and y (each shown as an 8 × 8 block), then the pixels of the 4-grid not yet
//! traced, then the 2-grid, then the rest, so every pixel is traced exactly once and the whole
//! costs one full render. The frame says `converged` once every pixel is traced. Any change of
//! camera, size, parameters or scene version starts over.
//!
//! Approximations: none beyond sampling (the reference defines "exact"); while not converged,
//! untraced pixels show their block's traced corner.
//!
//! ## Parameters
//!
//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;
//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->
//! | parameter | takes | default | a change redoes | what it does |
//! |---|---|---|---|---|
//! | `spp` | a whole number from 1 to 4096 | `1` | uniform | samples per pixel: 1 = the pixel centre; more = stratified jitter, averaged |
//! | `max_depth` | a whole number from 0 to 64 | `8` | uniform | most specular bounces on a path |
//! | `budget_ms` | a whole number from 0 to 60000 | `0` | uniform | progressive mode: milliseconds per call, coarse to fine (0: the whole image at once) |
//! <!-- end of the parameter table -->
//!
//! What they change:
//! - `spp`: samples per pixel. Cost is linear; more smooths edges.
//! - `max_depth`: the most specular bounces on a path. Cost grows with the paths
//!   that need it.
//! - `budget_ms`: the time one call may take in progressive mode; 0 traces the
//!   whole image in one call.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use specula_gpu::StageTimer;
use specula_scene::Camera;
use specula_trace::reference::{pixel_radiance, rays_traced_on_this_thread, trace_image, Tracer};
use specula_trace::Image;

use specula_core::live_scene::LiveScene;
use specula_core::{
    Context, Drawn, Invalidates, MethodInfo, Param, ParamKind, ParamSet, Pixels, Technique,
    TechniqueError, COUNTER_RAYS_TRACED, COUNTER_SHADOW_RAYS,
};

specula_core::params! {
    /// The reference's parameters (the table above).
    pub struct Params {
        spp: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 4096 },
            default: "1",
            doc: "samples per pixel: 1 = the pixel centre; more = stratified jitter, averaged",
            invalidates: Invalidates::Uniform,
        },
        max_depth: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 64 },
            default: "8",
            doc: "most specular bounces on a path",
            invalidates: Invalidates::Uniform,
        },
        budget_ms: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 60000 },
            default: "0",
            doc: "progressive mode: milliseconds per call, coarse to fine (0: the whole image at once)",
            invalidates: Invalidates::Uniform,
        },
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "reference",
    summary: "exact Whitted-style ray tracing on the CPU (the ground truth)",
    exact: true,
    needs_gpu: false,
    gpu_optional: false,
    progressive: true,
    delegates: &[],
    params: Params::SPECS,
    presets: &[],
    create: || Box::new(Reference::default()),
};

/// (x, y, radiance) of one traced pixel.
type TracedPixel = (u32, u32, Vec3);

/// Pixel strides of the progressive levels, coarse to fine.
const LEVELS: [u32; 4] = [8, 4, 2, 1];
/// Side of a work tile in pixels.
const TILE: u32 = 32;

/// What a progressive image was started for: a change of any part starts over.
#[derive(Clone, Debug, PartialEq)]
struct ViewKey {
    camera: Camera,
    width: u32,
    height: u32,
    spp: u32,
    max_depth: u32,
    scene: (u64, u64),
}

struct Progress {
    key: ViewKey,
    image: Image,
    /// Index into LEVELS, and the next tile of that level.
    level: usize,
    next_tile: u32,
}

#[derive(Default)]
pub struct Reference {
    pub params: Params,
    progress: Option<Progress>,
}

/// Whether pixel (x, y) is traced at progressive level `level`: on the level's grid and not on
/// the previous level's (already traced).
fn traced_at(x: u32, y: u32, level: usize) -> bool {
    let on = |s: u32| x.is_multiple_of(s) && y.is_multiple_of(s);
    on(LEVELS[level]) && !(level > 0 && on(LEVELS[level - 1]))
}

impl Technique for Reference {
    fn info(&self) -> &'static MethodInfo {
        &INFO
    }

    fn params(&self) -> &dyn ParamSet {
        &self.params
    }

    fn params_mut(&mut self) -> &mut dyn ParamSet {
        &mut self.params
    }

    fn invalidate(&mut self, _: Invalidates) {
        self.progress = None;
    }

    fn prepare(&mut self, _: &Context, _: &LiveScene) -> Result<(), TechniqueError> {
        // The BVH is the scene's own (LiveScene); nothing else depends on the scene.
        Ok(())
    }

    fn draw(
        &mut self,
        _: &Context,
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Drawn, TechniqueError> {
        let mut timer = StageTimer::wall_clock();
        timer.start(None);
        let (pixels, counters, converged) = if self.params.budget_ms == 0 {
            // The whole image at once (a fresh render, as bench times it).
            self.progress = None;
            let (image, counters) = self.whole_image(live, camera, width, height);
            (image, counters, true)
        } else {
            self.progressive_step(live, camera, width, height)
        };
        timer.lap(None, "ray tracing")?;
        let (stages, timing) = timer.finish(None)?;
        Ok(Drawn {
            pixels: Pixels::Image(pixels),
            stages,
            counters,
            timing,
            warnings: Vec::new(),
            converged,
        })
    }
}

impl Reference {
    fn tracer<'a>(&self, live: &'a LiveScene) -> Tracer<'a> {
        Tracer {
            scene: live.scene(),
            accel: live.accel(),
            max_depth: self.params.max_depth,
        }
    }

    /// The whole image, traced in place in bands of rows, nothing kept.
    fn whole_image(
        &self,
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> (Image, Vec<(String, u64)>) {
        let spp = self.params.spp;
        let pixel_rays = camera.pixel_rays(width, height);
        let mut image = Image::new(width, height);
        let (rays_traced, shadow_rays) =
            trace_image(&self.tracer(live), &pixel_rays, spp, &mut image, &|_, _| {});
        let counters = vec![
            (
                "camera rays".into(),
                width as u64 * height as u64 * spp as u64,
            ),
            (COUNTER_RAYS_TRACED.into(), rays_traced),
            (COUNTER_SHADOW_RAYS.into(), shadow_rays),
            ("pixels per side of a block".into(), 1),
        ];
        (image, counters)
    }

    /// One call of the progressive mode: levels of tiles, coarse to fine, until the budget is
    /// spent. Returns the image so far, the counters and whether it is complete.
    fn progressive_step(
        &mut self,
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> (Image, Vec<(String, u64)>, bool) {
        let start = Instant::now();
        let (spp, budget_ms) = (self.params.spp, self.params.budget_ms);
        let tracer = self.tracer(live);
        let pixel_rays = camera.pixel_rays(width, height);
        let key = ViewKey {
            camera: camera.clone(),
            width,
            height,
            spp,
            max_depth: self.params.max_depth,
            scene: (live.id(), live.version()),
        };
        if self.progress.as_ref().is_none_or(|p| p.key != key) {
            self.progress = Some(Progress {
                key,
                image: Image::new(width, height),
                level: 0,
                next_tile: 0,
            });
        }
        let progress = self.progress.as_mut().expect("set above");
        let (tiles_x, tiles_y) = (width.div_ceil(TILE), height.div_ceil(TILE));
        let tiles = tiles_x * tiles_y;
        let batch = (rayon::current_num_threads() as u32 * 2).max(1);
        let (mut camera_rays, mut rays_traced, mut shadow_rays) = (0u64, 0u64, 0u64);
        while progress.level < LEVELS.len() {
            let level = progress.level;
            let stride = LEVELS[level];
            let end = (progress.next_tile + batch).min(tiles);
            let tiles_traced: Vec<(Vec<TracedPixel>, (u64, u64))> = (progress.next_tile..end)
                .into_par_iter()
                .map(|tile| {
                    let (x0, y0) = ((tile % tiles_x) * TILE, (tile / tiles_x) * TILE);
                    let before = rays_traced_on_this_thread();
                    let pixels: Vec<TracedPixel> = (y0..(y0 + TILE).min(height))
                        .flat_map(|y| {
                            (x0..(x0 + TILE).min(width))
                                .filter(move |&x| traced_at(x, y, level))
                                .map(move |x| (x, y))
                        })
                        .map(|(x, y)| (x, y, pixel_radiance(&tracer, &pixel_rays, x, y, spp)))
                        .collect();
                    let after = rays_traced_on_this_thread();
                    (pixels, (after.0 - before.0, after.1 - before.1))
                })
                .collect();
            let mut traced = Vec::new();
            for (pixels, (rays, shadow)) in tiles_traced {
                camera_rays += pixels.len() as u64 * spp as u64;
                rays_traced += rays;
                shadow_rays += shadow;
                traced.extend(pixels);
            }
            for (x, y, radiance) in traced {
                for by in y..(y + stride).min(height) {
                    for bx in x..(x + stride).min(width) {
                        progress.image.pixels[(by * width + bx) as usize] = radiance;
                    }
                }
            }
            progress.next_tile = end;
            if end == tiles {
                progress.level += 1;
                progress.next_tile = 0;
            }
            if start.elapsed().as_millis() as u32 >= budget_ms {
                break;
            }
        }
        let converged = progress.level == LEVELS.len();
        let counters = vec![
            ("camera rays".into(), camera_rays),
            (COUNTER_RAYS_TRACED.into(), rays_traced),
            (COUNTER_SHADOW_RAYS.into(), shadow_rays),
            // The largest block still shown: the last finished level's stride (the first
            // level's while it runs).
            (
                "pixels per side of a block".into(),
                if converged {
                    1
                } else {
                    LEVELS[progress.level.saturating_sub(1)] as u64
                },
            ),
        ];
        (progress.image.clone(), counters, converged)
    }
}
