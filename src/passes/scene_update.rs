//! The scene update: a frame's first step when objects moved since the last frame. Each moved object's vertices
//! and triangles are placed in the world-space buffers the rasterizer draws (one dispatch of scene_update.comp per
//! object, from its object-space copies), and the BVH's instance records, which carry the transforms exact
//! transport and the eye view's glass trace read, are written from the host's copy in the command buffer. Nothing
//! is rebuilt, nothing waits: the frame's barriers order the writes after the last frame's reads.

use crate::gpu_types::SceneUpdatePush;
use crate::shaders;
use crate::shaders::consts::LINEAR_WG;
use crate::vk::pipeline::LazyPipeline;
use crate::vk::{Bind, BindKind, Buffer, Device, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct SceneUpdatePass {
    device: Arc<Device>,
    pipeline: LazyPipeline,
}

/// The largest vkCmdUpdateBuffer.
const UPDATE_CHUNK: usize = 65536;

impl SceneUpdatePass {
    pub fn new(device: &Arc<Device>) -> Self {
        let binds = [BindKind::Storage; 4];
        let push = std::mem::size_of::<SceneUpdatePush>() as u32;
        let pipeline = LazyPipeline::compute(device, "scene update", shaders::SCENE_UPDATE_COMP.words(), &binds, push);
        SceneUpdatePass { device: device.clone(), pipeline }
    }

    /// Place each object of `moves` (its push constants) from `object` space into `world` space (vertex buffer,
    /// index buffer).
    pub fn place(
        &self,
        cmd: vk::CommandBuffer,
        object: (&Buffer, &Buffer),
        world: (&Buffer, &Buffer),
        moves: &[SceneUpdatePush],
    ) -> VkResult<()> {
        let pipeline = self.pipeline.get()?;
        pipeline.bind(
            cmd,
            &[Bind::Storage(object.0), Bind::Storage(world.0), Bind::Storage(object.1), Bind::Storage(world.1)],
        );
        for m in moves {
            let groups = m.vertex_count.max(m.index_count / 3).div_ceil(LINEAR_WG);
            if groups == 0 {
                continue;
            }
            // Lavapipe caps a dimension at 65535 groups: the rest go in rows.
            let x = groups.min(65535);
            pipeline.push(cmd, m);
            unsafe { self.device.cmd_dispatch(cmd, x, groups.div_ceil(x), 1) };
        }
        Ok(())
    }

    /// Write `data` at the start of `buffer` from the command buffer (in chunks vkCmdUpdateBuffer takes).
    pub fn write<T: bytemuck::Pod>(&self, cmd: vk::CommandBuffer, buffer: &Buffer, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        for (k, chunk) in bytes.chunks(UPDATE_CHUNK).enumerate() {
            unsafe { self.device.cmd_update_buffer(cmd, buffer.raw, (k * UPDATE_CHUNK) as u64, chunk) };
        }
    }
}
