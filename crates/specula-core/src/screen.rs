//! The view as pixels: where a world point lands on the image ([`ScreenView`]), and what the
//! CPU knows of each pixel's first surface ([`PixelSurfaces`]: the ID buffer with positions),
//! read back from the scene raster pass's G-buffer or traced on the CPU where there is no GPU.

use glam::Vec3;
use rayon::prelude::*;
use specula_gpu::util::padded_row_bytes;
use specula_gpu::{GpuContext, GpuError};
use specula_scene::{Camera, PixelRays};
use specula_trace::reference::{pixel_radiance, rays_traced_on_this_thread, Tracer};
use specula_trace::Image;
use specula_trace::{Hit, Ray, SceneAccel};

/// How the camera maps world points to pixels (the raster pass's pinhole, top-left origin).
#[derive(Clone, Copy, Debug)]
pub struct ScreenView {
    pub eye: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    tan_half: f32,
    aspect: f32,
    pub width: u32,
    pub height: u32,
}

impl ScreenView {
    pub fn new(camera: &Camera, width: u32, height: u32) -> ScreenView {
        let frame = camera.frame();
        ScreenView {
            eye: camera.eye,
            right: frame.right,
            up: frame.up,
            forward: frame.forward,
            tan_half: (camera.fov_y_deg.to_radians() * 0.5).tan(),
            aspect: width as f32 / height as f32,
            width,
            height,
        }
    }

    /// Pixel coordinates (x right, y down, pixel centres at +0.5) and view depth of `p_world`;
    /// None behind the eye.
    pub fn project(&self, p_world: Vec3) -> Option<(f32, f32, f32)> {
        let v = p_world - self.eye;
        let z = v.dot(self.forward);
        if z <= 1e-6 {
            return None;
        }
        let x = v.dot(self.right) / (z * self.tan_half * self.aspect);
        let y = v.dot(self.up) / (z * self.tan_half);
        Some((
            (x + 1.0) * 0.5 * self.width as f32,
            (1.0 - y) * 0.5 * self.height as f32,
            z,
        ))
    }

    /// The side of one pixel, in metres, at view depth `z`.
    pub fn footprint(&self, z: f32) -> f32 {
        2.0 * z * self.tan_half / self.height as f32
    }
}

/// The side of the square tiles the CPU ID buffer is traced in (the reference's).
const TILE: usize = 32;

/// What [`PixelSurfaces::retrace_shading`] shades in the ID buffer's own pass: the pixels
/// whose first surface (a mesh, or None: the background) `now` takes, with `tracer`; and the
/// pixels whose hit and position it keeps: those `keep` takes (the others' are left as they
/// were, their memory not written: about 40 of 48 bytes a pixel for the rest of a scene that
/// nothing reads again). Every pixel's id is written.
pub struct ShadeAtOnce<'a> {
    pub tracer: &'a Tracer<'a>,
    pub now: &'a (dyn Fn(Option<u32>) -> bool + Sync),
    pub keep: &'a (dyn Fn(Option<u32>) -> bool + Sync),
}

/// The G-buffer as the CPU sees it: per pixel (mesh + 1, triangle) and the world position.
/// After [`PixelSurfaces::retrace_shading`] the hits and positions of the pixels its `keep`
/// left out are stale: read a pixel's only where its id shows a surface that was kept.
pub struct PixelSurfaces {
    pub ids: Vec<[u32; 2]>,
    pub position: Vec<[f32; 4]>,
    /// Each pixel's closest hit, where the buffer was traced on the CPU (empty when it was
    /// read back from a raster pass): shading from it needs no second primary ray.
    pub hits: Vec<Option<Hit>>,
}

impl PixelSurfaces {
    /// The ID buffer traced on the CPU: each pixel centre's closest hit from `camera`, as the
    /// reference's primary rays meet it (the same rays bit for bit: what a run without a GPU
    /// uses), the hits kept.
    pub fn trace(accel: &SceneAccel, camera: &Camera, width: u32, height: u32) -> PixelSurfaces {
        let mut surfaces = PixelSurfaces::empty();
        surfaces.retrace(accel, camera, width, height);
        surfaces
    }

    /// No pixels (to be traced into).
    pub fn empty() -> PixelSurfaces {
        PixelSurfaces {
            ids: Vec::new(),
            position: Vec::new(),
            hits: Vec::new(),
        }
    }

    /// [`PixelSurfaces::trace`] into this buffer's memory (a steady frame allocates nothing).
    pub fn retrace(&mut self, accel: &SceneAccel, camera: &Camera, width: u32, height: u32) {
        self.retrace_shading(accel, camera, width, height, None);
    }

    /// [`PixelSurfaces::retrace`], shading at once the pixels `shading` takes (by their first
    /// surface), each from its hit as [`PixelSurfaces::radiance`] would: the same value, while
    /// the hit is at hand, in the same pass. Returns the (closest-hit, shadow) rays the shading
    /// traced (the primary rays of the pixels shaded included, as `radiance` counts them).
    pub fn retrace_shading(
        &mut self,
        accel: &SceneAccel,
        camera: &Camera,
        width: u32,
        height: u32,
        shading: Option<(&ShadeAtOnce, &mut Image)>,
    ) -> (u64, u64) {
        let rays = camera.pixel_rays(width, height);
        let count = (width * height) as usize;
        self.ids.resize(count, [0, 0]);
        self.position.resize(count, [0.0; 4]);
        self.hits.resize(count, None);
        // Each column's and row's image-plane coordinate computed once (the same directions as
        // `PixelRays::direction` bit for bit).
        let columns: Vec<f32> = (0..width).map(|x| rays.column(x as f32 + 0.5)).collect();
        // Without shading nothing is written to this image: its zeroed pages are never touched.
        let mut unshaded;
        let (shading, image) = match shading {
            Some((shading, image)) => (Some(shading), image),
            None => {
                unshaded = Image::new(width, height);
                (None, &mut unshaded)
            }
        };
        // In the reference's 32 x 32 tiles (`in_tiles`): the shading's secondary rays together.
        let (line, side) = (width as usize, TILE);
        let band = side * line;
        self.hits
            .par_chunks_mut(band)
            .zip(self.ids.par_chunks_mut(band))
            .zip(self.position.par_chunks_mut(band))
            .zip(image.pixels.par_chunks_mut(band))
            .enumerate()
            .map(|(band, (((hits, ids), positions), shaded))| {
                // The band cut into its tiles' row segments.
                type Segment<'s> = (
                    &'s mut [Option<Hit>],
                    &'s mut [[u32; 2]],
                    &'s mut [[f32; 4]],
                    &'s mut [Vec3],
                );
                let mut tiles: Vec<Vec<Segment>> =
                    (0..line.div_ceil(side)).map(|_| Vec::new()).collect();
                for (((h, i), p), c) in hits
                    .chunks_mut(line)
                    .zip(ids.chunks_mut(line))
                    .zip(positions.chunks_mut(line))
                    .zip(shaded.chunks_mut(line))
                {
                    for (tile, (((h, i), p), c)) in h
                        .chunks_mut(side)
                        .zip(i.chunks_mut(side))
                        .zip(p.chunks_mut(side))
                        .zip(c.chunks_mut(side))
                        .enumerate()
                    {
                        tiles[tile].push((h, i, p, c));
                    }
                }
                tiles
                    .into_par_iter()
                    .enumerate()
                    .map(|(tile, segments)| {
                        let before = rays_traced_on_this_thread();
                        let x0 = tile * side;
                        for (dy, (hits, ids, positions, shaded)) in segments.into_iter().enumerate()
                        {
                            let row = rays.row((band * side + dy) as f32 + 0.5);
                            for ((((hit, id), position), pixel), &column) in hits
                                .iter_mut()
                                .zip(ids)
                                .zip(positions)
                                .zip(shaded)
                                .zip(&columns[x0..])
                            {
                                let ray = Ray {
                                    origin: rays.eye,
                                    dir: rays.direction_from(column, row),
                                };
                                let found = accel.intersect(&ray, f32::INFINITY);
                                let mesh = found.map(|hit| hit.mesh);
                                *id = found.map_or([0, 0], |hit| [hit.mesh + 1, hit.triangle]);
                                if shading.is_none_or(|shading| (shading.keep)(mesh)) {
                                    *hit = found;
                                    *position = found.map_or([0.0; 4], |hit| {
                                        let p = ray.origin + ray.dir * hit.t;
                                        [p.x, p.y, p.z, 1.0]
                                    });
                                }
                                if let Some(shading) = shading {
                                    if (shading.now)(mesh) {
                                        *pixel = shading
                                            .tracer
                                            .radiance_of_primary(&ray, found.as_ref());
                                    }
                                }
                            }
                        }
                        let after = rays_traced_on_this_thread();
                        (after.0 - before.0, after.1 - before.1)
                    })
                    .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    }

    /// The reference's radiance of pixel (`x`, `y`) of a `width`-pixel-wide view whose
    /// primary rays are `rays`: shaded from this buffer's hit where it was traced on the CPU
    /// (the same ray: no second intersection), else traced. The primary ray is counted once.
    pub fn radiance(&self, tracer: &Tracer, rays: &PixelRays, x: u32, y: u32, width: u32) -> Vec3 {
        match self.hits.get((y * width + x) as usize) {
            Some(hit) => {
                let ray = Ray {
                    origin: rays.eye,
                    dir: rays.direction(x as f32 + 0.5, y as f32 + 0.5),
                };
                tracer.radiance_of_primary(&ray, hit.as_ref())
            }
            None => pixel_radiance(tracer, rays, x, y, 1),
        }
    }

    /// The world position seen through pixel `k` (None where the background shows).
    pub fn position(&self, k: usize) -> Option<Vec3> {
        (self.ids[k][0] != 0).then(|| Vec3::from_slice(&self.position[k][..3]))
    }
}

/// The ID buffer and positions of a G-buffer read back to the CPU into one buffer kept between
/// frames (a steady frame creates nothing).
pub struct SurfaceReadback {
    buffer: wgpu::Buffer,
    pub width: u32,
    pub height: u32,
    ids_row: u32,
    position_row: u32,
    position_offset: u64,
}

impl SurfaceReadback {
    pub fn new(gpu: &GpuContext, width: u32, height: u32) -> SurfaceReadback {
        let ids_row = padded_row_bytes(width * 8);
        let position_row = padded_row_bytes(width * 16);
        let position_offset = (ids_row * height) as u64;
        let buffer = gpu.create_buffer(&wgpu::BufferDescriptor {
            label: Some("g-buffer readback (ids, positions)"),
            size: position_offset + (position_row * height) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        SurfaceReadback {
            buffer,
            width,
            height,
            ids_row,
            position_row,
            position_offset,
        }
    }

    pub fn read(
        &self,
        gpu: &GpuContext,
        g: &crate::raster::GBuffer,
    ) -> Result<PixelSurfaces, GpuError> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let size = wgpu::Extent3d {
            width: self.width,
            height: self.height,
            depth_or_array_layers: 1,
        };
        for (texture, offset, row) in [
            (&g.ids, 0, self.ids_row),
            (&g.position, self.position_offset, self.position_row),
        ] {
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset,
                        bytes_per_row: Some(row),
                        rows_per_image: Some(self.height),
                    },
                },
                size,
            );
        }
        gpu.queue.submit([encoder.finish()]);
        let (w, h) = (self.width as usize, self.height as usize);
        gpu.read_mapped(&self.buffer, |bytes| {
            let mut ids = Vec::with_capacity(w * h);
            let mut position = Vec::with_capacity(w * h);
            for y in 0..h {
                let row = &bytes[y * self.ids_row as usize..][..w * 8];
                ids.extend_from_slice(bytemuck::cast_slice::<u8, [u32; 2]>(row));
                let start = self.position_offset as usize + y * self.position_row as usize;
                let row = &bytes[start..][..w * 16];
                position.extend_from_slice(bytemuck::cast_slice::<u8, [f32; 4]>(row));
            }
            PixelSurfaces {
                ids,
                position,
                hits: Vec::new(),
            }
        })
    }
}
