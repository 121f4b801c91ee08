//! The BVH's records on the GPU: plain data, the one definition of each (build.rs writes their GLSL into
//! `generated/gpu_structs.glsl` and asserts every offset on both sides).

use bytemuck::{Pod, Zeroable};

/// "pair" layout: `lo[k].w` is the child's index bits (inner node, or first triangle), `hi[k].w` its triangle count
/// bits (0: inner node).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PairNode {
    pub lo0: [f32; 4],
    pub hi0: [f32; 4],
    pub lo1: [f32; 4],
    pub hi1: [f32; 4],
}

/// "single" layout: one box per node; `lo.w` is the first child (inner: children at `first`, `first + 1`) or the
/// first triangle, `hi.w` the triangle count (0: inner).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SingleNode {
    pub lo: [f32; 4],
    pub hi: [f32; 4],
}

/// "threaded" layout: one box per node in depth-first order, with an escape link, for a stackless traversal: a
/// hit inner node continues at the next node (its first child), a missed node or a finished leaf at its escape.
/// `lo.w`: escape index bits (`EMPTY`: done); `hi.w`: count << 29 | first triangle (count 0: inner node).
pub type ThreadedNode = SingleNode;

/// "wide" layout: a compressed 8-wide node (Ylitie, Karras and Laine 2017, as obvhs converts a binary tree to it),
/// 80 bytes, as twenty words in five `uvec4`s:
/// - words 0-2: the node box's low corner `p`; word 3: the per-axis scale exponents `e` (bytes 0-2: a child plane
///   is `p + 2^(e - 127) * q`) and the mask of inner children (byte 3);
/// - word 4: the first inner child (the inner children are consecutive nodes); word 5: the first of its leaves'
///   triangles in the wide triangle list (`SceneBvh::wide_prims`);
/// - words 6-7: a meta byte per child slot (0: empty; an inner child: `0b001_11sss`, 24 + its slot; a leaf:
///   its triangle count in unary in the top three bits, its first triangle's offset below);
/// - words 8-19: the children's quantized planes, a byte per child: low x (8-9), high x (10-11), low y (12-13),
///   high y (14-15), low z (16-17), high z (18-19), children 0-3 in the first word of each pair.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct WideNode {
    pub w0: [u32; 4],
    pub w1: [u32; 4],
    pub w2: [u32; 4],
    pub w3: [u32; 4],
    pub w4: [u32; 4],
}

impl WideNode {
    /// The node of `words` (in the order above).
    pub fn from_words(words: [u32; 20]) -> Self {
        bytemuck::cast(words)
    }

    /// Its twenty words.
    #[cfg(test)]
    pub fn words(&self) -> [u32; 20] {
        bytemuck::cast(*self)
    }
}

/// One instance of a mesh in the scene: where it is, and what it is made of.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuInstance {
    /// Rows of the 3x4 affine transform world → BVH space.
    pub object_from_world: [[f32; 4]; 3],
    /// Rows of the 3x4 affine transform BVH space → world.
    pub world_from_object: [[f32; 4]; 3],
    /// World-space bounds; `lo.w`: root node index bits in the pair layout.
    pub lo: [f32; 4],
    /// `hi.w`: root node index bits in the single layout.
    pub hi: [f32; 4],
    /// x: IOR (dielectric) or albedo (receiver); y: 1 dielectric, 2 mirror, 0 diffuse receiver; z: absorption
    /// coefficient inside a dielectric (1/m); w: a receiver's albedo texture layer + 1 (0: none), a dielectric's
    /// medium priority (0: an explicit interface; `SceneBvh::set_media`).
    pub material: [f32; 4],
    /// x: root node index bits in the threaded layout; y, z, w: a diffuse receiver's rgb albedo (the eye-view
    /// ray tracer shades with it), a dielectric's absorption spectrum (`RgbSpectrum` coefficients of `sigma_rgb`).
    pub pad: [f32; 4],
    /// Dielectric: IOR of the red, green and blue channels (`Material::ior_rgb`); a textured receiver: its uv
    /// transform's first row. w: root node index bits in the wide layout (`EMPTY`: a deforming mesh, whose
    /// instances the wide variant walks in the pair layout, which the refit keeps).
    pub ior_rgb: [f32; 4],
    /// Dielectric: absorption coefficient per channel (1/m), and in w the medium beyond its surface (the outside
    /// object's instance + 1, 0: air; `SceneBvh::set_media`); a textured receiver: its uv transform's second row.
    pub sigma_rgb: [f32; 4],
}

/// Three vertices of one triangle, in its instance's BVH space. In the triangles `w` holds each corner's texture
/// u, in their vertex normals its v (0 for a mesh without texture coordinates).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuTriangle {
    pub p: [[f32; 4]; 3],
}

/// One node of a deforming mesh's tree for the GPU refit (glsl/refit.comp): its parent and children
/// (indices into the refit nodes; `EMPTY` for none), its triangles (a leaf: `tri_count` > 0), and where its box
/// goes in each layout (the single and threaded node, and the pair node's slot as `node << 1 | slot`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RefitNode {
    pub parent: u32,
    pub left: u32,
    pub right: u32,
    pub first_tri: u32,
    pub tri_count: u32,
    pub single: u32,
    pub threaded: u32,
    pub pair: u32,
}
