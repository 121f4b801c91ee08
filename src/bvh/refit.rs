//! What the GPU refit of a deforming mesh's tree needs: its nodes' parents, children and places in each layout.

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
        let first_leaf = self.refit_leaves.len() as u32;
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
            if leaf {
                self.refit_leaves.push(first_node + k as u32);
            }
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
        let mut depth = vec![0u32; b2.nodes.len()];
        let mut stack = vec![0usize];
        while let Some(k) = stack.pop() {
            let n = &b2.nodes[k];
            if n.prim_count == 0 {
                for c in [n.first_index as usize, n.first_index as usize + 1] {
                    depth[c] = depth[k] + 1;
                    stack.push(c);
                }
            }
        }
        self.refit_meshes[mesh] = Some(RefitMesh {
            depth: depth.iter().copied().max().unwrap_or(0),
            first_leaf,
            leaf_count: self.refit_leaves.len() as u32 - first_leaf,
            first_node,
            first_tri: tri_base,
            rest_first,
            tri_count,
        });
    }

    /// Record each node's pair-layout slot in the refit nodes of mesh `refit` (just added).
    pub(super) fn set_pair_slots(&mut self, refit: Option<usize>, pair_slot: &[u32]) {
        let Some(r) = refit.and_then(|m| self.refit_meshes[m]) else { return };
        for (k, &slot) in pair_slot.iter().enumerate() {
            self.refit_nodes[r.first_node as usize + k].pair = slot;
        }
    }
}
