//! The SPIR-V that build.rs compiled from glsl/, one static per shader (and per variant).

/// SPIR-V bytes with the 4-byte alignment that `&[u32]` needs.
#[repr(C, align(4))]
pub struct Spv<B: ?Sized = [u8]>(pub B);

impl Spv {
    pub fn words(&self) -> &[u32] {
        bytemuck::cast_slice(&self.0)
    }
}

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

pub mod consts {
    include!("shader_consts.rs");
}
