//! A progressive vertex-tracing frame in the making: its stages as `bench` and `compare`
//! itemise them, what it holds between calls (set-up, packages, image), and its counters.

use specula_gpu::StageTimer;
use specula_trace::Image;

use super::refine::{OriginalSamples, Package};
use super::{FrameSetup, ViewKey};
use specula_core::{COUNTER_RAYS_TRACED, COUNTER_SHADOW_RAYS};

/// A frame's stages, as `bench` and `compare` itemise them. Without a GPU the first holds the
/// ID buffer's pass, which shades at once every pixel whose first surface is not a reflector
/// traced by vertices (as guessed from the last frame); the fourth, the reflectors traced per
/// pixel that the guess missed. With a GPU the first is the raster pass and its readback, the
/// fourth every reflector traced per pixel.
pub(super) const STAGES: [&str; 6] = [
    "visibility (ID buffer) and the rest of the scene",
    "reflector choice",
    "pixel owners and active triangles",
    "reflectors traced per pixel",
    "reflector: vertex rays, refinement, filling",
    "reflector: composition",
];
pub(super) const VERTICES_STAGE: usize = 4;

/// A timer holding every stage of [`STAGES`], in order, at these times so far.
pub(super) fn stage_timer(milliseconds: [f64; STAGES.len()]) -> StageTimer {
    let mut timer = StageTimer::wall_clock();
    timer.start(None);
    for (stage, ms) in STAGES.iter().zip(milliseconds) {
        timer.measured(stage, ms);
    }
    timer
}
pub(super) const COMPOSITION_STAGE: usize = 5;

pub(super) struct Progress {
    pub(super) key: ViewKey,
    pub(super) setup: FrameSetup,
    pub(super) packages: Vec<Package>,
    pub(super) originals: OriginalSamples,
    pub(super) image: Image,
    /// Milliseconds so far, every one of [`STAGES`] in order.
    pub(super) stages: StageTimer,
    pub(super) rest_rays: (u64, u64),
    /// Whether the ID buffer is on the GPU for composition on the raster.
    pub(super) ids_uploaded: bool,
}

impl Progress {
    /// The frame's counters, as `bench` and `compare` report them: measured where they happen
    /// (the packages' and the original samples' counts, the choice's tallies).
    pub(super) fn counters(&self, scene: &specula_scene::Scene) -> Vec<(String, u64)> {
        let mut totals = self.originals.counters;
        for package in &self.packages {
            totals.add(&package.counters);
        }
        let choices = &self.setup.choices;
        let mut counters = vec![
        (
            "reflector pixels".into(),
            choices.iter().map(|c| c.pixels as u64).sum(),
        ),
        (
            "reflectors traced by their vertices".into(),
            choices.iter().filter(|c| !c.per_pixel).count() as u64,
        ),
        (
            "reflectors traced per pixel".into(),
            choices.iter().filter(|c| c.per_pixel).count() as u64,
        ),
        (
            "reflector pixels traced per pixel".into(),
            choices.iter().filter(|c| c.per_pixel).map(|c| c.pixels as u64).sum(),
        ),
        (
            "vertices of the reflector triangles seen (every reflector)".into(),
            choices.iter().map(|c| c.vertices as u64).sum(),
        ),
        (
            "stray pixels (the ID buffer's triangle cannot be seen there; traced with trace_stray)".into(),
            self.setup.owners.stray() as u64,
        ),
        (
            "reflector triangles traced".into(),
            self.setup.active.len() as u64,
        ),
        ("task packages".into(), self.packages.len() as u64),
        (
            "reflector pixels composed on the GPU raster".into(),
            self.packages.iter().map(|p| p.pixels_from_raster).sum(),
        ),
        ("vertex rays".into(), totals.vertex_rays),
        ("filled pixels".into(), totals.filled_pixels),
        (
            "samples (vertex rays + filled pixels)".into(),
            totals.vertex_rays + totals.filled_pixels,
        ),
        ("edges split".into(), totals.edges_split),
        ("of which for flatness".into(), totals.flat_splits),
        ("unresolved edges".into(), totals.unresolved_edges),
        ("deepest level".into(), totals.deepest_level),
        (
            COUNTER_RAYS_TRACED.into(),
            totals.rays
                + totals.vertex_rays
                + self.rest_rays.0
                + choices.iter().map(|c| c.sample_rays.0).sum::<u64>(),
        ),
        (
            COUNTER_SHADOW_RAYS.into(),
            totals.shadow_rays
                + self.rest_rays.1
                + choices.iter().map(|c| c.sample_rays.1).sum::<u64>(),
        ),
    ];
        for c in choices {
            let name = &scene.meshes[c.mesh as usize].name;
            counters.extend([
                (
                    format!("reflector {name}: vertices of its triangles seen"),
                    c.vertices as u64,
                ),
                (format!("reflector {name}: pixels"), c.pixels as u64),
                (
                    format!("reflector {name}: rays per pixel path x 100 (sampled; 0: not)"),
                    c.path_rays.map_or(0, |rays| (rays * 100.0).round() as u64),
                ),
                (
                    format!("reflector {name}: traced per pixel (1) or by vertices (0)"),
                    c.per_pixel as u64,
                ),
            ]);
        }
        counters
    }
}
