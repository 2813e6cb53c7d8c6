//! Who owns what in a vertex-tracing frame: the reflector triangles ([`TriangleId`]), each
//! mesh's host triangles for its vertices and edges ([`Topology`]), and the ID buffer's pixels
//! owned by each triangle ([`PixelOwners`]).

use glam::Vec2;
use rustc_hash::FxHashMap as HashMap;
use specula_scene::Scene;

use super::{cross2, edge_key};
use specula_core::screen::{PixelSurfaces, ScreenView};

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

    pub(super) fn vertex_host(&self, mesh: u32, vertex: u32) -> u32 {
        self.mesh(mesh).vertex_host[vertex as usize]
    }

    pub(super) fn edge_host(&self, mesh: u32, edge: (u32, u32)) -> u32 {
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
