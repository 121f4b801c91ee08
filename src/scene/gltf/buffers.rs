//! glTF buffers: the GLB chunk, files beside the document, and data URIs.

use super::*;

pub(super) fn load_buffers(
    cx: &Cx,
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    path: &Path,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut out = Vec::new();
    for b in document.buffers() {
        let at = format!("buffers[{}]", b.index());
        let data = match b.source() {
            // EXT_meshopt_compression's fallback without data: its views are decoded into it.
            gltf::buffer::Source::Bin if super::meshopt::is_fallback(&b) => {
                if b.length() > 1 << 31 {
                    return Err(cx.err(format!("{at}.byteLength"), "is too large"));
                }
                vec![0; b.length()]
            }
            gltf::buffer::Source::Bin => {
                blob.take().ok_or_else(|| cx.err(&at, "has no `uri` and the file has no GLB binary chunk"))?
            }
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| cx.err(format!("{at}.uri"), "a data URI must be base64 (`data:...;base64,`)"))?;
                    base64_decode(payload)
                        .ok_or_else(|| cx.err(format!("{at}.uri"), "the data URI is not valid base64"))?
                } else {
                    let full = path.parent().unwrap_or(Path::new("")).join(percent_decode(uri));
                    std::fs::read(&full)
                        .map_err(|e| cx.err(format!("{at}.uri"), format!("cannot read {}: {e}", full.display())))?
                }
            }
        };
        if data.len() < b.length() {
            return Err(cx.err(
                format!("{at}.byteLength"),
                format!("says {} bytes but the data has {}", b.length(), data.len()),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

pub(super) fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            // Bytes, not `&s[..]`: a `%` before a multi-byte character must not split it.
            if let Some(v) = std::str::from_utf8(&b[i + 1..i + 3]).ok().and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

pub(super) fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let digits: Vec<u8> = s.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    let digits = digits.strip_suffix(b"==").or_else(|| digits.strip_suffix(b"=")).unwrap_or(&digits);
    if digits.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(digits.len() * 3 / 4);
    for chunk in digits.chunks(4) {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc |= val(c)? << (18 - 6 * k);
        }
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}
