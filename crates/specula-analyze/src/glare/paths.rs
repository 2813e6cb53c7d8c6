//! Each pixel's paths, followed as the reference follows them but top-down, carrying the
//! throughput of s- and p-polarised light apart (Fresnel per polarisation), and split by where
//! they end: the named source after a reflection on the surface (glare), the display through the
//! surface (what the glare veils), the sky after a reflection on the surface (where the sun may
//! be), anything else (the rest of the picture).
//!
//! s and p are taken relative to each bounce's own plane of incidence: exact where a path's
//! bounces share one plane (a cover's two faces, a thin pane, a flat mirror), an approximation
//! where the plane turns between bounces, where Stokes vectors would rotate the two into each
//! other (the error is second order in the plane's turn and only on paths of three or more
//! Fresnel bounces; specula does not track Stokes vectors).

use glam::Vec3;
use specula_scene::{Camera, MaterialKind};
use specula_trace::optics::{
    fresnel_dielectric_sp, fresnel_schlick, reflect, refract, thin_sheet_reflectance_of,
};
use specula_trace::reference::{offset_origin, surface_point, SurfacePoint, Tracer};
use specula_trace::Ray;

use super::luminance;

/// The throughput of s- and p-polarised light along a path, per colour channel.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Polarised {
    s: Vec3,
    p: Vec3,
}

impl Polarised {
    const ONE: Polarised = Polarised {
        s: Vec3::ONE,
        p: Vec3::ONE,
    };

    /// Unpolarised light's throughput: the mean of the two.
    fn mean(self) -> Vec3 {
        0.5 * (self.s + self.p)
    }

    fn times(self, s: Vec3, p: Vec3) -> Polarised {
        Polarised {
            s: self.s * s,
            p: self.p * p,
        }
    }

    fn times_scalar(self, s: f32, p: f32) -> Polarised {
        self.times(Vec3::splat(s), Vec3::splat(p))
    }
}

/// Which meshes play which part.
#[derive(Clone, Copy, Debug)]
pub struct Roles {
    pub surface: usize,
    /// The named source (None: the sun, met where a path leaves the scene).
    pub source: Option<usize>,
    pub display: Option<usize>,
}

/// Where on the sky a path from a pixel's centre ends after reflecting on the surface, how much
/// of the sky's luminance it carries, and how the exit direction moves across the pixel.
#[derive(Clone, Copy, Debug)]
pub struct SkyExit {
    pub dir: Vec3,
    /// Y of the path's unpolarised throughput: the luminance factor of what it sees there.
    pub factor: f64,
    /// Tangent basis at `dir` the footprint is expressed in.
    pub e1: Vec3,
    pub e2: Vec3,
    /// The exit direction's change per pixel along x (column 0) and y (column 1), in the
    /// tangent plane at `dir` (gnomonic, radians per pixel).
    pub footprint: [[f64; 2]; 2],
    /// Whether the footprint was measured on this path (else the camera's own pixel footprint
    /// stands in: the path's neighbours took other branches, at an edge).
    pub footprint_measured: bool,
    key: u64,
}

/// What one pixel's paths bring.
#[derive(Clone, Debug, Default)]
pub struct PixelPaths {
    /// Everything the pixel shows (scene units), the sun excluded.
    pub radiance: Vec3,
    /// The named source's light after a reflection on the surface (scene units).
    pub glare: Vec3,
    /// Σ over those paths of Y(throughput × source radiance) / Y(source radiance): the glare's
    /// luminance factor.
    pub source_factor: f64,
    /// Σ of Y(throughput) over the paths that reach the display through the surface without
    /// reflecting on it: the cover's transmittance τ towards the display.
    pub display_transmittance: f64,
    /// Paths ending on the sky after a reflection on the surface.
    pub sky: Vec<SkyExit>,
}

#[derive(Clone, Copy)]
struct PathState {
    /// The path has reflected on the surface.
    via: bool,
    /// The path has passed through the surface.
    through: bool,
    channel: Option<usize>,
    /// The branches taken so far, hashed: a path's identity across neighbouring pixels.
    key: u64,
}

impl PathState {
    fn branched(self, mesh: u32, branch: u64) -> PathState {
        let mut z = self.key ^ (u64::from(mesh) << 8 | branch);
        z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        PathState {
            key: z ^ (z >> 31),
            ..self
        }
    }
}

const REFLECTED: u64 = 1;
const TRANSMITTED: u64 = 2;

pub struct PathTracer<'a> {
    pub tracer: Tracer<'a>,
    pub roles: Roles,
}

/// The offset, in pixels, of the rays that measure a sky exit's footprint.
const FOOTPRINT_STEP: f32 = 0.25;

impl PathTracer<'_> {
    /// Pixel (x, y)'s paths from `camera`, with each sky exit's footprint.
    pub fn pixel(&self, camera: &Camera, x: u32, y: u32, width: u32, height: u32) -> PixelPaths {
        let at = |dx: f32, dy: f32| {
            let dir = camera.ray_direction(x as f32 + 0.5 + dx, y as f32 + 0.5 + dy, width, height);
            let mut out = PixelPaths::default();
            let ray = Ray {
                origin: camera.eye,
                dir,
            };
            let state = PathState {
                via: false,
                through: false,
                channel: None,
                key: 0,
            };
            self.follow(&ray, Polarised::ONE, 0, state, &mut out);
            out
        };
        let mut centre = at(0.0, 0.0);
        if centre.sky.is_empty() {
            return centre;
        }
        let h = FOOTPRINT_STEP;
        let neighbours = [at(h, 0.0), at(-h, 0.0), at(0.0, h), at(0.0, -h)];
        let pixel_angle = camera_pixel_angle(camera, x, y, width, height);
        for exit in &mut centre.sky {
            let column = |ahead: &PixelPaths, behind: &PixelPaths| {
                let moved = |paths: &PixelPaths, sign: f64| {
                    paths.sky.iter().find(|e| e.key == exit.key).map(|e| {
                        let [u, v] = gnomonic(exit, e.dir);
                        [u * sign / f64::from(h), v * sign / f64::from(h)]
                    })
                };
                moved(ahead, 1.0).or_else(|| moved(behind, -1.0))
            };
            match (
                column(&neighbours[0], &neighbours[1]),
                column(&neighbours[2], &neighbours[3]),
            ) {
                (Some(jx), Some(jy)) => {
                    exit.footprint = [jx, jy];
                    exit.footprint_measured = true;
                }
                _ => exit.footprint = [[pixel_angle, 0.0], [0.0, pixel_angle]],
            }
        }
        centre
    }

    fn spawn(
        &self,
        sp: &SurfacePoint,
        dir: Vec3,
        weight: Polarised,
        depth: u32,
        state: PathState,
        out: &mut PixelPaths,
    ) {
        let ray = Ray {
            origin: offset_origin(sp.p, sp.ng, dir),
            dir,
        };
        self.follow(&ray, weight, depth + 1, state, out);
    }

    fn follow(
        &self,
        ray: &Ray,
        weight: Polarised,
        depth: u32,
        state: PathState,
        out: &mut PixelPaths,
    ) {
        let scene = self.tracer.scene;
        let Some(hit) = self.tracer.accel.intersect(ray, f32::INFINITY) else {
            self.leave(ray.dir, weight, state, out);
            return;
        };
        let sp = surface_point(scene, ray, &hit);
        let mesh = hit.mesh as usize;
        let material = &scene.materials[sp.material];
        let on_surface = mesh == self.roles.surface;
        match material.kind {
            MaterialKind::Unlit | MaterialKind::Diffuse => {
                let base = material.color
                    * material
                        .texture
                        .map(|t| scene.textures[t].sample(sp.uv))
                        .unwrap_or(Vec3::ONE);
                let radiance = match material.kind {
                    MaterialKind::Unlit => base,
                    _ => self.tracer.diffuse(&sp, base),
                };
                self.land(mesh, radiance, weight, state, out);
            }
            MaterialKind::Mirror { fresnel } => {
                if depth >= self.tracer.max_depth {
                    return;
                }
                let cos_i = -ray.dir.dot(sp.ns);
                let f = if fresnel {
                    fresnel_schlick(material.color, cos_i)
                } else {
                    material.color
                };
                let next = PathState {
                    via: state.via || on_surface,
                    ..state.branched(hit.mesh, REFLECTED)
                };
                let reflected = reflect(ray.dir, sp.ns);
                self.spawn(&sp, reflected, weight.times(f, f), depth, next, out);
            }
            MaterialKind::Dielectric { ior, thin_walled } => {
                if depth >= self.tracer.max_depth {
                    return;
                }
                let glass = Interface {
                    ray,
                    sp: &sp,
                    mesh: hit.mesh,
                    thin: thin_walled,
                    on_surface,
                    depth,
                };
                match state.channel {
                    None if material.is_dispersive() => {
                        for c in 0..3 {
                            let only = Vec3::from_array(std::array::from_fn(|k| {
                                if k == c {
                                    1.0
                                } else {
                                    0.0
                                }
                            }));
                            let state = PathState {
                                channel: Some(c),
                                ..state.branched(hit.mesh, 16 + c as u64)
                            };
                            self.dielectric(&glass, ior[c], weight.times(only, only), state, out);
                        }
                    }
                    None => self.dielectric(&glass, ior.x, weight, state, out),
                    Some(c) => self.dielectric(&glass, ior[c], weight, state, out),
                }
            }
        }
    }

    /// A path ends on an unlit or lit surface of `radiance`.
    fn land(
        &self,
        mesh: usize,
        radiance: Vec3,
        weight: Polarised,
        state: PathState,
        out: &mut PixelPaths,
    ) {
        let seen = weight.mean() * radiance;
        out.radiance += seen;
        if state.via && Some(mesh) == self.roles.source {
            out.glare += seen;
            let own = luminance(radiance);
            if own > 0.0 {
                out.source_factor += luminance(seen) / own;
            }
        }
        if state.through && !state.via && Some(mesh) == self.roles.display {
            out.display_transmittance += luminance(weight.mean());
        }
    }

    /// A path leaves the scene towards `dir`.
    fn leave(&self, dir: Vec3, weight: Polarised, state: PathState, out: &mut PixelPaths) {
        let scene = self.tracer.scene;
        out.radiance += weight.mean() * scene.background.radiance(dir, &scene.textures);
        if state.via && self.roles.source.is_none() {
            let (e1, e2) = dir.any_orthonormal_pair();
            out.sky.push(SkyExit {
                dir,
                factor: luminance(weight.mean()),
                e1,
                e2,
                footprint: [[0.0; 2]; 2],
                footprint_measured: false,
                key: state.key,
            });
        }
    }

    /// A dielectric interface: s and p reflected and transmitted each with its own Fresnel
    /// factor; a thin sheet's two faces summed per polarisation.
    fn dielectric(
        &self,
        glass: &Interface,
        ior: f32,
        weight: Polarised,
        state: PathState,
        out: &mut PixelPaths,
    ) {
        let (ray, sp) = (glass.ray, glass.sp);
        let cos_i = (-ray.dir.dot(sp.ns)).clamp(0.0, 1.0);
        let reflected = reflect(ray.dir, sp.ns);
        let mirrored = PathState {
            via: state.via || glass.on_surface,
            ..state.branched(glass.mesh, REFLECTED)
        };
        let passed = PathState {
            through: state.through || glass.on_surface,
            ..state.branched(glass.mesh, TRANSMITTED)
        };
        let depth = glass.depth;
        if glass.thin {
            let (r_s, r_p) = fresnel_dielectric_sp(cos_i, 1.0 / ior);
            let (s, p) = (
                thin_sheet_reflectance_of(r_s),
                thin_sheet_reflectance_of(r_p),
            );
            self.spawn(
                sp,
                reflected,
                weight.times_scalar(s, p),
                depth,
                mirrored,
                out,
            );
            let through = weight.times_scalar(1.0 - s, 1.0 - p);
            self.spawn(sp, ray.dir, through, depth, passed, out);
            return;
        }
        let eta = if sp.backface { ior } else { 1.0 / ior };
        let (r_s, r_p) = fresnel_dielectric_sp(cos_i, eta);
        match refract(ray.dir, sp.ns, eta) {
            Some(transmitted) if r_s < 1.0 || r_p < 1.0 => {
                let t = weight.times_scalar(1.0 - r_s, 1.0 - r_p);
                self.spawn(sp, transmitted.normalize(), t, depth, passed, out);
                if r_s > 0.0 || r_p > 0.0 {
                    let r = weight.times_scalar(r_s, r_p);
                    self.spawn(sp, reflected, r, depth, mirrored, out);
                }
            }
            _ => self.spawn(sp, reflected, weight, depth, mirrored, out),
        }
    }
}

/// A ray meeting a dielectric.
struct Interface<'a> {
    ray: &'a Ray,
    sp: &'a SurfacePoint,
    mesh: u32,
    thin: bool,
    on_surface: bool,
    depth: u32,
}

/// `dir` in the tangent plane at `exit.dir` (gnomonic projection), radians.
pub fn gnomonic(exit: &SkyExit, dir: Vec3) -> [f64; 2] {
    let along = f64::from(dir.dot(exit.dir)).max(1e-9);
    [
        f64::from(dir.dot(exit.e1)) / along,
        f64::from(dir.dot(exit.e2)) / along,
    ]
}

/// The angle a camera pixel spans (radians), at pixel (x, y).
fn camera_pixel_angle(camera: &Camera, x: u32, y: u32, width: u32, height: u32) -> f64 {
    let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
    let a = camera.ray_direction(fx - 0.5, fy, width, height);
    let b = camera.ray_direction(fx + 0.5, fy, width, height);
    f64::from(a.dot(b).clamp(-1.0, 1.0)).acos()
}
