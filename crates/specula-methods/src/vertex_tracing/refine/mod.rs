//! One task package of vertex tracing (Ullmann et al. 2001, §3–3.2): a set of reflector
//! triangles, their vertices traced, their edges refined longest first, and their pixels
//! interpolated (Gouraud) or traced (triangle filling).
//!
//! A package's image depends only on its triangles, never on which other triangles share its
//! package: every decision is a function of what it decides on. A vertex's colour and ray tree
//! depend only on its position and its *host* triangle (the lowest-numbered triangle of its mesh
//! that holds it, the same in every package); an edge on a triangle's boundary is split or kept
//! by its end points alone (colour, ray tree, projected length, level), so both triangles beside
//! it split it alike wherever they are; the flatness rule, which looks at faces, applies only to
//! edges inside one triangle (with `flatness_inside_triangles`, the default: the paper's rule,
//! on any longest edge, lets a package split a border edge by the faces on its own side); and
//! the queue's order among one triangle's edges is by projected length, ties broken by
//! position. So a frame cut into packages any way — rayon's, or the MPI master's — composes the
//! same image bit for bit. The price is the paper's redundancy: a vertex
//! refinement adds on the border of two packages is traced in both (the original vertices are
//! traced once per process, [`OriginalSamples`]).

use std::collections::BinaryHeap;

// Fx hashing: the keys are small integers made here, and SipHash cost a refined frame more than
// its maps' work (a filled pixel's colour is stored and read back through one).
use rustc_hash::FxHashMap as HashMap;
use std::time::Instant;

use glam::{Vec2, Vec3};
use specula_scene::{Camera, Scene};
use specula_trace::reference::{
    rays_traced_on_this_thread, RayTree, Step, TextureHit, Tracer, TreeRecorder,
};
use specula_trace::{Hit, Ray, SceneAccel};

use super::compose::FaceVertex;
use super::Params;
use specula_core::screen::{PixelSurfaces, ScreenView};

/// Filled pixels per parallel job.
const PARALLEL_FILL_PIXELS: usize = 256;

/// With a deadline, the clock is read after every this many edge decisions.
const EDGES_PER_CLOCK_READ: u32 = 16;

/// How a frame shades a reflector's pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReflectorTracing {
    /// Per reflector, from the frame's counts: per pixel where its seen vertices outnumber
    /// `vertex_ratio` times its pixels (a dense, small or distant reflector) or where a sample
    /// of its pixel paths takes fewer than `min_path_rays` rays beyond the primary (a plain
    /// mirror), else by vertices.
    Auto,
    /// Every reflector by its vertices (the paper).
    Vertices,
    /// Every reflector per pixel: the reference's image.
    Pixels,
}

specula_core::choice!(ReflectorTracing {
    Auto = "auto",
    Vertices = "vertices",
    Pixels = "pixels",
});

/// A reflector triangle of the scene: the unit of work packages are made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TriangleId {
    pub mesh: u32,
    pub triangle: u32,
}

/// Each reflector mesh's host triangles: the lowest-numbered triangle holding each vertex and
/// each edge. A vertex is shaded as a point of its host, so that every package shades it alike.
#[derive(Debug, Default)]
pub struct Topology {
    /// Per scene mesh; None for a mesh that is not a reflector.
    meshes: Vec<Option<MeshTopology>>,
}

#[derive(Debug, Default)]
struct MeshTopology {
    vertex_host: Vec<u32>,
    edge_host: HashMap<(u32, u32), u32>,
}

impl Topology {
    /// The host triangles of every specular mesh of `scene`.
    pub fn new(scene: &Scene) -> Topology {
        let meshes = scene
            .meshes
            .iter()
            .map(|mesh| {
                if !scene.materials[mesh.material].is_specular() {
                    return None;
                }
                let mut topology = MeshTopology {
                    vertex_host: vec![u32::MAX; mesh.positions.len()],
                    edge_host: HashMap::default(),
                };
                for (t, tri) in mesh.triangles.iter().enumerate() {
                    let t = t as u32;
                    for i in 0..3 {
                        let host = &mut topology.vertex_host[tri[i] as usize];
                        *host = (*host).min(t);
                        topology
                            .edge_host
                            .entry(edge_key(tri[i], tri[(i + 1) % 3]))
                            .or_insert(t);
                    }
                }
                Some(topology)
            })
            .collect();
        Topology { meshes }
    }

    pub fn is_reflector(&self, mesh: u32) -> bool {
        self.meshes.get(mesh as usize).is_some_and(Option::is_some)
    }

    fn mesh(&self, mesh: u32) -> &MeshTopology {
        self.meshes[mesh as usize]
            .as_ref()
            .expect("a reflector's topology")
    }

    fn vertex_host(&self, mesh: u32, vertex: u32) -> u32 {
        self.mesh(mesh).vertex_host[vertex as usize]
    }

    fn edge_host(&self, mesh: u32, edge: (u32, u32)) -> u32 {
        self.mesh(mesh).edge_host[&edge]
    }
}

/// The pixels each reflector triangle owns: those whose first surface (the ID buffer) is it.
/// A pixel the ID buffer gives to a triangle that cannot be seen there — its centre outside
/// the triangle's screen projection, or a closed glass's back face (a raster depth buffer's
/// rounding between the two walls of a thin shell) — is *stray*: with `trace_stray` it is
/// traced, not interpolated from a surface it is not on.
#[derive(Debug, Default)]
pub struct PixelOwners {
    /// (mesh << 32 | triangle, pixel | STRAY), sorted.
    owned: Vec<(u64, u32)>,
}

const STRAY: u32 = 1 << 31;

fn owner_key(id: TriangleId) -> u64 {
    (id.mesh as u64) << 32 | id.triangle as u64
}

/// Whether triangle `id` can be what pixel `k`'s centre sees: the centre within half a pixel
/// of its screen projection, and a closed glass's triangle facing the eye.
fn plausible_owner(scene: &Scene, view: &ScreenView, id: TriangleId, k: u32) -> bool {
    let mesh = &scene.meshes[id.mesh as usize];
    let tri = mesh.triangles[id.triangle as usize].map(|v| v as usize);
    let [a, b, c] = tri.map(|v| mesh.positions[v]);
    if let specula_scene::MaterialKind::Dielectric {
        thin_walled: false, ..
    } = scene.materials[mesh.material].kind
    {
        let mut normal = (b - a).cross(c - a);
        let stored = mesh.normals[tri[0]] + mesh.normals[tri[1]] + mesh.normals[tri[2]];
        if normal.dot(stored) < 0.0 {
            normal = -normal;
        }
        if normal.dot(a - view.eye) > 0.0 {
            return false;
        }
    }
    let corners = [a, b, c].map(|p| view.project(p));
    let [Some(pa), Some(pb), Some(pc)] = corners else {
        // A corner behind the eye: no screen triangle to test against.
        return true;
    };
    let [sa, sb, sc] = [pa, pb, pc].map(|(x, y, _)| Vec2::new(x, y));
    let q = Vec2::new((k % view.width) as f32 + 0.5, (k / view.width) as f32 + 0.5);
    let orientation = cross2(sb - sa, sc - sa).signum();
    [(sa, sb), (sb, sc), (sc, sa)].iter().all(|&(from, to)| {
        let length = (to - from).length();
        length == 0.0 || orientation * cross2(to - from, q - from) / length >= -0.5
    })
}

impl PixelOwners {
    /// The owners of the pixels showing the meshes `by_vertices` marks (the reflectors traced
    /// by their vertices in this frame).
    pub fn new(
        surfaces: &PixelSurfaces,
        by_vertices: &[bool],
        scene: &Scene,
        view: &ScreenView,
    ) -> PixelOwners {
        use rayon::prelude::*;
        let mut owned: Vec<(u64, u32)> = surfaces
            .ids
            .par_iter()
            .enumerate()
            .filter(|(_, ids)| {
                ids[0] != 0
                    && by_vertices
                        .get(ids[0] as usize - 1)
                        .copied()
                        .unwrap_or(false)
            })
            .map(|(k, ids)| {
                let id = TriangleId {
                    mesh: ids[0] - 1,
                    triangle: ids[1],
                };
                let k = k as u32;
                let stray = !plausible_owner(scene, view, id, k);
                (owner_key(id), k | if stray { STRAY } else { 0 })
            })
            .collect();
        owned.par_sort_unstable();
        PixelOwners { owned }
    }

    /// The pixels `id` owns, in raster order, each with whether it is stray.
    pub fn owned(&self, id: TriangleId) -> impl Iterator<Item = (u32, bool)> + '_ {
        let key = owner_key(id);
        let start = self.owned.partition_point(|(k, _)| *k < key);
        self.owned[start..]
            .iter()
            .take_while(move |(k, _)| *k == key)
            .map(|(_, pixel)| (pixel & !STRAY, pixel & STRAY != 0))
    }

    /// Stray pixels in all.
    pub fn stray(&self) -> usize {
        self.owned.iter().filter(|(_, p)| p & STRAY != 0).count()
    }

    /// The pixels `id` owns, in raster order.
    pub fn pixels(&self, id: TriangleId) -> impl Iterator<Item = u32> + '_ {
        self.owned(id).map(|(pixel, _)| pixel)
    }

    pub fn owns_any(&self, id: TriangleId) -> bool {
        self.pixels(id).next().is_some()
    }

    /// Every pixel some triangle of a reflector traced by its vertices owns.
    pub fn all(&self) -> impl Iterator<Item = u32> + '_ {
        self.owned.iter().map(|(_, pixel)| pixel & !STRAY)
    }
}

/// What every package of one frame reads.
pub struct FrameInputs<'a> {
    pub scene: &'a Scene,
    pub accel: &'a SceneAccel,
    /// The reference's bound on specular bounces.
    pub max_depth: u32,
    pub camera: &'a Camera,
    pub view: ScreenView,
    pub surfaces: &'a PixelSurfaces,
    pub owners: &'a PixelOwners,
    pub topology: &'a Topology,
    pub settings: Params,
    /// The original vertices already traced, if this process traced them for all packages.
    pub originals: Option<&'a OriginalSamples>,
}

impl FrameInputs<'_> {
    fn tracer(&self) -> Tracer<'_> {
        Tracer {
            scene: self.scene,
            accel: self.accel,
            max_depth: self.max_depth,
        }
    }

    /// Whether `p_world`, a point of triangle `host` of mesh `mesh`, is seen (the ID buffer
    /// test): its pixel shows that mesh, and either that triangle or a surface at the point's
    /// distance within what the host's plane spans across the pixel (a neighbouring triangle
    /// of the same surface; not the back wall of a thin shell, or another fold of the mesh).
    pub fn is_visible(&self, mesh: u32, host: u32, p_world: Vec3) -> bool {
        let Some((x, y, z)) = self.view.project(p_world) else {
            return false;
        };
        let (w, h) = (self.view.width as f32, self.view.height as f32);
        if !(x >= 0.0 && y >= 0.0 && x < w && y < h) {
            return false;
        }
        let k = y as usize * self.view.width as usize + x as usize;
        let [seen_mesh, seen_triangle] = self.surfaces.ids[k];
        if seen_mesh != mesh + 1 {
            return false;
        }
        if seen_triangle == host {
            return true;
        }
        let eye = self.view.eye;
        let scene_mesh = &self.scene.meshes[mesh as usize];
        let [a, b, c] =
            scene_mesh.triangles[host as usize].map(|i| scene_mesh.positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        let cos = normal.dot((p_world - eye).normalize_or_zero()).abs();
        // The pixel centre is within 0.71 pixel of the point: along the plane, the distance
        // changes by at most that × tan θ footprints.
        let tan = ((1.0 - cos * cos).max(0.0).sqrt() / cos.max(0.05)).min(20.0);
        let tolerance = self.view.footprint(z) * (0.75 * tan + 0.25);
        self.surfaces.position(k).is_some_and(|seen| {
            ((seen - eye).length() - (p_world - eye).length()).abs() <= tolerance
        })
    }

    /// The reflector triangles a frame traces, of the meshes `by_vertices` marks: those with a
    /// visible vertex (the paper's rule: an edge is traced when one of its ends is seen) and,
    /// with `trace_unseen`, those with pixels of their own (a triangle seen only between its
    /// corners, which the paper leaves out), mesh by mesh, each mesh's along a Morton curve
    /// through its box.
    pub fn active_triangles(&self, by_vertices: &[bool]) -> Vec<TriangleId> {
        use rayon::prelude::*;
        let mut active = Vec::new();
        for (index, mesh) in self.scene.meshes.iter().enumerate() {
            if !by_vertices[index] {
                continue;
            }
            let index = index as u32;
            let visible: Vec<bool> = (0..mesh.positions.len() as u32)
                .into_par_iter()
                .map(|v| {
                    let host = self.topology.vertex_host(index, v);
                    host != u32::MAX && self.is_visible(index, host, mesh.positions[v as usize])
                })
                .collect();
            let bounds = mesh.bounds();
            let mut seen: Vec<(u32, TriangleId)> = mesh
                .triangles
                .iter()
                .enumerate()
                .map(|(t, _)| TriangleId {
                    mesh: index,
                    triangle: t as u32,
                })
                .filter(|id| {
                    let tri = mesh.triangles[id.triangle as usize];
                    tri.iter().any(|&v| visible[v as usize])
                        || (self.settings.trace_unseen && self.owners.owns_any(*id))
                })
                .map(|id| {
                    let tri = mesh.triangles[id.triangle as usize];
                    let centroid = tri
                        .iter()
                        .map(|&v| mesh.positions[v as usize])
                        .sum::<Vec3>()
                        / 3.0;
                    (morton(centroid, bounds.min, bounds.max), id)
                })
                .collect();
            // Along a space-filling curve, so that a range of the list — a package — is a
            // compact patch of the surface with a short border (the paper's future work:
            // "group the overall scene into spatial sectors"); mesh order would give strips.
            seen.sort_unstable();
            active.extend(seen.into_iter().map(|(_, id)| id));
        }
        active
    }
}

/// The Morton code (10 bits an axis, interleaved) of `p` in the box `lo`..`hi`.
fn morton(p: Vec3, lo: Vec3, hi: Vec3) -> u32 {
    let cell = ((p - lo) / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE)) * 1023.0)
        .clamp(Vec3::ZERO, Vec3::splat(1023.0));
    let spread = |v: f32| {
        let mut x = v as u32;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    spread(cell.x) | spread(cell.y) << 1 | spread(cell.z) << 2
}

/// How far apart two radiances look: the largest channel difference after clamping to the
/// display's range and a 2.2 gamma (what the refinement test compares with ε).
pub fn display_difference(a: Vec3, b: Vec3) -> f32 {
    let display = |c: Vec3| c.clamp(Vec3::ZERO, Vec3::ONE).powf(1.0 / 2.2);
    (display(a) - display(b)).abs().max_element()
}

/// CheckRefinement's test on an edge's two ends (§3): their ray trees differ (another object,
/// another optical path, a shadow edge), or their colours differ by more than ε. Beyond the
/// paper, for paths that read textures (a dial seen through the cover): with deferred textures
/// the texels are left out of the colours compared (they are read per pixel), and the reads'
/// coefficients are compared instead; without, a texture that changes between the ends'
/// texture coordinates by more than ε from its linear blend also splits the edge — the colours
/// of two ends alone cannot see a tick between them.
fn differ(a: &Vertex, b: &Vertex, inputs: &FrameInputs) -> bool {
    let epsilon = inputs.settings.epsilon;
    if !a.path.tree.same_as(&b.path.tree) {
        return true;
    }
    if inputs.settings.deferred_textures && a.path.read_count == b.path.read_count {
        // Textures are read per pixel at interpolated coordinates: what must vary gently is
        // the rest of the colour and each read's coefficient, not the texels.
        return display_difference(a.smooth, b.smooth) > epsilon
            || (0..a.path.read_count).any(|i| {
                let (ra, rb) = (&a.path.reads[i].hit, &b.path.reads[i].hit);
                // A crease of the textured surface (a floor meeting a wall in one mesh)
                // bends the texture coordinates' map: split there too.
                display_difference(ra.coefficient, rb.coefficient) > epsilon
                    || ra.normal.dot(rb.normal) < CREASE_COSINE
            });
    }
    if display_difference(a.color, b.color) > epsilon {
        return true;
    }
    let reads = a.path.read_count.min(b.path.read_count);
    (0..reads).any(|i| {
        let (texture, uv_a, uv_b) = (
            a.path.reads[i].hit.texture,
            a.path.reads[i].hit.uv,
            b.path.reads[i].hit.uv,
        );
        let texture = &inputs.scene.textures[texture];
        let texels = ((uv_b - uv_a) * Vec2::new(texture.width as f32, texture.height as f32))
            .abs()
            .max_element();
        let steps = texels.ceil().min(TEXTURE_TEST_SAMPLES) as u32;
        let (end_a, end_b) = (texture.sample(uv_a), texture.sample(uv_b));
        (1..steps).any(|s| {
            let t = s as f32 / steps as f32;
            display_difference(texture.sample(uv_a.lerp(uv_b, t)), end_a.lerp(end_b, t)) > epsilon
        })
    })
}

/// Work and results of a package so far.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PackageCounters {
    /// Vertices traced (each one primary ray aimed at it, its intersection known).
    pub vertex_rays: u64,
    /// Pixels traced by triangle filling.
    pub filled_pixels: u64,
    /// Closest-hit rays (secondary for vertices; all for filled pixels) and shadow rays.
    pub rays: u64,
    pub shadow_rays: u64,
    pub edges_split: u64,
    /// Of those, split by the flatness rule.
    pub flat_splits: u64,
    /// Edges whose ends differ but that the two-pixel floor or the level limit kept.
    pub unresolved_edges: u64,
    pub deepest_level: u64,
    /// Wall-clock seconds of work on this package (what the load balancer measures).
    pub seconds: f64,
}

impl PackageCounters {
    pub fn add(&mut self, other: &PackageCounters) {
        self.vertex_rays += other.vertex_rays;
        self.filled_pixels += other.filled_pixels;
        self.rays += other.rays;
        self.shadow_rays += other.shadow_rays;
        self.edges_split += other.edges_split;
        self.flat_splits += other.flat_splits;
        self.unresolved_edges += other.unresolved_edges;
        self.deepest_level = self.deepest_level.max(other.deepest_level);
        self.seconds += other.seconds;
    }
}

/// The texture reads of a path kept for the texture test (the first ones, in path order).
const TEXTURE_READS: usize = 2;
/// Ends whose textured surfaces' normals differ by more than about 8° split their edge.
const CREASE_COSINE: f32 = 0.99;
/// The most texture samples one edge's texture test takes.
const TEXTURE_TEST_SAMPLES: f32 = 64.0;

/// A texture read of a vertex's path.
#[derive(Clone, Copy, Debug, Default)]
struct TextureRead {
    hit: TextureHit,
    /// The view depth of the point that far along the primary ray (the textured point's
    /// virtual image): what perspective-correct interpolation of `uv` divides by.
    virtual_depth: f32,
}

/// What a vertex keeps of its path: the ray tree, and where it read textures.
#[derive(Clone, Copy, Debug)]
struct PathRecord {
    tree: RayTree,
    reads: [TextureRead; TEXTURE_READS],
    read_count: usize,
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

#[derive(Clone, Copy, Debug)]
struct Vertex {
    p_world: Vec3,
    /// Pixel coordinates (centres at +0.5) and view depth; depth ≤ 0 behind the eye.
    screen: Vec2,
    depth: f32,
    visible: bool,
    color: Vec3,
    /// The colour less what the path's texture reads contribute (what deferred texturing
    /// interpolates; the texels are read again at each pixel).
    smooth: Vec3,
    path: PathRecord,
}

/// What CheckRefinement decides for an edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Decision {
    Keep,
    /// Its ends differ but it may not be split (too short or too deep): its faces are filled.
    Unresolved,
    /// Split it; `flat`: for the flatness rule alone (its ends do not differ).
    Split {
        flat: bool,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum EdgeState {
    /// Not in the queue (made, or examined and kept).
    Idle,
    Queued,
    /// Its ends differ, but it is too short or too deep to split: its faces are filled.
    Unresolved,
    Split,
}

#[derive(Clone, Debug)]
struct Edge {
    a: u32,
    b: u32,
    level: u32,
    /// The original mesh edge (its vertex indices, ordered) it lies on; None inside a triangle.
    original: Option<(u32, u32)>,
    /// The leaf faces beside it (two inside a surface, one on its border, more where the mesh
    /// is not a manifold).
    faces: Vec<u32>,
    state: EdgeState,
}

#[derive(Clone, Copy, Debug)]
struct Face {
    v: [u32; 3],
    /// Index of its original triangle in the package.
    origin: u32,
    level: u32,
    /// Once split: the two halves (the first holds the split edge's first end), and the line
    /// from the new vertex to the opposite corner that separates them.
    children: Option<([u32; 2], [u32; 2])>,
}

/// A leaf face set up for shading its pixels.
struct Leaf {
    v: [u32; 3],
    s0: Vec2,
    e1: Vec2,
    e2: Vec2,
    /// Zero where the screen triangle is degenerate or a corner is behind the eye.
    inverse_area: f32,
    /// A corner is behind the eye: no screen triangle exists.
    behind_eye: bool,
    alike: bool,
}

impl Leaf {
    /// The screen weights of `q` (may be slightly negative just outside).
    fn weights(&self, q: Vec2) -> [f32; 3] {
        let d = q - self.s0;
        let l1 = cross2(d, self.e2) * self.inverse_area;
        let l2 = cross2(self.e1, d) * self.inverse_area;
        [1.0 - l1 - l2, l1, l2]
    }

    /// Whether `q` lies inside this leaf by more than rounding (a pixel centre on or near a
    /// separating line is located from the root instead).
    fn strictly_contains(&self, q: Vec2) -> bool {
        self.inverse_area != 0.0 && self.weights(q).iter().all(|&l| l >= 1e-3)
    }

    /// The weights of `q` if it lies in this leaf.
    fn weights_inside(&self, q: Vec2) -> Option<[f32; 3]> {
        if self.inverse_area == 0.0 {
            return None;
        }
        let at = self.weights(q);
        at.iter().all(|&l| l >= -1e-5).then_some(at)
    }
}

/// An edge in the queue: longest on the screen first; ties by position, which is the same in
/// every package (local indices are not).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Queued {
    length_bits: u32,
    midpoint_bits: [u32; 3],
    edge: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Preview,
    Refining,
    Filling { next: usize },
    Done,
}

/// One task package: a list of reflector triangles and their refinement.
pub struct Package {
    pub triangles: Vec<TriangleId>,
    vertices: Vec<Vertex>,
    /// (mesh, mesh vertex) → local vertex.
    originals: HashMap<(u32, u32), u32>,
    edges: Vec<Edge>,
    edge_of: HashMap<(u32, u32), u32>,
    faces: Vec<Face>,
    roots: Vec<u32>,
    queue: BinaryHeap<Queued>,
    filled: HashMap<u32, Vec3>,
    /// Triangles whose pixels changed since the last [`Package::take_pixels`].
    dirty: Vec<bool>,
    phase: Phase,
    pub counters: PackageCounters,
    /// Pixels [`Package::take_pixels`] took from the composition on the raster, so far.
    pub pixels_from_raster: u64,
    /// Rays this thread traced during [`Package::fill`]'s parallel tracing (its own share of
    /// the pixels, and any job it stole meanwhile, which counts itself): `run` leaves them out
    /// of its own count, the filled pixels being counted where they were traced.
    rays_counted_apart: (u64, u64),
}

fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

fn past(deadline: Option<Instant>) -> bool {
    deadline.is_some_and(|d| Instant::now() >= d)
}

/// Barycentric weights (of b and c) of `p` in triangle (a, b, c).
fn barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (f32, f32) {
    let (e1, e2, ep) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (dp1, dp2) = (ep.dot(e1), ep.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det.abs() <= f32::MIN_POSITIVE {
        return (0.0, 0.0);
    }
    ((d22 * dp1 - d12 * dp2) / det, (d11 * dp2 - d12 * dp1) / det)
}

fn cross2(a: Vec2, b: Vec2) -> f32 {
    a.x * b.y - a.y * b.x
}

/// The unit direction of the primary ray through pixel point `q`.
fn pixel_ray(inputs: &FrameInputs, q: Vec2) -> Vec3 {
    let view = &inputs.view;
    inputs
        .camera
        .ray_direction(q.x, q.y, view.width, view.height)
}

/// The weights of a, b and c (clamped to the triangle, summing to one) of the point where the
/// ray from `eye` along `dir` meets the plane of triangle (a, b, c) in front of the eye: the
/// Gouraud weights of rasterizing the triangle clipped at the near plane, which need no screen
/// position of its corners. None where the ray misses the plane.
fn weights_on_ray(eye: Vec3, dir: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<[f32; 3]> {
    let normal = (b - a).cross(c - a);
    let along = dir.dot(normal);
    if along.abs() <= f32::MIN_POSITIVE {
        return None;
    }
    let t = (a - eye).dot(normal) / along;
    if !t.is_finite() || t <= 0.0 {
        return None;
    }
    let (b1, b2) = barycentric(eye + dir * t, a, b, c);
    let weights = [1.0 - b1 - b2, b1, b2].map(|w| w.max(0.0));
    let total: f32 = weights.iter().sum();
    (total > 0.0).then(|| weights.map(|w| w / total))
}

/// A vertex at `p_world` on triangle `host` of `mesh`, traced: the primary ray from the eye
/// is aimed at it, so its intersection is known and not searched for (§3).
fn trace_vertex(inputs: &FrameInputs, mesh: u32, host: u32, p_world: Vec3) -> Vertex {
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
    samples: HashMap<(u32, u32), Vertex>,
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

impl Package {
    pub fn new(triangles: Vec<TriangleId>) -> Package {
        let count = triangles.len();
        Package {
            triangles,
            vertices: Vec::new(),
            originals: HashMap::default(),
            edges: Vec::new(),
            edge_of: HashMap::default(),
            faces: Vec::new(),
            roots: Vec::new(),
            queue: BinaryHeap::new(),
            filled: HashMap::default(),
            dirty: vec![false; count],
            phase: Phase::Preview,
            counters: PackageCounters::default(),
            pixels_from_raster: 0,
            rays_counted_apart: (0, 0),
        }
    }

    pub fn is_done(&self) -> bool {
        self.phase == Phase::Done
    }

    /// Whether the preview is traced.
    pub fn has_preview(&self) -> bool {
        self.phase != Phase::Preview
    }

    /// Works until `deadline` (None: to the end): the preview first (the triangles' own
    /// vertices), then refinement, then triangle filling. Returns whether it is done.
    pub fn run(&mut self, inputs: &FrameInputs, deadline: Option<Instant>) -> bool {
        let start = Instant::now();
        let before = rays_traced_on_this_thread();
        loop {
            match self.phase {
                Phase::Preview => {
                    self.preview(inputs);
                    self.phase = Phase::Refining;
                    if deadline.is_some() {
                        // The preview is shown before any refinement (the paper's first image).
                        break;
                    }
                }
                Phase::Refining => {
                    if !self.refine(inputs, deadline) {
                        break;
                    }
                    // Filling runs even without `fill`: stray pixels are traced (`trace_stray`).
                    self.phase = Phase::Filling { next: 0 };
                }
                Phase::Filling { .. } => {
                    if !self.fill(inputs, deadline) {
                        break;
                    }
                    self.phase = Phase::Done;
                }
                Phase::Done => break,
            }
        }
        let after = rays_traced_on_this_thread();
        let apart = std::mem::take(&mut self.rays_counted_apart);
        self.counters.rays += after.0 - before.0 - apart.0;
        self.counters.shadow_rays += after.1 - before.1 - apart.1;
        self.counters.seconds += start.elapsed().as_secs_f64();
        self.is_done()
    }

    fn mesh_of_face(&self, face: u32) -> u32 {
        self.triangles[self.faces[face as usize].origin as usize].mesh
    }

    /// A vertex at `p_world` on triangle `host` of `mesh`, traced.
    fn add_vertex(&mut self, inputs: &FrameInputs, mesh: u32, host: u32, p_world: Vec3) -> u32 {
        self.vertices
            .push(trace_vertex(inputs, mesh, host, p_world));
        self.counters.vertex_rays += 1;
        (self.vertices.len() - 1) as u32
    }

    fn edge(&mut self, a: u32, b: u32, level: u32, original: Option<(u32, u32)>) -> u32 {
        let key = edge_key(a, b);
        if let Some(&e) = self.edge_of.get(&key) {
            return e;
        }
        self.edges.push(Edge {
            a: key.0,
            b: key.1,
            level,
            original,
            faces: Vec::new(),
            state: EdgeState::Idle,
        });
        let e = (self.edges.len() - 1) as u32;
        self.edge_of.insert(key, e);
        e
    }

    fn enqueue(&mut self, e: u32, inputs: &FrameInputs) {
        let edge = &self.edges[e as usize];
        if !inputs.settings.refine || edge.state != EdgeState::Idle {
            return;
        }
        let (a, b) = (
            &self.vertices[edge.a as usize],
            &self.vertices[edge.b as usize],
        );
        // The paper's rule: an edge is refined only if one of its ends is seen.
        if !(a.visible || b.visible) {
            return;
        }
        let midpoint = (a.p_world + b.p_world) * 0.5;
        self.queue.push(Queued {
            length_bits: (a.screen - b.screen).length().to_bits(),
            midpoint_bits: midpoint.to_array().map(f32::to_bits),
            edge: e,
        });
        self.edges[e as usize].state = EdgeState::Queued;
    }

    /// The preview: every vertex of the package's triangles traced once, the triangles'
    /// edges put in the queue.
    fn preview(&mut self, inputs: &FrameInputs) {
        for index in 0..self.triangles.len() {
            let id = self.triangles[index];
            let mesh = &inputs.scene.meshes[id.mesh as usize];
            let tri = mesh.triangles[id.triangle as usize];
            let v = tri.map(|vertex| match self.originals.get(&(id.mesh, vertex)) {
                Some(&local) => local,
                None => {
                    let shared = inputs
                        .originals
                        .and_then(|o| o.samples.get(&(id.mesh, vertex)));
                    let local = match shared {
                        Some(sample) => {
                            self.vertices.push(*sample);
                            (self.vertices.len() - 1) as u32
                        }
                        None => {
                            let host = inputs.topology.vertex_host(id.mesh, vertex);
                            let p = mesh.positions[vertex as usize];
                            self.add_vertex(inputs, id.mesh, host, p)
                        }
                    };
                    self.originals.insert((id.mesh, vertex), local);
                    local
                }
            });
            self.faces.push(Face {
                v,
                origin: index as u32,
                level: 0,
                children: None,
            });
            let face = (self.faces.len() - 1) as u32;
            self.roots.push(face);
            for i in 0..3 {
                let e = self.edge(
                    v[i],
                    v[(i + 1) % 3],
                    0,
                    Some(edge_key(tri[i], tri[(i + 1) % 3])),
                );
                self.edges[e as usize].faces.push(face);
            }
            self.dirty[index] = true;
        }
        for e in 0..self.edges.len() as u32 {
            self.enqueue(e, inputs);
        }
    }

    /// The longest edge of `face` on the screen, its length and the face's height over it.
    fn longest_edge(&self, face: u32) -> (u32, f32, f32) {
        let v = self.faces[face as usize].v;
        let s = v.map(|i| self.vertices[i as usize].screen);
        let lengths = [0, 1, 2].map(|i| (s[(i + 1) % 3] - s[i]).length());
        let mut longest = 0;
        for i in 1..3 {
            if lengths[i] > lengths[longest] {
                longest = i;
            }
        }
        let c = lengths[longest];
        let area2 = cross2(s[1] - s[0], s[2] - s[0]).abs();
        let h = if c > 0.0 { area2 / c } else { 0.0 };
        let e = self.edge_of[&edge_key(v[longest], v[(longest + 1) % 3])];
        (e, c, h)
    }

    /// §3.2's factor of flatness: a refined face whose height is below `flatness` × its
    /// longest edge, and still at least two pixels, has that edge split.
    fn is_flat(&self, face: u32, settings: &Params) -> Option<u32> {
        let f = &self.faces[face as usize];
        if f.level == 0 || f.children.is_some() {
            return None;
        }
        let (e, c, h) = self.longest_edge(face);
        (c > 0.0 && h / c < settings.flatness && h >= 2.0).then_some(e)
    }

    /// CheckRefinement (Figure 6, line 4).
    fn check(&self, e: u32, inputs: &FrameInputs) -> Decision {
        let settings = &inputs.settings;
        let edge = &self.edges[e as usize];
        let (a, b) = (
            &self.vertices[edge.a as usize],
            &self.vertices[edge.b as usize],
        );
        if a.depth <= 0.0 || b.depth <= 0.0 {
            // Behind the eye no screen length exists; such faces' pixels are traced.
            return Decision::Keep;
        }
        let differ = differ(a, b, inputs);
        // With `flatness_inside_triangles`, a border edge is decided by its ends alone, the same
        // in both triangles beside it, whichever packages hold them.
        let flat = (edge.original.is_none() || !settings.flatness_inside_triangles)
            && edge
                .faces
                .iter()
                .any(|&f| self.is_flat(f, settings) == Some(e));
        if edge.level >= settings.max_level {
            return if differ {
                Decision::Unresolved
            } else {
                Decision::Keep
            };
        }
        if differ && (a.screen - b.screen).length() >= settings.min_edge_px {
            Decision::Split { flat: false }
        } else if flat {
            Decision::Split { flat: !differ }
        } else if differ {
            Decision::Unresolved
        } else {
            Decision::Keep
        }
    }

    /// RefineEdge: one new vertex at the edge's midpoint, each face beside it cut in two
    /// through it (Figure 4).
    fn split(&mut self, e: u32, inputs: &FrameInputs, flat: bool) {
        let edge = self.edges[e as usize].clone();
        let first_face = edge.faces[0];
        let mesh = self.mesh_of_face(first_face);
        let host = match edge.original {
            Some(original) => inputs.topology.edge_host(mesh, original),
            None => self.triangles[self.faces[first_face as usize].origin as usize].triangle,
        };
        let p_world =
            (self.vertices[edge.a as usize].p_world + self.vertices[edge.b as usize].p_world) * 0.5;
        let m = self.add_vertex(inputs, mesh, host, p_world);
        let level = edge.level + 1;
        self.edges[e as usize].state = EdgeState::Split;
        self.edges[e as usize].faces.clear();
        self.counters.edges_split += 1;
        self.counters.flat_splits += flat as u64;
        self.counters.deepest_level = self.counters.deepest_level.max(level as u64);
        let half_a = self.edge(edge.a, m, level, edge.original);
        let half_b = self.edge(m, edge.b, level, edge.original);
        let mut new_edges = vec![half_a, half_b];
        let mut new_faces = Vec::new();
        for &f in &edge.faces {
            let face = self.faces[f as usize];
            let i = (0..3)
                .find(|&i| edge_key(face.v[i], face.v[(i + 1) % 3]) == (edge.a, edge.b))
                .expect("a face beside an edge holds it");
            let (p, q, c) = (face.v[i], face.v[(i + 1) % 3], face.v[(i + 2) % 3]);
            let child_level = face.level.max(edge.level) + 1;
            let base = self.faces.len() as u32;
            let (first, second) = (base, base + 1);
            for v in [[p, m, c], [m, q, c]] {
                self.faces.push(Face {
                    v,
                    origin: face.origin,
                    level: child_level,
                    children: None,
                });
            }
            self.faces[f as usize].children = Some(([first, second], [m, c]));
            self.dirty[face.origin as usize] = true;
            let edge_p_m = self.edge_of[&edge_key(p, m)];
            self.edges[edge_p_m as usize].faces.push(first);
            let edge_m_q = self.edge_of[&edge_key(m, q)];
            self.edges[edge_m_q as usize].faces.push(second);
            let middle = self.edge(m, c, level, None);
            self.edges[middle as usize].faces.extend([first, second]);
            new_edges.push(middle);
            for (a, b, child) in [(q, c, second), (c, p, first)] {
                let side = self.edge_of[&edge_key(a, b)];
                for face_ref in &mut self.edges[side as usize].faces {
                    if *face_ref == f {
                        *face_ref = child;
                    }
                }
            }
            new_faces.extend([first, second]);
        }
        for new_edge in new_edges {
            self.enqueue(new_edge, inputs);
        }
        // A flat new face re-examines its longest edge even if that edge was kept before:
        // otherwise Figure 7's third edge is never cut and its neighbours never converge.
        for face in new_faces {
            if let Some(longest) = self.is_flat(face, &inputs.settings) {
                let edge = &self.edges[longest as usize];
                if (edge.original.is_none() || !inputs.settings.flatness_inside_triangles)
                    && edge.state == EdgeState::Idle
                {
                    self.enqueue(longest, inputs);
                }
            }
        }
    }

    /// Refine (Figure 6): until the queue is empty or the deadline passes.
    fn refine(&mut self, inputs: &FrameInputs, deadline: Option<Instant>) -> bool {
        let mut decisions = 0u32;
        while let Some(next) = self.queue.pop() {
            let e = next.edge;
            if self.edges[e as usize].state != EdgeState::Queued {
                continue;
            }
            match self.check(e, inputs) {
                Decision::Split { flat } => self.split(e, inputs, flat),
                Decision::Unresolved => {
                    self.edges[e as usize].state = EdgeState::Unresolved;
                    self.counters.unresolved_edges += 1;
                }
                Decision::Keep => self.edges[e as usize].state = EdgeState::Idle,
            }
            decisions += 1;
            if decisions.is_multiple_of(EDGES_PER_CLOCK_READ) && past(deadline) {
                return self.queue.is_empty();
            }
        }
        true
    }

    /// The leaf face of triangle `index` that holds pixel centre `q`.
    fn locate(&self, index: usize, q: Vec2, inputs: &FrameInputs) -> u32 {
        let mut face = self.roots[index];
        while let Some(([first, second], [m, c])) = self.faces[face as usize].children {
            let first_corner = &self.vertices[self.faces[first as usize].v[0] as usize];
            let (m, c) = (&self.vertices[m as usize], &self.vertices[c as usize]);
            let side = if c.depth <= 0.0 {
                // A corner behind the eye has no screen position: which side of the plane
                // through the eye and the separating line the pixel's ray passes.
                let eye = inputs.view.eye;
                let normal = (m.p_world - eye).cross(c.p_world - eye);
                pixel_ray(inputs, q).dot(normal) * (first_corner.p_world - eye).dot(normal)
            } else {
                let line = c.screen - m.screen;
                cross2(line, q - m.screen) * cross2(line, first_corner.screen - m.screen)
            };
            face = if side >= 0.0 { first } else { second };
        }
        face
    }

    /// Whether any leaf of triangle `index`'s refinement needs filling (most need none: their
    /// pixels are not looked at).
    fn any_leaf_needs_filling(&self, index: usize, settings: &Params) -> bool {
        let mut stack = vec![self.roots[index]];
        while let Some(face) = stack.pop() {
            match self.faces[face as usize].children {
                Some((children, _)) => stack.extend(children),
                None if self.needs_filling(face, settings) => return true,
                None => {}
            }
        }
        false
    }

    /// Whether triangle filling traces this leaf's pixels: refinement left one of its edges
    /// unresolved, none of its corners is seen (with `trace_unseen`), or a corner is behind
    /// the eye (with `trace_behind_eye`).
    fn needs_filling(&self, face: u32, settings: &Params) -> bool {
        let v = self.faces[face as usize].v;
        let corners = v.map(|i| &self.vertices[i as usize]);
        (settings.trace_behind_eye && corners.iter().any(|c| c.depth <= 0.0))
            || (settings.trace_unseen && corners.iter().all(|c| !c.visible))
            || (0..3).any(|i| {
                self.edge_of
                    .get(&edge_key(v[i], v[(i + 1) % 3]))
                    .is_some_and(|&e| self.edges[e as usize].state == EdgeState::Unresolved)
            })
    }

    /// Triangle filling (§3): every pixel of the faces refinement could not resolve traced
    /// as the reference traces it (with `fill`), and every stray pixel (with `trace_stray`).
    fn fill(&mut self, inputs: &FrameInputs, deadline: Option<Instant>) -> bool {
        let Phase::Filling { mut next } = self.phase else {
            return true;
        };
        let tracer = inputs.tracer();
        let settings = &inputs.settings;
        let (width, height) = (inputs.view.width, inputs.view.height);
        let pixel_rays = inputs.camera.pixel_rays(width, height);
        while next < self.triangles.len() {
            let any_leaf = settings.fill && self.any_leaf_needs_filling(next, settings);
            let pixels: Vec<(u32, bool)> = inputs
                .owners
                .owned(self.triangles[next])
                .filter(|&(_, stray)| (stray && settings.trace_stray) || any_leaf)
                .collect();
            // The leaf the last pixel fell in: the next is most often in it too, and finding
            // it from the root walks up to `max_level` separating lines.
            let mut last: Option<(u32, Leaf)> = None;
            let mut to_trace = Vec::new();
            for (k, stray) in pixels {
                let trace = (stray && settings.trace_stray) || {
                    let q = Vec2::new((k % width) as f32 + 0.5, (k / width) as f32 + 0.5);
                    let inside = last
                        .as_ref()
                        .filter(|(_, leaf)| leaf.strictly_contains(q))
                        .map(|(face, _)| *face);
                    let face = inside.unwrap_or_else(|| {
                        let face = self.locate(next, q, inputs);
                        last = Some((face, self.leaf(face, inputs)));
                        face
                    });
                    settings.fill && self.needs_filling(face, settings)
                };
                if trace {
                    to_trace.push(k);
                }
            }
            // Traced in parallel: one large triangle can hold most of a frame's filled pixels
            // (a pane of 12 vertices filled 97 % of its 225,660 pixels), and packages are
            // whole triangles. Each pixel's rays are counted on the thread that traced it;
            // what this thread traced meanwhile is left out of `run`'s count.
            use rayon::prelude::*;
            let here = rays_traced_on_this_thread();
            let traced: Vec<(u32, Vec3, (u64, u64))> = to_trace
                .par_iter()
                // Small fills stay on this thread: a job costs more than a few pixels.
                .with_min_len(PARALLEL_FILL_PIXELS)
                .map(|&k| {
                    let (x, y) = (k % width, k / width);
                    let before = rays_traced_on_this_thread();
                    let color = inputs.surfaces.radiance(&tracer, &pixel_rays, x, y, width);
                    let after = rays_traced_on_this_thread();
                    (k, color, (after.0 - before.0, after.1 - before.1))
                })
                .collect();
            let on_this_thread = rays_traced_on_this_thread();
            let (all, shadow) = traced
                .iter()
                .fold((0, 0), |sum, t| (sum.0 + t.2 .0, sum.1 + t.2 .1));
            self.counters.rays += all;
            self.counters.shadow_rays += shadow;
            self.rays_counted_apart.0 += on_this_thread.0 - here.0;
            self.rays_counted_apart.1 += on_this_thread.1 - here.1;
            for (k, color, _) in traced {
                self.filled.insert(k, color);
                self.counters.filled_pixels += 1;
                self.dirty[next] = true;
            }
            next += 1;
            self.phase = Phase::Filling { next };
            if past(deadline) {
                break;
            }
        }
        next == self.triangles.len()
    }

    /// What shading a leaf's pixels needs, computed once per leaf: its screen triangle, the
    /// inverse of its area, and whether deferred texturing applies.
    fn leaf(&self, face: u32, inputs: &FrameInputs) -> Leaf {
        let v = self.faces[face as usize].v;
        let corners = v.map(|i| &self.vertices[i as usize]);
        let [s0, s1, s2] = corners.map(|c| c.screen);
        let area = cross2(s1 - s0, s2 - s0);
        let behind_eye = corners.iter().any(|c| c.depth <= 0.0);
        let flat = area.abs() < 1e-12 || behind_eye;
        let alike = inputs.settings.deferred_textures
            && corners[0].path.read_count > 0
            && corners[1..].iter().all(|c| {
                c.path.tree.same_as(&corners[0].path.tree)
                    && c.path.read_count == corners[0].path.read_count
            });
        Leaf {
            v,
            s0,
            e1: s1 - s0,
            e2: s2 - s0,
            inverse_area: if flat { 0.0 } else { 1.0 / area },
            behind_eye,
            alike,
        }
    }

    /// Gouraud shading of pixel centre `q` (screen weights `at`) in `leaf`: with
    /// `perspective_correct` the weights divided by each corner's depth, else linear on the
    /// screen (the paper's). With deferred textures, where the three corners' paths are alike,
    /// the texture coordinates and coefficients of their texture reads are interpolated and
    /// the texels read here. A leaf with a corner behind the eye takes, without
    /// `trace_behind_eye`, the weights of the point where the pixel's ray meets it; any other
    /// leaf without a screen triangle the corners' mean.
    fn shade(&self, leaf: &Leaf, q: Vec2, at: [f32; 3], inputs: &FrameInputs) -> Vec3 {
        let settings = &inputs.settings;
        let corners = leaf.v.map(|i| &self.vertices[i as usize]);
        let mean = || corners.iter().map(|c| c.color).sum::<Vec3>() / 3.0;
        let blend = |weights: [f32; 3]| (0..3).map(|i| corners[i].color * weights[i]).sum();
        if leaf.behind_eye && !settings.trace_behind_eye {
            let [a, b, c] = corners.map(|c| c.p_world);
            return weights_on_ray(inputs.view.eye, pixel_ray(inputs, q), a, b, c)
                .map_or_else(mean, blend);
        }
        if leaf.inverse_area == 0.0 {
            return mean();
        }
        let at = at.map(|l| l.max(0.0));
        let mut weights = at;
        if settings.perspective_correct {
            for i in 0..3 {
                weights[i] /= corners[i].depth;
            }
        }
        let total: f32 = weights.iter().sum();
        if total <= 0.0 {
            return mean();
        }
        for w in &mut weights {
            *w /= total;
        }
        if !leaf.alike {
            return blend(weights);
        }
        let mut color: Vec3 = (0..3).map(|i| corners[i].smooth * weights[i]).sum();
        for read in 0..corners[0].path.read_count {
            let texture = &inputs.scene.textures[corners[0].path.reads[read].hit.texture];
            // Texture coordinates are perspective-correct for the textured surface's virtual
            // image (a floor seen through a sheet is deeper than the sheet).
            let mut uv_weights = [0.0f32; 3];
            for i in 0..3 {
                uv_weights[i] = at[i] / corners[i].path.reads[read].virtual_depth.max(1e-12);
            }
            let uv_total: f32 = uv_weights.iter().sum::<f32>().max(f32::MIN_POSITIVE);
            let uv: Vec2 = (0..3)
                .map(|i| corners[i].path.reads[read].hit.uv * (uv_weights[i] / uv_total))
                .sum();
            let coefficient: Vec3 = (0..3)
                .map(|i| corners[i].path.reads[read].hit.coefficient * weights[i])
                .sum();
            color += coefficient * texture.sample(uv);
        }
        color
    }

    /// The pixels of every triangle changed since the last call: (pixel, radiance). Pixels
    /// come in raster order, so the leaf of the last pixel is tried before the face tree is
    /// walked again.
    ///
    /// `composed`, where given, is the frame's composition on the raster (per pixel: colour
    /// and 1 where a face drawn there showed, see [`super::compose`]): those pixels take it and
    /// are not located; the rest are shaded here.
    pub fn take_pixels(
        &mut self,
        inputs: &FrameInputs,
        composed: Option<&[[f32; 4]]>,
    ) -> Vec<(u32, Vec3)> {
        let width = inputs.view.width;
        let mut out = Vec::new();
        for index in 0..self.triangles.len() {
            if !std::mem::take(&mut self.dirty[index]) {
                continue;
            }
            let mut last: Option<Leaf> = None;
            for k in inputs.owners.pixels(self.triangles[index]) {
                let filled = (!self.filled.is_empty())
                    .then(|| self.filled.get(&k))
                    .flatten();
                if let Some(&c) = filled {
                    out.push((k, c));
                    continue;
                }
                if let Some([r, g, b, 1.0]) = composed.map(|c| c[k as usize]) {
                    out.push((k, Vec3::new(r, g, b)));
                    self.pixels_from_raster += 1;
                    continue;
                }
                let q = Vec2::new((k % width) as f32 + 0.5, (k / width) as f32 + 0.5);
                let reuse = last.as_ref().and_then(|leaf| leaf.weights_inside(q));
                let (leaf, at) = match (last.take(), reuse) {
                    (Some(leaf), Some(at)) => (leaf, at),
                    _ => {
                        let leaf = self.leaf(self.locate(index, q, inputs), inputs);
                        let at = leaf.weights(q);
                        (leaf, at)
                    }
                };
                out.push((k, self.shade(&leaf, q, at, inputs)));
                last = Some(leaf);
            }
        }
        out
    }

    /// The leaf faces of the triangles changed since the last [`Package::take_pixels`], three
    /// corners each, for composition on the raster. A face whose pixels are all traced (filled)
    /// is left out; one the GPU cannot shade as [`Package::take_pixels`] does (deferred
    /// textures, a corner behind the eye, no screen area) is marked for the CPU.
    pub fn raster_faces(&self, inputs: &FrameInputs, out: &mut Vec<FaceVertex>) {
        let settings = &inputs.settings;
        let filled_all = settings.fill && self.phase == Phase::Done;
        for (face, f) in self.faces.iter().enumerate() {
            let face = face as u32;
            if f.children.is_some()
                || !self.dirty[f.origin as usize]
                || (filled_all && self.needs_filling(face, settings))
            {
                continue;
            }
            let leaf = self.leaf(face, inputs);
            let cpu_shaded = leaf.alike || leaf.behind_eye || leaf.inverse_area == 0.0;
            let id = self.triangles[f.origin as usize];
            for v in f.v {
                let corner = &self.vertices[v as usize];
                out.push(FaceVertex {
                    p_world: corner.p_world.to_array(),
                    color: corner.color.to_array(),
                    triangle_id: [id.mesh + 1, id.triangle],
                    cpu_shaded: cpu_shaded as u32,
                });
            }
        }
    }

    /// Leaf faces now (for the picture of the generated triangles, Figure 13).
    pub fn leaf_edges(&self) -> Vec<(Vec2, Vec2)> {
        self.faces
            .iter()
            .filter(|f| f.children.is_none())
            .flat_map(|f| {
                (0..3).map(move |i| {
                    (
                        self.vertices[f.v[i] as usize].screen,
                        self.vertices[f.v[(i + 1) % 3] as usize].screen,
                    )
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_on_ray_are_the_barycentrics_of_the_point_the_ray_meets() {
        let eye = Vec3::new(0.0, 1.0, 0.0);
        // A floor triangle with a corner behind the eye (the view looks along -z).
        let (a, b, c) = (
            Vec3::new(-2.0, 0.0, -6.0),
            Vec3::new(2.0, 0.0, -6.0),
            Vec3::new(0.0, 0.0, 4.0),
        );
        let expected = [0.2f32, 0.3, 0.5];
        let point = a * expected[0] + b * expected[1] + c * expected[2];
        let weights = weights_on_ray(eye, (point - eye).normalize(), a, b, c).unwrap();
        for (w, e) in weights.iter().zip(expected) {
            assert!((w - e).abs() < 1e-5, "{weights:?}");
        }
        // A point outside takes the face's nearest side: weights clamped, summing to one.
        let outside = a * 1.2 + b * 0.3 - c * 0.5;
        let clamped = weights_on_ray(eye, (outside - eye).normalize(), a, b, c).unwrap();
        assert!((clamped.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert_eq!(clamped[2], 0.0);
        // Away from the plane, or along it: no weights.
        assert!(weights_on_ray(eye, Vec3::Y, a, b, c).is_none());
        assert!(weights_on_ray(eye, Vec3::X, a, b, c).is_none());
    }
}
