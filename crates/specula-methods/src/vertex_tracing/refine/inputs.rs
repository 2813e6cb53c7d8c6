//! What every package of one frame reads ([`FrameInputs`]): the scene, the view and its ID
//! buffer, the settings; and from them the vertex visibility test and the active triangles in
//! Morton order.

use glam::Vec3;
use specula_scene::{Camera, Scene};
use specula_trace::reference::Tracer;
use specula_trace::SceneAccel;

use super::super::Params;
use super::{OriginalSamples, PixelOwners, Topology, TriangleId};
use specula_core::screen::{PixelSurfaces, ScreenView};

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
    pub(super) fn tracer(&self) -> Tracer<'_> {
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
