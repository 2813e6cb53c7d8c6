//! vertex-tracing's choice per reflector in sight: its vertices and pixels counted in the ID
//! buffer, its paths' rays measured on a sample of its pixels, and whether it is traced by its
//! vertices or per pixel.

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;
use specula_trace::reference::{rays_traced_on_this_thread, Tracer};
use specula_trace::Ray;

use super::refine::Topology;
use super::{Params, ReflectorTracing};
use specula_core::screen::PixelSurfaces;

/// One reflector's counts in a frame and the way it was chosen to be traced.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ReflectorChoice {
    pub(crate) mesh: u32,
    /// The distinct vertices of its triangles the ID buffer shows: about the vertex rays its
    /// preview costs (the active triangles add a border).
    pub(crate) vertices: usize,
    /// The pixels its triangles own in the ID buffer.
    pub(crate) pixels: usize,
    /// Closest-hit and shadow rays per pixel path beyond the primary ray, on a sample of its
    /// pixels (None: not sampled, the vertex count alone decided).
    pub(crate) path_rays: Option<f32>,
    /// The (closest-hit, shadow) rays the sample took.
    pub(crate) sample_rays: (u64, u64),
    pub(crate) per_pixel: bool,
}

/// Pixels of a candidate reflector traced to measure its paths, spread evenly over its pixels.
const PATH_SAMPLES: usize = 256;

/// A set of indices below a bound, set from many threads at once.
struct Bits(Vec<AtomicU64>);

impl Bits {
    fn new(len: usize) -> Bits {
        Bits((0..len.div_ceil(64)).map(|_| AtomicU64::new(0)).collect())
    }

    /// Adds `i`; an index past the bound (a raster ID buffer's stale triangle) is left out.
    fn set(&self, i: usize) {
        if let Some(word) = self.0.get(i / 64) {
            let bit = 1 << (i % 64);
            // Neighbouring pixels show the same triangle: read before writing.
            if word.load(Ordering::Relaxed) & bit == 0 {
                word.fetch_or(bit, Ordering::Relaxed);
            }
        }
    }

    fn count(&self) -> usize {
        self.0
            .iter()
            .map(|w| w.load(Ordering::Relaxed).count_ones() as usize)
            .sum()
    }

    /// The indices held, in order.
    fn ones(&self) -> impl Iterator<Item = usize> + '_ {
        self.0.iter().enumerate().flat_map(|(k, word)| {
            let mut w = word.load(Ordering::Relaxed);
            std::iter::from_fn(move || {
                (w != 0).then(|| {
                    let bit = w.trailing_zeros() as usize;
                    w &= w - 1;
                    64 * k + bit
                })
            })
        })
    }
}

impl ReflectorChoice {
    /// Every reflector the ID buffer `surfaces` shows, counted, and the choice `settings`
    /// makes: per pixel where its seen vertices outnumber `vertex_ratio` × its pixels (a dense,
    /// small or distant reflector: the vertices cost about what the pixels do), or where a
    /// sample of its pixels' paths takes fewer than `min_path_rays` rays beyond the primary
    /// (a plain mirror: owning, locating and interpolating a pixel costs about what its one
    /// reflected ray does); by vertices otherwise. In mesh order.
    pub(super) fn from_id_buffer(
        tracer: &Tracer,
        pixel_rays: &specula_scene::PixelRays,
        width: u32,
        surfaces: &PixelSurfaces,
        topology: &Topology,
        settings: &Params,
    ) -> Vec<ReflectorChoice> {
        let scene = tracer.scene;
        // In parallel over the pixels: each reflector's pixel count, and the triangles its
        // pixels show as bits (a 75k-triangle mesh: 1,200 words).
        let seen_triangles: Vec<Option<Bits>> = scene
            .meshes
            .iter()
            .enumerate()
            .map(|(mesh, m)| {
                topology
                    .is_reflector(mesh as u32)
                    .then(|| Bits::new(m.triangles.len()))
            })
            .collect();
        let pixel_counts = surfaces
            .ids
            .par_chunks(4096)
            .fold(
                || vec![0usize; scene.meshes.len()],
                |mut counts, ids| {
                    for &[mesh, triangle] in ids {
                        let Some(mesh) = mesh.checked_sub(1) else {
                            continue;
                        };
                        if let Some(Some(seen)) = seen_triangles.get(mesh as usize) {
                            counts[mesh as usize] += 1;
                            seen.set(triangle as usize);
                        }
                    }
                    counts
                },
            )
            .reduce(
                || vec![0usize; scene.meshes.len()],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
                    a
                },
            );
        let tallies = seen_triangles.into_iter().enumerate().map(|(mesh, seen)| {
            let seen = seen.filter(|_| pixel_counts[mesh] > 0)?;
            let scene_mesh = &scene.meshes[mesh];
            let seen_vertices = Bits::new(scene_mesh.positions.len());
            for t in seen.ones() {
                for &v in &scene_mesh.triangles[t] {
                    seen_vertices.set(v as usize);
                }
            }
            Some((pixel_counts[mesh], seen_vertices.count()))
        });
        // A candidate's pixels, for its path sample (raster order).
        let pixels_of = |mesh: usize| -> Vec<u32> {
            surfaces
                .ids
                .par_iter()
                .enumerate()
                .filter(|(_, ids)| ids[0] == mesh as u32 + 1)
                .map(|(k, _)| k as u32)
                .collect()
        };
        tallies
            .enumerate()
            .filter_map(|(mesh, tally)| {
                let (pixels, vertices) = tally?;
                let dense = vertices as f64 > settings.vertex_ratio as f64 * pixels as f64;
                let sampled = (settings.tracing == ReflectorTracing::Auto && !dense).then(|| {
                    sampled_path_rays(tracer, pixel_rays, width, surfaces, &pixels_of(mesh))
                });
                let path_rays = sampled.map(|(rays, _)| rays);
                let per_pixel = match settings.tracing {
                    ReflectorTracing::Vertices => false,
                    ReflectorTracing::Pixels => true,
                    ReflectorTracing::Auto => {
                        dense || path_rays.is_some_and(|rays| rays < settings.min_path_rays)
                    }
                };
                Some(ReflectorChoice {
                    mesh: mesh as u32,
                    vertices,
                    pixels,
                    path_rays,
                    sample_rays: sampled.map_or((0, 0), |(_, traced)| traced),
                    per_pixel,
                })
            })
            .collect()
    }
}

/// The mean closest-hit and shadow rays beyond the primary of up to [`PATH_SAMPLES`] pixels
/// spread evenly over `pixels` (raster order), traced as the reference traces them; with the
/// (closest-hit, shadow) rays the sample took. A pixel whose ray
/// meets nothing here (a raster ID buffer's rounding) is left out of the mean.
fn sampled_path_rays(
    tracer: &Tracer,
    pixel_rays: &specula_scene::PixelRays,
    width: u32,
    surfaces: &PixelSurfaces,
    pixels: &[u32],
) -> (f32, (u64, u64)) {
    let stride = pixels.len().div_ceil(PATH_SAMPLES).max(1);
    let sample: Vec<u32> = pixels.iter().step_by(stride).copied().collect();
    let paths: Vec<(bool, (u64, u64))> = sample
        .par_iter()
        .map(|&k| {
            let (x, y) = (k % width, k / width);
            let ray = Ray {
                origin: pixel_rays.eye,
                dir: pixel_rays.direction(x as f32 + 0.5, y as f32 + 0.5),
            };
            let before = rays_traced_on_this_thread();
            let hit = match surfaces.hits.get(k as usize) {
                Some(hit) => *hit,
                None => tracer.accel.intersect(&ray, f32::INFINITY),
            };
            if let Some(hit) = hit {
                tracer.radiance_at_hit_recorded(&ray, &hit, &mut ());
            }
            let after = rays_traced_on_this_thread();
            (hit.is_some(), (after.0 - before.0, after.1 - before.1))
        })
        .collect();
    let traced = paths.iter().filter(|(hit, _)| *hit).count();
    let beyond_primary: u64 = paths.iter().map(|(_, (rays, shadow))| rays + shadow).sum();
    // Without the CPU's hits each sampled pixel's primary ray was traced here too.
    let primaries = if surfaces.hits.is_empty() {
        sample.len() as u64
    } else {
        0
    };
    (
        beyond_primary as f32 / traced.max(1) as f32,
        (
            paths.iter().map(|(_, r)| r.0).sum::<u64>() + primaries,
            paths.iter().map(|(_, r)| r.1).sum(),
        ),
    )
}
