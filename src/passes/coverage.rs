//! The coverage pyramid: mip 0 from the refractor front buffer, then max/min reductions down to the 64² level.

use super::groups_2d;
use crate::gpu_types::CoveragePush;
use crate::shaders::{self, consts::*};
use crate::vk::pipeline::ordered;
use crate::vk::{Buffer, Device, Image, Pipeline, Sampler, Tracker, Use, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct CoverageInputs<'a> {
    pub ubo: &'a Buffer,
    pub coverage: &'a Buffer,
    pub front: &'a Image,
    pub recv: &'a Image,
    pub sampler: &'a Sampler,
    pub mips: u32,
}

pub struct CoveragePass {
    device: Arc<Device>,
    /// Mip 0 from the g-buffers, and a coarser mip from the one below (specialization constant 0 of
    /// glsl/coverage.comp).
    mip0: Pipeline,
    reduce: Pipeline,
}

/// Offsets of each mip in the coverage buffer, and the total length (entries).
pub fn pyramid_layout(gbuffer_res: u32, mips: u32) -> (Vec<u32>, u32) {
    let mut offsets = Vec::new();
    let mut total = 0u32;
    for m in 0..mips {
        offsets.push(total);
        let r = gbuffer_res >> m;
        total += r * r;
    }
    (offsets, total)
}

impl CoveragePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let pipeline = |name: &str, mip0: bool| {
            Pipeline::compute_specialized(
                device,
                name,
                shaders::COVERAGE_COMP.words(),
                &[(COVERAGE_MIP0_ID, mip0 as u32)],
            )
        };
        Ok(CoveragePass {
            device: device.clone(),
            mip0: pipeline("coverage (mip 0)", true)?,
            reduce: pipeline("coverage (coarser mips)", false)?,
        })
    }

    /// Build all mips of the pyramid over `front`; the coverage buffer ends in ComputeWrite.
    pub fn record(&self, cmd: vk::CommandBuffer, sync: &mut Tracker, i: &CoverageInputs) -> VkResult<()> {
        let (gbuffer_res, mips, coverage) = (i.front.extent.width, i.mips, i.coverage);
        let (offsets, _) = pyramid_layout(gbuffer_res, mips);
        let uses = ordered([
            (CV_FRAME, Use::Uniform(i.ubo)),
            (CV_COVERAGE, Use::Write(coverage)),
            (CV_FRONT, Use::Sampled(i.front, i.sampler)),
            (CV_RECEIVERS, Use::Sampled(i.recv, i.sampler)),
        ]);
        for m in 0..mips {
            // Each mip reads the one before it: declared again, the write is ordered after the last.
            let pipeline = if m == 0 { &self.mip0 } else { &self.reduce };
            pipeline.bind_uses(cmd, sync, &uses)?;
            let res = gbuffer_res >> m;
            let push = CoveragePush {
                mip: m,
                src_offset: if m > 0 { offsets[m as usize - 1] } else { 0 },
                dst_offset: offsets[m as usize],
                dst_res: res,
            };
            pipeline.push(cmd, &push);
            let (gx, gy) = groups_2d(res, res);
            unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
        }
        Ok(())
    }
}
