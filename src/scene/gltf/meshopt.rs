//! EXT_meshopt_compression (what `gltfpack -c` writes): a bufferView whose extension points at compressed bytes in
//! another buffer is decoded, by meshoptimizer's own decoder, into the view's place in its (fallback) buffer, so
//! that accessors read it as any other view. Every count, stride and range is checked before the decoder runs: its
//! C code asserts on them, and it is safe for untrusted bytes only within them.

use super::Cx;
use crate::scene::SceneError;
use serde_json::Value;

pub const EXTENSION: &str = "EXT_meshopt_compression";

/// Whether buffer `b` is the extension's fallback: its bytes are the decoded views', with no data of its own.
pub fn is_fallback(b: &gltf::Buffer) -> bool {
    b.extension_value(EXTENSION).and_then(|e| e.get("fallback")).and_then(Value::as_bool) == Some(true)
}

/// Decode every compressed view of `document` into `buffers`.
pub fn decode_views(cx: &Cx, document: &gltf::Document, buffers: &mut [Vec<u8>]) -> Result<(), SceneError> {
    for view in document.views() {
        let Some(ext) = view.extension_value(EXTENSION) else { continue };
        let at = format!("bufferViews[{}].extensions.{EXTENSION}", view.index());
        // Which primitive reads it, for the message: "corrupt" means nothing without the mesh it breaks.
        let err = |m: String| match user_of(document, view.index()) {
            Some(user) => cx.err(&at, format!("{m} (the view holds {user})")),
            None => cx.err(&at, m),
        };
        let field = |k: &str| ext.get(k).and_then(Value::as_u64);
        let need = |k: &str| field(k).ok_or_else(|| err(format!("needs an unsigned integer `{k}`")));
        let (src_buffer, length, stride, count) =
            (need("buffer")?, need("byteLength")?, need("byteStride")?, need("count")?);
        let offset = field("byteOffset").unwrap_or(0);
        let mode = ext.get("mode").and_then(Value::as_str).unwrap_or("");
        let filter = ext.get("filter").and_then(Value::as_str).unwrap_or("NONE");
        let (stride, count) = (stride as usize, count as usize);
        let src = buffers
            .get(src_buffer as usize)
            .and_then(|b| b.get(offset as usize..offset.checked_add(length)? as usize))
            .ok_or_else(|| err(format!("the compressed bytes lie outside buffers[{src_buffer}]")))?
            .to_vec();
        let size = count.checked_mul(stride).filter(|&n| n <= 1 << 31).ok_or_else(|| err("is too large".into()))?;
        if size > view.length() {
            return Err(err(format!("decodes to {size} bytes, more than the view's byteLength {}", view.length())));
        }
        let mut out = vec![0u8; size];
        decode(&mut out, &src, mode, filter, stride, count).map_err(err)?;
        let dst = buffers
            .get_mut(view.buffer().index())
            .and_then(|b| b.get_mut(view.offset()..view.offset() + size))
            .ok_or_else(|| cx.err(format!("bufferViews[{}]", view.index()), "lies outside its buffer"))?;
        dst.copy_from_slice(&out);
    }
    Ok(())
}

/// Decode `src` into `out` (`count` elements of `stride` bytes) by `mode`, then `filter`.
fn decode(out: &mut [u8], src: &[u8], mode: &str, filter: &str, stride: usize, count: usize) -> Result<(), String> {
    use meshopt::ffi;
    let code = match mode {
        "ATTRIBUTES" => {
            if stride == 0 || stride > 256 || !stride.is_multiple_of(4) {
                return Err(format!("ATTRIBUTES needs a byteStride that is a multiple of 4 up to 256 (got {stride})"));
            }
            // SAFETY: `out` holds count × stride bytes, the stride is one the decoder accepts, and it reads only
            // src.len() bytes of `src`.
            unsafe { ffi::meshopt_decodeVertexBuffer(out.as_mut_ptr().cast(), count, stride, src.as_ptr(), src.len()) }
        }
        "TRIANGLES" | "INDICES" => {
            if stride != 2 && stride != 4 {
                return Err(format!("{mode} needs a byteStride of 2 or 4 (got {stride})"));
            }
            if mode == "TRIANGLES" && !count.is_multiple_of(3) {
                return Err(format!("TRIANGLES needs a count that is a multiple of 3 (got {count})"));
            }
            let f = if mode == "TRIANGLES" { ffi::meshopt_decodeIndexBuffer } else { ffi::meshopt_decodeIndexSequence };
            // SAFETY: as above, with an index size of 2 or 4 and (for triangles) whole triangles.
            unsafe { f(out.as_mut_ptr().cast(), count, stride, src.as_ptr(), src.len()) }
        }
        other => return Err(format!("unknown mode `{other}` (ATTRIBUTES, TRIANGLES or INDICES)")),
    };
    if code != 0 {
        return Err(format!("the compressed data is corrupt (meshoptimizer's decoder returned {code})"));
    }
    let filter_fn = match (filter, mode, stride) {
        ("NONE", ..) => return Ok(()),
        ("OCTAHEDRAL", "ATTRIBUTES", 4 | 8) => ffi::meshopt_decodeFilterOct,
        ("QUATERNION", "ATTRIBUTES", 8) => ffi::meshopt_decodeFilterQuat,
        ("EXPONENTIAL", "ATTRIBUTES", _) => ffi::meshopt_decodeFilterExp,
        ("COLOR", "ATTRIBUTES", 4 | 8) => ffi::meshopt_decodeFilterColor,
        _ => return Err(format!("filter `{filter}` does not apply to mode {mode} with byteStride {stride}")),
    };
    // SAFETY: `out` holds count elements of `stride` bytes, a stride each filter accepts (checked above; the
    // exponential filter takes any multiple of 4).
    unsafe { filter_fn(out.as_mut_ptr().cast(), count, stride) };
    Ok(())
}

/// The first primitive attribute or index list whose accessor reads view `v`, as a JSON path.
fn user_of(document: &gltf::Document, v: usize) -> Option<String> {
    let reads = |a: &gltf::Accessor| a.view().map(|view| view.index()) == Some(v);
    for mesh in document.meshes() {
        for p in mesh.primitives() {
            let at = format!("meshes[{}].primitives[{}]", mesh.index(), p.index());
            if p.indices().is_some_and(|a| reads(&a)) {
                return Some(format!("{at}.indices"));
            }
            for (semantic, a) in p.attributes() {
                if reads(&a) {
                    return Some(format!("{at}.attributes.{}", semantic.to_string()));
                }
            }
        }
    }
    None
}
