//! The scene update: a frame's first step when objects moved or water changed since the last frame. Each moved
//! object's vertices and triangles are placed in the world-space buffers the rasterizer draws (one dispatch of
//! scene_update.comp per object, from its object-space copies), the BVH's instance records, which carry the
//! transforms exact transport and the eye view's glass trace read, are written from the host's copy in the command
//! buffer, each simulated water surface is stepped to the frame's time (water_step.comp: its drops, then one
//! dispatch per step, each after the one before), and each deforming object is deformed to the frame's time (water.comp for water, morph.comp for morph
//! targets, with the frame's weights written first: its raster vertices, and its BVH triangles) and its
//! bottom-level BVH refit bottom-up (refit.comp, then refit_wide.comp for its wide nodes). Nothing is rebuilt, nothing waits: the
//! frame's barriers order the writes after the last frame's reads.

use crate::gpu_types::{MorphPush, RefitPush, SceneUpdatePush, WaterPush, WaterStepPush};
use crate::scene_gpu::SceneBuffers;
use crate::shaders;
use crate::shaders::consts::LINEAR_WG;
use crate::vk::pipeline::LazyPipeline;
use crate::vk::{Bind, BindKind, Buffer, Device, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct SceneUpdatePass {
    device: Arc<Device>,
    place: LazyPipeline,
    water: LazyPipeline,
    water_bvh: LazyPipeline,
    water_step: LazyPipeline,
    morph: LazyPipeline,
    morph_bvh: LazyPipeline,
    refit: LazyPipeline,
    refit_wide: LazyPipeline,
}

/// The largest vkCmdUpdateBuffer.
const UPDATE_CHUNK: usize = 65536;

impl SceneUpdatePass {
    pub fn new(device: &Arc<Device>) -> Self {
        let size = |n: usize| n as u32;
        let place = LazyPipeline::compute(
            device,
            "scene update",
            shaders::SCENE_UPDATE_COMP.words(),
            &[BindKind::Storage; 4],
            size(std::mem::size_of::<SceneUpdatePush>()),
        );
        let water = LazyPipeline::compute(
            device,
            "water",
            shaders::WATER_COMP.words(),
            &[BindKind::Storage; 5],
            size(std::mem::size_of::<WaterPush>()),
        );
        let water_bvh = LazyPipeline::compute(
            device,
            "water (BVH triangles)",
            shaders::WATER_COMP_BVH.words(),
            &[BindKind::Storage; 4],
            size(std::mem::size_of::<WaterPush>()),
        );
        let water_step = LazyPipeline::compute(
            device,
            "water step",
            shaders::WATER_STEP_COMP.words(),
            &[BindKind::Storage; 1],
            size(std::mem::size_of::<WaterStepPush>()),
        );
        let morph = LazyPipeline::compute(
            device,
            "morph",
            shaders::MORPH_COMP.words(),
            &[BindKind::Storage; 4],
            size(std::mem::size_of::<MorphPush>()),
        );
        let morph_bvh = LazyPipeline::compute(
            device,
            "morph (BVH triangles)",
            shaders::MORPH_COMP_BVH.words(),
            &[BindKind::Storage; 7],
            size(std::mem::size_of::<MorphPush>()),
        );
        let refit = LazyPipeline::compute(
            device,
            "refit",
            shaders::REFIT_COMP.words(),
            &[BindKind::Storage; 7],
            size(std::mem::size_of::<RefitPush>()),
        );
        let refit_wide = LazyPipeline::compute(
            device,
            "refit (wide nodes)",
            shaders::REFIT_WIDE_COMP.words(),
            &[BindKind::Storage; 5],
            size(std::mem::size_of::<RefitPush>()),
        );
        SceneUpdatePass {
            device: device.clone(),
            place,
            water,
            water_bvh,
            water_step,
            morph,
            morph_bvh,
            refit,
            refit_wide,
        }
    }

    /// Dispatch `groups` work groups of LINEAR_WG in rows (lavapipe caps a dimension at 65535 groups).
    fn dispatch(&self, cmd: vk::CommandBuffer, items: u32) {
        let groups = items.div_ceil(LINEAR_WG);
        if groups == 0 {
            return;
        }
        let x = groups.min(65535);
        unsafe { self.device.cmd_dispatch(cmd, x, groups.div_ceil(x), 1) };
    }

    /// Bind `pipeline` to `binds` and dispatch one job each: its push constants, over `items(job)` invocations.
    /// Without jobs nothing is recorded (and a pipeline never needed is never created).
    fn run<P: bytemuck::Pod>(
        &self,
        cmd: vk::CommandBuffer,
        pipeline: &LazyPipeline,
        binds: &[Bind],
        jobs: &[P],
        items: impl Fn(&P) -> u32,
    ) -> VkResult<()> {
        if jobs.is_empty() {
            return Ok(());
        }
        let pipeline = pipeline.get()?;
        pipeline.bind(cmd, binds);
        for j in jobs {
            pipeline.push(cmd, j);
            self.dispatch(cmd, items(j));
        }
        Ok(())
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
        let binds = [Bind::Storage(object.0), Bind::Storage(world.0), Bind::Storage(object.1), Bind::Storage(world.1)];
        self.run(cmd, &self.place, &binds, moves, |m| m.vertex_count.max(m.index_count / 3))
    }

    /// Displace water's raster vertices (each job one object, to world space).
    pub fn water_vertices(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, jobs: &[WaterPush]) -> VkResult<()> {
        let binds = [
            Bind::Storage(&sb.waves),
            Bind::Storage(&sb.object_vertices),
            Bind::Storage(&sb.vertices),
            Bind::Storage(&sb.heights),
            Bind::Storage(&sb.displaced),
        ];
        self.run(cmd, &self.water, &binds, jobs, |j| j.count)
    }

    /// Gather water's BVH triangles from its displaced vertices (each job one water mesh, in object space).
    pub fn water_triangles(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, jobs: &[WaterPush]) -> VkResult<()> {
        let b = &sb.bvh;
        let binds = [
            Bind::Storage(&sb.displaced),
            Bind::Storage(&b.rest_corners),
            Bind::Storage(&b.triangles),
            Bind::Storage(&b.normals),
        ];
        self.run(cmd, &self.water_bvh, &binds, jobs, |j| j.count)
    }

    /// One job of a simulated water surface (a drop, or a step) over its nodes. The caller orders each job after
    /// the one before.
    pub fn water_step(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, job: &WaterStepPush) -> VkResult<()> {
        self.run(cmd, &self.water_step, &[Bind::Storage(&sb.heights)], std::slice::from_ref(job), |j| j.nodes * j.nodes)
    }

    /// Put simulated surfaces back at rest: each range of `sb.heights` (first float, count) zeroed.
    pub fn water_rest(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, ranges: &[(u32, u32)]) {
        for &(first, count) in ranges {
            unsafe { self.device.cmd_fill_buffer(cmd, sb.heights.raw, first as u64 * 4, count as u64 * 4, 0) };
        }
    }

    /// Morph the raster vertices of morphing objects (each job one object, to world space), with the weights in
    /// `sb.morph_weights`.
    pub fn morph_vertices(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, jobs: &[MorphPush]) -> VkResult<()> {
        let binds = [
            Bind::Storage(&sb.morphs),
            Bind::Storage(&sb.morph_weights),
            Bind::Storage(&sb.object_vertices),
            Bind::Storage(&sb.vertices),
        ];
        self.run(cmd, &self.morph, &binds, jobs, |j| j.count)
    }

    /// Morph the BVH triangles of morphing meshes (each job one mesh, in object space).
    pub fn morph_triangles(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, jobs: &[MorphPush]) -> VkResult<()> {
        let b = &sb.bvh;
        let binds = [
            Bind::Storage(&sb.morphs),
            Bind::Storage(&sb.morph_weights),
            Bind::Storage(&b.rest_tris),
            Bind::Storage(&b.rest_normals),
            Bind::Storage(&b.rest_corners),
            Bind::Storage(&b.triangles),
            Bind::Storage(&b.normals),
        ];
        self.run(cmd, &self.morph_bvh, &binds, jobs, |j| j.count)
    }

    /// Bound one height of a deforming mesh's bottom-level BVH (the heights below it bounded before).
    pub fn refit(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, job: &RefitPush) -> VkResult<()> {
        let b = &sb.bvh;
        let binds = [
            Bind::Storage(&b.refit_nodes),
            Bind::Storage(&b.refit_order),
            Bind::Storage(&b.refit_boxes),
            Bind::Storage(&b.triangles),
            Bind::Storage(&b.pair_nodes),
            Bind::Storage(&b.single_nodes),
            Bind::Storage(&b.threaded_nodes),
        ];
        self.run(cmd, &self.refit, &binds, std::slice::from_ref(job), |j| j.count)
    }

    /// Requantize one height of a deforming mesh's wide nodes over its refit triangles (the heights below it
    /// done before), rewriting its wide triangle list.
    pub fn refit_wide(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, job: &RefitPush) -> VkResult<()> {
        let b = &sb.bvh;
        let binds = [
            Bind::Storage(&b.wide_refit_order),
            Bind::Storage(&b.wide_refit_boxes),
            Bind::Storage(&b.triangles),
            Bind::Storage(&b.wide_nodes),
            Bind::Storage(&b.wide_prims),
        ];
        self.run(cmd, &self.refit_wide, &binds, std::slice::from_ref(job), |j| j.count)
    }

    /// Write `data` at the start of `buffer` from the command buffer (in chunks vkCmdUpdateBuffer takes).
    pub fn write<T: bytemuck::Pod>(&self, cmd: vk::CommandBuffer, buffer: &Buffer, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        for (k, chunk) in bytes.chunks(UPDATE_CHUNK).enumerate() {
            unsafe { self.device.cmd_update_buffer(cmd, buffer.raw, (k * UPDATE_CHUNK) as u64, chunk) };
        }
    }
}
