//! KHR_draco_mesh_compression (what `gltf-transform draco` and `optimize --compress draco` write): a primitive's
//! attributes and indices live in one Draco bitstream in a bufferView, and its accessors have no view of their own.
//! Each such primitive is decoded (the `draco-core` crate, bitstream-compatible with Google's Draco), its values
//! written in each accessor's own component type into a new buffer, and the accessors given views of it: the
//! returned document then reads them as any other. Morph targets stay uncompressed, in the points' order (the
//! extension requires encoders to keep it, as glTF-Transform does with its sequential encoding for such meshes).

use super::Cx;
use crate::scene::SceneError;
use gltf::json::{self, validation::Checked, Index};
use serde_json::Value;

pub const EXTENSION: &str = "KHR_draco_mesh_compression";

/// The accessors that Draco primitives read from their bitstreams (their indices and compressed attributes).
pub fn accessors(root: &json::Root) -> Vec<usize> {
    let mut out = Vec::new();
    for mesh in &root.meshes {
        for p in &mesh.primitives {
            let Some(ext) = p.extensions.as_ref().and_then(|e| e.others.get(EXTENSION)) else { continue };
            out.extend(p.indices.map(|i| i.value()));
            let names = ext.get("attributes").and_then(Value::as_object);
            for (semantic, a) in &p.attributes {
                let name = match semantic {
                    Checked::Valid(s) => s.to_string(),
                    Checked::Invalid => continue,
                };
                if names.is_some_and(|n| n.contains_key(&name)) {
                    out.push(a.value());
                }
            }
        }
    }
    out
}

/// The document with every Draco primitive's accessors pointing at their decoded values (appended to `buffers` as
/// one buffer), or None when no primitive is compressed.
pub fn inflate(
    cx: &Cx,
    document: &gltf::Document,
    buffers: &mut Vec<Vec<u8>>,
) -> Result<Option<gltf::Document>, SceneError> {
    let mut root = document.as_json().clone();
    let new_buffer = buffers.len();
    let mut data: Vec<u8> = Vec::new();
    let mut any = false;
    for mesh in document.meshes() {
        for p in mesh.primitives() {
            let Some(ext) = p.extension_value(EXTENSION) else { continue };
            any = true;
            let at = format!("meshes[{}].primitives[{}].extensions.{EXTENSION}", mesh.index(), p.index());
            let decoded = decode(cx, document, buffers, ext, &at)?;
            let points = decoded.num_points();
            if let Some(acc) = p.indices() {
                let mut values = Vec::with_capacity(decoded.num_faces() * 3);
                for f in 0..decoded.num_faces() {
                    values.extend(decoded.face(draco_core::FaceIndex(f as u32)).iter().map(|i| i.0 as f64));
                }
                write(cx, &mut root, &mut data, acc.index(), &values, 1, new_buffer, &format!("{at} (indices)"))?;
            }
            let attributes = ext.get("attributes").and_then(Value::as_object).ok_or_else(|| {
                cx.err(&at, "needs an object `attributes` (the glTF attributes' Draco ids)".to_string())
            })?;
            for (name, id) in attributes {
                let a_at = format!("{at}.attributes.{name}");
                let id = id.as_u64().ok_or_else(|| cx.err(&a_at, "must be an unsigned integer"))?;
                let Some(acc) = p.attributes().find(|(s, _)| s.to_string() == *name).map(|(_, a)| a) else {
                    return Err(cx.err(&a_at, "names no attribute of the primitive"));
                };
                let att = decoded
                    .attribute_by_unique_id(id as u32)
                    .ok_or_else(|| cx.err(&a_at, format!("the Draco data has no attribute {id}")))?;
                let comps = acc.dimensions().multiplicity();
                if (att.num_components() as usize) < comps || acc.count() != points {
                    return Err(cx.err(
                        &a_at,
                        format!(
                            "the Draco attribute has {} components for {points} points; accessors[{}] wants {comps} for {}",
                            att.num_components(),
                            acc.index(),
                            acc.count()
                        ),
                    ));
                }
                let values = attribute_values(att, points, comps).map_err(|m| cx.err(&a_at, m))?;
                write(cx, &mut root, &mut data, acc.index(), &values, comps, new_buffer, &a_at)?;
            }
        }
    }
    if !any {
        return Ok(None);
    }
    root.buffers.push(json::Buffer {
        byte_length: data.len().into(),
        name: None,
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    buffers.push(data);
    Ok(Some(gltf::Document::from_json_without_validation(root)))
}

/// The Draco mesh in the bufferView that `ext` names.
fn decode(
    cx: &Cx,
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    ext: &Value,
    at: &str,
) -> Result<draco_core::Mesh, SceneError> {
    let v = ext.get("bufferView").and_then(Value::as_u64).ok_or_else(|| cx.err(at, "needs a `bufferView`"))?;
    let view = document.views().nth(v as usize).ok_or_else(|| cx.err(at, format!("bufferView {v} is out of range")))?;
    let bytes = buffers
        .get(view.buffer().index())
        .and_then(|b| b.get(view.offset()..view.offset().checked_add(view.length())?))
        .ok_or_else(|| cx.err(at, format!("bufferViews[{v}] lies outside its buffer")))?;
    // The decoder is meant to refuse corrupt data; should it panic on some, the file is refused all the same.
    let decoded = std::panic::catch_unwind(|| {
        let mut mesh = draco_core::Mesh::new();
        let mut input = draco_core::DecoderBuffer::new(bytes);
        draco_core::MeshDecoder::new().decode(&mut input, &mut mesh).map(|_| mesh).map_err(|e| e.to_string())
    })
    .unwrap_or_else(|_| Err("the decoder failed on it".to_string()));
    decoded.map_err(|e| cx.err(at, format!("the Draco data cannot be decoded: {e}")))
}

/// `comps` values per point of a decoded attribute, as numbers.
fn attribute_values(att: &draco_core::PointAttribute, points: usize, comps: usize) -> Result<Vec<f64>, String> {
    use draco_core::DataType as D;
    let size = att.data_type().byte_length();
    let stride = att.byte_stride() as usize;
    let bytes = att.buffer().data();
    let mut out = Vec::with_capacity(points * comps);
    for p in 0..points {
        let avi = att.mapped_index(draco_core::PointIndex(p as u32)).0 as usize;
        for c in 0..comps {
            let o = avi.checked_mul(stride).and_then(|x| x.checked_add(c * size));
            let b = o.and_then(|o| bytes.get(o..o + size)).ok_or("a point maps to no value in the Draco data")?;
            out.push(match att.data_type() {
                D::Float32 => f32::from_le_bytes(b.try_into().unwrap_or_default()) as f64,
                D::Float64 => f64::from_le_bytes(b.try_into().unwrap_or_default()),
                D::Int8 => b[0] as i8 as f64,
                D::Uint8 => b[0] as f64,
                D::Int16 => i16::from_le_bytes([b[0], b[1]]) as f64,
                D::Uint16 => u16::from_le_bytes([b[0], b[1]]) as f64,
                D::Int32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                D::Uint32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                other => return Err(format!("values of type {other:?} are not supported")),
            });
        }
    }
    Ok(out)
}

/// Append `values` to `data` in accessor `a`'s own component type, and point the accessor at them.
#[allow(clippy::too_many_arguments)]
fn write(
    cx: &Cx,
    root: &mut json::Root,
    data: &mut Vec<u8>,
    a: usize,
    values: &[f64],
    comps: usize,
    buffer: usize,
    at: &str,
) -> Result<(), SceneError> {
    use json::accessor::ComponentType as C;
    let acc = &root.accessors[a];
    let Checked::Valid(t) = acc.component_type else {
        return Err(cx.err(at, format!("accessors[{a}] has no valid componentType")));
    };
    if values.len() != acc.count.0 as usize * comps {
        return Err(cx.err(
            at,
            format!(
                "the Draco data has {} values; accessors[{a}] wants {}",
                values.len(),
                acc.count.0 as usize * comps
            ),
        ));
    }
    while !data.len().is_multiple_of(4) {
        data.push(0);
    }
    let offset = data.len();
    let (lo, hi) = match t.0 {
        C::F32 => (f64::NEG_INFINITY, f64::INFINITY),
        C::I8 => (i8::MIN as f64, i8::MAX as f64),
        C::U8 => (0.0, u8::MAX as f64),
        C::I16 => (i16::MIN as f64, i16::MAX as f64),
        C::U16 => (0.0, u16::MAX as f64),
        C::U32 => (0.0, u32::MAX as f64),
    };
    for &v in values {
        if !(lo..=hi).contains(&v) {
            return Err(cx.err(at, format!("the Draco value {v} does not fit accessors[{a}]'s {:?}", t.0)));
        }
        match t.0 {
            C::F32 => data.extend((v as f32).to_le_bytes()),
            C::I8 => data.extend((v as i8).to_le_bytes()),
            C::U8 => data.push(v as u8),
            C::I16 => data.extend((v as i16).to_le_bytes()),
            C::U16 => data.extend((v as u16).to_le_bytes()),
            C::U32 => data.extend((v as u32).to_le_bytes()),
        }
    }
    let view = root.buffer_views.len();
    root.buffer_views.push(json::buffer::View {
        buffer: Index::new(buffer as u32),
        byte_length: (data.len() - offset).into(),
        byte_offset: Some(offset.into()),
        byte_stride: None,
        name: None,
        target: None,
        extensions: None,
        extras: Default::default(),
    });
    let acc = &mut root.accessors[a];
    acc.buffer_view = Some(Index::new(view as u32));
    acc.byte_offset = Some(0usize.into());
    acc.sparse = None;
    Ok(())
}
