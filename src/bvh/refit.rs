//! What the GPU refit of a deforming mesh's tree needs: its nodes' children and places in each layout, and its
//! nodes grouped by height (a leaf's is 0, an inner node's one more than its higher child's), so that the refit
//! bounds one height per dispatch, each after the one below.

use super::*;

impl SceneBvh {
    /// The refit nodes of the BVH just added (obvhs' `b2`), with its rest triangles (the ones just pushed).
    pub(super) fn add_refit(
        &mut self,
        mesh: usize,
        b2: &obvhs::bvh2::Bvh2,
        tri_base: u32,
        single_base: u32,
        threaded_base: u32,
        pos: &[u32],
    ) {
        let first_node = self.refit_nodes.len() as u32;
        let mut parent = vec![EMPTY; b2.nodes.len()];
        for (k, n) in b2.nodes.iter().enumerate() {
            if n.prim_count == 0 {
                parent[n.first_index as usize] = k as u32;
                parent[n.first_index as usize + 1] = k as u32;
            }
        }
        let abs = |k: u32| if k == EMPTY { EMPTY } else { first_node + k };
        for (k, n) in b2.nodes.iter().enumerate() {
            let leaf = n.prim_count > 0;
            self.refit_nodes.push(RefitNode {
                parent: abs(parent[k]),
                left: if leaf { EMPTY } else { first_node + n.first_index },
                right: if leaf { EMPTY } else { first_node + n.first_index + 1 },
                first_tri: if leaf { tri_base + n.first_index } else { 0 },
                tri_count: n.prim_count,
                single: single_base + k as u32,
                threaded: threaded_base + pos[k],
                pair: EMPTY,
            });
        }
        let tri_count = self.triangles.len() as u32 - tri_base;
        let rest_first = self.rest_tris.len() as u32;
        self.rest_tris.extend_from_slice(&self.triangles[tri_base as usize..]);
        self.rest_normals.extend_from_slice(&self.normals[tri_base as usize..]);
        // Heights, children before parents (the reverse of a breadth-first order from the root).
        let mut order = vec![0usize];
        let mut k = 0;
        while k < order.len() {
            let n = &b2.nodes[order[k]];
            if n.prim_count == 0 {
                order.extend([n.first_index as usize, n.first_index as usize + 1]);
            }
            k += 1;
        }
        let mut height = vec![0u32; b2.nodes.len()];
        for &k in order.iter().rev() {
            let n = &b2.nodes[k];
            if n.prim_count == 0 {
                height[k] = 1 + height[n.first_index as usize].max(height[n.first_index as usize + 1]);
            }
        }
        let first_level = self.refit_levels.len() as u32;
        let levels = height.iter().copied().max().map_or(0, |h| h + 1);
        for h in 0..levels {
            let first = self.refit_order.len() as u32;
            self.refit_order.extend((0..b2.nodes.len()).filter(|&k| height[k] == h).map(|k| first_node + k as u32));
            self.refit_levels.push([first, self.refit_order.len() as u32 - first]);
        }
        self.refit_meshes[mesh] = Some(RefitMesh {
            first_level,
            levels,
            first_node,
            first_tri: tri_base,
            rest_first,
            tri_count,
            ..RefitMesh::default()
        });
    }

    /// The wide nodes of mesh `mesh` (just added, from `first` on; its refit data added before) grouped by height,
    /// so that the GPU requantizes each after its inner children (glsl/refit_wide.comp). Children follow their
    /// parent in the wide layout (obvhs' conversion appends them), so one backward pass finds every height.
    pub(super) fn add_wide_refit(&mut self, mesh: usize, first: u32) {
        let nodes = &self.wide_nodes[first as usize..];
        let mut height = vec![0u32; nodes.len()];
        for k in (0..nodes.len()).rev() {
            let (imask, base) = (nodes[k].w0[3] >> 24, nodes[k].w1[0] - first);
            height[k] = (0..imask.count_ones()).map(|c| 1 + height[(base + c) as usize]).max().unwrap_or(0);
        }
        let first_level = self.wide_refit_levels.len() as u32;
        let levels = height.iter().copied().max().map_or(0, |h| h + 1);
        for h in 0..levels {
            let at = self.wide_refit_order.len() as u32;
            self.wide_refit_order
                .extend((0..nodes.len() as u32).filter(|&k| height[k as usize] == h).map(|k| first + k));
            self.wide_refit_levels.push([at, self.wide_refit_order.len() as u32 - at]);
        }
        if let Some(r) = self.refit_meshes[mesh].as_mut() {
            r.wide_first_level = first_level;
            r.wide_levels = levels;
        }
    }

    /// Record each node's pair-layout slot in the refit nodes of mesh `refit` (just added).
    pub(super) fn set_pair_slots(&mut self, refit: Option<usize>, pair_slot: &[u32]) {
        let Some(r) = refit.and_then(|m| self.refit_meshes[m]) else { return };
        for (k, &slot) in pair_slot.iter().enumerate() {
            self.refit_nodes[r.first_node as usize + k].pair = slot;
        }
    }
}
