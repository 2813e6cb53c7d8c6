//! The continuous 3-ray camera (C3RC; Popescu et al. 2006, as used by Mei, Popescu and Sacks
//! 2007, §5): a non-pinhole camera that interpolates three rays. Its image plane is the
//! triangle of the rays' tails (the base); its view volume is swept by the triangle
//! `T(λ) = (v1 + λ d1, v2 + λ d2, v3 + λ d3)`, λ ≥ 0, which cuts equal lengths on the three
//! unit rays.
//!
//! - Projection (§5.1): Q projects where a `T(λ)` contains it: `det[w1 − Q, w2 − Q, w3 − Q] = 0`
//!   is a cubic in λ; every real root λ ≥ 0 at which Q's barycentric coordinates in `T(λ)` are
//!   all in [0, 1] is a valid projection, at those barycentric coordinates of the base. All of
//!   them are returned (the paper's GPU could issue only one).
//! - Where multiple projections can occur (§5.1): only where `T(λ)` self-intersects, which needs
//!   a construction ray to have crossed the plane of `T(λ)`; ray i lies in that plane where
//!   `n(λ) · d_i = 0`, a quadratic. [`C3rc::multiple_projection_intervals`] gives the λ
//!   intervals where the rays are not all on one side.
//! - Box–view-volume intersection (§5.2): the paper's two conditions
//!   ([`C3rc::corner_inside_or_face_meets_wall`]): a box is kept if one of its corners has a
//!   valid projection (the box may be inside) or a face meets a side wall: a wall crosses one
//!   of its 12 edges (the paper's arcs p(α) against each face's frame, solved as one quadratic
//!   per wall and edge), or an arc ends inside a face (a construction ray or a base edge meets
//!   the box). Conservative ([`C3rc::may_see_box`]): also where the base triangle's inside meets
//!   the box, and around folds, the cases the two conditions miss.
//!
//! All arithmetic is in f64: the cubic's coefficients are differences of triple products of
//! nearly parallel vectors for small reflector triangles.

use glam::DVec3;

/// Barycentric slack for points on an edge shared by two cameras (both project them).
const BARY_EPS: f64 = 1e-9;
/// Sweep slack for points on the base.
const LAMBDA_EPS: f64 = 1e-9;

/// A continuous 3-ray camera: base vertices `v` (the reflector triangle) and unit construction
/// ray directions `d` (the reflected rays at those vertices).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct C3rc {
    pub v: [DVec3; 3],
    pub d: [DVec3; 3],
}

/// A camera's projection cubic as affine functions of the point (see [`C3rc::projector`]).
#[derive(Clone, Copy, Debug)]
pub struct Projector {
    constant: [f64; 4],
    linear: [DVec3; 4],
}

impl Projector {
    pub fn cubic(&self, q: DVec3) -> [f64; 4] {
        std::array::from_fn(|k| self.constant[k] + self.linear[k].dot(q))
    }
}

/// One valid projection of a point: the sweep parameter and the barycentric coordinates in the
/// base (and in `T(λ)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    pub lambda: f64,
    pub bary: [f64; 3],
}

impl Projection {
    /// The image point on the base (on the reflector triangle).
    pub fn base_point(&self, camera: &C3rc) -> DVec3 {
        camera.v[0] * self.bary[0] + camera.v[1] * self.bary[1] + camera.v[2] * self.bary[2]
    }
}

fn det(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    a.dot(b.cross(c))
}

/// A cheap convex bound of a camera's view volume: up to four planes, each with the whole
/// volume on its positive side: the base's plane (when every ray leaves the base to one side),
/// and through each base edge the plane containing the edge and the outermost ray as seen
/// along the edge (the other rays and the opposite vertex lie inside it). A point
/// x = Σ bᵢ vᵢ + λ Σ bᵢ dᵢ is then on the positive side of each plane, being a non-negative
/// combination of non-negative terms.
#[derive(Clone, Copy, Debug)]
pub struct PlaneBound {
    planes: [(DVec3, f64); 4],
    count: usize,
}

impl PlaneBound {
    /// False only when no point of the box `[lo, hi]` can be in the view volume.
    pub fn may_meet_box(&self, lo: DVec3, hi: DVec3) -> bool {
        self.planes[..self.count].iter().all(|&(n, offset)| {
            // The box corner farthest along n.
            let corner = DVec3::select(n.cmpge(DVec3::ZERO), hi, lo);
            n.dot(corner) >= offset
        })
    }

    /// The planes as (normal, offset): the volume lies where normal · x ≥ offset.
    pub fn planes(&self) -> &[(DVec3, f64)] {
        &self.planes[..self.count]
    }

    /// False only when `q` cannot be in the view volume.
    pub fn may_contain(&self, q: DVec3) -> bool {
        self.planes[..self.count]
            .iter()
            .all(|&(n, offset)| n.dot(q) >= offset)
    }
}

impl C3rc {
    /// Coefficients of the projection cubic as affine functions of the point: every term of
    /// `det[v1 + λd1 − Q, v2 + λd2 − Q, v3 + λd3 − Q]` is affine in Q (the Q × Q terms
    /// vanish), so `c_k(Q) = constant_k + linear_k · Q` is precomputed once per camera.
    pub fn projector(&self) -> Projector {
        // c0 = det[v1 − Q, v2 − Q, v3 − Q] = det[v1, v2, v3] − Q · (v2×v3 + v3×v1 + v1×v2).
        // For a column pair (x, y) the affine part of (x − Q) × (y − Q) is x×y − x×Q − Q×y
        //   = x×y + (y − x)×Q... collected below via dot products with the third column.
        let [v1, v2, v3] = self.v;
        let [d1, d2, d3] = self.d;
        // t(a, x, y) = a · ((x − Q) × (y − Q)) = a·(x×y) − Q·(y×a + a×x)... written as
        // constant a·(x×y) and linear −(y×a + a×x) (from a·(x×Q) = Q·(a×x), a·(Q×y) = Q·(y×a)).
        let term = |a: DVec3, x: DVec3, y: DVec3| (a.dot(x.cross(y)), -(y.cross(a) + a.cross(x)));
        // Column-wise: det[p, q, r] with p = x1 − Q ... ; the Q-free columns (d's) enter as a.
        // c0: det[v1 − Q, v2 − Q, v3 − Q].
        let c0 = (
            v1.dot(v2.cross(v3)),
            -(v2.cross(v3) + v3.cross(v1) + v1.cross(v2)),
        );
        // c1 = det[d1, v2 − Q, v3 − Q] + det[v1 − Q, d2, v3 − Q] + det[v1 − Q, v2 − Q, d3].
        let c1 = [term(d1, v2, v3), term(d2, v3, v1), term(d3, v1, v2)];
        // c2 = det[d1, d2, v3 − Q] + det[d1, v2 − Q, d3] + det[v1 − Q, d2, d3]: linear in Q.
        let (e3, e2, e1) = (d1.cross(d2), d3.cross(d1), d2.cross(d3));
        let c2 = (e3.dot(v3) + e2.dot(v2) + e1.dot(v1), -(e3 + e2 + e1));
        let c3 = d1.dot(d2.cross(d3));
        Projector {
            constant: [c0.0, c1.iter().map(|t| t.0).sum(), c2.0, c3],
            linear: [c0.1, c1.iter().map(|t| t.1).sum(), c2.1, DVec3::ZERO],
        }
    }

    /// The [`PlaneBound`] of this camera's view volume.
    pub fn plane_bound(&self) -> PlaneBound {
        let mut bound = PlaneBound {
            planes: [(DVec3::ZERO, 0.0); 4],
            count: 0,
        };
        let mut add = |n: DVec3, through: DVec3| {
            bound.planes[bound.count] = (n, n.dot(through));
            bound.count += 1;
        };
        const SLACK: f64 = -1e-12;
        let mut base = (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0]);
        if base.dot(self.d[0] + self.d[1] + self.d[2]) < 0.0 {
            base = -base;
        }
        if self.d.iter().all(|d| base.dot(*d) >= SLACK) {
            add(base, self.v[0]);
        }
        // Through each base edge, the plane that contains the edge and the outermost of the
        // three rays (seen along the edge): the others and the opposite vertex lie inside.
        let unit_base = base.normalize_or_zero();
        for a in 0..3 {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let edge = self.v[b] - self.v[a];
            let mut inward = unit_base.cross(edge).normalize_or_zero();
            if inward.dot(self.v[c] - self.v[a]) < 0.0 {
                inward = -inward;
            }
            // Angles from `inward` towards the base normal; the opposite vertex is at 0.
            let outermost = self
                .d
                .iter()
                .map(|d| d.dot(unit_base).atan2(d.dot(inward)))
                .fold(0.0f64, f64::max);
            let least = self
                .d
                .iter()
                .map(|d| d.dot(unit_base).atan2(d.dot(inward)))
                .fold(0.0f64, f64::min);
            if outermost - least >= std::f64::consts::PI - 1e-6 {
                continue;
            }
            let theta = outermost + 1e-9;
            let n = inward * theta.sin() - unit_base * theta.cos();
            add(n, self.v[a]);
        }
        bound
    }

    /// The camera of a reflector triangle seen from `eye`: each vertex's ray is the view
    /// direction reflected about the vertex normal.
    pub fn reflector(v: [DVec3; 3], n: [DVec3; 3], eye: DVec3) -> C3rc {
        let d = std::array::from_fn(|i| {
            let view = (v[i] - eye).normalize_or_zero();
            let normal = n[i].normalize_or_zero();
            (view - 2.0 * view.dot(normal) * normal).normalize_or_zero()
        });
        C3rc { v, d }
    }

    /// The camera in another space (a rigid transform keeps unit rays unit).
    pub fn transformed(&self, to: &glam::DMat4) -> C3rc {
        C3rc {
            v: self.v.map(|p| to.transform_point3(p)),
            d: self.d.map(|d| to.transform_vector3(d)),
        }
    }

    /// Vertex i of the sweeping triangle `T(λ)`.
    pub fn sweep_vertex(&self, i: usize, lambda: f64) -> DVec3 {
        self.v[i] + self.d[i] * lambda
    }

    /// Area of `T(λ)`: the cross-section a point at λ is magnified or minified by.
    pub fn sweep_area(&self, lambda: f64) -> f64 {
        self.sweep_normal(lambda).length() * 0.5
    }

    /// `(w2 − w1) × (w3 − w1)` of `T(λ)`.
    fn sweep_normal(&self, lambda: f64) -> DVec3 {
        let w = |i| self.sweep_vertex(i, lambda);
        (w(1) - w(0)).cross(w(2) - w(0))
    }

    /// Coefficients (c0, c1, c2, c3) of `det[w1 − Q, w2 − Q, w3 − Q]` as a polynomial in λ
    /// (directly; [`Projector`] evaluates the same affine forms faster).
    pub fn projection_cubic(&self, q: DVec3) -> [f64; 4] {
        let [a1, a2, a3] = self.v.map(|v| v - q);
        let [d1, d2, d3] = self.d;
        [
            det(a1, a2, a3),
            det(d1, a2, a3) + det(a1, d2, a3) + det(a1, a2, d3),
            det(d1, d2, a3) + det(d1, a2, d3) + det(a1, d2, d3),
            det(d1, d2, d3),
        ]
    }

    /// Q's barycentric coordinates in `T(λ)` (Q is in its plane).
    fn sweep_bary(&self, q: DVec3, lambda: f64) -> Option<[f64; 3]> {
        let [w1, w2, w3] = [0, 1, 2].map(|i| self.sweep_vertex(i, lambda));
        let n = (w2 - w1).cross(w3 - w1);
        let nn = n.length_squared();
        if nn <= 0.0 || !nn.is_finite() {
            return None;
        }
        let b1 = (w2 - q).cross(w3 - q).dot(n) / nn;
        let b2 = (w3 - q).cross(w1 - q).dot(n) / nn;
        Some([b1, b2, 1.0 - b1 - b2])
    }

    /// Every valid projection of `q` (at most three), in increasing λ. `first_only` stops at
    /// the first one (for cameras that cannot project a point twice, and for inside tests).
    pub fn project(&self, q: DVec3, first_only: bool) -> ([Projection; 3], usize) {
        self.project_with(self.projection_cubic(q), q, f64::INFINITY, first_only)
    }

    /// [`C3rc::project`] given the cubic's coefficients for `q`.
    /// Roots past `lambda_max` (where nothing the caller projects can be) are not checked.
    pub fn project_with(
        &self,
        cubic: [f64; 4],
        q: DVec3,
        lambda_max: f64,
        first_only: bool,
    ) -> ([Projection; 3], usize) {
        let mut out = [Projection {
            lambda: 0.0,
            bary: [0.0; 3],
        }; 3];
        let mut count = 0;
        let (roots, n) = real_roots(cubic);
        for &lambda in &roots[..n] {
            // Points on the base (λ = 0) come out a rounding error either side.
            if lambda < -LAMBDA_EPS || lambda > lambda_max {
                continue;
            }
            let lambda = lambda.max(0.0);
            let Some(bary) = self.sweep_bary(q, lambda) else {
                continue;
            };
            if bary
                .iter()
                .all(|&b| (-BARY_EPS..=1.0 + BARY_EPS).contains(&b))
            {
                out[count] = Projection { lambda, bary };
                count += 1;
                if first_only {
                    break;
                }
            }
        }
        (out, count)
    }

    /// The barycentrics on the base where `q` projects at the root of `cubic` (its projection
    /// cubic) nearest `lambda`, inside the base or not: for the footprint of a point's
    /// neighbourhood, whose edge may project just outside the triangle.
    pub fn bary_near(&self, cubic: [f64; 4], q: DVec3, lambda: f64) -> Option<[f64; 3]> {
        let (roots, n) = real_roots(cubic);
        let nearest = roots[..n]
            .iter()
            .copied()
            .filter(|&l| l >= -LAMBDA_EPS)
            .min_by(|a, b| (a - lambda).abs().total_cmp(&(b - lambda).abs()))?;
        self.sweep_bary(q, nearest.max(0.0))
    }

    /// Whether `q` lies in the view volume (has a valid projection).
    pub fn contains(&self, q: DVec3) -> bool {
        self.project(q, true).1 > 0
    }

    /// The λ intervals (λ ≥ 0; the last may end at infinity) in which the three construction
    /// rays are not all on the same side of `T(λ)`'s plane: the only places where `T(λ)` can
    /// cut an earlier position of itself, so the only places a point can project twice. Empty
    /// for cameras that project every point at most once.
    pub fn multiple_projection_intervals(&self) -> Vec<(f64, f64)> {
        let e1 = self.v[1] - self.v[0];
        let e2 = self.v[2] - self.v[0];
        let f1 = self.d[1] - self.d[0];
        let f2 = self.d[2] - self.d[0];
        // n(λ) = n0 + λ n1 + λ² n2.
        let n0 = e1.cross(e2);
        let n1 = e1.cross(f2) + f1.cross(e2);
        let n2 = f1.cross(f2);
        let side = |i: usize, lambda: f64| {
            let d = self.d[i];
            let s = n0.dot(d) + lambda * (n1.dot(d) + lambda * n2.dot(d));
            s > 0.0
        };
        let mut cuts: Vec<f64> = Vec::new();
        for d in self.d {
            let (roots, n) = real_roots([n0.dot(d), n1.dot(d), n2.dot(d), 0.0]);
            cuts.extend(roots[..n].iter().filter(|&&r| r > 0.0));
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        let mut bounds = vec![0.0];
        bounds.extend(&cuts);
        let mut intervals: Vec<(f64, f64)> = Vec::new();
        for (k, &start) in bounds.iter().enumerate() {
            let end = bounds.get(k + 1).copied().unwrap_or(f64::INFINITY);
            let probe = if end.is_finite() {
                0.5 * (start + end)
            } else {
                start * 2.0 + 1.0
            };
            let sides = [0, 1, 2].map(|i| side(i, probe));
            if sides[0] != sides[1] || sides[1] != sides[2] {
                match intervals.last_mut() {
                    Some(last) if last.1 == start => last.1 = end,
                    _ => intervals.push((start, end)),
                }
            }
        }
        intervals
    }

    /// The largest λ at which the view volume can reach the box `[lo, hi]`: a point at λ lies
    /// λ·|Σ bᵢ dᵢ| from its base point, and |Σ bᵢ dᵢ| ≥ minᵢ dᵢ·d̄ (d̄ the rays' mean
    /// direction). Infinite when the rays spread over a half-space.
    pub fn lambda_bound(&self, lo: DVec3, hi: DVec3) -> f64 {
        let mean = (self.d[0] + self.d[1] + self.d[2]).normalize_or_zero();
        let least = self
            .d
            .iter()
            .map(|d| d.dot(mean))
            .fold(f64::INFINITY, f64::min);
        if least < 0.05 {
            return f64::INFINITY;
        }
        let reach = self
            .v
            .iter()
            .map(|v| (v - (lo + hi) * 0.5).length() + (hi - lo).length() * 0.5)
            .fold(0.0, f64::max);
        reach / least
    }

    /// Boxes around the parts of the view volume where the sweeping triangle can fold over
    /// itself (this camera's [`C3rc::multiple_projection_intervals`], cut at `lambda_max`):
    /// `T(λ)` for λ in
    /// [a, b] lies in the hull of `T(a)` and `T(b)`, since each vertex moves along a segment.
    /// The fold's surface bounds the view volume there and is neither a side wall nor the
    /// base, so the §5.2 conditions miss it; an unbounded interval gives an unbounded box.
    pub fn fold_boxes(&self, intervals: &[(f64, f64)], lambda_max: f64) -> Vec<(DVec3, DVec3)> {
        intervals
            .iter()
            .filter(|&&(a, _)| a <= lambda_max)
            .map(|&(a, b)| {
                let b = b.min(lambda_max);
                if !b.is_finite() {
                    return (DVec3::NEG_INFINITY, DVec3::INFINITY);
                }
                let mut lo = DVec3::INFINITY;
                let mut hi = DVec3::NEG_INFINITY;
                for i in 0..3 {
                    for lambda in [a, b] {
                        let p = self.sweep_vertex(i, lambda);
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                }
                (lo, hi)
            })
            .collect()
    }

    /// Conservative box test (§5.2 with the missing cases): false only when the axis-aligned
    /// box `[lo, hi]` holds no point of the view volume. `folds` are this camera's
    /// [`C3rc::fold_boxes`] (empty for cameras that project every point once).
    pub fn may_see_box(&self, lo: DVec3, hi: DVec3, folds: &[(DVec3, DVec3)]) -> bool {
        // Where the sweeping triangle folds over, the volume's boundary is the fold.
        if folds
            .iter()
            .any(|(a, b)| a.cmple(hi).all() && lo.cmple(*b).all())
        {
            return true;
        }
        if self.corner_inside_or_face_meets_wall(lo, hi) {
            return true;
        }
        // The base's inside pierced by a box edge: a box straddling the base, whose corner
        // tested above lies behind it.
        box_edges(lo, hi).any(|(a, b)| segment_meets_triangle(a, b, self.v))
    }

    /// The paper's box test (§5.2): true unless both of its conditions hold, (1) the box is
    /// not wholly inside (an arbitrary corner, `lo`, has no valid projection) and (2) no face
    /// of the box meets a side wall. A wall meets a face where its arc p(α) in the face's plane
    /// crosses the face's frame (the paper's quadratics: the wall crosses a box edge) or has an
    /// end inside the face (a construction ray, the arc's end at α = 0 or 1, or a base edge,
    /// its end at λ = 0, meets the box); testing the frame alone would cull every box that a
    /// narrow volume passes through. It misses boxes that the base's inside pierces with the
    /// tested corner behind the base, and folds; [`C3rc::may_see_box`] keeps those.
    pub fn corner_inside_or_face_meets_wall(&self, lo: DVec3, hi: DVec3) -> bool {
        // The arcs' end points first (cheapest): a construction ray meets the box.
        if self
            .v
            .iter()
            .zip(&self.d)
            .any(|(&o, &d)| ray_meets_box(o, d, f64::INFINITY, lo, hi))
        {
            return true;
        }
        // A corner inside: the box may lie wholly inside the view volume.
        if self.contains(lo) {
            return true;
        }
        // The arcs' ends on the base: a base edge meets the box.
        if (0..3).any(|i| {
            let (a, b) = (self.v[i], self.v[(i + 1) % 3]);
            ray_meets_box(a, b - a, 1.0, lo, hi)
        }) {
            return true;
        }
        // A side wall crosses a box edge (the arc against a face's frame).
        (0..3).any(|i| self.wall_crosses_box_edges(i, (i + 1) % 3, lo, hi))
    }

    /// Whether the side wall `S(α, λ) = (1−α) v_a + α v_b + λ ((1−α) d_a + α d_b)`, α ∈ [0, 1],
    /// λ ≥ 0, crosses one of the box's 12 edges.
    fn wall_crosses_box_edges(&self, a: usize, b: usize, lo: DVec3, hi: DVec3) -> bool {
        let (base, along) = (self.v[a], self.v[b] - self.v[a]);
        let (dir, dir_change) = (self.d[a], self.d[b] - self.d[a]);
        const EPS: f64 = 1e-9;
        for k in 0..3 {
            // Edges along axis k sit at fixed coordinates on the two other axes.
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            for ci in [lo[i], hi[i]] {
                for cj in [lo[j], hi[j]] {
                    // S_i = ci and S_j = cj: eliminate λ, a quadratic in α.
                    let (p0i, p1i) = (ci - base[i], -along[i]);
                    let (p0j, p1j) = (cj - base[j], -along[j]);
                    let (q0i, q1i) = (dir[i], dir_change[i]);
                    let (q0j, q1j) = (dir[j], dir_change[j]);
                    let coefficients = [
                        p0i * q0j - p0j * q0i,
                        p0i * q1j + p1i * q0j - p0j * q1i - p1j * q0i,
                        p1i * q1j - p1j * q1i,
                        0.0,
                    ];
                    let scale = coefficients.iter().fold(0.0f64, |m, c| m.max(c.abs()));
                    if scale == 0.0 {
                        // The edge's line lies in the wall's ruling family: keep the box.
                        return true;
                    }
                    let (roots, n) = real_roots(coefficients);
                    for &alpha in &roots[..n] {
                        if !(-EPS..=1.0 + EPS).contains(&alpha) {
                            continue;
                        }
                        let qi = q0i + q1i * alpha;
                        let qj = q0j + q1j * alpha;
                        let lambda = if qi.abs() >= qj.abs() {
                            (p0i + p1i * alpha) / qi
                        } else {
                            (p0j + p1j * alpha) / qj
                        };
                        if !lambda.is_finite() || lambda < -EPS {
                            continue;
                        }
                        let s_k =
                            base[k] + along[k] * alpha + lambda * (dir[k] + dir_change[k] * alpha);
                        let slack = EPS * (1.0 + hi[k].abs().max(lo[k].abs()));
                        if s_k >= lo[k] - slack && s_k <= hi[k] + slack {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

/// The 12 edges of a box as segments.
fn box_edges(lo: DVec3, hi: DVec3) -> impl Iterator<Item = (DVec3, DVec3)> {
    let corner = move |m: usize| {
        DVec3::new(
            if m & 1 != 0 { hi.x } else { lo.x },
            if m & 2 != 0 { hi.y } else { lo.y },
            if m & 4 != 0 { hi.z } else { lo.z },
        )
    };
    (0..8usize).flat_map(move |m| {
        [1usize, 2, 4]
            .into_iter()
            .filter(move |bit| m & bit == 0)
            .map(move |bit| (corner(m), corner(m | bit)))
    })
}

/// Whether `o + t d`, t ∈ [0, t_max], meets the box (slab test, closed boxes).
fn ray_meets_box(o: DVec3, d: DVec3, t_max: f64, lo: DVec3, hi: DVec3) -> bool {
    let (mut t0, mut t1) = (0.0f64, t_max);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Whether the segment a–b meets the triangle (Möller–Trumbore, closed).
fn segment_meets_triangle(a: DVec3, b: DVec3, tri: [DVec3; 3]) -> bool {
    let dir = b - a;
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    let scale = e1.length() * e2.length() * dir.length();
    if det.abs() <= 1e-12 * scale {
        return false;
    }
    let s = a - tri[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    let t = e2.dot(q) / det;
    const E: f64 = 1e-9;
    u >= -E && v >= -E && u + v <= 1.0 + E && (-E..=1.0 + E).contains(&t)
}

/// Real roots of `c0 + c1 x + c2 x² + c3 x³` (degree taken from the largest non-negligible
/// coefficient), each polished by Newton steps. Returns the roots and how many there are.
pub fn real_roots(c: [f64; 4]) -> ([f64; 3], usize) {
    let scale = c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut out = [0.0; 3];
    if scale == 0.0 || !scale.is_finite() {
        return (out, 0);
    }
    // Relative to the largest coefficient, below this a leading coefficient is taken as zero.
    const TINY: f64 = 1e-12;
    let tiny = TINY * scale;
    let n;
    // The monic polynomial x³ + a x² + b x + cc (or of lower degree) the roots are polished on.
    let (a, b, cc, cubic);
    if c[3].abs() > tiny {
        let inv = 1.0 / c[3];
        (a, b, cc, cubic) = (c[2] * inv, c[1] * inv, c[0] * inv, true);
        // Depressed cubic t³ + p t + q with x = t − a/3.
        let p = b - a * a * (1.0 / 3.0);
        let q = a * a * a * (2.0 / 27.0) - a * b * (1.0 / 3.0) + cc;
        let shift = -a * (1.0 / 3.0);
        let disc = q * q * 0.25 + p * p * p * (1.0 / 27.0);
        if disc > 0.0 {
            let s = disc.sqrt();
            out[0] = (-0.5 * q + s).cbrt() + (-0.5 * q - s).cbrt() + shift;
            n = 1;
        } else if p == 0.0 {
            out[0] = shift;
            n = 1;
        } else {
            // Three real roots: the largest by trigonometry, the other two from the quadratic
            // left after dividing it out, t³ + pt + q = (t − r)(t² + rt + r² + p).
            let m = (-p * (1.0 / 3.0)).sqrt();
            let phi = (-q / (2.0 * m * m * m)).clamp(-1.0, 1.0).acos();
            let r = 2.0 * m * (phi * (1.0 / 3.0)).cos();
            let s = (-3.0 * r * r - 4.0 * p).max(0.0).sqrt();
            out = [r + shift, 0.5 * (-r + s) + shift, 0.5 * (-r - s) + shift];
            n = 3;
        }
    } else if c[2].abs() > tiny {
        let inv = 1.0 / c[2];
        (a, b, cc, cubic) = (0.0, c[1] * inv, c[0] * inv, false);
        // x² + b x + cc, the numerically stable pair.
        let disc = b * b - 4.0 * cc;
        if disc >= 0.0 {
            let s = disc.sqrt();
            let half = -0.5 * (b + if b >= 0.0 { s } else { -s });
            if half != 0.0 {
                out[0] = half;
                out[1] = cc / half;
                n = 2;
            } else {
                n = 1;
            }
        } else {
            n = 0;
        }
    } else if c[1].abs() > tiny {
        out[0] = -c[0] / c[1];
        return (out, 1);
    } else {
        return (out, 0);
    }
    // Newton steps on the monic polynomial.
    for x in out.iter_mut().take(n) {
        for _ in 0..2 {
            let (f, df) = if cubic {
                (((*x + a) * *x + b) * *x + cc, (3.0 * *x + 2.0 * a) * *x + b)
            } else {
                ((*x + b) * *x + cc, 2.0 * *x + b)
            };
            if df == 0.0 {
                break;
            }
            let step = f / df;
            if !step.is_finite() {
                break;
            }
            *x -= step;
        }
    }
    // Three-element sorting network.
    if n == 3 {
        if out[0] > out[1] {
            out.swap(0, 1);
        }
        if out[1] > out[2] {
            out.swap(1, 2);
        }
        if out[0] > out[1] {
            out.swap(0, 1);
        }
    } else if n == 2 && out[0] > out[1] {
        out.swap(0, 1);
    }
    (out, n)
}
