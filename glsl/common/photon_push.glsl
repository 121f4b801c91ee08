// Push constants of the photon passes.
#ifndef PHOTON_PUSH_GLSL
#define PHOTON_PUSH_GLSL
layout(push_constant) uniform PhotonPush {
    uint level;      // traversal level (traverse, stats) or dense level
    uint mode;       // init: 0 frame start, 1 batch start, 2 dense; stats: 0 level, 1 last level (commit)
    uint wg_side;    // traversal work-group side the dispatch arguments are computed for
    uint row0;       // dense emit: first row of this band
    uint debug;      // splat: 1 = dump photons into the debug buffer
    uint rows;       // dense emit: rows in this band
    uint debug_min_level;  // splat: dump only photons at this level or deeper
    uint pad2;
} pc;
#endif
