//! The exact reference: a Whitted-style ray tracer over the BVH, with DESIGN.md's semantics.
//!
//! - unlit: base colour × texture;
//! - diffuse: albedo/π × Σ lights (irradiance × cos θ, hard shadows by an any-hit ray) plus
//!   albedo × the scene's ambient radiance;
//! - mirror: F × L(reflected), F = Schlick(F0, cos θ) or F0 when Fresnel is off;
//! - dielectric: exact unpolarised Fresnel R; R × L(reflected) + (1 − R) × L(refracted), both
//!   branches followed; total internal reflection sends everything to the reflected branch; a
//!   dispersive material (one IOR per channel) splits into one ray per RGB channel; thin-walled
//!   sheets reflect ½[2R_s/(1+R_s) + 2R_p/(1+R_p)] (s and p summed apart) and pass the rest
//!   straight through;
//! - a ray that leaves the scene sees the background.
//!
//! `max_depth` bounds the number of specular bounces on a path (reflections and refractions);
//! a ray that would exceed it returns black. With `spp` = 1 each pixel gets exactly one ray
//! through its centre; with more, the samples are stratified in x and in y (Latin hypercube,
//! jittered within strata, deterministic per pixel) and averaged (box filter).

use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use specula_scene::{MaterialKind, Scene};

use crate::accel::{Hit, Ray, SceneAccel};
use crate::image_io::Image;
use crate::optics::{
    fresnel_dielectric, fresnel_schlick, reflect, refract, thin_sheet_reflectance,
};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 640,
            height: 480,
            spp: 1,
            max_depth: 8,
        }
    }
}

/// The side of the square tiles a whole image is traced in.
const TILE: u32 = 32;

/// What the shading at a hit needs: position, normals facing the incoming ray, texture
/// coordinate, and whether the ray arrived from the back of the surface.
pub struct SurfacePoint {
    pub p: Vec3,
    /// Geometric normal, flipped to face the incoming ray.
    pub ng: Vec3,
    /// Interpolated shading normal, on the same side as `ng`.
    pub ns: Vec3,
    pub uv: Vec2,
    /// The ray hit the side opposite to the mesh's stored normals (i.e. it is leaving a solid).
    pub backface: bool,
    pub material: usize,
}

pub fn surface_point(scene: &Scene, ray: &Ray, hit: &Hit) -> SurfacePoint {
    let mesh = &scene.meshes[hit.mesh as usize];
    let [i0, i1, i2] = mesh.triangles[hit.triangle as usize].map(|i| i as usize);
    let b0 = 1.0 - hit.b1 - hit.b2;
    let (p0, p1, p2) = (mesh.positions[i0], mesh.positions[i1], mesh.positions[i2]);
    let p = p0 * b0 + p1 * hit.b1 + p2 * hit.b2;
    let mut ng = (p1 - p0).cross(p2 - p0).normalize();
    let mut ns = (mesh.normals[i0] * b0 + mesh.normals[i1] * hit.b1 + mesh.normals[i2] * hit.b2)
        .try_normalize()
        .unwrap_or(ng);
    // Meshes whose stored normals disagree with the winding: trust the normals' side.
    if ns.dot(ng) < 0.0 {
        ng = -ng;
    }
    let backface = ray.dir.dot(ng) > 0.0;
    if backface {
        ng = -ng;
        ns = -ns;
    }
    let uv = if mesh.uvs.is_empty() {
        Vec2::ZERO
    } else {
        mesh.uvs[i0] * b0 + mesh.uvs[i1] * hit.b1 + mesh.uvs[i2] * hit.b2
    };
    SurfacePoint {
        p,
        ng,
        ns,
        uv,
        backface,
        material: mesh.material,
    }
}

/// Origin for a ray leaving `p` in direction `dir`: pushed off the surface along the geometric
/// normal, on the side `dir` goes, by an amount relative to the coordinates' magnitude so that
/// the new ray does not hit the surface it starts on.
pub fn offset_origin(p: Vec3, ng: Vec3, dir: Vec3) -> Vec3 {
    let eps = 2e-5 * (1.0 + p.abs().max_element());
    if dir.dot(ng) >= 0.0 {
        p + ng * eps
    } else {
        p - ng * eps
    }
}

thread_local! {
    /// Rays this thread has traced: (closest-hit rays, shadow rays).
    static RAYS_TRACED: Cell<(u64, u64)> = const { Cell::new((0, 0)) };
}

/// How many rays the calling thread has traced so far through [`Tracer`]: closest-hit rays
/// (primary and secondary alike) and shadow rays. A caller that wants the rays of some work
/// reads it before and after, on the thread that did the work (a thread-local counter costs
/// nothing next to a ray; an atomic shared by all threads would).
pub fn rays_traced_on_this_thread() -> (u64, u64) {
    RAYS_TRACED.with(Cell::get)
}

fn count_ray(shadow: bool) {
    RAYS_TRACED.with(|c| {
        let (rays, shadows) = c.get();
        c.set(if shadow {
            (rays, shadows + 1)
        } else {
            (rays + 1, shadows)
        });
    });
}

pub struct Tracer<'a> {
    pub scene: &'a Scene,
    pub accel: &'a SceneAccel,
    pub max_depth: u32,
}

/// What a path records of the rays it traces: nothing (the reference), or a [`RayTree`].
pub trait TreeRecorder {
    /// A closest-hit ray of `step` met mesh `mesh` (None: it left the scene).
    fn ray(&mut self, step: Step, mesh: Option<u32>);
    /// The shadow ray towards light `light`, from a surface whose radiance reaches the path's
    /// start with `weight`, was blocked or not.
    fn shadow(&mut self, light: usize, occluded: bool, weight: f32);
    /// The path read a texture (an unlit or diffuse surface's colour).
    fn texture(&mut self, _read: &TextureHit) {}
}

/// A texture read on a path: the path's radiance holds `coefficient` × the texel of `texture`
/// at `uv`, linearly.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TextureHit {
    pub texture: usize,
    pub uv: Vec2,
    pub coefficient: Vec3,
    /// Path length from the path's start to the textured point.
    pub distance: f32,
    /// The textured surface's geometric normal there.
    pub normal: Vec3,
}

/// Why a closest-hit ray was traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Branch {
    Primary = 1,
    Reflected = 2,
    Refracted = 3,
    /// Straight through a thin-walled sheet.
    Through = 4,
}

/// One ray of a path: why it was traced, the factor its radiance is scaled by on the way to
/// the path's start (1 for a primary ray; the Fresnel terms' product after bounces), and how
/// far along the path its origin is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    pub kind: Branch,
    pub throughput: Vec3,
    pub distance: f32,
}

impl Step {
    const PRIMARY: Step = Step {
        kind: Branch::Primary,
        throughput: Vec3::ONE,
        distance: 0.0,
    };

    /// The same ray, its end `t` further along.
    fn advanced(self, t: f32) -> Step {
        Step {
            distance: self.distance + t,
            ..self
        }
    }

    fn child(self, kind: Branch, factor: Vec3) -> Step {
        Step {
            kind,
            throughput: self.throughput * factor,
            distance: self.distance,
        }
    }

    /// The largest channel of the throughput.
    pub fn weight(&self) -> f32 {
        self.throughput.max_element()
    }
}

impl TreeRecorder for () {
    fn ray(&mut self, _: Step, _: Option<u32>) {}
    fn shadow(&mut self, _: usize, _: bool, _: f32) {}
}

/// A path's ray tree (Whitted; Glassner's "ray tree"): which object each reflected, refracted
/// and primary ray met, in depth-first order, and which shadow rays were blocked; rays whose
/// weight is below `min_weight` are left out (a third internal bounce in a glass, whose
/// radiance reaches the eye at 0.01 %, changes the tree but not the picture). Two samples
/// with equal trees see the same objects by the same optical paths under the same lights, so
/// between them the radiance varies smoothly; a changed tree marks a discontinuity (an object's
/// silhouette, a shadow edge, total internal reflection starting). Kept as a 64-bit FNV-1a
/// digest of that sequence and the number of its nodes, so that comparing two trees is one
/// comparison and a tree travels in 12 bytes (two different trees share a digest with
/// probability about 2⁻⁶⁴).
#[derive(Clone, Copy, Debug)]
pub struct RayTree {
    pub digest: u64,
    pub nodes: u32,
    pub min_weight: f32,
}

impl Default for RayTree {
    fn default() -> Self {
        RayTree::with_min_weight(0.0)
    }
}

impl RayTree {
    pub fn with_min_weight(min_weight: f32) -> RayTree {
        RayTree {
            digest: 0xcbf2_9ce4_8422_2325,
            nodes: 0,
            min_weight,
        }
    }

    /// Whether two trees hold the same rays (digest and size).
    pub fn same_as(&self, other: &RayTree) -> bool {
        self.digest == other.digest && self.nodes == other.nodes
    }

    fn push(&mut self, word: u32) {
        for byte in word.to_le_bytes() {
            self.digest = (self.digest ^ byte as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
        self.nodes += 1;
    }
}

impl TreeRecorder for RayTree {
    fn ray(&mut self, step: Step, mesh: Option<u32>) {
        if step.weight() >= self.min_weight {
            self.push(step.kind as u32);
            self.push(mesh.map_or(0, |m| m + 1));
        }
    }

    fn shadow(&mut self, light: usize, occluded: bool, weight: f32) {
        if weight >= self.min_weight {
            self.push(0x8000_0000 | (light as u32) << 1 | occluded as u32);
        }
    }
}

impl Tracer<'_> {
    /// Radiance arriving along `ray` (towards its origin). `channel` is Some(c) once a
    /// dispersive interface has split the path into one ray per colour channel; then only that
    /// component of the result is used.
    pub fn radiance(&self, ray: &Ray, depth: u32, channel: Option<usize>) -> Vec3 {
        self.radiance_recorded(ray, Step::PRIMARY, depth, channel, &mut ())
    }

    /// [`Tracer::radiance`] of a primary ray, with its ray tree.
    pub fn radiance_with_tree(&self, ray: &Ray) -> (Vec3, RayTree) {
        let mut tree = RayTree::default();
        let radiance = self.radiance_recorded(ray, Step::PRIMARY, 0, None, &mut tree);
        (radiance, tree)
    }

    fn radiance_recorded<R: TreeRecorder>(
        &self,
        ray: &Ray,
        step: Step,
        depth: u32,
        channel: Option<usize>,
        tree: &mut R,
    ) -> Vec3 {
        count_ray(false);
        let hit = self.accel.intersect(ray, f32::INFINITY);
        self.shade_or_background(ray, hit.as_ref(), step, depth, channel, tree)
    }

    /// [`Tracer::radiance`] of a primary ray whose closest hit was already found (`None`: it
    /// meets nothing): the same value bit for bit, the ray counted as traced once here.
    pub fn radiance_of_primary(&self, ray: &Ray, hit: Option<&Hit>) -> Vec3 {
        count_ray(false);
        self.shade_or_background(ray, hit, Step::PRIMARY, 0, None, &mut ())
    }

    fn shade_or_background<R: TreeRecorder>(
        &self,
        ray: &Ray,
        hit: Option<&Hit>,
        step: Step,
        depth: u32,
        channel: Option<usize>,
        tree: &mut R,
    ) -> Vec3 {
        let Some(hit) = hit else {
            tree.ray(step, None);
            return self
                .scene
                .background
                .radiance(ray.dir, &self.scene.textures);
        };
        self.shade_recorded(ray, hit, step, depth, channel, tree)
    }

    /// The radiance leaving the known first hit `hit` of the primary ray `ray` towards its
    /// origin, its path told to `recorder`: a path whose primary intersection is given (a vertex the ray
    /// was aimed at) and not searched for. The primary ray is in the tree but not counted as
    /// traced.
    pub fn radiance_at_hit_recorded<R: TreeRecorder>(
        &self,
        ray: &Ray,
        hit: &Hit,
        recorder: &mut R,
    ) -> Vec3 {
        self.shade_recorded(ray, hit, Step::PRIMARY, 0, None, recorder)
    }

    fn shade_recorded<R: TreeRecorder>(
        &self,
        ray: &Ray,
        hit: &Hit,
        step: Step,
        depth: u32,
        channel: Option<usize>,
        tree: &mut R,
    ) -> Vec3 {
        let scene = self.scene;
        tree.ray(step, Some(hit.mesh));
        let material = &scene.materials[scene.meshes[hit.mesh as usize].material];
        // An unlit, untextured surface's radiance is its colour: nothing of the hit is needed.
        if material.kind == MaterialKind::Unlit && material.texture.is_none() {
            return material.color;
        }
        // Children start at this hit.
        let step = step.advanced(hit.t);
        let sp = surface_point(scene, ray, hit);
        let base = || {
            let texture = material
                .texture
                .map(|t| scene.textures[t].sample(sp.uv))
                .unwrap_or(Vec3::ONE);
            material.color * texture
        };
        match material.kind {
            MaterialKind::Unlit => {
                if let Some(texture) = material.texture {
                    tree.texture(&TextureHit {
                        texture,
                        uv: sp.uv,
                        coefficient: step.throughput * material.color,
                        distance: step.distance,
                        normal: sp.ng,
                    });
                }
                base()
            }
            MaterialKind::Diffuse => {
                // Lambert is linear in the albedo: the light it receives, times the albedo.
                let received = self.diffuse_recorded(&sp, Vec3::ONE, step.weight(), tree);
                if let Some(texture) = material.texture {
                    tree.texture(&TextureHit {
                        texture,
                        uv: sp.uv,
                        coefficient: step.throughput * material.color * received,
                        distance: step.distance,
                        normal: sp.ng,
                    });
                }
                base() * received
            }
            MaterialKind::Mirror { fresnel } => {
                if depth >= self.max_depth {
                    return Vec3::ZERO;
                }
                let cos_i = -ray.dir.dot(sp.ns);
                let f = if fresnel {
                    fresnel_schlick(material.color, cos_i)
                } else {
                    material.color
                };
                let reflected = reflect(ray.dir, sp.ns);
                let next = step.child(Branch::Reflected, f);
                f * self.spawn(&sp, reflected, next, depth, channel, tree)
            }
            MaterialKind::Dielectric { ior, thin_walled } => {
                if depth >= self.max_depth {
                    return Vec3::ZERO;
                }
                let mut at = |ior: f32, channel| {
                    self.dielectric(ray, &sp, ior, thin_walled, step, depth, channel, tree)
                };
                match channel {
                    None if material.is_dispersive() => {
                        let mut sum = Vec3::ZERO;
                        for c in 0..3 {
                            sum[c] = at(ior[c], Some(c))[c];
                        }
                        sum
                    }
                    None => at(ior.x, None),
                    Some(c) => at(ior[c], Some(c)),
                }
            }
        }
    }

    /// Radiance a Lambertian surface of `albedo` leaves at `sp` towards the side its normals
    /// face: every light's irradiance where a shadow ray reaches it, plus the ambient term.
    pub fn diffuse(&self, sp: &SurfacePoint, albedo: Vec3) -> Vec3 {
        self.diffuse_recorded(sp, albedo, 1.0, &mut ())
    }

    fn diffuse_recorded<R: TreeRecorder>(
        &self,
        sp: &SurfacePoint,
        albedo: Vec3,
        weight: f32,
        tree: &mut R,
    ) -> Vec3 {
        let mut irradiance = Vec3::ZERO;
        for (index, light) in self.scene.lights.iter().enumerate() {
            let sample = light.sample(sp.p);
            let cos = sp.ns.dot(sample.to_light);
            if cos <= 0.0 || sample.irradiance == Vec3::ZERO {
                continue;
            }
            let shadow = Ray {
                origin: offset_origin(sp.p, sp.ng, sample.to_light),
                dir: sample.to_light,
            };
            count_ray(true);
            let occluded = self.accel.occluded(&shadow, sample.distance);
            tree.shadow(index, occluded, weight);
            if !occluded {
                irradiance += sample.irradiance * cos;
            }
        }
        albedo * (irradiance / std::f32::consts::PI + self.scene.ambient)
    }

    fn spawn<R: TreeRecorder>(
        &self,
        sp: &SurfacePoint,
        dir: Vec3,
        step: Step,
        depth: u32,
        channel: Option<usize>,
        tree: &mut R,
    ) -> Vec3 {
        let ray = Ray {
            origin: offset_origin(sp.p, sp.ng, dir),
            dir,
        };
        self.radiance_recorded(&ray, step, depth + 1, channel, tree)
    }

    #[allow(clippy::too_many_arguments)]
    fn dielectric<R: TreeRecorder>(
        &self,
        ray: &Ray,
        sp: &SurfacePoint,
        ior: f32,
        thin: bool,
        step: Step,
        depth: u32,
        channel: Option<usize>,
        tree: &mut R,
    ) -> Vec3 {
        let cos_i = (-ray.dir.dot(sp.ns)).clamp(0.0, 1.0);
        let reflected = reflect(ray.dir, sp.ns);
        if thin {
            let r = thin_sheet_reflectance(cos_i, ior);
            let (mirrored, through) = (
                step.child(Branch::Reflected, Vec3::splat(r)),
                step.child(Branch::Through, Vec3::splat(1.0 - r)),
            );
            return r * self.spawn(sp, reflected, mirrored, depth, channel, tree)
                + (1.0 - r) * self.spawn(sp, ray.dir, through, depth, channel, tree);
        }
        // Leaving the solid when the ray hit its back face.
        let eta = if sp.backface { ior } else { 1.0 / ior };
        let r = fresnel_dielectric(cos_i, eta);
        match refract(ray.dir, sp.ns, eta) {
            Some(transmitted) if r < 1.0 => {
                let t = self.spawn(
                    sp,
                    transmitted.normalize(),
                    step.child(Branch::Refracted, Vec3::splat(1.0 - r)),
                    depth,
                    channel,
                    tree,
                );
                let rr = if r > 0.0 {
                    let mirrored = step.child(Branch::Reflected, Vec3::splat(r));
                    self.spawn(sp, reflected, mirrored, depth, channel, tree)
                } else {
                    Vec3::ZERO
                };
                r * rr + (1.0 - r) * t
            }
            _ => self.spawn(
                sp,
                reflected,
                step.child(Branch::Reflected, Vec3::ONE),
                depth,
                channel,
                tree,
            ),
        }
    }
}

/// Small deterministic hash-based generator (PCG output function) for sample jitter.
fn hash(mut x: u32) -> u32 {
    x = x.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((x >> ((x >> 28) + 4)) ^ x).wrapping_mul(277803737);
    (word >> 22) ^ word
}

fn unit_float(x: u32) -> f32 {
    (hash(x) >> 8) as f32 / (1u32 << 24) as f32
}

/// Offsets in [0,1)² of the `spp` samples of pixel (`x`, `y`): the centre for one sample,
/// otherwise one sample per row stratum and per column stratum (Latin hypercube), jittered.
pub fn pixel_samples(x: u32, y: u32, spp: u32) -> Vec<Vec2> {
    if spp <= 1 {
        return vec![Vec2::splat(0.5)];
    }
    let seed = hash(x.wrapping_mul(73856093) ^ y.wrapping_mul(19349663));
    let mut columns: Vec<u32> = (0..spp).collect();
    // Fisher–Yates shuffle of the column strata.
    for i in (1..spp as usize).rev() {
        let j = (hash(seed.wrapping_add(i as u32)) as usize) % (i + 1);
        columns.swap(i, j);
    }
    (0..spp)
        .map(|i| {
            let jx = unit_float(seed ^ (i * 2 + 1).wrapping_mul(0x9E3779B9));
            let jy = unit_float(seed ^ (i * 2 + 2).wrapping_mul(0x85EBCA6B));
            Vec2::new(
                (columns[i as usize] as f32 + jx) / spp as f32,
                (i as f32 + jy) / spp as f32,
            )
        })
        .collect()
}

/// The radiance of pixel (`x`, `y`) of `camera`'s `width` × `height` view: the mean of its
/// `spp` samples ([`pixel_samples`]).
pub fn pixel_radiance(
    tracer: &Tracer,
    rays: &specula_scene::PixelRays,
    x: u32,
    y: u32,
    spp: u32,
) -> Vec3 {
    let trace = |s: Vec2| {
        let dir = rays.direction(x as f32 + s.x, y as f32 + s.y);
        tracer.radiance(
            &Ray {
                origin: rays.eye,
                dir,
            },
            0,
            None,
        )
    };
    // One ray through the centre: no sample list to make.
    if spp <= 1 {
        return trace(Vec2::splat(0.5));
    }
    let samples = pixel_samples(x, y, spp);
    let sum: Vec3 = samples.iter().map(|s| trace(*s)).sum();
    sum / samples.len() as f32
}

/// Renders the scene's camera view. `progress(done, total)` is called as bands of rows finish
/// (from worker threads).
pub fn render(
    scene: &Scene,
    accel: &SceneAccel,
    settings: &RenderSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Image {
    let RenderSettings {
        width,
        height,
        spp,
        max_depth,
    } = *settings;
    let tracer = Tracer {
        scene,
        accel,
        max_depth,
    };
    let rays = scene.camera.pixel_rays(width, height);
    let mut image = Image::new(width, height);
    trace_image(&tracer, &rays, spp, &mut image, progress);
    image
}

/// Traces every pixel of `image` (its size is the view's) with `spp` samples through `rays`,
/// in parallel square tiles written in place ([`in_tiles`]), and returns the (closest-hit,
/// shadow) rays traced. `progress(done, total)` is called as bands of tiles finish.
pub fn trace_image(
    tracer: &Tracer,
    rays: &specula_scene::PixelRays,
    spp: u32,
    image: &mut Image,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> (u64, u64) {
    // One ray through each pixel centre: each column's and row's image-plane coordinate is
    // computed once (the same directions as `pixel_radiance`'s, bit for bit).
    let columns: Vec<f32> = (0..image.width)
        .map(|x| rays.column(x as f32 + 0.5))
        .collect();
    in_tiles(&mut image.pixels, image.width, progress, |x0, y, line| {
        if spp <= 1 {
            let row = rays.row(y as f32 + 0.5);
            for (pixel, &column) in line.iter_mut().zip(&columns[x0 as usize..]) {
                let ray = Ray {
                    origin: rays.eye,
                    dir: rays.direction_from(column, row),
                };
                *pixel = tracer.radiance(&ray, 0, None);
            }
        } else {
            for (x, pixel) in (x0..).zip(line.iter_mut()) {
                *pixel = pixel_radiance(tracer, rays, x, y, spp);
            }
        }
    })
}

/// Runs `trace(x0, y, segment)` on every row segment of every 32 × 32 tile of a `width`-pixel-
/// wide image, tiles in parallel, each segment a slice of `pixels` (its first pixel at column
/// `x0` of row `y`) written in place; returns the (closest-hit, shadow) rays the tiles traced,
/// counted on the threads that traced them. Square tiles keep neighbouring secondary rays
/// together: a glass dragon's reference frame took 1.2–1.4× as long in bands of 16 rows.
/// `progress(done, total)` is called as each band of tiles finishes (from worker threads).
pub fn in_tiles(
    pixels: &mut [Vec3],
    width: u32,
    progress: &(dyn Fn(usize, usize) + Sync),
    trace: impl Fn(u32, u32, &mut [Vec3]) + Sync,
) -> (u64, u64) {
    let (width, side) = (width as usize, TILE as usize);
    let total = (pixels.len() / width.max(1)).div_ceil(side);
    let done = AtomicUsize::new(0);
    pixels
        .par_chunks_mut(side * width)
        .enumerate()
        .map(|(band, band_pixels)| {
            // The band cut into its tiles' row segments, so each tile is written in place.
            let mut tiles: Vec<Vec<&mut [Vec3]>> =
                (0..width.div_ceil(side)).map(|_| Vec::new()).collect();
            for line in band_pixels.chunks_mut(width) {
                for (tile, segment) in line.chunks_mut(side).enumerate() {
                    tiles[tile].push(segment);
                }
            }
            let traced = tiles
                .into_par_iter()
                .enumerate()
                .map(|(tile, lines)| {
                    let before = rays_traced_on_this_thread();
                    for (dy, line) in lines.into_iter().enumerate() {
                        trace((tile * side) as u32, (band * side + dy) as u32, line);
                    }
                    let after = rays_traced_on_this_thread();
                    (after.0 - before.0, after.1 - before.1)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            traced
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// The closest hit of the ray through each pixel centre of a `width` × `height` image (row
/// by row from the top-left), as the reference's primary rays with one sample per pixel.
pub fn primary_hits(
    scene: &Scene,
    accel: &SceneAccel,
    width: u32,
    height: u32,
) -> Vec<Option<Hit>> {
    (0..width * height)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let dir = scene
                .camera
                .ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
            accel.intersect(
                &Ray {
                    origin: scene.camera.eye,
                    dir,
                },
                f32::INFINITY,
            )
        })
        .collect()
}
