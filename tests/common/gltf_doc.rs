//! Writing glTF files in tests: JSON documents with their binary buffer, embedded as a data URI or as GLB.
#![allow(dead_code)]

use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Base64 (standard alphabet, padded).
pub fn b64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// `doc` with its buffer embedded as a base64 data URI.
pub fn embedded(mut doc: Value, bin: &[u8]) -> String {
    doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", b64(bin)));
    serde_json::to_string_pretty(&doc).unwrap()
}

/// `doc` and `bin` as a GLB container (JSON chunk, then BIN chunk; both padded to 4 bytes).
pub fn glb(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(doc).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

/// Write `data` to `dir/name`.
pub fn write(dir: &Path, name: &str, data: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, data).unwrap();
    p
}

/// `bytes` appended to `bin` at a 4-byte boundary as a new bufferView (with `stride`, for interleaved data);
/// returns the view's index.
pub fn add_view(doc: &mut Value, bin: &mut Vec<u8>, bytes: &[u8], stride: Option<usize>) -> usize {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let views = doc["bufferViews"].as_array_mut().unwrap();
    let mut v = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()});
    if let Some(s) = stride {
        v["byteStride"] = json!(s);
    }
    views.push(v);
    let index = views.len() - 1;
    bin.extend_from_slice(bytes);
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    index
}

/// `acc` appended to the accessors; returns its index.
pub fn push_accessor(doc: &mut Value, acc: Value) -> usize {
    let accessors = doc["accessors"].as_array_mut().unwrap();
    accessors.push(acc);
    accessors.len() - 1
}

/// Append `data` (f32) to `bin` as a new bufferView and accessor of `kind` (SCALAR, VEC3 or VEC4); SCALAR
/// accessors get their min and max. Returns the accessor's index.
pub fn add_accessor(doc: &mut Value, bin: &mut Vec<u8>, data: &[f32], kind: &str) -> usize {
    let view = add_view(doc, bin, bytemuck::cast_slice(data), None);
    let per = match kind {
        "SCALAR" => 1,
        "VEC3" => 3,
        _ => 4,
    };
    let mut acc = json!({"bufferView": view, "componentType": 5126, "count": data.len() / per, "type": kind});
    if kind == "SCALAR" {
        let (lo, hi) = data.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
        acc["min"] = json!([lo]);
        acc["max"] = json!([hi]);
    }
    push_accessor(doc, acc)
}

/// Append `mesh` (positions, normals, u32 indices) to `doc` and `bin` as a new mesh of one primitive with
/// `material` (an index into `materials`, which the caller writes). Returns the mesh's index.
pub fn add_mesh(
    doc: &mut Value,
    bin: &mut Vec<u8>,
    name: &str,
    mesh: &caustics::scene::Mesh,
    material: usize,
) -> usize {
    let flat = |v: &[glam::Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
    let p = add_accessor(doc, bin, &flat(&mesh.positions), "VEC3");
    let (lo, hi) = mesh.bounds();
    doc["accessors"][p]["min"] = json!(lo.to_array());
    doc["accessors"][p]["max"] = json!(hi.to_array());
    let n = add_accessor(doc, bin, &flat(&mesh.normals), "VEC3");
    let view = add_view(doc, bin, bytemuck::cast_slice(&mesh.indices), None);
    let i = push_accessor(
        doc,
        json!({"bufferView": view, "componentType": 5125, "count": mesh.indices.len(), "type": "SCALAR"}),
    );
    let meshes = doc["meshes"].as_array_mut().unwrap();
    meshes.push(json!({"name": name, "primitives": [
        {"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "material": material}]}));
    meshes.len() - 1
}
