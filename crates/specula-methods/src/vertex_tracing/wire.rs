//! The messages of distributed vertex tracing (§4), as bytes: what the MPI master and workers
//! send each other, and what the discrete-event simulation charges the network for. Little
//! endian; a pixel result is 16 bytes (index and three f32).
//!
//! Without the feature `mpi` only the simulation uses this module (its message sizes); the
//! codec is for the MPI master and workers (`super::distributed`) and its tests.
#![cfg_attr(not(feature = "mpi"), allow(dead_code))]

use glam::Vec3;
use specula_scene::Camera;

use super::refine::PackageCounters;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum WireError {
    #[error("message ends after {at} of the {needed} bytes it needs")]
    Truncated { at: usize, needed: usize },
    #[error("unknown message kind {0}")]
    UnknownKind(u8),
}

#[derive(Clone, Debug, PartialEq)]
pub enum Message {
    /// A new frame: every worker computes its ID buffer for this view.
    Frame {
        frame: u32,
        camera: Camera,
        width: u32,
        height: u32,
    },
    /// Refine the frame's active triangles `start..end`.
    Package {
        frame: u32,
        id: u32,
        start: u32,
        end: u32,
    },
    /// A package's pixels and what it cost.
    Result {
        frame: u32,
        id: u32,
        counters: PackageCounters,
        pixels: Vec<(u32, Vec3)>,
    },
    /// The run is over; `finalize` false: a rank was lost, exit without MPI_Finalize (it would
    /// wait for the lost rank).
    Quit { finalize: bool },
}

struct Writer(Vec<u8>);

impl Writer {
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn vec3(&mut self, v: Vec3) {
        v.to_array().into_iter().for_each(|c| self.f32(c));
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], WireError> {
        let end = self.at + N;
        let slice = self.bytes.get(self.at..end).ok_or(WireError::Truncated {
            at: self.bytes.len(),
            needed: end,
        })?;
        self.at = end;
        Ok(slice.try_into().expect("N bytes"))
    }
    fn u8(&mut self) -> Result<u8, WireError> {
        Ok(self.take::<1>()?[0])
    }
    fn u32(&mut self) -> Result<u32, WireError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn u64(&mut self) -> Result<u64, WireError> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    fn f32(&mut self) -> Result<f32, WireError> {
        Ok(f32::from_le_bytes(self.take()?))
    }
    fn f64(&mut self) -> Result<f64, WireError> {
        Ok(f64::from_le_bytes(self.take()?))
    }
    fn vec3(&mut self) -> Result<Vec3, WireError> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
}

/// Bytes of a result message holding `pixels` pixels.
pub fn result_bytes(pixels: usize) -> usize {
    1 + 4 + 4 + 8 * 8 + 8 + 4 + 16 * pixels
}

/// Bytes of a package message.
pub const PACKAGE_BYTES: usize = 17;

impl Message {
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Writer(Vec::new());
        match self {
            Message::Frame {
                frame,
                camera,
                width,
                height,
            } => {
                w.0.push(1);
                w.u32(*frame);
                w.vec3(camera.eye);
                w.vec3(camera.target);
                w.vec3(camera.up);
                w.f32(camera.fov_y_deg);
                w.f32(camera.aspect.unwrap_or(0.0));
                w.u32(*width);
                w.u32(*height);
            }
            Message::Package {
                frame,
                id,
                start,
                end,
            } => {
                w.0.push(2);
                for v in [*frame, *id, *start, *end] {
                    w.u32(v);
                }
            }
            Message::Result {
                frame,
                id,
                counters: c,
                pixels,
            } => {
                w.0.reserve(result_bytes(pixels.len()));
                w.0.push(3);
                w.u32(*frame);
                w.u32(*id);
                for v in [
                    c.vertex_rays,
                    c.filled_pixels,
                    c.rays,
                    c.shadow_rays,
                    c.edges_split,
                    c.flat_splits,
                    c.unresolved_edges,
                    c.deepest_level,
                ] {
                    w.u64(v);
                }
                w.f64(c.seconds);
                w.u32(pixels.len() as u32);
                for (k, color) in pixels {
                    w.u32(*k);
                    w.vec3(*color);
                }
            }
            Message::Quit { finalize } => {
                w.0.push(4);
                w.0.push(*finalize as u8);
            }
        }
        w.0
    }

    pub fn decode(bytes: &[u8]) -> Result<Message, WireError> {
        let mut r = Reader { bytes, at: 0 };
        Ok(match r.u8()? {
            1 => {
                let frame = r.u32()?;
                let (eye, target, up) = (r.vec3()?, r.vec3()?, r.vec3()?);
                let fov_y_deg = r.f32()?;
                let aspect = r.f32()?;
                Message::Frame {
                    frame,
                    camera: Camera {
                        eye,
                        target,
                        up,
                        fov_y_deg,
                        aspect: (aspect > 0.0).then_some(aspect),
                    },
                    width: r.u32()?,
                    height: r.u32()?,
                }
            }
            2 => Message::Package {
                frame: r.u32()?,
                id: r.u32()?,
                start: r.u32()?,
                end: r.u32()?,
            },
            3 => {
                let frame = r.u32()?;
                let id = r.u32()?;
                let mut c = PackageCounters::default();
                for v in [
                    &mut c.vertex_rays,
                    &mut c.filled_pixels,
                    &mut c.rays,
                    &mut c.shadow_rays,
                    &mut c.edges_split,
                    &mut c.flat_splits,
                    &mut c.unresolved_edges,
                    &mut c.deepest_level,
                ] {
                    *v = r.u64()?;
                }
                c.seconds = r.f64()?;
                let count = r.u32()? as usize;
                let mut pixels = Vec::with_capacity(count.min(bytes.len() / 16));
                for _ in 0..count {
                    pixels.push((r.u32()?, r.vec3()?));
                }
                Message::Result {
                    frame,
                    id,
                    counters: c,
                    pixels,
                }
            }
            4 => Message::Quit {
                finalize: r.u8()? != 0,
            },
            kind => return Err(WireError::UnknownKind(kind)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_round_trip_and_sizes_hold() {
        let camera = Camera {
            eye: Vec3::new(1.0, 2.0, 3.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 35.0,
            aspect: None,
        };
        let result = Message::Result {
            frame: 2,
            id: 9,
            counters: PackageCounters {
                vertex_rays: 5,
                seconds: 0.25,
                ..Default::default()
            },
            pixels: vec![(7, Vec3::new(0.5, 1.5, 2.5)), (8, Vec3::ONE)],
        };
        let package = Message::Package {
            frame: 1,
            id: 3,
            start: 10,
            end: 20,
        };
        assert_eq!(package.encode().len(), PACKAGE_BYTES);
        assert_eq!(result.encode().len(), result_bytes(2));
        for m in [
            Message::Frame {
                frame: 1,
                camera,
                width: 64,
                height: 48,
            },
            package,
            result,
            Message::Quit { finalize: false },
        ] {
            assert_eq!(Message::decode(&m.encode()), Ok(m));
        }
    }

    #[test]
    fn truncated_and_unknown_messages_are_errors() {
        let bytes = Message::Quit { finalize: true }.encode();
        assert!(matches!(
            Message::decode(&bytes[..1]),
            Err(WireError::Truncated { .. })
        ));
        assert_eq!(Message::decode(&[99]), Err(WireError::UnknownKind(99)));
        assert!(Message::decode(&[]).is_err());
    }
}
