#!/usr/bin/env python3
"""Mitsuba 3's roughplastic constants, read off its BSDF: K (the coat's internal diffuse
reflectance) and T(1) T(0.5) (its transmittance head-on times at 60 degrees), for GGX at ior 1.5
and roughness 0.3, 0.7 and 1 (alpha = roughness^2), as tests/bsdfs/plastic.rs quotes them.

With `nonlinear`, its diffuse term is a / (1 - a K) x T(cos_i) T(cos_o) cos_o / (pi eta^2), so
two albedos a at the same directions, the specular term (albedo 0) subtracted, give K, and then
T(cos_i) T(cos_o).

Usage: python3 benches/mitsuba/roughplastic_constants.py  (Mitsuba 3 installed; its LLVM
variant needs DRJIT_LIBLLVM_PATH where libLLVM is not found by itself)
"""

import math

import mitsuba as mi

mi.set_variant("scalar_rgb")


def diffuse_eval(alpha, albedo, wi, wo, ior=1.5):
    bsdf = mi.load_dict({
        "type": "roughplastic", "distribution": "ggx", "alpha": alpha,
        "int_ior": ior, "ext_ior": 1.0, "nonlinear": True,
        "diffuse_reflectance": {"type": "rgb", "value": [albedo] * 3},
    })
    si = mi.SurfaceInteraction3f()
    si.wi = wi
    si.sh_frame = mi.Frame3f([0, 0, 1])
    return bsdf.eval(mi.BSDFContext(), si, wo)[0]


def main():
    head_on = mi.Vector3f(0, 0, 1)
    # 60 degrees, out of the plane of incidence: far from the specular peak.
    at_60 = mi.Vector3f(0, math.sin(math.radians(60)), math.cos(math.radians(60)))
    for roughness in [0.3, 0.7, 1.0]:
        alpha = roughness * roughness
        specular = diffuse_eval(alpha, 0.0, head_on, at_60)
        half = diffuse_eval(alpha, 0.5, head_on, at_60) - specular
        white = diffuse_eval(alpha, 1.0, head_on, at_60) - specular
        ratio = white / half  # 2 (1 - K / 2) / (1 - K)
        k = (ratio - 2) / (ratio - 1)
        tt = white * (1 - k) * math.pi * 1.5**2 / at_60[2]
        print(f"roughness {roughness}: K {k:.5f}, T(1) T(0.5) {tt:.5f}")


if __name__ == "__main__":
    main()
