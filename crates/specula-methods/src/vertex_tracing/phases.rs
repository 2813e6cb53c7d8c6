//! One frame of vertex tracing taken apart into the phases the paper's Table 1 times apart
//! (`specula-compare`'s `vertex_tracing_table1` bench): the ID buffer, the rest of the scene,
//! and the reflector shaded, which can be run again with other refinement settings on the same
//! ID buffer (which reflectors are traced by their vertices is fixed with the ID buffer, by the
//! settings `visibility` is given: `tracing`, `vertex_ratio`, `min_path_rays`).

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use specula_gpu::GpuContext;
use specula_scene::Camera;
use specula_trace::Image;

use super::compose::RasterComposition;
use super::refine::{OriginalSamples, PackageCounters, Topology};
use super::Params;
use super::{compose_on_raster, FrameSetup, RasterFrame};
use specula_core::live_scene::LiveScene;
use specula_core::raster;
use specula_core::TechniqueError;

/// A frame of `camera`'s view with CPU visibility, its phases run one at a time.
pub struct FramePhases<'a> {
    live: &'a LiveScene,
    camera: &'a Camera,
    max_depth: u32,
    setup: FrameSetup,
}

impl<'a> FramePhases<'a> {
    /// The visibility phase: the scene's topology, the ID buffer of `camera`'s `width` ×
    /// `height` view from CPU primary rays (what `visibility=cpu` and every MPI rank
    /// compute), and the reflector triangles to trace, as the technique finds them with
    /// `settings`; paths are traced to `max_depth` bounces in every phase.
    pub fn visibility(
        live: &'a LiveScene,
        camera: &'a Camera,
        width: u32,
        height: u32,
        settings: Params,
        max_depth: u32,
    ) -> FramePhases<'a> {
        let topology = Arc::new(Topology::new(live.scene()));
        let setup = FrameSetup::traced(
            live, camera, width, height, topology, settings, max_depth, None,
        );
        FramePhases {
            live,
            camera,
            max_depth,
            setup,
        }
    }

    /// The image of everything but the reflectors traced by their vertices (the reference's
    /// shading of each pixel's primary ray), their pixels black.
    pub fn rest_of_scene(&self) -> Image {
        self.setup
            .rest_of_scene(self.live, self.camera, self.max_depth)
            .0
    }

    /// The pixels the reflectors traced by their vertices own in the ID buffer (index y ×
    /// width + x).
    pub fn reflector_pixels(&self) -> impl Iterator<Item = u32> + '_ {
        self.setup.owners.all()
    }

    /// The reflector phase as the technique runs it in one call without a budget: the
    /// original vertices traced once, then the technique's own packages (`package_triangles`
    /// 0) refined and filled in parallel with `settings`, then composed — on the CPU, or with
    /// `raster` on that GPU's raster (`composition=gpu`) — their pixels written into `image`.
    /// Returns the work of all of them together and the milliseconds composition took.
    pub fn shade_reflector(
        &self,
        settings: Params,
        image: &mut Image,
        raster: Option<(&GpuContext, &mut RasterComposition)>,
    ) -> Result<(PackageCounters, f64), TechniqueError> {
        let (live, camera, max_depth) = (self.live, self.camera, self.max_depth);
        let originals = OriginalSamples::trace(
            &self.setup.inputs(live, camera, settings, max_depth),
            &self.setup.active,
        );
        let mut inputs = self.setup.inputs(live, camera, settings, max_depth);
        inputs.originals = Some(&originals);
        let mut packages = self.setup.packages(0);
        packages.par_iter_mut().for_each(|p| {
            p.run(&inputs, None);
        });
        let clock = Instant::now();
        let composed = match raster {
            Some((gpu, composer)) => {
                let (width, height) = (image.width, image.height);
                let uniform = raster::camera_uniform(camera, &live.scene().bounds(), width, height);
                let mut ids_uploaded = false;
                let frame = RasterFrame {
                    ids: &self.setup.surfaces.ids,
                    width,
                    height,
                    ids_uploaded: &mut ids_uploaded,
                };
                let mut warnings = Vec::new();
                compose_on_raster(
                    gpu,
                    composer,
                    frame,
                    &packages,
                    &inputs,
                    &uniform,
                    &mut warnings,
                )?
            }
            None => None,
        };
        let results: Vec<Vec<(u32, Vec3)>> = packages
            .par_iter_mut()
            .map(|p| p.take_pixels(&inputs, composed.as_deref()))
            .collect();
        for (k, c) in results.into_iter().flatten() {
            image.pixels[k as usize] = c;
        }
        let composition_ms = clock.elapsed().as_secs_f64() * 1e3;
        let mut totals = originals.counters;
        for p in &packages {
            totals.add(&p.counters);
        }
        Ok((totals, composition_ms))
    }
}
