//! glTF accessors: vertex attributes and indices as floats and integers, quantized ones included
//! (KHR_mesh_quantization), bounds-checked.

use super::*;

/// An accessor's elements, densely packed (`count` × its element size): read from its bufferView through the
/// view's byteStride (interleaved attributes), or zeros without one, then with its sparse substitutions applied.
/// Everything is bounds-checked.
pub(super) fn dense(cx: &Cx, a: &gltf::Accessor, at: &str, buffers: &[Vec<u8>]) -> Result<Vec<u8>, SceneError> {
    let acc_at = format!("accessors[{}]", a.index());
    let ctx = |m: &str| cx.err(format!("{at} ({acc_at})"), m.to_string());
    let view_bytes = |view: &gltf::buffer::View| -> Result<&[u8], SceneError> {
        let buf = &buffers[view.buffer().index()];
        view.offset()
            .checked_add(view.length())
            .and_then(|end| buf.get(view.offset()..end))
            .ok_or_else(|| ctx("the bufferView lies outside its buffer"))
    };
    let elem = a.size();
    let n = a.count();
    let total = n.checked_mul(elem).filter(|&t| t <= 1 << 31).ok_or_else(|| ctx("the accessor is too large"))?;
    let mut out = vec![0u8; total];
    if let Some(view) = a.view() {
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(ctx("byteStride is smaller than the element"));
        }
        let bytes = view_bytes(&view)?;
        if n > 0 {
            let end =
                (n - 1).checked_mul(stride).and_then(|x| x.checked_add(elem)).and_then(|x| x.checked_add(a.offset()));
            if !matches!(end, Some(e) if e <= bytes.len()) {
                return Err(ctx("the accessor's data lies outside its bufferView"));
            }
        }
        for i in 0..n {
            let src = a.offset() + i * stride;
            out[i * elem..(i + 1) * elem].copy_from_slice(&bytes[src..src + elem]);
        }
    }
    if let Some(sparse) = a.sparse() {
        let k = sparse.count();
        let idx = sparse.indices();
        let isize = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let ib = view_bytes(&idx.view())?;
        let ib = idx.offset().checked_add(k * isize).and_then(|end| ib.get(idx.offset()..end));
        let ib = ib.ok_or_else(|| ctx("the sparse indices lie outside their bufferView"))?;
        let vals = sparse.values();
        let vb = view_bytes(&vals.view())?;
        let vb = vals.offset().checked_add(k * elem).and_then(|end| vb.get(vals.offset()..end));
        let vb = vb.ok_or_else(|| ctx("the sparse values lie outside their bufferView"))?;
        let mut last = None;
        for j in 0..k {
            let b = &ib[j * isize..(j + 1) * isize];
            let i = match isize {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if i >= n || last.is_some_and(|l| i <= l) {
                return Err(ctx("sparse indices must increase and lie below the accessor's count"));
            }
            last = Some(i);
            out[i * elem..(i + 1) * elem].copy_from_slice(&vb[j * elem..(j + 1) * elem]);
        }
    }
    Ok(out)
}

/// An accessor of `width` components per element as floats: FLOAT, or normalized integers mapped as glTF 2.0
/// §3.11 says (c / 127 for signed bytes, c / 65535 for unsigned shorts, ...).
pub(super) fn read_floats(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
    width: usize,
) -> Result<Vec<f32>, SceneError> {
    decode_floats(cx, a, at, buffers, width, false)
}

/// [`read_floats`], where `plain_ints` also takes integers that are not normalized as their values (the vertex
/// attributes of KHR_mesh_quantization: a position of shorts is scaled by its node's transform).
pub(super) fn decode_floats(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
    width: usize,
    plain_ints: bool,
) -> Result<Vec<f32>, SceneError> {
    use gltf::accessor::DataType;
    let comps = a.dimensions().multiplicity();
    if comps != width {
        return Err(cx.err(
            format!("{at} (accessors[{}])", a.index()),
            format!("must have {width} components per element (got {:?})", a.dimensions()),
        ));
    }
    let bytes = dense(cx, a, at, buffers)?;
    let read: fn(&[u8]) -> f32 = match (a.data_type(), a.normalized()) {
        (DataType::F32, _) => |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        (DataType::I8, true) => |b| (b[0] as i8 as f32 / 127.0).max(-1.0),
        (DataType::U8, true) => |b| b[0] as f32 / 255.0,
        (DataType::I16, true) => |b| (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
        (DataType::U16, true) => |b| u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
        (DataType::I8, false) if plain_ints => |b| b[0] as i8 as f32,
        (DataType::U8, false) if plain_ints => |b| b[0] as f32,
        (DataType::I16, false) if plain_ints => |b| i16::from_le_bytes([b[0], b[1]]) as f32,
        (DataType::U16, false) if plain_ints => |b| u16::from_le_bytes([b[0], b[1]]) as f32,
        (t, n) => {
            let n = if n { "normalized " } else { "" };
            return Err(cx.err(
                format!("{at} (accessors[{}])", a.index()),
                format!("must be FLOAT or normalized integers (got {n}{t:?})"),
            ));
        }
    };
    let size = a.data_type().size();
    // A matrix's columns are padded to 4 bytes (§3.6.2.4): only MAT2 and MAT3 of bytes or shorts differ, and no
    // accessor read here is one.
    Ok(bytes.chunks_exact(size).map(read).collect())
}

/// The component types a vertex attribute may have (glTF 2.0 §3.7.2.1 with KHR_mesh_quantization), each as
/// (type, normalized); FLOAT is always allowed.
pub(super) mod quantized {
    use gltf::accessor::DataType::{self, I16, I8, U16, U8};
    pub const POSITION: &[(DataType, bool)] =
        &[(I8, false), (I8, true), (U8, false), (U8, true), (I16, false), (I16, true), (U16, false), (U16, true)];
    pub const NORMAL: &[(DataType, bool)] = &[(I8, true), (I16, true)];
    pub const TEXCOORD: &[(DataType, bool)] = POSITION;
    /// A morph target's POSITION displacements.
    pub const DELTA: &[(DataType, bool)] = &[(I8, false), (I8, true), (I16, false), (I16, true)];
}

/// A vertex attribute of `dims`, as floats: FLOAT, or one of the integer types in `ints` ([`quantized`]).
pub(super) fn read_attribute(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
    dims: gltf::accessor::Dimensions,
    ints: &[(gltf::accessor::DataType, bool)],
) -> Result<Vec<f32>, SceneError> {
    use gltf::accessor::DataType;
    let (t, n) = (a.data_type(), a.normalized());
    if a.dimensions() != dims || !(t == DataType::F32 && !n || ints.contains(&(t, n))) {
        // glTF's own names: "normalized UNSIGNED_SHORT", "VEC3".
        let name = |t: DataType, n: bool| {
            let t = match t {
                DataType::I8 => "BYTE",
                DataType::U8 => "UNSIGNED_BYTE",
                DataType::I16 => "SHORT",
                DataType::U16 => "UNSIGNED_SHORT",
                DataType::U32 => "UNSIGNED_INT",
                DataType::F32 => "FLOAT",
            };
            format!("{}{t}", if n { "normalized " } else { "" })
        };
        let allowed: Vec<String> = ints.iter().map(|&(t, n)| name(t, n)).collect();
        let dims_name = |d: gltf::accessor::Dimensions| format!("{d:?}").to_uppercase();
        return Err(cx.err(
            format!("{at} (accessors[{}])", a.index()),
            format!(
                "must be {} of FLOAT, or (KHR_mesh_quantization) of {} (got {} of {})",
                dims_name(dims),
                allowed.join(", "),
                dims_name(a.dimensions()),
                name(t, n)
            ),
        ));
    }
    decode_floats(cx, a, at, buffers, dims.multiplicity(), true)
}

pub(super) fn read_vec3(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
    ints: &[(gltf::accessor::DataType, bool)],
) -> Result<Vec<Vec3>, SceneError> {
    let v = read_attribute(cx, a, at, buffers, gltf::accessor::Dimensions::Vec3, ints)?;
    Ok(v.chunks_exact(3).map(Vec3::from_slice).collect())
}

/// TEXCOORD data: VEC2 of FLOAT, or of normalized unsigned bytes or shorts, or (KHR_mesh_quantization) of any
/// byte or short, which the texture's KHR_texture_transform scales; finite.
pub(super) fn read_uvs(
    cx: &Cx,
    a: &gltf::Accessor,
    at: &str,
    buffers: &[Vec<u8>],
) -> Result<Vec<glam::Vec2>, SceneError> {
    let uvs: Vec<glam::Vec2> =
        read_attribute(cx, a, at, buffers, gltf::accessor::Dimensions::Vec2, quantized::TEXCOORD)?
            .chunks_exact(2)
            .map(glam::Vec2::from_slice)
            .collect();
    if uvs.iter().any(|uv| !uv.is_finite()) {
        return Err(cx.err(at.to_string(), "texture coordinates must be finite"));
    }
    Ok(uvs)
}

pub(super) fn read_indices(cx: &Cx, a: &gltf::Accessor, at: &str, buffers: &[Vec<u8>]) -> Result<Vec<u32>, SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    if a.dimensions() != Dimensions::Scalar {
        return Err(cx.err(format!("{at} (accessors[{}])", a.index()), "indices must be SCALAR"));
    }
    let read: fn(&[u8]) -> u32 = match a.data_type() {
        DataType::U8 => |b| b[0] as u32,
        DataType::U16 => |b| u16::from_le_bytes([b[0], b[1]]) as u32,
        DataType::U32 => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        t => {
            return Err(cx.err(
                format!("{at} (accessors[{}])", a.index()),
                format!("indices must be unsigned integers (got {t:?})"),
            ))
        }
    };
    let size = a.data_type().size();
    Ok(dense(cx, a, at, buffers)?.chunks_exact(size).map(read).collect())
}
