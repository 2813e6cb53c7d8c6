//! Steps 2–3 of pvrr: virtual viewpoints and view volumes, one per patch of a reflector, with
//! the principal-curvature up vector of §4.3 and the adaptive subdivision that §4.1 leaves to
//! future work (`max_patches=1`: one patch, as the paper).

use glam::{Mat3, Vec3};
use specula_gpu::shaders::CameraUniform;
use specula_scene::Mesh;

use super::rays::Segment;

/// Where a patch's 1st pass looks from and along.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewBasis {
    pub viewpoint: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
}

impl ViewBasis {
    /// `p` in this basis: x right, y up, z depth along `forward`.
    pub fn local(&self, p: Vec3) -> Vec3 {
        let q = p - self.viewpoint;
        Vec3::new(q.dot(self.right), q.dot(self.up), q.dot(self.forward))
    }

    /// The same viewpoint looking back (toward the mirror, in the zooming region): `forward`
    /// and `right` reversed, `up` kept.
    pub fn reversed(&self) -> ViewBasis {
        ViewBasis {
            viewpoint: self.viewpoint,
            right: -self.right,
            up: self.up,
            forward: -self.forward,
        }
    }
}

/// The view volume of a basis around a set of exit segments and hit points.
#[derive(Clone, Debug, PartialEq)]
pub struct Extents {
    pub near: f32,
    pub far: f32,
    pub tan_x: f32,
    pub tan_y: f32,
    /// How many hit points lie behind the viewpoint, where no map looking forward shows them.
    pub behind: usize,
    /// How many hit points it was made for.
    pub hits: usize,
}

/// The fewest hits behind a patch's viewpoint, and at least a quarter of its hits, that get it
/// a zooming view (two 1st passes); fewer are ray traced (`unresolved`). Near a lens's or a
/// ball's caustic, the patches that split off hold a hit or two behind: on the suite's glass
/// sphere a zooming view for each (127) doubled the frame at the same mean FLIP (0.0287).
const MIN_ZOOMING_HITS: usize = 8;

/// A limit on the view volume's half-angle tangents: beyond it the perspective map is useless.
const MAX_TAN: f32 = 50.0;

impl Extents {
    /// Full field of view (degrees) across the wider of the two axes.
    pub fn fov_deg(&self) -> f32 {
        2.0 * self.tan_x.max(self.tan_y).atan().to_degrees()
    }

    /// Near plane just in front of the segments' origins (the mirror), far plane past every
    /// hit and every corner of the scene's bounds `scene_corners` (so that the map holds what
    /// lies beyond the hits between vertices), sides containing every hit and, with
    /// `whole_lines` (§3.3: "the frustum should contain all reflection lines between the near
    /// and far clipping planes"), the part of every segment between the planes.
    pub fn new(
        basis: &ViewBasis,
        segments: &[(Vec3, Vec3)],
        scene_corners: &[Vec3],
        whole_lines: bool,
    ) -> Extents {
        let far = segments
            .iter()
            .map(|&(_, p)| p)
            .chain(scene_corners.iter().copied())
            .map(|p| basis.local(p).z)
            .fold(0.0f32, f32::max)
            .max(1e-3)
            * 1.05;
        let mirror_depth = segments
            .iter()
            .map(|&(o, _)| basis.local(o).z)
            .fold(f32::NEG_INFINITY, f32::max);
        let near = if mirror_depth > 0.0 {
            (mirror_depth * 1.0001).min(far * 0.5)
        } else {
            far * 1e-3
        };
        let (mut tan_x, mut tan_y) = (1e-3f32, 1e-3f32);
        let mut behind = 0;
        for &(o, p) in segments {
            let (o, p) = (basis.local(o), basis.local(p));
            if p.z <= 0.0 {
                behind += 1;
                continue;
            }
            // The 2nd pass looks the map up only between the hits' projections (a triangle's
            // texture coordinates interpolate its corners'), so the hits bound what it needs.
            // Where the segments spread from near the viewpoint (a ball lens, a sphere's
            // patches), their entries span many times the hits' angle and left the hits a
            // fraction of the map's texels: the suite's glass sphere 0.242 -> 0.029.
            // The segment enters the volume where it crosses the near plane (or at its origin).
            // A P before the near plane (an object touching the mirror) still projects; the
            // map shows what lies beyond the plane in its direction.
            let entry = if !whole_lines || p.z <= near {
                p
            } else if o.z >= near {
                o
            } else {
                o + (p - o) * ((near - o.z) / (p.z - o.z))
            };
            for q in [entry, p] {
                tan_x = tan_x.max(q.x.abs() / q.z);
                tan_y = tan_y.max(q.y.abs() / q.z);
            }
        }
        Extents {
            near,
            far,
            tan_x: tan_x.min(MAX_TAN) * 1.02,
            tan_y: tan_y.min(MAX_TAN) * 1.02,
            behind,
            hits: segments.len(),
        }
    }

    /// The zooming view of §7 (`basis` is the patch's basis [`ViewBasis::reversed`]): from the
    /// viewpoint back toward the mirror, holding every hit P — those before the viewpoint
    /// (between the mirror and the rays' convergence) as they project, those beyond it through
    /// the viewpoint, on the far side of its centre (where the map holds the forward view's
    /// content, drawn first). The far plane lies just before the nearest exit point (the
    /// mirror), so that the reversed depth test (farthest kept) finds the surface nearest the
    /// mirror; where a P lies beyond that, the far plane moves past it. Its `behind` counts
    /// the hits too close to the viewpoint's plane to show (beyond `MAX_TAN`, or before the
    /// near plane).
    pub fn zooming(basis: &ViewBasis, segments: &[(Vec3, Vec3)]) -> Extents {
        let mirror_depth = segments
            .iter()
            .map(|&(o, _)| basis.local(o).z)
            .fold(f32::INFINITY, f32::min);
        let zooming_depths = segments
            .iter()
            .map(|&(_, p)| basis.local(p).z)
            .filter(|&z| z > 0.0);
        let (nearest, farthest) =
            zooming_depths.fold((f32::INFINITY, 0.0f32), |(n, f), z| (n.min(z), f.max(z)));
        let far = if mirror_depth > 0.0 {
            (mirror_depth * 0.999).max(farthest * 1.001)
        } else {
            farthest * 1.001
        }
        .max(1e-3);
        // The reversed depth test decides at the far end, where depth is least precise: the
        // near plane stays within 10⁴ of the far one, and a P nearer than that is not shown.
        let near = (0.5 * nearest).clamp(far * 1e-4, far * 1e-3);
        let (mut tan_x, mut tan_y) = (1e-3f32, 1e-3f32);
        let mut behind = 0;
        for &(_, p) in segments {
            let q = basis.local(p);
            let (x, y) = (q.x.abs() / q.z.abs(), q.y.abs() / q.z.abs());
            let clipped = q.z > 0.0 && q.z < near;
            if x.max(y) > MAX_TAN || !x.is_finite() || !y.is_finite() || clipped {
                behind += 1;
                continue;
            }
            tan_x = tan_x.max(x);
            tan_y = tan_y.max(y);
        }
        Extents {
            near,
            far,
            tan_x: tan_x * 1.02,
            tan_y: tan_y * 1.02,
            behind,
            hits: segments.len(),
        }
    }

    /// The 1st pass camera: height `resolution` texels, width following the aspect ratio.
    pub fn camera(&self, basis: &ViewBasis, resolution: u32) -> CameraUniform {
        let height = resolution.max(1);
        let width = ((height as f32 * self.tan_x / self.tan_y).round() as u32).clamp(1, 4 * height);
        // The aspect CameraUniform derives from the texel counts must still cover tan_x.
        let tan_y = self.tan_y.max(self.tan_x * height as f32 / width as f32);
        CameraUniform::new(
            basis.viewpoint,
            basis.right,
            basis.up,
            basis.forward,
            2.0 * tan_y.atan().to_degrees(),
            width,
            height,
            self.near,
            self.far,
        )
    }
}

/// The point nearest, in the least-squares sense, to all lines:
/// (Σ (I − r rᵀ)) c = Σ (I − r rᵀ) o. None when the lines are (nearly) parallel.
pub fn least_squares_viewpoint<'a>(lines: impl Iterator<Item = &'a Segment>) -> Option<Vec3> {
    let (mut a, mut b, mut count) = (Mat3::ZERO, Vec3::ZERO, 0usize);
    for s in lines {
        let r = s.dir;
        let projector = Mat3::IDENTITY - Mat3::from_cols(r * r.x, r * r.y, r * r.z);
        a += projector;
        b += projector * s.origin;
        count += 1;
    }
    let solvable = a.determinant().abs() > 1e-6 * (count as f32).powi(3);
    solvable.then(|| a.inverse() * b).filter(|c| c.is_finite())
}

/// Principal curvature directions of a patch: the shape operator S (dn = S dp in the tangent
/// plane of the patch's mean normal) fitted by least squares over the patch's edges, then
/// diagonalised. None for a patch too small or degenerate to fit.
pub fn principal_directions(mesh: &Mesh, triangles: &[u32]) -> Option<[Vec3; 2]> {
    let mean_normal = triangles
        .iter()
        .flat_map(|&t| mesh.triangles[t as usize])
        .map(|i| mesh.normals[i as usize])
        .sum::<Vec3>()
        .try_normalize()?;
    let t1 = mean_normal.any_orthonormal_vector();
    let t2 = mean_normal.cross(t1);
    // Σ dp dpᵀ and Σ dn dpᵀ as 2 × 2 matrices (row-major).
    let (mut pp, mut np) = ([0.0f32; 4], [0.0f32; 4]);
    for &t in triangles {
        let tri = mesh.triangles[t as usize];
        for k in 0..3 {
            let (i, j) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
            let dp = mesh.positions[j] - mesh.positions[i];
            let dn = mesh.normals[j] - mesh.normals[i];
            let (p, n) = ([dp.dot(t1), dp.dot(t2)], [dn.dot(t1), dn.dot(t2)]);
            for r in 0..2 {
                for c in 0..2 {
                    pp[r * 2 + c] += p[r] * p[c];
                    np[r * 2 + c] += n[r] * p[c];
                }
            }
        }
    }
    let det = pp[0] * pp[3] - pp[1] * pp[2];
    if det.abs() <= 1e-12 * (pp[0] + pp[3]).powi(2) || det == 0.0 {
        return None;
    }
    let inv = [pp[3] / det, -pp[1] / det, -pp[2] / det, pp[0] / det];
    let s = [
        np[0] * inv[0] + np[1] * inv[2],
        np[0] * inv[1] + np[1] * inv[3],
        np[2] * inv[0] + np[3] * inv[2],
        np[2] * inv[1] + np[3] * inv[3],
    ];
    let (s11, s12, s22) = (s[0], 0.5 * (s[1] + s[2]), s[3]);
    let angle = 0.5 * (2.0 * s12).atan2(s11 - s22);
    let e1 = t1 * angle.cos() + t2 * angle.sin();
    Some([e1, mean_normal.cross(e1)])
}

/// Candidate frames looking along `forward` from `viewpoint`: the world-up one, then one per
/// principal direction (§4.3), each direction projected onto the image plane as the up vector.
fn candidate_bases(viewpoint: Vec3, forward: Vec3, principal: Option<[Vec3; 2]>) -> Vec<ViewBasis> {
    let world_up = if forward.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let mut ups = vec![world_up];
    if let Some(dirs) = principal {
        ups.extend(dirs);
    }
    ups.into_iter()
        .filter_map(|up_hint| {
            let right = forward.cross(up_hint).try_normalize()?;
            Some(ViewBasis {
                viewpoint,
                right,
                up: right.cross(forward),
                forward,
            })
        })
        .collect()
}

impl Patch {
    /// Itself without its zooming view if that is wider than `max_fov_deg`: a wider one is a
    /// worse map than ray tracing those hits (on the suite's lit room, a teapot patch's 173°
    /// zooming view took the mean FLIP from 0.131 to 0.133).
    fn zooming_within(self, max_fov_deg: f32) -> Patch {
        Patch {
            zooming: self.zooming.filter(|z| z.fov_deg() <= max_fov_deg),
            ..self
        }
    }

    /// The view volume its 2nd pass reads: the zooming one where it has one.
    pub fn map_extents(&self) -> &Extents {
        self.zooming.as_ref().unwrap_or(&self.extents)
    }

    /// Whether its view volume is good enough to keep as it is.
    fn acceptable(&self, max_fov_deg: f32) -> bool {
        let extents = self.map_extents();
        extents.behind == 0 && extents.fov_deg() <= max_fov_deg
    }

    /// How badly it needs splitting: hits it cannot show, then the widest field of view.
    fn badness(&self) -> f32 {
        let extents = self.map_extents();
        if extents.behind > 0 {
            1000.0 + extents.behind as f32
        } else {
            extents.fov_deg()
        }
    }
}

/// One patch of a reflector: its triangles (indices into the mesh's), and its 1st pass view.
#[derive(Clone, Debug)]
pub struct Patch {
    pub triangles: Vec<u32>,
    pub basis: ViewBasis,
    pub extents: Extents,
    /// With a zooming view (`PatchLimits::zooming_view`) and hits behind the viewpoint: the
    /// view volume of [`Extents::zooming`], looking along `basis.reversed()`, which the 2nd
    /// pass then reads for all the patch's vertices.
    pub zooming: Option<Extents>,
    /// Whether the up vector is a principal direction (§4.3) rather than the world's up.
    pub principal_up: bool,
    /// Set when no least-squares viewpoint existed and a fallback view was used.
    pub fallback: Option<String>,
}

/// What the patch construction needs per vertex.
pub struct PatchInput<'a> {
    pub mesh: &'a Mesh,
    pub visible: &'a [bool],
    /// Exit segments of the channel that places the viewpoint.
    pub primary: &'a [Segment],
    /// Per channel, per vertex: (exit segment origin, hit point P).
    pub segments: Vec<Vec<(Vec3, Vec3)>>,
    /// Per channel, per vertex: whether the scene raster draws what lies at P (not a mirror
    /// or lens, which it leaves black).
    pub drawn: &'a [Vec<bool>],
    /// The corners of the scene's bounding box, for the far plane.
    pub scene_corners: &'a [Vec3],
    /// View volumes contain the whole reflection lines (§3.3), not only their hits.
    pub whole_lines: bool,
}

#[derive(Clone, Copy)]
pub struct PatchLimits {
    pub max_fov_deg: f32,
    pub max_patches: usize,
    /// A patch with enough hits behind its viewpoint (`MIN_ZOOMING_HITS`) gets a zooming view
    /// (§7) instead of being split for them.
    pub zooming_view: bool,
}

impl PatchInput<'_> {
    fn patch_vertices(&self, triangles: &[u32]) -> Vec<usize> {
        let mut vertices: Vec<usize> = triangles
            .iter()
            .flat_map(|&t| self.mesh.triangles[t as usize])
            .map(|i| i as usize)
            .collect();
        vertices.sort_unstable();
        vertices.dedup();
        let visible: Vec<usize> = vertices
            .iter()
            .copied()
            .filter(|&v| self.visible[v])
            .collect();
        if visible.is_empty() {
            vertices
        } else {
            visible
        }
    }

    fn segments_of(&self, vertices: &[usize]) -> Vec<(Vec3, Vec3)> {
        self.segments
            .iter()
            .flat_map(|channel| vertices.iter().map(move |&v| channel[v]))
            .collect()
    }

    /// `drawn` for the segments of [`PatchInput::segments_of`].
    fn drawn_of(&self, vertices: &[usize]) -> Vec<bool> {
        self.drawn
            .iter()
            .flat_map(|channel| vertices.iter().map(move |&v| channel[v]))
            .collect()
    }

    /// Viewpoint, basis and extents for the triangles `triangles`, choosing among the up
    /// vectors the one with the smallest view-volume cross-section.
    fn view(&self, triangles: &[u32], limits: &PatchLimits) -> Patch {
        let vertices = self.patch_vertices(triangles);
        let lines: Vec<Segment> = vertices.iter().map(|&v| self.primary[v]).collect();
        let forward = lines
            .iter()
            .map(|s| s.dir)
            .sum::<Vec3>()
            .normalize_or(Vec3::Z);
        let origins_center =
            lines.iter().map(|s| s.origin).sum::<Vec3>() / lines.len().max(1) as f32;
        let mut fallback = None;
        let viewpoint = match least_squares_viewpoint(lines.iter()) {
            Some(c) => c,
            None => {
                let radius = lines
                    .iter()
                    .map(|s| (s.origin - origins_center).length())
                    .fold(1e-3f32, f32::max);
                fallback = Some(format!(
                    "pvrr: mirror '{}': {} reflection lines are (nearly) parallel, so no least-squares viewpoint exists; looking along their mean direction from 10 mirror radii behind the mirror instead",
                    self.mesh.name,
                    lines.len()
                ));
                origins_center - forward * radius * 10.0
            }
        };
        let segments = self.segments_of(&vertices);
        let drawn = self.drawn_of(&vertices);
        let principal = principal_directions(self.mesh, triangles);
        candidate_bases(viewpoint, forward, principal)
            .into_iter()
            .enumerate()
            .map(|(k, basis)| {
                let (extents, zooming) =
                    self.extents_in(&basis, &segments, &drawn, limits.zooming_view);
                Patch {
                    triangles: triangles.to_vec(),
                    basis,
                    extents,
                    zooming,
                    principal_up: k > 0,
                    fallback: fallback.clone(),
                }
            })
            // Whether a zooming view is wanted does not depend on the up vector (depth runs
            // along `forward`), so every candidate compares the same kind of volume.
            .min_by(|a, b| {
                let area = |p: &Patch| p.map_extents().tan_x * p.map_extents().tan_y;
                area(a).total_cmp(&area(b))
            })
            .expect("the world-up basis always exists")
            .zooming_within(limits.max_fov_deg)
    }

    /// The forward view volume of `basis` around `segments` and, with `zooming_view` where
    /// enough hits lie behind the viewpoint (`MIN_ZOOMING_HITS`) on surfaces the raster draws
    /// (`drawn`), the zooming one.
    fn extents_in(
        &self,
        basis: &ViewBasis,
        segments: &[(Vec3, Vec3)],
        drawn: &[bool],
        zooming_view: bool,
    ) -> (Extents, Option<Extents>) {
        let extents = Extents::new(basis, segments, self.scene_corners, self.whole_lines);
        let shown_behind = segments
            .iter()
            .zip(drawn)
            .filter(|&(&(_, p), &drawn)| drawn && basis.local(p).z <= 0.0)
            .count();
        let zooming =
            (zooming_view && shown_behind >= MIN_ZOOMING_HITS && 4 * shown_behind >= extents.hits)
                .then(|| Extents::zooming(&basis.reversed(), segments));
        (extents, zooming)
    }

    /// The view volumes of an already chosen patch for the current hits (the cached mode).
    pub fn refit(&self, patch: &Patch, limits: &PatchLimits) -> Patch {
        let vertices = self.patch_vertices(&patch.triangles);
        let (extents, zooming) = self.extents_in(
            &patch.basis,
            &self.segments_of(&vertices),
            &self.drawn_of(&vertices),
            limits.zooming_view,
        );
        Patch {
            extents,
            zooming,
            ..patch.clone()
        }
        .zooming_within(limits.max_fov_deg)
    }

    /// The adaptive subdivision §4.1 sketches: the reflector's triangles that the eye can see
    /// are split in halves (at the median centroid along the longest axis) until each patch's
    /// view volume is under the field-of-view limit with every hit in front of its viewpoint,
    /// or with a zooming view (`zooming_view`) every hit off its viewpoint's plane
    /// (or `max_patches` is reached; 1: the whole reflector, the paper's one view). Adjacent
    /// patches share their boundary vertices, whose hit points P are the same in both, so the
    /// images meet there exactly.
    pub fn patches(&self, limits: &PatchLimits) -> Vec<Patch> {
        let triangles: Vec<u32> = (0..self.mesh.triangles.len() as u32)
            .filter(|&t| {
                self.mesh.triangles[t as usize]
                    .iter()
                    .any(|&i| self.visible[i as usize])
            })
            .collect();
        if triangles.is_empty() {
            return Vec::new();
        }
        // Always split the worst patch first, so that a limited budget goes where the view
        // volumes are worst: hits they cannot show, then the widest field of view.
        let mut patches = vec![self.view(&triangles, limits)];
        while patches.len() < limits.max_patches {
            let worst = patches
                .iter()
                .enumerate()
                .filter(|(_, p)| !p.acceptable(limits.max_fov_deg) && p.triangles.len() > 1)
                .max_by(|a, b| a.1.badness().total_cmp(&b.1.badness()))
                .map(|(k, _)| k);
            let Some(worst) = worst else {
                break;
            };
            let patch = patches.swap_remove(worst);
            let (a, b) = self.split(&patch.triangles);
            patches.push(self.view(&a, limits));
            patches.push(self.view(&b, limits));
        }
        patches
    }

    fn split(&self, triangles: &[u32]) -> (Vec<u32>, Vec<u32>) {
        let centroid = |t: u32| {
            self.mesh.triangles[t as usize]
                .iter()
                .map(|&i| self.mesh.positions[i as usize])
                .sum::<Vec3>()
                / 3.0
        };
        let (lo, hi) = triangles.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &t| (lo.min(centroid(t)), hi.max(centroid(t))),
        );
        let axis = (hi - lo).max_position();
        let mut sorted = triangles.to_vec();
        sorted.sort_by(|&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
        let second = sorted.split_off(sorted.len() / 2);
        (sorted, second)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Segments that leave a mirror just in front of the viewpoint and spread widely, to hits
    /// on a far wall within a narrow cone (a ball lens's): the volume fitted to the hits is
    /// many times narrower than §3.3's, and still holds every hit.
    #[test]
    fn a_volume_fitted_to_the_hits_holds_them_and_is_narrower_than_the_whole_lines() {
        let basis = ViewBasis {
            viewpoint: Vec3::ZERO,
            right: Vec3::X,
            up: Vec3::Y,
            forward: Vec3::NEG_Z,
        };
        let segments: Vec<(Vec3, Vec3)> = (0..9)
            .map(|k| {
                let (x, y) = ((k % 3) as f32 - 1.0, (k / 3) as f32 - 1.0);
                // Origins 0.1 before the viewpoint, 0.05 off axis; hits 10 away, 0.5 off.
                (
                    Vec3::new(-x * 0.05, -y * 0.05, 0.1),
                    Vec3::new(x * 0.5, y * 0.5, -10.0),
                )
            })
            .collect();
        let corners = [Vec3::new(0.0, 0.0, -12.0)];
        let whole = Extents::new(&basis, &segments, &corners, true);
        let fitted = Extents::new(&basis, &segments, &corners, false);
        for &(_, p) in &segments {
            let q = basis.local(p);
            assert!(q.x.abs() / q.z <= fitted.tan_x && q.y.abs() / q.z <= fitted.tan_y);
        }
        assert!(
            fitted.tan_x * 5.0 < whole.tan_x && fitted.tan_y * 5.0 < whole.tan_y,
            "fitted {fitted:?}, whole lines {whole:?}"
        );
        assert_eq!((fitted.near, fitted.far), (whole.near, whole.far));
    }

    /// A concave mirror's zooming view: from the viewpoint back toward the mirror, its far
    /// plane just before the nearest exit point, every hit inside it (those beyond the
    /// viewpoint through it), a hit on the viewpoint's plane counted as not shown.
    #[test]
    fn a_zooming_volume_ends_before_the_mirror_and_holds_every_hit() {
        let basis = ViewBasis {
            viewpoint: Vec3::new(0.0, 0.0, 3.0),
            right: Vec3::NEG_X,
            up: Vec3::Y,
            forward: Vec3::NEG_Z,
        };
        // Exit points on the mirror 2.6–3 before the viewpoint; hits 1–2 before it, and
        // beyond it; one on its plane.
        let mut segments: Vec<(Vec3, Vec3)> = (0..8)
            .map(|k| {
                let x = k as f32 * 0.1 - 0.35;
                let mirror = Vec3::new(x, 0.2 * x, 0.4 * x * x);
                let toward = basis.viewpoint - mirror;
                let t = if k % 3 == 0 {
                    1.5
                } else {
                    0.3 + 0.05 * k as f32
                };
                (mirror, mirror + toward * t)
            })
            .collect();
        segments.push((Vec3::new(0.5, 0.0, 0.1), basis.viewpoint + Vec3::X * 0.4));
        let zooming = Extents::zooming(&basis, &segments);
        assert!(0.0 < zooming.near && zooming.near < zooming.far);
        let nearest_mirror = segments
            .iter()
            .map(|&(o, _)| basis.local(o).z)
            .fold(f32::INFINITY, f32::min);
        assert!(zooming.far < nearest_mirror, "{zooming:?}");
        assert!(zooming.far > nearest_mirror * 0.99, "{zooming:?}");
        assert_eq!(zooming.behind, 1, "the hit on the viewpoint's plane");
        for &(_, p) in &segments[..8] {
            let q = basis.local(p);
            assert!(q.x.abs() / q.z.abs() <= zooming.tan_x, "{q}");
            assert!(q.y.abs() / q.z.abs() <= zooming.tan_y, "{q}");
            if q.z > 0.0 {
                assert!(zooming.near < q.z && q.z < zooming.far, "{q} {zooming:?}");
            }
        }
    }
}
