//! Step 1 of pvrr: the exact path of the eye's ray through every reflector vertex — reflected
//! once at a mirror vertex, or refracted at a lens vertex, traced through the solid and
//! refracted again where it leaves (§4.5) — ending in the segment that leaves the reflector,
//! and that segment's nearest hit P in the scene.

use glam::Vec3;
use rayon::prelude::*;
use specula_scene::{MaterialKind, Scene};
use specula_trace::optics::{fresnel_dielectric, reflect, refract};
use specula_trace::reference::{offset_origin, surface_point};
use specula_trace::{Ray, SceneAccel};

/// Internal reflections followed inside a solid before a path is given up as trapped.
const MAX_INTERNAL_BOUNCES: u32 = 8;

/// How a reflector's vertices turn the eye's rays.
#[derive(Clone, Debug, PartialEq)]
pub enum Interaction {
    Reflect,
    /// Refraction through a solid, one index per colour channel that is drawn separately
    /// (one entry when the three are equal).
    Refract {
        iors: Vec<f32>,
    },
    /// A thin-walled sheet: rays pass straight through, attenuated by the sheet's reflectance.
    Sheet {
        ior: f32,
    },
    /// The light a dielectric's surface reflects towards the eye: a mirror whose weight is the
    /// exact Fresnel reflectance (a thin sheet's, s and p summed apart, ½ Σ 2R_σ / (1 + R_σ),
    /// when `thin`).
    SurfaceReflect {
        ior: f32,
        thin: bool,
    },
    /// The light reflected once inside a solid: refracted in, partly reflected where it first
    /// meets the surface again, refracted out where it meets it next. Weight 0 where either
    /// meeting is a total internal reflection (the first is `Refract`'s path; after the second
    /// the path would wander inside the solid).
    InternalReflect {
        ior: f32,
    },
}

impl Interaction {
    /// The reflection off a dielectric's surface, for a material that has one.
    pub fn surface_reflection(
        kind: &MaterialKind,
        ior_override: Option<Vec3>,
    ) -> Option<Interaction> {
        match *kind {
            MaterialKind::Dielectric { ior, thin_walled } => Some(Interaction::SurfaceReflect {
                ior: ior_override.unwrap_or(ior).y,
                thin: thin_walled,
            }),
            _ => None,
        }
    }

    /// The light reflected inside a solid dielectric (not a thin sheet).
    pub fn internal_reflection(
        kind: &MaterialKind,
        ior_override: Option<Vec3>,
    ) -> Option<Interaction> {
        match *kind {
            MaterialKind::Dielectric {
                ior,
                thin_walled: false,
            } => Some(Interaction::InternalReflect {
                ior: ior_override.unwrap_or(ior).y,
            }),
            _ => None,
        }
    }

    /// The interaction of `material`; `ior_override` replaces a dielectric's indices.
    pub fn of(kind: &MaterialKind, ior_override: Option<Vec3>) -> Option<Interaction> {
        match *kind {
            MaterialKind::Mirror { .. } => Some(Interaction::Reflect),
            MaterialKind::Dielectric { ior, thin_walled } => {
                let ior = ior_override.unwrap_or(ior);
                Some(if thin_walled {
                    Interaction::Sheet { ior: ior.y }
                } else if ior.x == ior.y && ior.y == ior.z {
                    Interaction::Refract { iors: vec![ior.y] }
                } else {
                    Interaction::Refract {
                        iors: ior.to_array().to_vec(),
                    }
                })
            }
            _ => None,
        }
    }
}

/// The straight piece of a path after it leaves the reflector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub origin: Vec3,
    pub dir: Vec3,
}

/// One colour channel's paths, per mesh vertex.
#[derive(Clone, Debug)]
pub struct ChannelPaths {
    pub exits: Vec<Segment>,
    /// Fraction of the light that survives the surfaces crossed (Fresnel transmittance; 1 at
    /// mirrors, whose Fresnel term the 2nd pass applies).
    pub weights: Vec<f32>,
}

/// Paths for every vertex of one reflector mesh, seen from one eye.
#[derive(Clone, Debug)]
pub struct MeshPaths {
    /// Whether the eye sees the vertex's side of the surface, i.e. the mesh does not hide the
    /// vertex from the eye. Only these vertices shape the virtual viewpoints.
    pub visible: Vec<bool>,
    pub channels: Vec<ChannelPaths>,
    /// Rays cast for these paths (visibility, inside the solid).
    pub rays: u64,
}

/// Step 1 for `mesh` seen from `eye`: visibility and exit segments, in parallel.
pub fn trace_paths(
    scene: &Scene,
    accel: &SceneAccel,
    mesh: usize,
    eye: Vec3,
    interaction: &Interaction,
) -> MeshPaths {
    let m = &scene.meshes[mesh];
    let visible: Vec<bool> = m
        .positions
        .par_iter()
        .map(|&v| {
            let to_vertex = v - eye;
            let distance = to_vertex.length();
            let ray = Ray {
                origin: eye,
                dir: to_vertex / distance,
            };
            accel
                .intersect(&ray, distance * (1.0 - 1e-4))
                .is_none_or(|hit| hit.mesh as usize != mesh)
        })
        .collect();
    let channel_count = match interaction {
        Interaction::Refract { iors } => iors.len(),
        Interaction::Reflect
        | Interaction::Sheet { .. }
        | Interaction::SurfaceReflect { .. }
        | Interaction::InternalReflect { .. } => 1,
    };
    let mut rays = m.positions.len() as u64;
    let channels: Vec<ChannelPaths> = (0..channel_count)
        .map(|channel| {
            let traced: Vec<(Segment, f32, u64)> = m
                .positions
                .par_iter()
                .zip(&m.normals)
                .map(|(&v, &n)| {
                    let d = (v - eye).normalize_or(Vec3::NEG_Z);
                    // The normal on the eye's side, for the open surfaces.
                    let facing = if d.dot(n) > 0.0 { -n } else { n };
                    let mirrored = || {
                        let r = reflect(d, facing);
                        Segment {
                            origin: offset_origin(v, facing, r),
                            dir: r,
                        }
                    };
                    match interaction {
                        Interaction::Refract { iors } => {
                            refract_through(scene, accel, mesh, v, n, d, iors[channel], false)
                        }
                        Interaction::InternalReflect { ior } => {
                            refract_through(scene, accel, mesh, v, n, d, *ior, true)
                        }
                        Interaction::Sheet { ior } => {
                            let r =
                                specula_trace::optics::thin_sheet_reflectance(-d.dot(facing), *ior);
                            let exit = Segment {
                                origin: offset_origin(v, facing, d),
                                dir: d,
                            };
                            (exit, 1.0 - r, 0)
                        }
                        Interaction::Reflect => (mirrored(), 1.0, 0),
                        Interaction::SurfaceReflect { ior, thin } => {
                            let cos_i = -d.dot(facing);
                            // Seen from inside a solid (the eye in the glass), the surface
                            // reflects as an interface from glass to air.
                            let eta = if d.dot(n) > 0.0 && !thin {
                                *ior
                            } else {
                                1.0 / *ior
                            };
                            let weight = if *thin {
                                specula_trace::optics::thin_sheet_reflectance(cos_i, *ior)
                            } else {
                                fresnel_dielectric(cos_i, eta)
                            };
                            (mirrored(), weight, 0)
                        }
                    }
                })
                .collect();
            rays += traced.iter().map(|t| t.2).sum::<u64>();
            ChannelPaths {
                exits: traced.iter().map(|t| t.0).collect(),
                weights: traced.iter().map(|t| t.1).collect(),
            }
        })
        .collect();
    // Paths that carry nothing (an internal reflection that is total) do not shape the views.
    let visible = visible
        .iter()
        .enumerate()
        .map(|(i, &v)| v && channels.iter().any(|c| c.weights[i] > 0.0))
        .collect();
    MeshPaths {
        visible,
        channels,
        rays,
    }
}

/// Refracts the eye ray `d` into the solid at vertex `v` (normal `n`), follows it through the
/// solid (internal reflection where total) and refracts it out where it leaves `mesh`. With
/// `reflect_first`, the path takes the partial reflection at the first surface it meets inside
/// (weight R) instead of leaving there, and must leave at the next (weight 0 where either is
/// a total internal reflection).
/// Returns the exit segment, the Fresnel weight along the way and the rays cast.
#[allow(clippy::too_many_arguments)]
fn refract_through(
    scene: &Scene,
    accel: &SceneAccel,
    mesh: usize,
    v: Vec3,
    n: Vec3,
    d: Vec3,
    ior: f32,
    reflect_first: bool,
) -> (Segment, f32, u64) {
    let (n, eta) = if d.dot(n) < 0.0 {
        (n, 1.0 / ior)
    } else {
        (-n, ior)
    };
    let Some(inside) = refract(d, n, eta) else {
        let r = reflect(d, n);
        let exit = Segment {
            origin: offset_origin(v, n, r),
            dir: r,
        };
        return (exit, if reflect_first { 0.0 } else { 1.0 }, 0);
    };
    let mut weight = 1.0 - fresnel_dielectric(-d.dot(n), eta);
    let mut reflect_next = reflect_first;
    let mut ray = Ray {
        origin: offset_origin(v, n, inside),
        dir: inside.normalize(),
    };
    let mut rays = 0;
    for _ in 0..MAX_INTERNAL_BOUNCES {
        rays += 1;
        let Some(hit) = accel.intersect(&ray, f32::INFINITY) else {
            break;
        };
        if hit.mesh as usize != mesh {
            break;
        }
        let sp = surface_point(scene, &ray, &hit);
        let eta = if sp.backface { ior } else { 1.0 / ior };
        let (dir, leaving) = match refract(ray.dir, sp.ns, eta) {
            Some(_) if reflect_next => {
                weight *= fresnel_dielectric(-ray.dir.dot(sp.ns), eta);
                (reflect(ray.dir, sp.ns), false)
            }
            Some(t) => {
                weight *= 1.0 - fresnel_dielectric(-ray.dir.dot(sp.ns), eta);
                (t.normalize(), sp.backface)
            }
            // The reflected path carries only what leaves at its next meeting: a total
            // internal reflection there (or at the first, which the plain path follows) ends it.
            None if reflect_first => {
                weight = 0.0;
                (reflect(ray.dir, sp.ns), true)
            }
            None => (reflect(ray.dir, sp.ns), false),
        };
        reflect_next = false;
        ray = Ray {
            origin: offset_origin(sp.p, sp.ng, dir),
            dir,
        };
        if leaving {
            break;
        }
    }
    // A path that met something else inside the solid (or nothing) before its reflection
    // carries none of the reflected light.
    if reflect_next {
        weight = 0.0;
    }
    let exit = Segment {
        origin: ray.origin,
        dir: ray.dir,
    };
    (exit, weight, rays)
}

/// The second half of step 1: every exit segment traced to its nearest hit P (or a point
/// `far_distance` along it when it leaves the scene), and whether the scene raster draws what
/// lies there (not a mirror or dielectric, which it leaves black; a miss is the background).
pub fn trace_hits(
    scene: &Scene,
    accel: &SceneAccel,
    exits: &[Segment],
    far_distance: f32,
) -> (Vec<Vec3>, Vec<bool>) {
    exits
        .par_iter()
        .map(|s| {
            let ray = Ray {
                origin: s.origin,
                dir: s.dir,
            };
            match accel.intersect(&ray, f32::INFINITY) {
                Some(hit) => {
                    let mesh = &scene.meshes[hit.mesh as usize];
                    let drawn = !scene.materials[mesh.material].is_specular();
                    (s.origin + s.dir * hit.t, drawn)
                }
                None => (s.origin + s.dir * far_distance, true),
            }
        })
        .unzip()
}

/// A rigid frame (the eye's) for expressing paths relative to it, so that a lens fixed to the
/// eye can reuse them as both move (the cached mode of §5).
#[derive(Clone, Copy, Debug)]
pub struct EyeFrame {
    pub origin: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
}

impl EyeFrame {
    pub fn point_to_local(&self, p: Vec3) -> Vec3 {
        self.vector_to_local(p - self.origin)
    }
    pub fn vector_to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.right), v.dot(self.up), v.dot(self.forward))
    }
    pub fn point_to_world(&self, p: Vec3) -> Vec3 {
        self.origin + self.vector_to_world(p)
    }
    pub fn vector_to_world(&self, v: Vec3) -> Vec3 {
        self.right * v.x + self.up * v.y + self.forward * v.z
    }
}
