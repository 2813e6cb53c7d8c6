//! Vertex rays (§3): a vertex traced through the reference with its path recorded (ray tree and
//! texture reads), and the original vertices traced once per process for every package
//! ([`OriginalSamples`]).

use std::time::Instant;

use glam::{Vec2, Vec3};
use rustc_hash::FxHashMap as HashMap;
use specula_trace::reference::{
    rays_traced_on_this_thread, RayTree, Step, TextureHit, TreeRecorder,
};
use specula_trace::{Hit, Ray};

use super::{barycentric, FrameInputs, Package, PackageCounters, TriangleId, Vertex};

/// The texture reads of a path kept for the texture test (the first ones, in path order).
const TEXTURE_READS: usize = 2;

/// A texture read of a vertex's path.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct TextureRead {
    pub(super) hit: TextureHit,
    /// The view depth of the point that far along the primary ray (the textured point's
    /// virtual image): what perspective-correct interpolation of `uv` divides by.
    pub(super) virtual_depth: f32,
}

/// What a vertex keeps of its path: the ray tree, and where it read textures.
#[derive(Clone, Copy, Debug)]
pub(super) struct PathRecord {
    pub(super) tree: RayTree,
    pub(super) reads: [TextureRead; TEXTURE_READS],
    pub(super) read_count: usize,
}

impl PathRecord {
    fn new(min_weight: f32) -> PathRecord {
        PathRecord {
            tree: RayTree::with_min_weight(min_weight),
            reads: [TextureRead::default(); TEXTURE_READS],
            read_count: 0,
        }
    }
}

impl TreeRecorder for PathRecord {
    fn ray(&mut self, step: Step, mesh: Option<u32>) {
        self.tree.ray(step, mesh);
    }

    fn shadow(&mut self, light: usize, occluded: bool, weight: f32) {
        self.tree.shadow(light, occluded, weight);
    }

    fn texture(&mut self, read: &TextureHit) {
        if read.coefficient.max_element() >= self.tree.min_weight && self.read_count < TEXTURE_READS
        {
            self.reads[self.read_count] = TextureRead {
                hit: *read,
                virtual_depth: 0.0,
            };
            self.read_count += 1;
        }
    }
}

/// A vertex at `p_world` on triangle `host` of `mesh`, traced: the primary ray from the eye
/// is aimed at it, so its intersection is known and not searched for (§3).
pub(super) fn trace_vertex(inputs: &FrameInputs, mesh: u32, host: u32, p_world: Vec3) -> Vertex {
    let scene_mesh = &inputs.scene.meshes[mesh as usize];
    let [i0, i1, i2] = scene_mesh.triangles[host as usize].map(|i| i as usize);
    let (b1, b2) = barycentric(
        p_world,
        scene_mesh.positions[i0],
        scene_mesh.positions[i1],
        scene_mesh.positions[i2],
    );
    let eye = inputs.view.eye;
    let to_vertex = p_world - eye;
    let ray = Ray {
        origin: eye,
        dir: to_vertex.normalize(),
    };
    let hit = Hit {
        t: to_vertex.length(),
        b1,
        b2,
        mesh,
        triangle: host,
    };
    let mut path = PathRecord::new(inputs.settings.tree_weight);
    let color = inputs
        .tracer()
        .radiance_at_hit_recorded(&ray, &hit, &mut path);
    let (screen, depth) = match inputs.view.project(p_world) {
        Some((x, y, z)) => (Vec2::new(x, y), z),
        None => (Vec2::ZERO, 0.0),
    };
    let textured: Vec3 = path.reads[..path.read_count]
        .iter()
        .map(|r| r.hit.coefficient * inputs.scene.textures[r.hit.texture].sample(r.hit.uv))
        .sum();
    // Seen along the primary ray, the textured point is at its path length: its view depth
    // is that length × the ray's cosine to the view axis.
    let cosine = if to_vertex.length() > 0.0 {
        depth / to_vertex.length()
    } else {
        1.0
    };
    for read in &mut path.reads[..path.read_count] {
        read.virtual_depth = read.hit.distance * cosine;
    }
    Vertex {
        p_world,
        screen,
        depth,
        visible: inputs.is_visible(mesh, host, p_world),
        color,
        smooth: color - textured,
        path,
    }
}

/// (mesh, vertex), its sample, and the (closest-hit, shadow) rays it took.
type TracedOriginal = ((u32, u32), Vertex, (u64, u64));

/// The original vertices of a frame's active triangles, each traced once for every package
/// (a process refining all packages itself shares them; an MPI worker traces its own).
#[derive(Default)]
pub struct OriginalSamples {
    pub(super) samples: HashMap<(u32, u32), Vertex>,
    pub counters: PackageCounters,
}

impl OriginalSamples {
    /// Keeps the original-vertex samples `package` traced, for the next packages this
    /// process refines in the frame (an MPI worker's packages follow one another on the mesh:
    /// their borders are traced once).
    #[cfg_attr(not(feature = "mpi"), allow(dead_code))]
    pub fn absorb(&mut self, package: &Package) {
        for (&key, &local) in &package.originals {
            self.samples
                .entry(key)
                .or_insert(package.vertices[local as usize]);
        }
    }

    pub fn trace(inputs: &FrameInputs, active: &[TriangleId]) -> OriginalSamples {
        use rayon::prelude::*;
        let start = Instant::now();
        let mut keys: Vec<(u32, u32)> = active
            .iter()
            .flat_map(|id| {
                inputs.scene.meshes[id.mesh as usize].triangles[id.triangle as usize]
                    .map(|v| (id.mesh, v))
            })
            .collect();
        keys.sort_unstable();
        keys.dedup();
        let traced: Vec<TracedOriginal> = keys
            .par_iter()
            .map(|&(mesh, vertex)| {
                let before = rays_traced_on_this_thread();
                let host = inputs.topology.vertex_host(mesh, vertex);
                let p = inputs.scene.meshes[mesh as usize].positions[vertex as usize];
                let sample = trace_vertex(inputs, mesh, host, p);
                let after = rays_traced_on_this_thread();
                (
                    (mesh, vertex),
                    sample,
                    (after.0 - before.0, after.1 - before.1),
                )
            })
            .collect();
        let mut counters = PackageCounters {
            vertex_rays: traced.len() as u64,
            ..Default::default()
        };
        let mut samples = HashMap::with_capacity_and_hasher(traced.len(), Default::default());
        for (key, sample, (rays, shadow)) in traced {
            counters.rays += rays;
            counters.shadow_rays += shadow;
            samples.insert(key, sample);
        }
        counters.seconds = start.elapsed().as_secs_f64();
        OriginalSamples { samples, counters }
    }
}
