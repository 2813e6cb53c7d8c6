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
use specula_trace::reference::rays_traced_on_this_thread;

mod criteria;
mod fill;
mod inputs;
mod samples;
mod topology;

pub use inputs::FrameInputs;
pub use samples::OriginalSamples;
use samples::{trace_vertex, PathRecord};
pub use topology::{PixelOwners, Topology, TriangleId};

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
