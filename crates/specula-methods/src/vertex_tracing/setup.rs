//! One frame's view of the scene for vertex tracing, the same on every rank: the ID buffer
//! (drawn or traced, the rest of the scene shaded with it), the reflectors' choices, the pixel
//! owners and active triangles, and the packages cut from them.

use std::sync::Arc;
use std::time::Instant;

use specula_scene::Camera;
use specula_trace::reference::{in_tiles, Tracer};
use specula_trace::Image;

use super::choice::ReflectorChoice;
use super::refine::{FrameInputs, Package, PixelOwners, Topology, TriangleId};
use super::{Params, PACKAGES_PER_THREAD};
use specula_core::live_scene::LiveScene;
use specula_core::screen::{PixelSurfaces, ScreenView, ShadeAtOnce};

/// One frame's view of the scene, the same on every rank: the ID buffer, who owns each pixel,
/// and the reflector triangles to trace.
pub(crate) struct FrameSetup {
    pub(crate) view: ScreenView,
    pub(crate) surfaces: PixelSurfaces,
    pub(crate) owners: PixelOwners,
    /// Built once per scene ([`Topology::new`]): a rigid move does not change it.
    pub(crate) topology: Arc<Topology>,
    /// Per scene mesh: a reflector traced by its vertices in this frame.
    by_vertices: Vec<bool>,
    pub(crate) active: Vec<TriangleId>,
    /// What each reflector in sight was counted and how it is traced, in mesh order.
    pub(crate) choices: Vec<ReflectorChoice>,
    /// Milliseconds [`FrameSetup::new`] took to choose ([`ReflectorChoice::from_id_buffer`])
    /// and to find the pixel owners and active triangles of the reflectors traced by vertices.
    pub(crate) choice_ms: f64,
    pub(crate) owners_ms: f64,
}

impl FrameSetup {
    /// From an ID buffer (`surfaces`) of `camera`'s `width` × `height` view, with the scene's
    /// `topology`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
        surfaces: PixelSurfaces,
        topology: Arc<Topology>,
        settings: Params,
        max_depth: u32,
    ) -> FrameSetup {
        let view = ScreenView::new(camera, width, height);
        let scene = live.scene();
        let tracer = Tracer {
            scene,
            accel: live.accel(),
            max_depth,
        };
        let pixel_rays = camera.pixel_rays(width, height);
        let clock = Instant::now();
        let choices = ReflectorChoice::from_id_buffer(
            &tracer,
            &pixel_rays,
            width,
            &surfaces,
            &topology,
            &settings,
        );
        let mut by_vertices: Vec<bool> = (0..scene.meshes.len() as u32)
            .map(|mesh| topology.is_reflector(mesh))
            .collect();
        for choice in choices.iter().filter(|choice| choice.per_pixel) {
            by_vertices[choice.mesh as usize] = false;
        }
        let choice_ms = clock.elapsed().as_secs_f64() * 1e3;
        let clock = Instant::now();
        // Every reflector in sight traced per pixel: no pixel has an owner to find, no
        // triangle is traced by its vertices.
        let any_by_vertices = choices.iter().any(|choice| !choice.per_pixel);
        let owners = if any_by_vertices {
            PixelOwners::new(&surfaces, &by_vertices, scene, &view)
        } else {
            PixelOwners::default()
        };
        let mut setup = FrameSetup {
            view,
            surfaces,
            owners,
            topology,
            by_vertices,
            active: Vec::new(),
            choices,
            choice_ms,
            owners_ms: 0.0,
        };
        if any_by_vertices {
            setup.active = setup
                .inputs(live, camera, settings, max_depth)
                .active_triangles(&setup.by_vertices);
        }
        setup.owners_ms = clock.elapsed().as_secs_f64() * 1e3;
        setup
    }

    /// Whether the pixels showing mesh `mesh` are traced one by one: not a reflector (the rest
    /// of the scene), or a reflector chosen to be traced per pixel.
    fn traced_one_by_one(&self, mesh: u32) -> bool {
        !self.by_vertices[mesh as usize]
    }

    /// The same from the CPU's ID buffer (what every MPI rank computes for itself), traced
    /// into the memory of a `recycled` earlier frame's where given.
    #[allow(clippy::too_many_arguments)]
    pub fn traced(
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
        topology: Arc<Topology>,
        settings: Params,
        max_depth: u32,
        recycled: Option<PixelSurfaces>,
    ) -> FrameSetup {
        let mut surfaces = recycled.unwrap_or_else(PixelSurfaces::empty);
        surfaces.retrace(live.accel(), camera, width, height);
        FrameSetup::new(
            live, camera, width, height, surfaces, topology, settings, max_depth,
        )
    }

    /// [`FrameSetup::traced`] with most of the rest of the scene: every pixel whose first
    /// surface is not a reflector (or is the background), or is a reflector `guess_per_pixel`
    /// marks (the last frame's choice: most likely this frame's), shaded in the ID buffer's own
    /// pass from its fresh hit: one pass over the image instead of two, as the reference makes.
    /// [`FrameSetup::trace_reflectors_per_pixel_but`] the guessed meshes then completes
    /// [`FrameSetup::rest_of_scene`]'s image (the same pixels bit for bit: a pixel's shading
    /// does not depend on when it is done; a guessed reflector chosen by its vertices after all
    /// has its pixels composed over, its rays spent and counted). Returns the setup, the image
    /// and the rays its shading traced.
    #[allow(clippy::too_many_arguments)]
    pub fn traced_shading_the_rest(
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
        topology: Arc<Topology>,
        settings: Params,
        max_depth: u32,
        recycled: Option<PixelSurfaces>,
        guess_per_pixel: &[bool],
    ) -> (FrameSetup, Image, (u64, u64)) {
        let mut surfaces = recycled.unwrap_or_else(PixelSurfaces::empty);
        let tracer = Tracer {
            scene: live.scene(),
            accel: live.accel(),
            max_depth,
        };
        let now = |mesh: Option<u32>| {
            mesh.is_none_or(|mesh| {
                !topology.is_reflector(mesh) || guess_per_pixel.get(mesh as usize) == Some(&true)
            })
        };
        // Only reflector pixels' hits and positions are read again (vertex visibility, filling,
        // the per-pixel choice's sample, reflectors traced per pixel).
        let keep = |mesh: Option<u32>| mesh.is_some_and(|mesh| topology.is_reflector(mesh));
        let shading = ShadeAtOnce {
            tracer: &tracer,
            now: &now,
            keep: &keep,
        };
        let mut image = Image::new(width, height);
        let early = surfaces.retrace_shading(
            live.accel(),
            camera,
            width,
            height,
            Some((&shading, &mut image)),
        );
        let setup = FrameSetup::new(
            live, camera, width, height, surfaces, topology, settings, max_depth,
        );
        (setup, image, early)
    }

    pub fn inputs<'a>(
        &'a self,
        live: &'a LiveScene,
        camera: &'a Camera,
        settings: Params,
        max_depth: u32,
    ) -> FrameInputs<'a> {
        FrameInputs {
            scene: live.scene(),
            accel: live.accel(),
            max_depth,
            camera,
            view: self.view,
            surfaces: &self.surfaces,
            owners: &self.owners,
            topology: &self.topology,
            settings,
            originals: None,
        }
    }

    /// The active triangles `range` (indices into [`FrameSetup::active`]) as one package.
    pub fn package(&self, range: std::ops::Range<usize>) -> Package {
        Package::new(self.active[range].to_vec())
    }

    /// The active triangles cut into packages of `package_triangles` (0: sixteen packages per
    /// rayon thread), in order.
    pub fn packages(&self, package_triangles: usize) -> Vec<Package> {
        let count = self.active.len();
        let size = match package_triangles {
            0 => count
                .div_ceil(PACKAGES_PER_THREAD * rayon::current_num_threads())
                .max(1),
            n => n,
        };
        (0..count)
            .step_by(size)
            .map(|start| self.package(start..(start + size).min(count)))
            .collect()
    }

    /// The image of everything but the reflectors traced by vertices, from the reference's
    /// shading of each pixel's primary ray (the CPU's stand-in for the raster pass's colour),
    /// those reflectors' pixels left black; with the closest-hit and shadow rays it traced.
    pub fn rest_of_scene(
        &self,
        live: &LiveScene,
        camera: &Camera,
        max_depth: u32,
    ) -> (Image, (u64, u64)) {
        let mut image = Image::new(self.view.width, self.view.height);
        let rays = self.trace_pixels(live, camera, max_depth, &mut image, |mesh| {
            mesh.is_none_or(|mesh| self.traced_one_by_one(mesh))
        });
        (image, rays)
    }

    /// Traces into `image` each pixel whose first surface `select` takes (a mesh, or None: the
    /// background): the reference's value, shaded from the ID buffer's
    /// hit where it was traced on the CPU. Returns the closest-hit and shadow rays traced.
    fn trace_pixels(
        &self,
        live: &LiveScene,
        camera: &Camera,
        max_depth: u32,
        image: &mut Image,
        select: impl Fn(Option<u32>) -> bool + Sync,
    ) -> (u64, u64) {
        let width = self.view.width;
        let tracer = Tracer {
            scene: live.scene(),
            accel: live.accel(),
            max_depth,
        };
        let pixel_rays = camera.pixel_rays(width, self.view.height);
        // In the reference's 32 x 32 tiles, written in place: neighbouring secondary rays
        // together (in 16-row bands a glass dragon's frame took 1.20x the reference's).
        in_tiles(&mut image.pixels, width, &|_, _| {}, |x0, y, line| {
            for (x, pixel) in (x0..).zip(line.iter_mut()) {
                let [mesh, _] = self.surfaces.ids[(y * width + x) as usize];
                if select(mesh.checked_sub(1)) {
                    *pixel = self.surfaces.radiance(&tracer, &pixel_rays, x, y, width);
                }
            }
        })
    }

    /// On the raster pass's image (the rest of the scene), the pixels of the reflectors chosen
    /// to be traced per pixel; with the rays traced.
    pub(super) fn trace_reflectors_per_pixel(
        &self,
        live: &LiveScene,
        camera: &Camera,
        max_depth: u32,
        image: &mut Image,
    ) -> (u64, u64) {
        self.trace_reflectors_per_pixel_but(live, camera, max_depth, image, &[])
    }

    /// [`FrameSetup::trace_reflectors_per_pixel`], leaving out the meshes `shaded` marks (their
    /// pixels shaded already).
    pub(super) fn trace_reflectors_per_pixel_but(
        &self,
        live: &LiveScene,
        camera: &Camera,
        max_depth: u32,
        image: &mut Image,
        shaded: &[bool],
    ) -> (u64, u64) {
        let take = |mesh: u32| {
            self.topology.is_reflector(mesh)
                && self.traced_one_by_one(mesh)
                && !shaded.get(mesh as usize).copied().unwrap_or(false)
        };
        if !self.choices.iter().any(|choice| take(choice.mesh)) {
            return (0, 0);
        }
        self.trace_pixels(live, camera, max_depth, image, |mesh| {
            mesh.is_some_and(take)
        })
    }

    /// Per scene mesh: a reflector in sight traced per pixel in this frame (the next frame's
    /// guess, [`FrameSetup::traced_shading_the_rest`]'s `guess_per_pixel`).
    pub(crate) fn per_pixel_meshes(&self) -> Vec<bool> {
        let mut per_pixel = vec![false; self.by_vertices.len()];
        for choice in self.choices.iter().filter(|c| c.per_pixel) {
            per_pixel[choice.mesh as usize] = true;
        }
        per_pixel
    }
}
