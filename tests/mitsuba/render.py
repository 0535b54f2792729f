"""Renders a scene description written by tests/mitsuba.rs with Mitsuba 3 (scalar_rgb path
tracer, box pixel filter) into an OpenEXR image: the independent renderer the project's CPU
reference is cross-checked against (issue 16).

Usage: python render.py SCENE.json OUT.exr

The conventions mapping, written down once (the Rust side writes the JSON in these terms):
- camera: `eye`, `target`, `up`, vertical field of view `yfov_deg`, `width` × `height`;
  Mitsuba's perspective sensor with fov_axis "y" and a look-at transform.
- meshes: OBJ files in world space with per-vertex normals; `bsdf` one of
  diffuse {reflectance}, conductor {eta, k} (per channel, the glTF/specula ν, κ),
  dielectric {ior} (solid, from air; an optional `sigma_a` per channel [1/m] fills it with
  a purely absorbing homogeneous medium: KHR_materials_volume's Beer–Lambert, rendered with
  the volumetric path tracer), thindielectric {ior}, black (emitters: reflectance 0);
  an optional `radiance` makes the mesh an area emitter (specula's emission is radiance).
  An optional `radiance_texture` (a PNG of sRGB bytes, the glTF emissive texture with
  factor 1) makes the radiance a bilinear, repeating bitmap; glTF's uv has v = 0 at the
  image's top row, Mitsuba's bitmap at its bottom row: the OBJ's `vt` carry 1 − v
  (measured: without the flip the textured wall of tests/mitsuba.rs falls to 15.7 dB).
- lights: point {position, intensity} (W/sr, specula's glTF intensity 1:1), directional
  {direction, irradiance} (W/m²), spot {position, direction, intensity, beam_deg,
  cutoff_deg}: glTF's inner and outer cone angles as Mitsuba's beam width and cutoff. The
  two differ on purpose inside the ramp (Mitsuba's own curve against glTF's squared ramp
  in cos θ, which specula follows): the test compares outside it.
- integrator: path tracing to `max_depth` (specula's `depth` + 1: Mitsuba counts the camera
  segment), no Russian roulette before that depth; or, with `"integrator": "ptracer"`,
  Mitsuba's particle tracer (light paths from the emitters, every diffuse vertex connected to
  the camera: it samples point-light caustics, L S+ D E, which a path tracer cannot), with
  `spp` × width × height particles; specular surfaces seen directly stay black in it.
"""
import json
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def bsdf(b):
    kind = b["type"]
    if kind == "diffuse":
        return {"type": "diffuse", "reflectance": rgb(b["reflectance"])}
    if kind == "black":
        return {"type": "diffuse", "reflectance": rgb([0.0, 0.0, 0.0])}
    if kind == "conductor":
        return {"type": "conductor", "eta": rgb(b["eta"]), "k": rgb(b["k"])}
    if kind == "dielectric":
        return {"type": "dielectric", "int_ior": float(b["ior"]), "ext_ior": 1.0}
    if kind == "thindielectric":
        return {"type": "thindielectric", "int_ior": float(b["ior"]), "ext_ior": 1.0}
    raise ValueError(f"unknown bsdf {kind}")


def main():
    desc = json.load(open(sys.argv[1]))
    cam = desc["camera"]
    scene = {
        "type": "scene",
        "integrator": {"type": desc.get("integrator", "path"), "max_depth": int(desc["max_depth"]), "rr_depth": int(desc["max_depth"]) + 1},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": float(cam["yfov_deg"]),
            "near_clip": float(cam.get("znear", 0.01)),
            "to_world": mi.ScalarTransform4f().look_at(origin=cam["eye"], target=cam["target"], up=cam["up"]),
            "film": {
                "type": "hdrfilm",
                "width": int(cam["width"]),
                "height": int(cam["height"]),
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "stratified", "sample_count": int(desc["spp"]), "seed": 7},
        },
    }
    for i, m in enumerate(desc["meshes"]):
        shape = {"type": "obj", "filename": m["obj"], "face_normals": False, "bsdf": bsdf(m["bsdf"])}
        if "sigma_a" in m["bsdf"]:
            # Mitsuba takes colours in 0..1: σ as a colour times a scale.
            sigma = [float(x) for x in m["bsdf"]["sigma_a"]]
            scale = max(max(sigma), 1e-30)
            shape["interior"] = {"type": "homogeneous", "sigma_t": rgb([x / scale for x in sigma]), "scale": scale, "albedo": rgb([0.0, 0.0, 0.0])}
            scene["integrator"]["type"] = "volpath"
        if "radiance_texture" in m:
            shape["emitter"] = {"type": "area", "radiance": {"type": "bitmap", "filename": m["radiance_texture"], "filter_type": "bilinear", "wrap_mode": "repeat"}}
        elif "radiance" in m:
            shape["emitter"] = {"type": "area", "radiance": rgb(m["radiance"])}
        scene[f"mesh{i}"] = shape
    for i, l in enumerate(desc.get("lights", [])):
        if l["type"] == "point":
            scene[f"light{i}"] = {"type": "point", "position": l["position"], "intensity": rgb(l["intensity"])}
        elif l["type"] == "directional":
            scene[f"light{i}"] = {"type": "directional", "direction": l["direction"], "irradiance": rgb(l["irradiance"])}
        elif l["type"] == "spot":
            p, d = l["position"], l["direction"]
            up = [0.0, 0.0, 1.0] if abs(d[1]) > 0.9 else [0.0, 1.0, 0.0]
            scene[f"light{i}"] = {
                "type": "spot",
                "to_world": mi.ScalarTransform4f().look_at(origin=p, target=[p[k] + d[k] for k in range(3)], up=up),
                "intensity": rgb(l["intensity"]),
                "beam_width": float(l["beam_deg"]),
                "cutoff_angle": float(l["cutoff_deg"]),
            }
        else:
            raise ValueError(f"unknown light {l['type']}")
    image = mi.render(mi.load_dict(scene))
    mi.Bitmap(image).write(sys.argv[2])


if __name__ == "__main__":
    main()
