"""Renders a scene description written by tests/mitsuba.rs with Mitsuba 3 (scalar_rgb path
tracer, box pixel filter) into an OpenEXR image: the independent renderer the project's CPU
reference is cross-checked against (issue 16).

Usage: python render.py SCENE.json OUT.exr

The conventions mapping, written down once (the Rust side writes the JSON in these terms):
- camera: `eye`, `target`, `up`, vertical field of view `yfov_deg`, `width` × `height`;
  Mitsuba's perspective sensor with fov_axis "y" and a look-at transform.
- meshes: OBJ files in world space with per-vertex normals; `bsdf` one of
  diffuse {reflectance}, conductor {eta, k} (per channel, the glTF/specula ν, κ),
  dielectric {ior} (solid, from air), thindielectric {ior}, black (emitters: reflectance 0);
  an optional `radiance` makes the mesh an area emitter (specula's emission is radiance).
- lights: point {position, intensity} (W/sr, specula's glTF intensity 1:1), directional
  {direction, irradiance} (W/m²).
- integrator: path tracing to `max_depth` (specula's `depth` + 1: Mitsuba counts the camera
  segment), no Russian roulette before that depth.
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
        "integrator": {"type": "path", "max_depth": int(desc["max_depth"]), "rr_depth": int(desc["max_depth"]) + 1},
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
        if "radiance" in m:
            shape["emitter"] = {"type": "area", "radiance": rgb(m["radiance"])}
        scene[f"mesh{i}"] = shape
    for i, l in enumerate(desc.get("lights", [])):
        if l["type"] == "point":
            scene[f"light{i}"] = {"type": "point", "position": l["position"], "intensity": rgb(l["intensity"])}
        elif l["type"] == "directional":
            scene[f"light{i}"] = {"type": "directional", "direction": l["direction"], "irradiance": rgb(l["irradiance"])}
        else:
            raise ValueError(f"unknown light {l['type']}")
    image = mi.render(mi.load_dict(scene))
    mi.Bitmap(image).write(sys.argv[2])


if __name__ == "__main__":
    main()
