//! Binary data of a glTF file: buffers (GLB chunk, data URIs, files), buffer views,
//! accessors (strides, sparse substitutions, normalized integers) and images, each read
//! bounds-checked so that malformed input is an error naming the field, never a panic.

use std::borrow::Cow;

use base64::Engine;
use gltf::accessor::{DataType, Dimensions};

use super::Importer;
use crate::error::Result;
use crate::scene::Texture;

/// Largest element count accepted for an accessor without a buffer view (all zeros).
const MAX_ZERO_ELEMENTS: usize = 1 << 24;

/// A URI for messages: data URIs are cut short.
fn short_uri(uri: &str) -> String {
    if uri.starts_with("data:") {
        let head: String = uri.chars().take(32).collect();
        format!("{head}…")
    } else {
        uri.to_string()
    }
}

fn decode_data_uri(uri: &str) -> std::result::Result<Vec<u8>, String> {
    let rest = &uri["data:".len()..];
    let Some((_, payload)) = rest.split_once(";base64,") else {
        return Err("only base64 data URIs are supported".into());
    };
    let engine = base64::engine::GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        base64::engine::GeneralPurposeConfig::new().with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
    );
    engine.decode(payload.trim()).map_err(|e| format!("invalid base64 data: {e}"))
}

/// Percent-decodes a relative URI into a path string.
fn percent_decode(uri: &str) -> std::result::Result<String, String> {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok().and_then(|h| u8::from_str_radix(h, 16).ok());
            if let Some(v) = hex {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8(out).map_err(|_| "URI does not decode to UTF-8".to_string())
}

impl Importer<'_> {
    // ---------------------------------------------------------------- binary data

    pub(super) fn load_buffers(&self, mut blob: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>> {
        let mut out = Vec::new();
        for buffer in self.doc.buffers() {
            let i = buffer.index();
            let (field, data) = match buffer.source() {
                gltf::buffer::Source::Bin => {
                    let field = format!("buffers[{i}] (GLB BIN chunk)");
                    match blob.take() {
                        Some(b) => (field, b),
                        // Only a .glb has a BIN chunk: in a .gltf a buffer without uri is the error.
                        None if !self.glb => {
                            return Err(self.err(format!("buffers[{i}].uri"), "is missing (only the first buffer of a .glb may omit it)"))
                        }
                        None => return Err(self.err(field, "refers to the GLB BIN chunk, but the file has none (or it is already used)")),
                    }
                }
                gltf::buffer::Source::Uri(uri) => {
                    let field = format!("buffers[{i}] (uri {:?})", short_uri(uri));
                    let data = self.read_uri(uri).map_err(|m| self.err(&field, m))?;
                    (field, data)
                }
            };
            if data.len() < buffer.length() {
                return Err(self.err(field, format!("declares byteLength {} but holds only {} bytes", buffer.length(), data.len())));
            }
            out.push(data);
        }
        Ok(out)
    }

    /// Reads a data URI or a file relative to the glTF file.
    fn read_uri(&self, uri: &str) -> std::result::Result<Vec<u8>, String> {
        if uri.starts_with("data:") {
            return decode_data_uri(uri);
        }
        let relative = if let Some(rest) = uri.strip_prefix("file://") {
            rest
        } else if let Some(rest) = uri.strip_prefix("file:") {
            rest
        } else if let Some((scheme, _)) = uri.split_once(':') {
            // A one-letter "scheme" is a Windows drive letter.
            if scheme.len() > 1 && !scheme.contains(['/', '\\']) {
                return Err(format!("unsupported URI scheme '{scheme}:'"));
            }
            uri
        } else {
            uri
        };
        let decoded = percent_decode(relative)?;
        let path = self.base.join(&decoded);
        std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))
    }

    /// The bytes of a buffer view, range-checked against its buffer.
    fn view_bytes(&self, view: &gltf::buffer::View) -> Result<&[u8]> {
        let b = view.buffer();
        let data = &self.buffers[b.index()];
        let limit = b.length().min(data.len());
        match view.offset().checked_add(view.length()) {
            Some(end) if end <= limit => Ok(&data[view.offset()..end]),
            _ => Err(self.err(
                format!("bufferViews[{}]", view.index()),
                format!("byteOffset {} + byteLength {} exceeds buffers[{}] ({} bytes)", view.offset(), view.length(), b.index(), limit),
            )),
        }
    }

    /// Checks that the accessor's elements lie within its buffer view (or, without one, that
    /// its count is sane) and returns the element count; call before allocating for them.
    fn checked_count(&self, acc: &gltf::Accessor) -> Result<usize> {
        let field = format!("accessors[{}]", acc.index());
        let (elem, count) = (acc.size(), acc.count());
        let Some(view) = acc.view() else {
            if count > MAX_ZERO_ELEMENTS {
                return Err(self.err(field, format!("{count} elements without a bufferView is too many")));
            }
            return Ok(count);
        };
        let bytes = self.view_bytes(&view)?;
        let stride = view.stride().unwrap_or(elem);
        if count > 0 {
            let end = stride.checked_mul(count - 1).and_then(|x| x.checked_add(acc.offset())).and_then(|x| x.checked_add(elem));
            if end.is_none_or(|end| end > bytes.len()) {
                return Err(self.err(
                    field,
                    format!(
                        "byteOffset {} + {count} elements of {elem} bytes (stride {stride}) exceed bufferViews[{}] ({} bytes)",
                        acc.offset(),
                        view.index(),
                        bytes.len()
                    ),
                ));
            }
        }
        Ok(count)
    }

    /// Calls `f(i, element bytes)` for every element of the accessor (sparse substitutions
    /// are delivered after the base values, so the last call for an index wins).
    fn for_each_element(&self, acc: &gltf::Accessor, mut f: impl FnMut(usize, &[u8])) -> Result<()> {
        let field = format!("accessors[{}]", acc.index());
        let elem = acc.size();
        let count = self.checked_count(acc)?;
        match acc.view() {
            Some(view) => {
                let bytes = self.view_bytes(&view)?;
                let stride = view.stride().unwrap_or(elem);
                for i in 0..count {
                    let start = acc.offset() + stride * i;
                    f(i, &bytes[start..start + elem]);
                }
            }
            None => {
                let zeros = vec![0u8; elem];
                for i in 0..count {
                    f(i, &zeros);
                }
            }
        }
        if let Some(sparse) = acc.sparse() {
            let n = sparse.count();
            let iv = sparse.indices().view();
            let isize = sparse.indices().index_type().size();
            let ibytes = self.view_bytes(&iv)?;
            let vv = sparse.values().view();
            let vbytes = self.view_bytes(&vv)?;
            let fits =
                |off: usize, size: usize, len: usize| n.checked_mul(size).and_then(|x| x.checked_add(off)).is_some_and(|end| end <= len);
            if !fits(sparse.indices().offset(), isize, ibytes.len()) {
                return Err(self.err(format!("{field}.sparse.indices"), format!("{n} indices exceed bufferViews[{}]", iv.index())));
            }
            if !fits(sparse.values().offset(), elem, vbytes.len()) {
                return Err(self.err(format!("{field}.sparse.values"), format!("{n} values exceed bufferViews[{}]", vv.index())));
            }
            for k in 0..n {
                let s = sparse.indices().offset() + k * isize;
                let idx = match isize {
                    1 => ibytes[s] as usize,
                    2 => u16::from_le_bytes([ibytes[s], ibytes[s + 1]]) as usize,
                    _ => u32::from_le_bytes([ibytes[s], ibytes[s + 1], ibytes[s + 2], ibytes[s + 3]]) as usize,
                };
                if idx >= count {
                    return Err(self.err(format!("{field}.sparse.indices"), format!("index {idx} out of range ({count} elements)")));
                }
                let s = sparse.values().offset() + k * elem;
                f(idx, &vbytes[s..s + elem]);
            }
        }
        Ok(())
    }

    /// Reads a float-valued accessor with `dims` components per element; integer types are
    /// accepted when normalized and listed in `allowed`.
    pub(super) fn read_floats(&self, acc: &gltf::Accessor, dims: Dimensions, allowed: &[DataType], field: &str) -> Result<Vec<f32>> {
        let dt = acc.data_type();
        if acc.dimensions() != dims || !allowed.contains(&dt) || (dt != DataType::F32 && !acc.normalized()) {
            return Err(self.err(
                field,
                format!(
                    "accessors[{}] is {:?} {:?}{}, expected {:?} of {:?}",
                    acc.index(),
                    acc.dimensions(),
                    dt,
                    if acc.normalized() { " (normalized)" } else { "" },
                    dims,
                    allowed
                ),
            ));
        }
        let n = dims.multiplicity();
        let cs = dt.size();
        let mut out = vec![0f32; self.checked_count(acc)? * n];
        self.for_each_element(acc, |i, b| {
            for c in 0..n {
                let x = &b[c * cs..(c + 1) * cs];
                out[i * n + c] = match dt {
                    DataType::F32 => f32::from_le_bytes([x[0], x[1], x[2], x[3]]),
                    DataType::U8 => x[0] as f32 / 255.0,
                    DataType::I8 => (x[0] as i8 as f32 / 127.0).max(-1.0),
                    DataType::U16 => u16::from_le_bytes([x[0], x[1]]) as f32 / 65535.0,
                    DataType::I16 => (i16::from_le_bytes([x[0], x[1]]) as f32 / 32767.0).max(-1.0),
                    DataType::U32 => u32::from_le_bytes([x[0], x[1], x[2], x[3]]) as f32,
                };
            }
        })?;
        Ok(out)
    }

    pub(super) fn read_indices(&self, acc: &gltf::Accessor, field: &str) -> Result<Vec<u32>> {
        let dt = acc.data_type();
        if acc.dimensions() != Dimensions::Scalar || !matches!(dt, DataType::U8 | DataType::U16 | DataType::U32) {
            return Err(
                self.err(field, format!("accessors[{}] is {:?} {:?}, expected a scalar U8, U16 or U32", acc.index(), acc.dimensions(), dt))
            );
        }
        let mut out = vec![0u32; self.checked_count(acc)?];
        self.for_each_element(acc, |i, x| {
            out[i] = match dt {
                DataType::U8 => x[0] as u32,
                DataType::U16 => u16::from_le_bytes([x[0], x[1]]) as u32,
                _ => u32::from_le_bytes([x[0], x[1], x[2], x[3]]),
            };
        })?;
        Ok(out)
    }

    // ---------------------------------------------------------------- images

    pub(super) fn texture_index(&mut self, image: usize, used_by: &str) -> Result<usize> {
        if let Some(&t) = self.textures.get(&image) {
            return Ok(t);
        }
        let json = &self.doc.as_json().images[image];
        let (field, bytes): (String, Cow<[u8]>) = match (&json.uri, &json.buffer_view) {
            (Some(uri), _) => {
                let field = format!("images[{image}] (uri {:?})", short_uri(uri));
                let bytes = self.read_uri(uri).map_err(|m| self.err(&field, format!("{m} (used by {used_by})")))?;
                (field, Cow::Owned(bytes))
            }
            (None, Some(view)) => {
                let field = format!("images[{image}] (bufferView {})", view.value());
                let view = self.doc.views().nth(view.value()).ok_or_else(|| self.err(&field, "bufferView out of range"))?;
                (field, Cow::Borrowed(self.view_bytes(&view)?))
            }
            (None, None) => return Err(self.err(format!("images[{image}]"), "has neither uri nor bufferView")),
        };
        // Declared sizes are checked before decoding (a small file may declare a huge image).
        let limits = crate::scene::LoadLimits::default();
        let reader = || image::ImageReader::new(std::io::Cursor::new(&bytes[..])).with_guessed_format();
        if let Ok((w, h)) = reader().map_err(image::ImageError::IoError).and_then(|r| r.into_dimensions()) {
            limits.check(&field, w as u64, h as u64).map_err(|e| self.err(&field, format!("{e} (used by {used_by})")))?;
        }
        let decoded = image::ImageReader::new(std::io::Cursor::new(&bytes[..]))
            .with_guessed_format()
            .map_err(|e| self.err(&field, format!("cannot read image (used by {used_by}): {e}")))
            .and_then(|mut r| {
                r.limits(limits.image_limits());
                r.decode().map_err(|e| self.err(&field, format!("cannot decode image (used by {used_by}): {e}")))
            })?
            .to_rgba8();
        let name = json
            .name
            .clone()
            .or_else(|| json.uri.as_ref().filter(|u| !u.starts_with("data:")).cloned())
            .unwrap_or_else(|| format!("image{image}"));
        let (width, height) = decoded.dimensions();
        self.scene.textures.push(Texture { name, width, height, rgba8: decoded.into_raw() });
        let t = self.scene.textures.len() - 1;
        self.textures.insert(image, t);
        Ok(t)
    }
}
