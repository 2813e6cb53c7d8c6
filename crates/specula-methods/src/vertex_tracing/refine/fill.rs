//! A package's pixels (§3): its leaf faces located per pixel, filled by tracing where their
//! corners differ or Gouraud-interpolated where they agree, and what it hands on (changed
//! pixels, faces for the raster composition, leaf edges for `show_faces`).

use std::time::Instant;

use glam::{Vec2, Vec3};
use specula_trace::reference::rays_traced_on_this_thread;

use super::super::compose::FaceVertex;
use super::super::Params;
use super::{
    cross2, edge_key, past, pixel_ray, weights_on_ray, EdgeState, FrameInputs, Package, Phase,
};

/// Filled pixels per parallel job.
const PARALLEL_FILL_PIXELS: usize = 256;

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

impl Package {
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
    pub(super) fn fill(&mut self, inputs: &FrameInputs, deadline: Option<Instant>) -> bool {
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
