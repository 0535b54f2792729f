//! The glTF 2.0 schema's rules that the `gltf` crate does not enforce, checked on the JSON
//! before anything is read, each refusal naming the JSON path and the value:
//! - `asset.version` must be "2.x" ("1.0", "3.0", non-numbers refused); `asset.minVersion`,
//!   when present, must be at most the version and one this importer reads (2.0);
//! - `extensionsRequired` may only name extensions this importer implements;
//! - `bufferViews[i].byteStride` must be 4..=252 and a multiple of 4, and at least the
//!   element size of every accessor that reads through it;
//! - material factors in their schema ranges: base colour, metallic, roughness and emissive
//!   in [0, 1]; `KHR_materials_transmission.transmissionFactor` in [0, 1];
//!   `KHR_materials_volume.thicknessFactor` ≥ 0 and `attenuationDistance` > 0;
//!   `KHR_materials_specular.specularFactor` in [0, 1] and `specularColorFactor` ≥ 0;
//!   `KHR_materials_emissive_strength.emissiveStrength` ≥ 0; `KHR_materials_ior.ior` = 0 or
//!   ≥ 1 (0 is the extension's specular-glossiness compatibility mode: infinite IOR, Fresnel 1
//!   at every angle — imported as an ideal mirror of reflectance 1 for a transmissive
//!   material; a non-transmissive material's specular layer is not modelled);
//! - cameras: perspective `yfov` > 0, `znear` > 0, `zfar` > `znear`, `aspectRatio` > 0;
//!   orthographic `xmag`, `ymag` ≠ 0, `znear` ≥ 0, `zfar` > `znear`;
//! - `KHR_lights_punctual`: colour in [0, 1], `intensity` ≥ 0, `range` > 0, spot cone angles
//!   0 ≤ inner < outer ≤ π/2.

use serde_json::Value;

use crate::error::{clip, Error, Result};

/// The extensions the importer implements (others may be used, not required).
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_dispersion",
    "KHR_materials_specular",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
];

struct Check<'a> {
    file: &'a str,
}

impl Check<'_> {
    fn err(&self, path: impl Into<String>, message: impl Into<String>) -> Error {
        Error::scene(self.file, path, message)
    }

    /// The number at `v[key]`, if present; a non-number is an error.
    fn number(&self, v: &Value, key: &str, path: &str) -> Result<Option<f64>> {
        match v.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(x) => x
                .as_f64()
                .map(Some)
                .ok_or_else(|| self.err(format!("{path}.{key}"), format!("must be a number, got {}", clip(&x.to_string())))),
        }
    }

    /// `v[key]` within `lo..=hi` (either bound open when `None`), or absent.
    fn range(&self, v: &Value, key: &str, path: &str, lo: Option<f64>, hi: Option<f64>, open_lo: bool) -> Result<()> {
        let Some(x) = self.number(v, key, path)? else { return Ok(()) };
        let below = lo.is_some_and(|l| if open_lo { x <= l } else { x < l });
        let above = hi.is_some_and(|h| x > h);
        if below || above || !x.is_finite() {
            let want = match (lo, hi) {
                (Some(l), Some(h)) => format!("in [{l}, {h}]"),
                (Some(l), None) if open_lo => format!("> {l}"),
                (Some(l), None) => format!("≥ {l}"),
                (None, Some(h)) => format!("≤ {h}"),
                (None, None) => "finite".to_string(),
            };
            return Err(self.err(format!("{path}.{key}"), format!("must be {want}, got {x}")));
        }
        Ok(())
    }

    /// Every component of the array `v[key]` within `lo..=hi`.
    fn components(&self, v: &Value, key: &str, path: &str, lo: f64, hi: Option<f64>) -> Result<()> {
        let Some(a) = v.get(key).and_then(Value::as_array) else { return Ok(()) };
        for (i, x) in a.iter().enumerate() {
            let x = x
                .as_f64()
                .ok_or_else(|| self.err(format!("{path}.{key}[{i}]"), format!("must be a number, got {}", clip(&x.to_string()))))?;
            if !(x >= lo && hi.is_none_or(|h| x <= h) && x.is_finite()) {
                let want = hi.map_or(format!("≥ {lo}"), |h| format!("in [{lo}, {h}]"));
                return Err(self.err(format!("{path}.{key}[{i}]"), format!("must be {want}, got {x}")));
            }
        }
        Ok(())
    }
}

/// "2.1" → (2, 1); anything else → None.
fn version(s: &str) -> Option<(u32, u32)> {
    let (a, b) = s.split_once('.')?;
    if a.is_empty() || b.is_empty() || !a.bytes().all(|c| c.is_ascii_digit()) || !b.bytes().all(|c| c.is_ascii_digit()) {
        return None;
    }
    Some((a.parse().ok()?, b.parse().ok()?))
}

/// Bytes of one element of an accessor (componentType × type), if both are known.
fn element_size(accessor: &Value) -> Option<u64> {
    let component = match accessor.get("componentType")?.as_u64()? {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        5125 | 5126 => 4,
        _ => return None,
    };
    let count = match accessor.get("type")?.as_str()? {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        _ => return None,
    };
    Some(component * count)
}

/// Checks the document's JSON against the schema rules above.
pub fn check(file: &str, json: &Value) -> Result<()> {
    let c = Check { file };
    // asset.version and minVersion.
    let asset = json.get("asset").ok_or_else(|| c.err("asset", "is missing (every glTF has asset.version)"))?;
    let v = asset.get("version").and_then(Value::as_str).ok_or_else(|| c.err("asset.version", "is missing or not a string"))?;
    match version(v) {
        Some((2, _)) => {}
        _ => return Err(c.err("asset.version", format!("\"{}\" is not a glTF 2.x version: this importer reads glTF 2.0", clip(v)))),
    }
    if let Some(m) = asset.get("minVersion") {
        let m = m.as_str().ok_or_else(|| c.err("asset.minVersion", format!("must be a string, got {}", clip(&m.to_string()))))?;
        match (version(m), version(v)) {
            (Some(min), Some(ver)) if min > ver => {
                return Err(c.err("asset.minVersion", format!("\"{m}\" is above asset.version \"{v}\"")));
            }
            (Some(min), _) if min > (2, 0) => {
                return Err(c.err("asset.minVersion", format!("\"{m}\": the asset needs glTF {m}, this importer reads 2.0")));
            }
            (None, _) => return Err(c.err("asset.minVersion", format!("\"{}\" is not a version major.minor", clip(m)))),
            _ => {}
        }
    }
    // extensionsRequired.
    if let Some(req) = json.get("extensionsRequired").and_then(Value::as_array) {
        for (i, e) in req.iter().enumerate() {
            let name = e.as_str().unwrap_or("");
            if !SUPPORTED_EXTENSIONS.contains(&name) {
                return Err(c.err(
                    format!("extensionsRequired[{i}]"),
                    format!(
                        "\"{}\" is required by the asset but not supported (supported: {})",
                        clip(&e.to_string()).trim_matches('"'),
                        SUPPORTED_EXTENSIONS.join(", ")
                    ),
                ));
            }
        }
    }
    // bufferViews[].byteStride, and the accessors that read through a strided view.
    let views = json.get("bufferViews").and_then(Value::as_array).cloned().unwrap_or_default();
    for (i, view) in views.iter().enumerate() {
        let Some(s) = c.number(view, "byteStride", &format!("bufferViews[{i}]"))? else { continue };
        if !(4.0..=252.0).contains(&s) || s.fract() != 0.0 || !(s as u64).is_multiple_of(4) {
            return Err(c.err(format!("bufferViews[{i}].byteStride"), format!("must be a multiple of 4 in 4..=252, got {s}")));
        }
    }
    if let Some(accessors) = json.get("accessors").and_then(Value::as_array) {
        for (i, a) in accessors.iter().enumerate() {
            let (Some(view), Some(size)) = (a.get("bufferView").and_then(Value::as_u64), element_size(a)) else { continue };
            let Some(stride) = views.get(view as usize).and_then(|v| v.get("byteStride")).and_then(Value::as_u64) else { continue };
            if stride < size {
                return Err(c.err(
                    format!("bufferViews[{view}].byteStride"),
                    format!("{stride} is below the {size}-byte elements of accessors[{i}] that read through it"),
                ));
            }
        }
    }
    // Materials.
    for (i, m) in json.get("materials").and_then(Value::as_array).into_iter().flatten().enumerate() {
        let path = format!("materials[{i}]");
        if let Some(pbr) = m.get("pbrMetallicRoughness") {
            let p = format!("{path}.pbrMetallicRoughness");
            c.components(pbr, "baseColorFactor", &p, 0.0, Some(1.0))?;
            c.range(pbr, "metallicFactor", &p, Some(0.0), Some(1.0), false)?;
            c.range(pbr, "roughnessFactor", &p, Some(0.0), Some(1.0), false)?;
        }
        c.components(m, "emissiveFactor", &path, 0.0, Some(1.0))?;
        let Some(ext) = m.get("extensions") else { continue };
        let e = |name: &str| (ext.get(name), format!("{path}.extensions.{name}"));
        if let (Some(t), p) = e("KHR_materials_transmission") {
            c.range(t, "transmissionFactor", &p, Some(0.0), Some(1.0), false)?;
        }
        if let (Some(v), p) = e("KHR_materials_volume") {
            c.range(v, "thicknessFactor", &p, Some(0.0), None, false)?;
            c.range(v, "attenuationDistance", &p, Some(0.0), None, true)?;
            c.components(v, "attenuationColor", &p, 0.0, Some(1.0))?;
        }
        if let (Some(d), p) = e("KHR_materials_dispersion") {
            c.range(d, "dispersion", &p, Some(0.0), None, false)?;
        }
        if let (Some(s), p) = e("KHR_materials_specular") {
            c.range(s, "specularFactor", &p, Some(0.0), Some(1.0), false)?;
            c.components(s, "specularColorFactor", &p, 0.0, None)?;
        }
        if let (Some(s), p) = e("KHR_materials_emissive_strength") {
            c.range(s, "emissiveStrength", &p, Some(0.0), None, false)?;
        }
        if let (Some(s), p) = e("KHR_materials_ior") {
            if let Some(ior) = c.number(s, "ior", &p)? {
                if !(ior == 0.0 || (ior >= 1.0 && ior.is_finite())) {
                    return Err(c.err(format!("{p}.ior"), format!("must be 0 (the extension's infinite-IOR mode) or ≥ 1, got {ior}")));
                }
            }
        }
    }
    // Cameras.
    for (i, cam) in json.get("cameras").and_then(Value::as_array).into_iter().flatten().enumerate() {
        if let Some(p) = cam.get("perspective") {
            let path = format!("cameras[{i}].perspective");
            c.range(p, "yfov", &path, Some(0.0), None, true)?;
            c.range(p, "znear", &path, Some(0.0), None, true)?;
            c.range(p, "aspectRatio", &path, Some(0.0), None, true)?;
            if let (Some(n), Some(f)) = (c.number(p, "znear", &path)?, c.number(p, "zfar", &path)?) {
                if f <= n {
                    return Err(c.err(format!("{path}.zfar"), format!("must be > znear ({n}), got {f}")));
                }
            }
        }
        if let Some(o) = cam.get("orthographic") {
            let path = format!("cameras[{i}].orthographic");
            for k in ["xmag", "ymag"] {
                if c.number(o, k, &path)? == Some(0.0) {
                    return Err(c.err(format!("{path}.{k}"), "must not be 0"));
                }
            }
            c.range(o, "znear", &path, Some(0.0), None, false)?;
            if let (Some(n), Some(f)) = (c.number(o, "znear", &path)?, c.number(o, "zfar", &path)?) {
                if f <= n {
                    return Err(c.err(format!("{path}.zfar"), format!("must be > znear ({n}), got {f}")));
                }
            }
        }
    }
    // KHR_lights_punctual.
    let lights = json.pointer("/extensions/KHR_lights_punctual/lights").and_then(Value::as_array).cloned().unwrap_or_default();
    for (i, l) in lights.iter().enumerate() {
        let path = format!("extensions.KHR_lights_punctual.lights[{i}]");
        c.components(l, "color", &path, 0.0, Some(1.0))?;
        c.range(l, "intensity", &path, Some(0.0), None, false)?;
        c.range(l, "range", &path, Some(0.0), None, true)?;
        if let Some(s) = l.get("spot") {
            let sp = format!("{path}.spot");
            let half_pi = std::f64::consts::FRAC_PI_2;
            c.range(s, "innerConeAngle", &sp, Some(0.0), Some(half_pi), false)?;
            c.range(s, "outerConeAngle", &sp, Some(0.0), Some(half_pi), true)?;
            let inner = c.number(s, "innerConeAngle", &sp)?.unwrap_or(0.0);
            let outer = c.number(s, "outerConeAngle", &sp)?.unwrap_or(std::f64::consts::FRAC_PI_4);
            if inner >= outer {
                return Err(c.err(format!("{sp}.innerConeAngle"), format!("must be below outerConeAngle ({outer}), got {inner}")));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn ok(doc: Value) {
        check("t.gltf", &doc).unwrap();
    }

    fn refused(doc: Value, needles: &[&str]) {
        let e = check("t.gltf", &doc).unwrap_err().to_string();
        for n in needles {
            assert!(e.contains(n), "{e} lacks {n}");
        }
    }

    fn with(patch: Value) -> Value {
        let mut d = json!({ "asset": { "version": "2.0" } });
        for (k, v) in patch.as_object().unwrap() {
            d[k] = v.clone();
        }
        d
    }

    #[test]
    fn versions() {
        ok(json!({ "asset": { "version": "2.0" } }));
        ok(json!({ "asset": { "version": "2.1" } }));
        ok(json!({ "asset": { "version": "2.1", "minVersion": "2.0" } }));
        for v in ["1.0", "3.0", "two", "2", "2.x", ""] {
            refused(json!({ "asset": { "version": v } }), &["asset.version"]);
        }
        refused(json!({ "asset": { "version": 2.0 } }), &["asset.version"]);
        refused(json!({}), &["asset"]);
        refused(json!({ "asset": { "version": "2.1", "minVersion": "2.1" } }), &["asset.minVersion", "2.1"]);
        refused(json!({ "asset": { "version": "2.0", "minVersion": "2.1" } }), &["asset.minVersion", "above"]);
    }

    #[test]
    fn required_extensions() {
        ok(with(json!({ "extensionsRequired": ["KHR_materials_ior"] })));
        refused(
            with(json!({ "extensionsRequired": ["KHR_draco_mesh_compression"] })),
            &["extensionsRequired[0]", "KHR_draco_mesh_compression"],
        );
    }

    #[test]
    fn strides() {
        let acc = json!([{ "bufferView": 0, "componentType": 5126, "count": 1, "type": "VEC3" }]);
        ok(with(json!({ "bufferViews": [{ "buffer": 0, "byteLength": 24, "byteStride": 12 }], "accessors": acc })));
        for s in [2, 6, 256, 0] {
            refused(
                with(json!({ "bufferViews": [{ "buffer": 0, "byteLength": 24, "byteStride": s }] })),
                &["bufferViews[0].byteStride", &s.to_string()],
            );
        }
        refused(
            with(json!({ "bufferViews": [{ "buffer": 0, "byteLength": 24, "byteStride": 8 }], "accessors": acc })),
            &["bufferViews[0].byteStride", "12-byte", "accessors[0]"],
        );
    }

    #[test]
    fn factors() {
        let m = |m: Value| with(json!({ "materials": [m] }));
        ok(m(json!({ "pbrMetallicRoughness": { "baseColorFactor": [1, 0.5, 0, 1] }, "emissiveFactor": [1, 1, 1] })));
        refused(m(json!({ "pbrMetallicRoughness": { "baseColorFactor": [2, 0.5, 0, 1] } })), &["baseColorFactor[0]", "2"]);
        refused(m(json!({ "emissiveFactor": [-1, 0, 0] })), &["materials[0].emissiveFactor[0]", "-1"]);
        refused(m(json!({ "pbrMetallicRoughness": { "metallicFactor": 1.5 } })), &["metallicFactor", "1.5"]);
        for t in [2.0, -1.0] {
            refused(
                m(json!({ "extensions": { "KHR_materials_transmission": { "transmissionFactor": t } } })),
                &["transmissionFactor", &t.to_string()],
            );
        }
        refused(m(json!({ "extensions": { "KHR_materials_volume": { "thicknessFactor": -0.5 } } })), &["thicknessFactor", "-0.5"]);
        ok(m(json!({ "extensions": { "KHR_materials_ior": { "ior": 0 } } })));
        ok(m(json!({ "extensions": { "KHR_materials_ior": { "ior": 1.0 } } })));
        refused(m(json!({ "extensions": { "KHR_materials_ior": { "ior": 0.5 } } })), &["KHR_materials_ior.ior", "0.5"]);
        refused(m(json!({ "extensions": { "KHR_materials_ior": { "ior": "glass" } } })), &["KHR_materials_ior.ior", "number"]);
        refused(m(json!({ "extensions": { "KHR_materials_specular": { "specularFactor": 3 } } })), &["specularFactor"]);
        refused(m(json!({ "extensions": { "KHR_materials_dispersion": { "dispersion": -0.1 } } })), &["dispersion", "-0.1"]);
        ok(m(json!({ "extensions": { "KHR_materials_dispersion": { "dispersion": 0.5 } } })));
        refused(m(json!({ "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": -2 } } })), &["emissiveStrength"]);
    }

    #[test]
    fn cameras_and_lights() {
        let cam = |p: Value| with(json!({ "cameras": [{ "type": "perspective", "perspective": p }] }));
        ok(cam(json!({ "yfov": 0.8, "znear": 0.01, "zfar": 100, "aspectRatio": 1.5 })));
        refused(cam(json!({ "yfov": 0.8, "znear": 0.01, "aspectRatio": 0 })), &["aspectRatio", "> 0"]);
        refused(cam(json!({ "yfov": 0, "znear": 0.01 })), &["yfov"]);
        refused(cam(json!({ "yfov": 0.8, "znear": 1, "zfar": 0.5 })), &["zfar"]);
        let light = |l: Value| with(json!({ "extensions": { "KHR_lights_punctual": { "lights": [l] } } }));
        ok(light(json!({ "type": "spot", "intensity": 5, "spot": { "innerConeAngle": 0.1, "outerConeAngle": 0.5 } })));
        refused(light(json!({ "type": "point", "intensity": -5 })), &["lights[0].intensity", "-5"]);
        refused(light(json!({ "type": "point", "range": 0 })), &["lights[0].range"]);
        refused(light(json!({ "type": "spot", "spot": { "innerConeAngle": 0.6, "outerConeAngle": 0.5 } })), &["innerConeAngle"]);
        refused(light(json!({ "type": "spot", "spot": { "outerConeAngle": 2.0 } })), &["outerConeAngle"]);
        refused(light(json!({ "type": "point", "color": [1.5, 1, 1] })), &["color[0]"]);
    }
}
