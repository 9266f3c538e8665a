"""Mitsuba 3's roughplastic (ggx, sample_visible, nonlinear = false) evaluated at a few direction
pairs: the reference values of raylab's plastic tests (crates/raylab-core/src/shading/bsdf/plastic.rs,
`agrees_with_mitsuba`). Prints, for each pair (wo toward the viewer, wi toward the light, both
in the local frame as raylab names them), the specular and diffuse parts of f (Mitsuba's eval
divided by cos θ_i) and the pdf.

    python3 scripts/mitsuba/plastic_values.py
"""

import math

import mitsuba as mi

mi.set_variant("scalar_rgb")


def direction(theta, phi):
    return mi.Vector3f(
        math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)
    )


PAIRS = [
    (0.0, 0.0, 0.0, 0.0),
    (0.3, 0.0, 0.3, math.pi),
    (0.3, 0.0, 0.35, math.pi),
    (0.5, 0.0, 0.5, math.pi),
    (0.7, 0.2, 1.1, 2.0),
    (1.2, 0.0, 1.0, 1.0),
    (1.4, 0.5, 1.35, 0.5 + math.pi),
]

for alpha in [0.1, 0.3]:
    bsdf = mi.load_dict(
        {
            "type": "roughplastic",
            "distribution": "ggx",
            "alpha": alpha,
            "int_ior": 1.5,
            "ext_ior": 1.0,
            "diffuse_reflectance": {"type": "rgb", "value": [0.15, 0.15, 0.75]},
            "specular_reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]},
            "nonlinear": False,
        }
    )
    si = mi.SurfaceInteraction3f()
    for to, po, ti, pi in PAIRS:
        si.wi = direction(to, po)
        wi = direction(ti, pi)
        parts = []
        for component in [0, 1]:
            ctx = mi.BSDFContext()
            ctx.component = component
            value = bsdf.eval(ctx, si, wi) / wi.z
            parts.append(f"[{value[0]:.6e}, {value[2]:.6e}]")
        pdf = bsdf.pdf(mi.BSDFContext(), si, wi)
        print(f"(α {alpha}) ({to}, {po:.6f}, {ti}, {pi:.6f}): spec {parts[0]}, diffuse {parts[1]}, pdf {pdf:.6e}")
