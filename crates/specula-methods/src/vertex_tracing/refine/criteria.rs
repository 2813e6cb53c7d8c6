//! The refinement criteria (the paper's CheckRefinement, §3 and Figure 6): when two traced
//! vertices differ (colour on the display, ray tree, creases, textures between them), and whether
//! a package's edge is kept, split, or left unresolved (longest edge, §3.2's flatness, length and
//! depth bounds).

use glam::{Vec2, Vec3};

use super::super::Params;
use super::{cross2, edge_key, Decision, FrameInputs, Package, Vertex};

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
pub(super) fn differ(a: &Vertex, b: &Vertex, inputs: &FrameInputs) -> bool {
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

/// Ends whose textured surfaces' normals differ by more than about 8° split their edge.
const CREASE_COSINE: f32 = 0.99;

/// The most texture samples one edge's texture test takes.
const TEXTURE_TEST_SAMPLES: f32 = 64.0;

impl Package {
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
    pub(super) fn is_flat(&self, face: u32, settings: &Params) -> Option<u32> {
        let f = &self.faces[face as usize];
        if f.level == 0 || f.children.is_some() {
            return None;
        }
        let (e, c, h) = self.longest_edge(face);
        (c > 0.0 && h / c < settings.flatness && h >= 2.0).then_some(e)
    }

    /// CheckRefinement (Figure 6, line 4).
    pub(super) fn check(&self, e: u32, inputs: &FrameInputs) -> Decision {
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
}
