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
use crate::shaders::consts::*;
use crate::vk::pipeline::{ordered, LazyPipeline};
use crate::vk::{Buffer, Device, Tracker, Use, VkResult};
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
        let place = LazyPipeline::compute(device, "scene update", shaders::SCENE_UPDATE_COMP.words());
        let water = LazyPipeline::compute(device, "water", shaders::WATER_COMP.words());
        let water_bvh = LazyPipeline::compute(device, "water (BVH triangles)", shaders::WATER_COMP_BVH.words());
        let water_step = LazyPipeline::compute(device, "water step", shaders::WATER_STEP_COMP.words());
        let morph = LazyPipeline::compute(device, "morph", shaders::MORPH_COMP.words());
        let morph_bvh = LazyPipeline::compute(device, "morph (BVH triangles)", shaders::MORPH_COMP_BVH.words());
        let refit = LazyPipeline::compute(device, "refit", shaders::REFIT_COMP.words());
        let refit_wide = LazyPipeline::compute(device, "refit (wide nodes)", shaders::REFIT_WIDE_COMP.words());
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

    /// Bind `pipeline` to `uses` (declared to `sync`, which orders the pipeline's dispatches after the writes and
    /// reads before them) and dispatch one job each: its push constants, over `items(job)` invocations. The jobs
    /// of one call write disjoint ranges, so nothing orders them among themselves. Without jobs nothing is
    /// recorded (and a pipeline never needed is never created).
    fn run<P: bytemuck::Pod>(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        pipeline: &LazyPipeline,
        uses: &[Use],
        jobs: &[P],
        items: impl Fn(&P) -> u32,
    ) -> VkResult<()> {
        if jobs.is_empty() {
            return Ok(());
        }
        let pipeline = pipeline.get()?;
        pipeline.bind_uses(cmd, sync, uses)?;
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
        sync: &mut Tracker,
        object: (&Buffer, &Buffer),
        world: (&Buffer, &Buffer),
        moves: &[SceneUpdatePush],
    ) -> VkResult<()> {
        let uses = ordered([
            (SU_OBJECT_VERTICES, Use::Read(object.0)),
            (SU_WORLD_VERTICES, Use::Write(world.0)),
            (SU_OBJECT_INDICES, Use::Read(object.1)),
            (SU_WORLD_INDICES, Use::Write(world.1)),
        ]);
        self.run(cmd, sync, &self.place, &uses, moves, |m| m.vertex_count.max(m.index_count / 3))
    }

    /// Displace water's raster vertices (each job one object, to world space).
    pub fn water_vertices(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        sb: &SceneBuffers,
        jobs: &[WaterPush],
    ) -> VkResult<()> {
        let uses = ordered([
            (WA_WAVES, Use::Read(&sb.waves)),
            (WA_OBJECT_VERTICES, Use::Read(&sb.object_vertices)),
            (WA_WORLD_VERTICES, Use::Write(&sb.vertices)),
            (WA_HEIGHTS, Use::Read(&sb.heights)),
            (WA_DISPLACED, Use::Write(&sb.displaced)),
        ]);
        self.run(cmd, sync, &self.water, &uses, jobs, |j| j.count)
    }

    /// Gather water's BVH triangles from its displaced vertices (each job one water mesh, in object space).
    pub fn water_triangles(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        sb: &SceneBuffers,
        jobs: &[WaterPush],
    ) -> VkResult<()> {
        let b = &sb.bvh;
        let uses = ordered([
            (WA_BVH_DISPLACED, Use::Read(&sb.displaced)),
            (WA_REST_CORNERS, Use::Read(&b.rest_corners)),
            (WA_BVH_TRIS, Use::Write(&b.triangles)),
            (WA_BVH_NORMALS, Use::Write(&b.normals)),
        ]);
        self.run(cmd, sync, &self.water_bvh, &uses, jobs, |j| j.count)
    }

    /// One job of a simulated water surface (a drop, or a step) over its nodes, ordered after the one before.
    pub fn water_step(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        sb: &SceneBuffers,
        job: &WaterStepPush,
    ) -> VkResult<()> {
        let uses = ordered([(WS_HEIGHTS, Use::Write(&sb.heights))]);
        self.run(cmd, sync, &self.water_step, &uses, std::slice::from_ref(job), |j| j.nodes * j.nodes)
    }

    /// Put simulated surfaces back at rest: each range of `sb.heights` (first float, count) zeroed.
    pub fn water_rest(&self, cmd: vk::CommandBuffer, sb: &SceneBuffers, ranges: &[(u32, u32)]) {
        for &(first, count) in ranges {
            unsafe { self.device.cmd_fill_buffer(cmd, sb.heights.raw, first as u64 * 4, count as u64 * 4, 0) };
        }
    }

    /// Morph the raster vertices of morphing objects (each job one object, to world space), with the weights in
    /// `sb.morph_weights`.
    pub fn morph_vertices(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        sb: &SceneBuffers,
        jobs: &[MorphPush],
    ) -> VkResult<()> {
        let uses = ordered([
            (MO_MORPHS, Use::Read(&sb.morphs)),
            (MO_WEIGHTS, Use::Read(&sb.morph_weights)),
            (MO_OBJECT_VERTICES, Use::Read(&sb.object_vertices)),
            (MO_WORLD_VERTICES, Use::Write(&sb.vertices)),
        ]);
        self.run(cmd, sync, &self.morph, &uses, jobs, |j| j.count)
    }

    /// Morph the BVH triangles of morphing meshes (each job one mesh, in object space).
    pub fn morph_triangles(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        sb: &SceneBuffers,
        jobs: &[MorphPush],
    ) -> VkResult<()> {
        let b = &sb.bvh;
        let uses = ordered([
            (MO_MORPHS, Use::Read(&sb.morphs)),
            (MO_WEIGHTS, Use::Read(&sb.morph_weights)),
            (MO_REST_TRIS, Use::Read(&b.rest_tris)),
            (MO_REST_NORMALS, Use::Read(&b.rest_normals)),
            (MO_REST_CORNERS, Use::Read(&b.rest_corners)),
            (MO_BVH_TRIS, Use::Write(&b.triangles)),
            (MO_BVH_NORMALS, Use::Write(&b.normals)),
        ]);
        self.run(cmd, sync, &self.morph_bvh, &uses, jobs, |j| j.count)
    }

    /// Bound one height of a deforming mesh's bottom-level BVH, after the heights below it (whose boxes it reads).
    pub fn refit(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        sb: &SceneBuffers,
        job: &RefitPush,
    ) -> VkResult<()> {
        let b = &sb.bvh;
        let uses = ordered([
            (RF_NODES, Use::Read(&b.refit_nodes)),
            (RF_ORDER, Use::Read(&b.refit_order)),
            (RF_BOXES, Use::Write(&b.refit_boxes)),
            (RF_TRIS, Use::Read(&b.triangles)),
            (RF_PAIR, Use::Write(&b.pair_nodes)),
            (RF_SINGLE, Use::Write(&b.single_nodes)),
            (RF_THREADED, Use::Write(&b.threaded_nodes)),
        ]);
        self.run(cmd, sync, &self.refit, &uses, std::slice::from_ref(job), |j| j.count)
    }

    /// Requantize one height of a deforming mesh's wide nodes over its refit triangles, after the heights below it,
    /// rewriting its wide triangle list.
    pub fn refit_wide(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        sb: &SceneBuffers,
        job: &RefitPush,
    ) -> VkResult<()> {
        let b = &sb.bvh;
        let uses = ordered([
            (RW_ORDER, Use::Read(&b.wide_refit_order)),
            (RW_BOXES, Use::Write(&b.wide_refit_boxes)),
            (RW_TRIS, Use::Read(&b.triangles)),
            (RW_NODES, Use::Write(&b.wide_nodes)),
            (RW_PRIMS, Use::Write(&b.wide_prims)),
        ]);
        self.run(cmd, sync, &self.refit_wide, &uses, std::slice::from_ref(job), |j| j.count)
    }

    /// Write `data` at the start of `buffer` from the command buffer (in chunks vkCmdUpdateBuffer takes).
    pub fn write<T: bytemuck::Pod>(&self, cmd: vk::CommandBuffer, buffer: &Buffer, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        for (k, chunk) in bytes.chunks(UPDATE_CHUNK).enumerate() {
            unsafe { self.device.cmd_update_buffer(cmd, buffer.raw, (k * UPDATE_CHUNK) as u64, chunk) };
        }
    }
}
