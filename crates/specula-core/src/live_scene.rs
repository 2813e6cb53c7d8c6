//! The scene every technique renders, shared and kept up to date as objects move: the CPU
//! scene, its BVH, and (once a GPU technique asks) its GPU upload.
//!
//! A rigid move of an object ([`LiveScene::move_object`]) transforms the mesh, rewrites its
//! vertex range on the GPU in place, refits the BVH, and bumps [`LiveScene::version`]; a
//! technique compares the version it last drew with and redraws only what depends on geometry.
//! No technique prepares again.
//!
//! Refit against rebuild: refitting keeps the tree's topology, so its quality decays as objects
//! move far from where the tree was built. The BVH is rebuilt when the refitted tree's SAH cost
//! exceeds [`REBUILD_COST_RATIO`] × the cost of the last fresh build (a fresh build at the new
//! pose is not computed to compare against: that would be the rebuild itself).

use std::cell::OnceCell;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Mat4, Vec3};
use specula_gpu::GpuContext;
use specula_scene::Scene;
use specula_trace::SceneAccel;

use crate::gpu_scene::GpuScene;

/// A refitted BVH whose SAH cost grows past this multiple of its last fresh build's is rebuilt.
pub const REBUILD_COST_RATIO: f32 = 1.5;

static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// What a move did to the BVH.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AccelUpdate {
    /// Boxes refitted; the tree's SAH cost is now `cost_ratio` × its last fresh build's.
    Refitted { cost_ratio: f32 },
    /// The refit's cost ratio was `cost_ratio`, past [`REBUILD_COST_RATIO`]: rebuilt.
    Rebuilt { cost_ratio: f32 },
}

pub struct LiveScene {
    scene: Scene,
    accel: SceneAccel,
    gpu: OnceCell<GpuScene>,
    id: u64,
    version: u64,
    fresh_cost: f32,
    /// Each mesh's rigid motion since the scene was loaded.
    world_from_loaded: Vec<Mat4>,
}

#[derive(Debug, thiserror::Error)]
pub enum MoveError {
    #[error("no object named '{name}'; objects: {objects}")]
    UnknownObject { name: String, objects: String },
    #[error("the move is not rigid or not finite: {0}")]
    NotRigid(String),
}

impl LiveScene {
    pub fn new(scene: Scene) -> LiveScene {
        let accel = SceneAccel::new(&scene);
        let fresh_cost = accel.sah_cost();
        LiveScene {
            accel,
            gpu: OnceCell::new(),
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            version: 0,
            fresh_cost,
            world_from_loaded: vec![Mat4::IDENTITY; scene.meshes.len()],
            scene,
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    pub fn accel(&self) -> &SceneAccel {
        &self.accel
    }

    /// The scene on the GPU, uploaded at the first call.
    pub fn gpu(&self, ctx: &GpuContext) -> &GpuScene {
        self.gpu.get_or_init(|| GpuScene::upload(ctx, &self.scene))
    }

    /// Unique per loaded scene: a technique prepared for another id prepares again.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Bumped by every move: a technique whose maps were drawn at another version redraws them.
    pub fn version(&self) -> u64 {
        self.version
    }

    /// The rigid motion of mesh `mesh` since the scene was loaded: what a technique that keeps
    /// per-object data in the loaded pose (a point tree) maps through.
    pub fn world_from_loaded(&self, mesh: usize) -> Mat4 {
        self.world_from_loaded[mesh]
    }

    /// The mesh named `name` (an object the user can move).
    pub fn object(&self, name: &str) -> Result<usize, MoveError> {
        self.scene
            .meshes
            .iter()
            .position(|m| m.name == name)
            .ok_or_else(|| MoveError::UnknownObject {
                name: name.to_string(),
                objects: self
                    .scene
                    .meshes
                    .iter()
                    .map(|m| m.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// Moves mesh `mesh` rigidly by `world_from_before` (rotation and translation): its
    /// vertices here and on the GPU (when uploaded; `ctx` must then be given), and the BVH.
    pub fn move_object(
        &mut self,
        ctx: Option<&GpuContext>,
        mesh: usize,
        world_from_before: Mat4,
    ) -> Result<AccelUpdate, MoveError> {
        let linear = glam::Mat3::from_mat4(world_from_before);
        let rigid = (linear * linear.transpose()).abs_diff_eq(glam::Mat3::IDENTITY, 1e-4)
            && linear.determinant() > 0.0
            && world_from_before.is_finite();
        if !rigid {
            return Err(MoveError::NotRigid(format!("{world_from_before}")));
        }
        self.scene.meshes[mesh].transform(world_from_before);
        self.world_from_loaded[mesh] = world_from_before * self.world_from_loaded[mesh];
        if let (Some(gpu), Some(ctx)) = (self.gpu.get(), ctx) {
            gpu.write_mesh(ctx, mesh, &self.scene.meshes[mesh]);
        }
        self.version += 1;
        let cost = self.accel.refit(&self.scene);
        let cost_ratio = cost / self.fresh_cost.max(f32::MIN_POSITIVE);
        if cost_ratio > REBUILD_COST_RATIO {
            self.accel = SceneAccel::new(&self.scene);
            self.fresh_cost = self.accel.sah_cost();
            Ok(AccelUpdate::Rebuilt { cost_ratio })
        } else {
            Ok(AccelUpdate::Refitted { cost_ratio })
        }
    }

    /// Moves mesh `mesh` by `by` (world space, metres).
    pub fn translate_object(
        &mut self,
        ctx: Option<&GpuContext>,
        mesh: usize,
        by: Vec3,
    ) -> Result<AccelUpdate, MoveError> {
        self.move_object(ctx, mesh, Mat4::from_translation(by))
    }

    /// Turns mesh `mesh` by `degrees` about the world `axis` through its bounding-box centre.
    pub fn rotate_object(
        &mut self,
        ctx: Option<&GpuContext>,
        mesh: usize,
        axis: Vec3,
        degrees: f32,
    ) -> Result<AccelUpdate, MoveError> {
        let center = self.scene.meshes[mesh].bounds().center();
        let world_from_before = specula_scene::mesh::rotation_about(center, axis, degrees)
            .ok_or_else(|| {
                MoveError::NotRigid(format!("rotation by {degrees} degrees about {axis}"))
            })?;
        self.move_object(ctx, mesh, world_from_before)
    }
}
