#!/usr/bin/env python3
"""Reduce measured complex IOR spectra (eta, k) of metals to linear-sRGB triples,
reproducing Mitsuba 3's RGB-variant behaviour for `conductor`/`roughconductor`
with `material="<name>"`.

Mitsuba 3 code path (mitsuba-renderer/mitsuba3 @ b45b0a930275114de0f8c34e8cf52775e176ca9a):
  src/bsdfs/conductor.cpp        -> complex_ior_from_file<Spectrum, Texture>(material)
  include/mitsuba/render/ior.h   -> ior_from_file("data/ior/<m>.eta.spd" / ".k.spd"):
                                    spectrum_from_file(); then in RGB modes
                                    spectrum_list_to_srgb(wl, values, bounded=false, d65=false)
                                    and an 'srgb' texture with unbounded=true (stored as-is).
  src/core/spectrum.cpp          -> spectrum_list_to_srgb(): 1000 wavelengths
                                    w_i = 360 + i/999 * 470 nm, i = 0..999; samples outside
                                    [wl.front(), wl.back()] are SKIPPED (contribute 0);
                                    piecewise-linear interpolation of the data; accumulate
                                    cie1931_xyz(w_i) * v(w_i) [* cie_d65(w_i) if d65];
                                    xyz *= 470 * MI_CIE_Y_NORMALIZATION / 1000;
                                    rgb = xyz_to_srgb(xyz); negative channels -> 0 (unbounded).
  include/mitsuba/core/spectrum.h -> cie1931_xyz(): 95-entry 5 nm table (float32), linear
                                    interpolation; MI_CIE_Y_NORMALIZATION = 1/106.7502593994140625;
                                    xyz_to_srgb() matrix (below); cie_d65() with 1/98.99741751876255.

Run:  python3 tools/metals/reduce.py            (prints tables, writes table.rs next to this file)
"""
import os
import sys
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "data")

# ---------------------------------------------------------------- Mitsuba constants
CIE_MIN, CIE_MAX, CIE_SAMPLES = 360.0, 830.0, 95
CIE_Y_NORMALIZATION = 1.0 / 106.7502593994140625
CIE_D65_NORMALIZATION = 1.0 / 98.99741751876255
XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                        [-0.969256, 1.875991, 0.041556],
                        [0.055648, -0.204043, 1.057311]], dtype=np.float32).astype(np.float64)

_tab = np.loadtxt(os.path.join(DATA, "mitsuba_cie1931_d65.txt"))
assert _tab.shape == (CIE_SAMPLES, 5)
CMF = _tab[:, 1:4].astype(np.float32).astype(np.float64)   # Mitsuba stores float32
D65 = _tab[:, 4].astype(np.float32).astype(np.float64)


def _table_lerp(w, table):
    """Mitsuba's cie1931_xyz()/cie_d65() lookup: linear interpolation in a 5 nm table."""
    t = (w - CIE_MIN) * ((CIE_SAMPLES - 1) / (CIE_MAX - CIE_MIN))
    active = (w >= CIE_MIN) & (w <= CIE_MAX)
    i0 = np.clip(t.astype(np.int64), 0, CIE_SAMPLES - 2)
    w1 = t - i0
    w0 = 1.0 - w1
    if table.ndim == 1:
        return np.where(active, w0 * table[i0] + w1 * table[i0 + 1], 0.0)
    return np.where(active[:, None], w0[:, None] * table[i0] + w1[:, None] * table[i0 + 1], 0.0)


def spectrum_list_to_srgb(wl, val, bounded=False, d65=False, clamp=True):
    """Port of mitsuba::spectrum_list_to_srgb (src/core/spectrum.cpp). Returns (rgb, raw_rgb)."""
    wl = np.asarray(wl, dtype=np.float64)
    val = np.asarray(val, dtype=np.float64)
    steps = 1000
    w = CIE_MIN + (np.arange(steps) / (steps - 1)) * (CIE_MAX - CIE_MIN)
    keep = (w >= wl[0]) & (w <= wl[-1])          # outside the data: skipped, i.e. zero
    w = w[keep]
    # math::find_interval: largest idx in [0, n-2] with wl[idx] <= w
    idx = np.clip(np.searchsorted(wl, w, side="right") - 1, 0, len(wl) - 2)
    w0, w1, v0, v1 = wl[idx], wl[idx + 1], val[idx], val[idx + 1]
    v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
    weight = v * (_table_lerp(w, D65) * CIE_D65_NORMALIZATION if d65 else 1.0)
    xyz = (_table_lerp(w, CMF) * weight[:, None]).sum(axis=0)
    xyz *= (CIE_MAX - CIE_MIN) * CIE_Y_NORMALIZATION / steps
    raw = XYZ_TO_SRGB @ xyz
    rgb = raw.copy()
    if clamp:
        rgb = np.clip(rgb, 0.0, 1.0) if bounded else np.maximum(rgb, 0.0)
    # Mitsuba stores the texture colour as float32
    return rgb.astype(np.float32).astype(np.float64), raw


# ---------------------------------------------------------------- data loaders
def load_spd(path):
    """Port of spectrum_from_file for .spd: '#' comments, 'wavelength value' per line."""
    wl, v = [], []
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            a, b = line.split()[:2]
            wl.append(float(a))
            v.append(float(b))
    return np.array(wl), np.array(v)


def load_rii_nk(path):
    """refractiveindex.info YAML, single 'tabulated nk' block (wavelength in um)."""
    rows, inside = [], False
    with open(path) as f:
        for line in f:
            s = line.strip()
            if s.startswith("type:") or s.startswith("- type:"):
                assert "tabulated nk" in s, (path, s)
            if s.startswith("data:"):
                inside = True
                continue
            if inside:
                parts = s.split()
                if len(parts) == 3:
                    try:
                        rows.append([float(p) for p in parts])
                        continue
                    except ValueError:
                        pass
                inside = False
    a = np.array(rows)
    return a[:, 0] * 1000.0, a[:, 1], a[:, 2]


def mitsuba_pair(name):
    d = os.path.join(DATA, "mitsuba")
    wl_e, eta = load_spd(os.path.join(d, name + ".eta.spd"))
    wl_k, k = load_spd(os.path.join(d, name + ".k.spd"))
    return (wl_e, eta), (wl_k, k)


def rii_pair(fname):
    wl, n, k = load_rii_nk(os.path.join(DATA, "refractiveindex.info", fname))
    return (wl, n), (wl, k)


# metal -> (loader, argument, short citation)
SOURCES = {
    "Ag": (mitsuba_pair, "Ag", "mitsuba-data ior/Ag.{eta,k}.spd (Luxpop/PBRT, Palik-based)"),
    "Al": (mitsuba_pair, "Al", "mitsuba-data ior/Al.{eta,k}.spd (Luxpop/PBRT, Palik-based)"),
    "Au": (mitsuba_pair, "Au", "mitsuba-data ior/Au.{eta,k}.spd (Luxpop/PBRT, Palik-based)"),
    "Cr": (mitsuba_pair, "Cr", "mitsuba-data ior/Cr.{eta,k}.spd (Luxpop: Cr_llnl_cxro + Cr_palik)"),
    "Cu": (mitsuba_pair, "Cu", "mitsuba-data ior/Cu.{eta,k}.spd (Luxpop/PBRT, Palik-based)"),
    "Fe": (rii_pair, "Fe-Johnson.yml", "refractiveindex.info main/Fe/nk/Johnson.yml (Johnson & Christy 1974)"),
    "Ni": (mitsuba_pair, "Ni_palik", "mitsuba-data ior/Ni_palik.{eta,k}.spd (Palik 1985 via Luxpop)"),
    "Ti": (rii_pair, "Ti-Johnson.yml", "refractiveindex.info main/Ti/nk/Johnson.yml (Johnson & Christy 1974)"),
}

# cross-check datasets (not used for the table)
CROSSCHECK = {
    "Ag": "Ag-Johnson.yml", "Au": "Au-Johnson.yml", "Cu": "Cu-Johnson.yml",
    "Cr": "Cr-Johnson.yml", "Ni": "Ni-Johnson.yml", "Al": "Al-Rakic.yml",
}


def f0(eta, k):
    return ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2)


def spectral_f0_rgb(eta_s, k_s):
    """'Ground truth' for comparison: spectral normal-incidence reflectance R(lambda)
    on the union of both wavelength grids, reduced as a reflectance (D65-weighted,
    i.e. what Mitsuba does for a reflectance <spectrum> in RGB mode)."""
    (we, e), (wk, k) = eta_s, k_s
    wl = np.union1d(we, wk)
    e_i, k_i = np.interp(wl, we, e), np.interp(wl, wk, k)
    return spectrum_list_to_srgb(wl, f0(e_i, k_i), bounded=True, d65=True)[1]  # unclamped


def reduce(eta_s, k_s, d65=False):
    e, e_raw = spectrum_list_to_srgb(*eta_s, bounded=False, d65=d65)
    k, k_raw = spectrum_list_to_srgb(*k_s, bounded=False, d65=d65)
    return e, k, e_raw, k_raw


def sig4(x):
    return float("%.4g" % x)


def fmt4(x):
    s = "%#.4g" % x
    if "e" in s:
        s = "%.6f" % sig4(x)
    if "." not in s:
        s += ".0"
    return s


def main():
    # self-check: unit spectrum -> XYZ ~ (1,1,1) (d65=False) and sRGB ~ (1,1,1) (d65=True)
    flat = ([300.0, 900.0], [1.0, 1.0])
    e_white = spectrum_list_to_srgb(*flat, d65=False)[0]
    d_white = spectrum_list_to_srgb(*flat, d65=True)[0]
    print("unit spectrum -> sRGB, d65=False (Mitsuba material= path): %s" % np.round(e_white, 4))
    print("unit spectrum -> sRGB, d65=True  (reflectance path)       : %s" % np.round(d_white, 4))
    print()

    rows = {}
    for m in sorted(SOURCES):
        loader, arg, cite = SOURCES[m]
        eta_s, k_s = loader(arg)
        cover = (min(eta_s[0][0], k_s[0][0]), max(eta_s[0][-1], k_s[0][-1]))
        assert eta_s[0][0] <= CIE_MIN and k_s[0][0] <= CIE_MIN and \
            eta_s[0][-1] >= CIE_MAX and k_s[0][-1] >= CIE_MAX, (m, cover)
        e, k, e_raw, k_raw = reduce(eta_s, k_s, d65=False)
        e65, k65, _, _ = reduce(eta_s, k_s, d65=True)
        rows[m] = dict(eta=e, k=k, eta_raw=e_raw, k_raw=k_raw, eta65=e65, k65=k65,
                       f0=f0(e, k), f0_65=f0(e65, k65), f0_spec=spectral_f0_rgb(eta_s, k_s),
                       cite=cite, cover=cover, n=(len(eta_s[0]), len(k_s[0])))

    np.set_printoptions(precision=4, suppress=True)
    print("== Mitsuba 3 RGB reduction (material= path: d65=False, negatives clamped to 0)")
    for m, r in rows.items():
        neg = "" if (r["eta_raw"].min() >= 0 and r["k_raw"].min() >= 0) else \
            "   (raw before clamp: eta %s k %s)" % (r["eta_raw"], r["k_raw"])
        print("%-2s eta %-28s k %-28s F0 %s%s" % (m, r["eta"], r["k"], r["f0"], neg))
    print()
    print("== Alternative: D65-weighted (d65=True) reduction of eta and k")
    for m, r in rows.items():
        print("%-2s eta %-28s k %-28s F0 %s" % (m, r["eta65"], r["k65"], r["f0_65"]))
    print()
    print("== Spectral F0(lambda) reduced as a D65 reflectance (reference colour, unclamped)")
    for m, r in rows.items():
        print("%-2s F0 %s   ratio material=-path F0/ref %s   d65-path F0/ref %s" %
              (m, r["f0_spec"], r["f0"] / r["f0_spec"], r["f0_65"] / r["f0_spec"]))
    print()
    print("== Cross-check: other datasets, same (material=) reduction")
    for m, fn in sorted(CROSSCHECK.items()):
        e, k, _, _ = reduce(*rii_pair(fn))
        print("%-2s %-18s eta %-28s k %-28s F0 %s" % (m, fn, e, k, f0(e, k)))

    # ---- check against numbers produced by Mitsuba 3 itself (see mitsuba_reference.py)
    ref_path = os.path.join(DATA, "mitsuba_reference_scalar_rgb.txt")
    if os.path.exists(ref_path):
        name_map = {"Ni_palik": "Ni"}
        worst = 0.0
        print("\n== Check against Mitsuba 3 output (%s)" % os.path.basename(ref_path))
        for line in open(ref_path):
            if line.startswith("#") or not line.strip():
                continue
            path, name, *vals = line.split()
            ref = np.array([float(v) for v in vals])
            m = name_map.get(name, name)
            if m not in rows:
                continue
            r = rows[m]
            mine = np.concatenate([r["eta65"], r["k65"]]) if path == "spectrum_file" else \
                np.concatenate([r["eta"], r["k"]])
            rel = np.max(np.abs(mine - ref) / np.abs(ref))
            worst = max(worst, rel)
            print("  %-13s %-8s max rel diff %.2e" % (path, name, rel))
        print("  worst relative difference: %.2e" % worst)
        assert worst < 1e-5, "reduction does not reproduce Mitsuba"

    # ---- Rust table
    out = os.path.join(HERE, "table.rs")
    with open(out, "w") as f:
        f.write(RUST_HEADER)
        for m, r in rows.items():
            f.write("//   %s: %s\n" % (m, r["cite"]))
        f.write(RUST_HEADER2)
        f.write("pub const METALS: &[(&str, [f32; 3], [f32; 3])] = &[\n")
        for m, r in rows.items():
            f.write('    ("%s", [%s], [%s]),\n' % (
                m, ", ".join(fmt4(x) for x in r["eta"]), ", ".join(fmt4(x) for x in r["k"])))
        f.write("];\n")
    print("\nwrote", out)

    if "--markdown" in sys.argv:
        print("\n| metal | eta (R,G,B) | k (R,G,B) | F0 (R,G,B) | F0 spectral ref (R,G,B) |")
        print("|---|---|---|---|---|")
        for m, r in rows.items():
            j = lambda v: ", ".join(fmt4(x) for x in v)
            print("| %s | %s | %s | %s | %s |" % (m, j(r["eta"]), j(r["k"]), j(r["f0"]), j(r["f0_spec"])))
        print("\n| metal | eta d65 (R,G,B) | k d65 (R,G,B) | F0 d65 (R,G,B) |")
        print("|---|---|---|---|")
        for m, r in rows.items():
            j = lambda v: ", ".join(fmt4(x) for x in v)
            print("| %s | %s | %s | %s |" % (m, j(r["eta65"]), j(r["k65"]), j(r["f0_65"])))


RUST_HEADER = """\
// Measured complex index of refraction (eta + i k) of metals, relative to air (ior 1),
// reduced to linear-sRGB (Rec. 709 primaries) channel values. Generated by reduce.py.
//
// Data sources:
//   Ag, Al, Au, Cr, Cu, Ni: the spectra Mitsuba 3 ships for conductor `material=` presets,
//     mitsuba-renderer/mitsuba-data @ 01100fa9b0b154492061a92404f26dcd7b784dbb, ior/<name>.{eta,k}.spd
//     (same files as PBRT; from the Luxpop database, based on E. D. Palik (ed.), Handbook of
//     Optical Constants of Solids, Academic Press 1985/1998; Cr additionally LLNL/CXRO data).
//     Mitsuba has no plain "Ni" preset; its "Ni_palik" files are used.
//   Fe, Ti: not in Mitsuba; P. B. Johnson and R. W. Christy, "Optical constants of transition
//     metals: Ti, V, Cr, Mn, Fe, Co, Ni, and Pd", Phys. Rev. B 9, 5056 (1974), as tabulated in
//     polyanskiy/refractiveindex.info-database @ ff11b5897ef0754b15d939d921eb6c745693cbd1,
//     database/data/main/{Fe,Ti}/nk/Johnson.yml (188-1937 nm, covers 360-830 nm; no extrapolation).
// Per metal:
"""

RUST_HEADER2 = """\
//
// Reduction (identical to Mitsuba 3 RGB variants for conductor `material="..."`, i.e.
// ior_from_file -> spectrum_list_to_srgb(bounded=false, d65=false)): eta(lambda) and k(lambda)
// are each linearly interpolated at 1000 evenly spaced wavelengths in [360, 830] nm, weighted by
// the CIE 1931 2-degree colour matching functions (no illuminant; equal-energy weighting),
// summed and scaled by 470/1000/106.75026 so that a unit spectrum has Y = 1, then converted
// XYZ -> linear sRGB with Mitsuba's matrix [3.240479 -1.537150 -0.498535; -0.969256 1.875991
// 0.041556; 0.055648 -0.204043 1.057311]; negative channels would be clamped to 0 (none occur).
// Note: with this (Mitsuba) convention a wavelength-constant value c maps to c*(1.205, 0.948, 0.909).
"""

if __name__ == "__main__":
    main()
