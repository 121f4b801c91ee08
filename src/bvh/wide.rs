//! The wide layout: a bottom-level tree collapsed into compressed 8-wide nodes (Ylitie, Karras and Laine 2017),
//! and the triangle list its leaves index.

use super::*;

impl SceneBvh {
    /// The wide layout of tree `b2` (whose triangles start at `tri_base`): its leaves split into one-triangle
    /// leaves, then collapsed by obvhs' cost-driven conversion into 8-wide nodes with leaves of up to three
    /// triangles, children ordered for the octant walk. Returns its root.
    pub(super) fn add_wide(&mut self, tris: &[[Vec4; 3]], b2: &Bvh2, tri_base: u32) -> u32 {
        let cw = obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(&unit_leaves(b2, tris), 3, true, false);
        // Leaf order: where each of the mesh's triangles sits in `triangles`.
        let mut slot_of = vec![0u32; tris.len()];
        for (s, &i) in b2.primitive_indices.iter().enumerate() {
            slot_of[i as usize] = tri_base + s as u32;
        }
        let (node_base, prim_base) = (self.wide_nodes.len() as u32, self.wide_prims.len() as u32);
        self.wide_prims.extend(cw.primitive_indices.iter().map(|&i| slot_of[i as usize]));
        let pack = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        for n in &cw.nodes {
            let mut w = [0u32; 20];
            w[0] = n.p.x.to_bits();
            w[1] = n.p.y.to_bits();
            w[2] = n.p.z.to_bits();
            w[3] = u32::from_le_bytes([n.e[0], n.e[1], n.e[2], n.imask]);
            w[4] = node_base + n.child_base_idx;
            w[5] = prim_base + n.primitive_base_idx;
            let planes = [
                &n.child_meta,
                &n.child_min_x,
                &n.child_max_x,
                &n.child_min_y,
                &n.child_max_y,
                &n.child_min_z,
                &n.child_max_z,
            ];
            for (k, bytes) in planes.iter().enumerate() {
                w[6 + 2 * k] = pack(&bytes[..4]);
                w[7 + 2 * k] = pack(&bytes[4..]);
            }
            self.wide_nodes.push(WideNode::from_words(w));
        }
        node_base
    }

    /// The wide triangle list as the GPU reads it (`bvh_wide_prim` in glsl/common/bvh.glsl): per entry its
    /// triangle's three vertices (the bits of x, y, z), the first's w the triangle's index in `triangles`. A leaf's
    /// test then reads no index before its vertices (on a CPU driver each read is a call).
    pub fn wide_triangle_records(&self) -> Vec<[u32; 4]> {
        let mut out = Vec::with_capacity(3 * self.wide_prims.len());
        for &t in &self.wide_prims {
            let p = &self.triangles[t as usize].p;
            for (k, v) in p.iter().enumerate() {
                out.push([v[0].to_bits(), v[1].to_bits(), v[2].to_bits(), if k == 0 { t } else { 0 }]);
            }
        }
        out
    }
}

/// `b2` with each leaf split into one-triangle leaves (a balanced subtree over the leaf's triangles, in their
/// order), the tree obvhs' wide conversion takes. The triangle order is kept.
pub(super) fn unit_leaves(b2: &Bvh2, tris: &[[Vec4; 3]]) -> Bvh2 {
    use obvhs::{aabb::Aabb, bvh2::node::Bvh2Node};
    let tri_box = |slot: u32| {
        let t = &tris[b2.primitive_indices[slot as usize] as usize];
        let mut a = Aabb::empty();
        for p in t {
            a.extend(Vec3A::from(p.truncate()));
        }
        a
    };
    // What a new node stands for: an old node, or a run of one old leaf's triangles.
    enum Part {
        Node(usize),
        Run(u32, u32),
    }
    let halves =
        |first: u32, count: u32| [Part::Run(first, count / 2), Part::Run(first + count / 2, count - count / 2)];
    let mut nodes = vec![Bvh2Node::default()];
    let mut todo = vec![(0usize, Part::Node(0))];
    while let Some((at, part)) = todo.pop() {
        // A one-triangle leaf is final; anything else becomes an inner node over two parts.
        let (aabb, [a, b]) = match part {
            Part::Node(k) => {
                let n = &b2.nodes[k];
                let f = n.first_index;
                match n.prim_count {
                    0 => (n.aabb, [Part::Node(f as usize), Part::Node(f as usize + 1)]),
                    1 => {
                        nodes[at] = Bvh2Node::new(n.aabb, 1, f);
                        continue;
                    }
                    c => (n.aabb, halves(f, c)),
                }
            }
            Part::Run(first, 1) => {
                nodes[at] = Bvh2Node::new(tri_box(first), 1, first);
                continue;
            }
            Part::Run(first, count) => {
                let aabb = (first..first + count).map(tri_box).fold(Aabb::empty(), |a, b| a.union(&b));
                (aabb, halves(first, count))
            }
        };
        let first = nodes.len();
        nodes.push(Bvh2Node::default());
        nodes.push(Bvh2Node::default());
        nodes[at] = Bvh2Node::new(aabb, 0, first as u32);
        todo.push((first, a));
        todo.push((first + 1, b));
    }
    Bvh2 { nodes, primitive_indices: b2.primitive_indices.clone(), ..Bvh2::default() }
}
