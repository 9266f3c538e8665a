#!/usr/bin/env python3
"""The lab's Cornell box in Mitsuba 3: an independent reference for raylab's renders.

The scene is built exactly as raylab's crates/raylab-core/src/shapes/scene/cornell.rs builds it (30 triangles, the same
transform, so y points DOWN) with the lab's point light and pinhole camera. The EXR it writes
holds pi x radiance, which is raylab's image unit (raylab's rho * D = pi x radiance).

    python3 scripts/mitsuba/cornell.py --integrator direct --spp 64 --out /tmp/m.exr

See README.md beside this file for the conventions and the presets.
"""

import argparse
import math
import os
import sys

# drjit's LLVM backend needs libLLVM; Debian's libllvm19 puts it here (see install.sh).
LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
if os.path.exists(LIBLLVM):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LIBLLVM)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

L = 555.0
REFLECTANCE = {
    "red": (0.75, 0.15, 0.15),
    "yellow": (0.75, 0.75, 0.15),
    "green": (0.15, 0.75, 0.15),
    "cyan": (0.15, 0.75, 0.75),
    "blue": (0.15, 0.15, 0.75),
    "purple": (0.75, 0.15, 0.75),
    "white": (0.75, 0.75, 0.75),
}


def triangles():
    """The 30 triangles (v0, v1, v2, material) in raylab's order, in box units (0..555)."""
    A, B, C, D = (L, 0, 0), (0, 0, 0), (L, 0, L), (0, 0, L)
    E, F, G, H = (L, L, 0), (0, L, 0), (L, L, L), (0, L, L)
    tris = [
        (C, B, A, "green"), (C, D, B, "green"),  # floor
        (A, E, C, "purple"), (C, E, G, "purple"),  # left wall
        (F, B, D, "yellow"), (H, F, D, "yellow"),  # right wall
        (E, F, G, "cyan"), (F, H, G, "cyan"),  # ceiling
        (G, D, C, "white"), (G, H, D, "white"),  # back wall
    ]

    def block(xz, height, material):
        a, b, c, d = [(x, 0, z) for x, z in xz]
        e, f, g, h = [(x, height, z) for x, z in xz]
        for t in [(e, b, a), (e, f, b), (f, d, b), (f, h, d), (h, c, d),
                  (h, g, c), (g, e, c), (e, a, c), (g, f, e), (g, h, f)]:
            tris.append((*t, material))

    block([(290, 114), (130, 65), (240, 272), (82, 225)], 165, "red")  # short: 10-19
    block([(423, 247), (265, 296), (472, 406), (314, 456)], 330, "blue")  # tall: 20-29
    return tris


def to_scene(p):
    """raylab's transform, in f32 as raylab does it: p*2/L - 1, then x = -x, y = -y."""
    q = np.asarray(p, np.float32) * np.float32(2) / np.float32(L) - np.float32(1)
    return q * np.array([-1, -1, 1], np.float32)


def bsdf(name, preset, roughness=0.2):
    diffuse = {"type": "twosided",
               "bsdf": {"type": "diffuse",
                        "reflectance": {"type": "rgb", "value": REFLECTANCE[name]}}}
    if name == "blue" and preset in ("mirror", "both"):
        return {"type": "twosided",
                "bsdf": {"type": "conductor", "material": "none",
                         "specular_reflectance": {"type": "rgb", "value": [0.9] * 3}}}
    if name == "blue" and preset == "rough":
        # raylab's rough metal: GGX of alpha `roughness`, no Fresnel falloff (material none),
        # visible-normal sampling, Smith's separable shadowing (Mitsuba's defaults).
        return {"type": "twosided",
                "bsdf": {"type": "roughconductor", "material": "none", "distribution": "ggx",
                         "alpha": roughness,
                         "specular_reflectance": {"type": "rgb", "value": [0.9] * 3}}}
    if name == "blue" and preset == "plastic":
        # raylab's plastic preset: Mitsuba's roughplastic as it is, GGX of alpha `roughness`
        # with visible-normal sampling, index 1.5 inside and exactly 1.0 outside, the block's
        # own blue as the diffuse base under a white specular coating, `nonlinear` off.
        return {"type": "twosided",
                "bsdf": {"type": "roughplastic", "distribution": "ggx", "alpha": roughness,
                         "int_ior": 1.5, "ext_ior": 1.0, "nonlinear": False,
                         "diffuse_reflectance": {"type": "rgb", "value": REFLECTANCE["blue"]},
                         "specular_reflectance": {"type": "rgb", "value": [1.0] * 3}}}
    if name == "red" and preset in ("glass", "both"):
        # ext_ior 1.0 exactly: Mitsuba's default "air" is 1.000277.
        return {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
    return diffuse


def mesh(name, tris, preset, roughness=0.2):
    """One Mitsuba mesh of the given triangles, with face normals equal to raylab's."""
    # raylab's normal is cross(v2 - v0, v1 - v0); Mitsuba's is cross(v1 - v0, v2 - v0), so each
    # triangle goes in as (v0, v2, v1). This matters for the glass (ior inside = behind normal).
    verts = np.array([to_scene(p) for t in tris for p in (t[0], t[2], t[1])], np.float32)
    faces = np.arange(len(verts), dtype=np.uint32)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf(name, preset, roughness))
    m = mi.Mesh(name, len(verts), len(tris), props=props)
    params = mi.traverse(m)
    params["vertex_positions"] = mi.Float(verts.ravel())
    params["faces"] = mi.UInt32(faces)
    params.update()
    return m


def scene_dict(width=512, height=512, spp=64, integrator="path", max_depth=-1, rr_depth=5,
               light=(0.0, -0.5, -0.7), light_power=14.0, camera=(0.0, 0.0, -3.001),
               focal=None, preset="none", roughness=0.2, light_shape="point", light_size=0.0,
               light_aim=(0.0, 1.0, -0.2), spot_cutoff=25.0, spot_beam=15.0):
    focal = width if focal is None else focal
    groups = {}
    for t in triangles():
        groups.setdefault(t[3], []).append(t)
    d = {"type": "scene"}
    for name, tris in groups.items():
        d[name] = mesh(name, tris, preset, roughness)
    # An emitter's surface reflects nothing, as raylab's lights: without a BSDF Mitsuba would
    # give it a white-ish diffuse one (reflectance 0.5), lighting the room a second time.
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    if light_shape == "quad":
        # A square of side S in the plane y = light.y, emitting toward +y (the floor), of
        # radiance P/(pi S^2): the rectangle [-1, 1]^2 (normal +z) scaled by S/2, turned so its
        # normal is +y, moved to the light.
        s = light_size
        d["light"] = {"type": "rectangle",
                      "to_world": mi.ScalarTransform4f().translate(list(light))
                      @ mi.ScalarTransform4f().rotate([1, 0, 0], -90)
                      @ mi.ScalarTransform4f().scale([s / 2, s / 2, 1]),
                      "bsdf": black,
                      "emitter": {"type": "area", "radiance": {
                          "type": "rgb", "value": [light_power / (math.pi * s * s)] * 3}}}
    elif light_shape == "sphere":
        r = light_size
        d["light"] = {"type": "sphere", "center": list(light), "radius": r, "bsdf": black,
                      "emitter": {"type": "area", "radiance": {
                          "type": "rgb",
                          "value": [light_power / (4 * math.pi ** 2 * r * r)] * 3}}}
    elif light_shape == "spot":
        # Mitsuba's spot: intensity I (W/sr) inside the beam width, falling linearly in the
        # angle to 0 at the cutoff; raylab's default I is the lab's P/4pi. Its local +z is
        # the axis, aimed by look_at (any up not along the axis).
        axis = np.asarray(light_aim, np.float64) - np.asarray(light, np.float64)
        up = [0, 0, 1] if abs(axis[2]) < 0.9 * np.linalg.norm(axis) else [1, 0, 0]
        d["light"] = {"type": "spot", "cutoff_angle": spot_cutoff, "beam_width": spot_beam,
                      "to_world": mi.ScalarTransform4f().look_at(
                          origin=list(light), target=list(light_aim), up=up),
                      "intensity": {"type": "rgb", "value": [light_power / (4 * math.pi)] * 3}}
    else:
        d["light"] = {"type": "point", "position": list(light),
                      "intensity": {"type": "rgb", "value": [light_power / (4 * math.pi)] * 3}}
    if integrator == "path":
        d["integrator"] = {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth}
    else:
        d["integrator"] = {"type": "direct"}
    cam = mi.ScalarPoint3f(camera)
    d["sensor"] = {
        "type": "perspective",
        "fov_axis": "x",
        "fov": math.degrees(2 * math.atan(width / 2 / focal)),
        # Looking along +z with up = -y: Mitsuba's image then has x to the right (+x) and
        # y downward (+y), as raylab's does. (Mitsuba's camera-space x points left; look_at's
        # up vector takes care of it — no extra flip needed.)
        "to_world": mi.ScalarTransform4f().look_at(origin=cam, target=cam + mi.ScalarVector3f(0, 0, 1),
                                                   up=mi.ScalarVector3f(0, -1, 0)),
        "near_clip": 1e-3,
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": "independent", "sample_count": spp},
    }
    return d


def vec3(s):
    v = tuple(float(x) for x in s.split(","))
    if len(v) != 3:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z, got {s!r}")
    return v


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--width", type=int, default=512)
    p.add_argument("--height", type=int, default=512)
    p.add_argument("--focal", type=float, default=None, help="in pixels (default: the width)")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--integrator", choices=["path", "direct"], default="path")
    p.add_argument("--max-depth", type=int, default=-1, help="-1 = unlimited")
    p.add_argument("--rr-depth", type=int, default=5)
    p.add_argument("--light", type=vec3, default=(0.0, -0.5, -0.7))
    p.add_argument("--light-power", type=float, default=14.0, help="P in W per channel")
    p.add_argument("--camera", type=vec3, default=(0.0, 0.0, -3.001))
    p.add_argument("--preset", choices=["none", "mirror", "glass", "both", "rough", "plastic"], default="none")
    p.add_argument("--roughness", type=float, default=0.2, help="the rough and plastic presets' GGX alpha")
    p.add_argument("--light-shape", choices=["point", "sphere", "quad", "spot"], default="point")
    p.add_argument("--light-size", type=float, default=0.5,
                   help="the sphere's radius or the quad's side")
    p.add_argument("--light-aim", type=vec3, default=(0.0, 1.0, -0.2),
                   help="the point the spot light is aimed at")
    p.add_argument("--spot-cutoff", type=float, default=25.0, help="degrees")
    p.add_argument("--spot-beam", type=float, default=15.0, help="degrees")
    p.add_argument("--threads", type=int, default=None, help="drjit threads (default: all)")
    p.add_argument("--out", default="mitsuba.exr", help="EXR of pi x radiance")
    return p.parse_args(argv)


def main():
    a = parse_args()
    mi.set_variant("llvm_ad_rgb")
    if a.threads:
        dr.set_thread_count(a.threads)
    scene = mi.load_dict(scene_dict(a.width, a.height, a.spp, a.integrator, a.max_depth,
                                    a.rr_depth, a.light, a.light_power, a.camera, a.focal,
                                    a.preset, a.roughness, a.light_shape, a.light_size,
                                    a.light_aim, a.spot_cutoff, a.spot_beam))
    img = mi.render(scene, spp=a.spp, seed=a.seed) * math.pi  # raylab's units
    mi.Bitmap(img).write(a.out)
    means = np.array(img, np.float64).reshape(-1, 3).mean(axis=0)
    print(f"mitsuba {mi.__version__} {a.integrator} {a.width}x{a.height} {a.spp} spp "
          f"preset={a.preset} light={a.light_shape}: mean (pi x radiance) R {means[0]:.6f} G {means[1]:.6f} "
          f"B {means[2]:.6f} -> {a.out}")


if __name__ == "__main__":
    sys.exit(main())
