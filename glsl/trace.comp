#version 460
// Photon trace (docs/design.md step 4, two-interface): each emitted photon is refracted through the front surface
// (Fresnel), to the back surface, out again, and to the receivers; its landing point, flux and splat radius go
// into a splat record. Dispatched indirectly over the batch's emitted photons, with arguments the stats shader
// wrote. Tracing in compute rather than in the splat's vertex shader keeps the heavy arithmetic on every shader
// core (GPUs such as the H100 run graphics stages on a few units only); the splat then only rasterizes.
#include "common/photon_bindings.glsl"
layout(push_constant) uniform TracePushBlock { TracePush pc; };
#include "common/coverage.glsl"
#include "common/photon.glsl"

layout(local_size_x = LINEAR_WG) in;

void main() {
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * LINEAR_WG + gl_LocalInvocationIndex;
    if (i >= draw_cmd.x) return;
    uint j = draw_cmd.z + i;
    uvec2 cell = photons[j];
    uint level = cell_level(cell);
    uvec2 xy = cell_xy(cell);
    Hit h = trace_cell(level, xy, true);
    uint r = set_narrowed_radius(cell_splat_radius(cell));
    bool ok = h.status == HIT_OK;
    splats[j] = GpuSplat(h.map_px, ok ? h.flux : 0.0, ok ? float(r) : 0.0);
    if (pc.debug != 0u && level >= pc.debug_min_level) {
        uint k = atomicAdd(debug_header.x, 1u);
        if (k < debug_header.y) {
            vec2 uv = cell_sample_uv(level, xy);
            debug_photons[k] =
                GpuDebugPhoton(xy.x, xy.y, level | (h.status << 8) | (r << 16), h.flux, uv, h.map_px, vec4(h.pos, 0.0));
        }
    }
}
