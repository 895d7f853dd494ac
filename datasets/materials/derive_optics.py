#!/usr/bin/env python3
"""Derives the estimated optical coefficients in polyjet.json and fdm.json.

No published per-channel coefficients for these exact grades are reproduced in
this project, so the optics are estimates built from two assumptions per
material: a reduced scattering coefficient sigma_s' (1/mm) and either

  * a target thick-slab albedo (the material's preview colour, sRGB decoded to
    linear RGB, floored at 0.01), from which sigma_a is solved per channel, or
  * an explicit sigma_a (clear materials, which have no meaningful thick-slab
    colour).

The albedo written to the files is always recomputed from sigma_a, sigma_s'
and eta with the semi-infinite dipole diffusion relation (Jensen et al. 2001,
"A practical model for subsurface light transport"):

  alpha' = sigma_s' / (sigma_s' + sigma_a)
  Fdr    = -1.440/eta^2 + 0.710/eta + 0.668 + 0.0636 eta
  A      = (1 + Fdr) / (1 - Fdr)
  Rd     = alpha'/2 * (1 + exp(-4/3 A sqrt(3(1-alpha')))) * exp(-sqrt(3(1-alpha')))

Run: python3 derive_optics.py   (prints one JSON "optical" value set per material)
"""
import json
import math


def srgb_to_linear(c):
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def diffuse_albedo(sigma_a, sigma_s_reduced, eta):
    alpha = sigma_s_reduced / (sigma_s_reduced + sigma_a)
    fdr = -1.440 / eta**2 + 0.710 / eta + 0.668 + 0.0636 * eta
    a = (1 + fdr) / (1 - fdr)
    root = math.sqrt(3 * (1 - alpha))
    return alpha / 2 * (1 + math.exp(-4 / 3 * a * root)) * math.exp(-root)


def solve_sigma_a(target, sigma_s_reduced, eta):
    # Rd falls monotonically as sigma_a grows; bisect on log(sigma_a).
    lo, hi = 1e-8, 1e6
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        if diffuse_albedo(mid, sigma_s_reduced, eta) > target:
            lo = mid
        else:
            hi = mid
    return math.sqrt(lo * hi)


def sig(x, digits=4):
    return float(f"{x:.{digits}g}")


# name: (preview sRGB, sigma_s' per channel, eta, explicit sigma_a or None)
MATERIALS = {
    "VeroWhitePlus": ([0.94, 0.94, 0.92], [2.6, 2.8, 3.0], 1.50, None),
    "VeroBlackPlus": ([0.10, 0.10, 0.10], [0.5, 0.5, 0.5], 1.50, None),
    "VeroCyan": ([0.00, 0.62, 0.85], [1.0, 1.0, 1.0], 1.50, None),
    "VeroMagenta": ([0.85, 0.10, 0.55], [1.0, 1.0, 1.0], 1.50, None),
    "VeroYellow": ([0.93, 0.83, 0.10], [1.0, 1.0, 1.0], 1.50, None),
    "VeroClear": ([0.92, 0.94, 0.95], [0.002, 0.002, 0.002], 1.50, [0.004, 0.005, 0.010]),
    "TangoPlus": ([0.93, 0.88, 0.70], [0.05, 0.05, 0.05], 1.48, [0.010, 0.020, 0.060]),
    "TangoBlackPlus": ([0.12, 0.12, 0.12], [0.3, 0.3, 0.3], 1.48, None),
    "Agilus30Clear": ([0.93, 0.91, 0.82], [0.02, 0.02, 0.02], 1.48, [0.008, 0.012, 0.030]),
    "FullCure705": ([0.92, 0.90, 0.82], [1.5, 1.5, 1.5], 1.47, None),
    "PLA": ([0.95, 0.95, 0.93], [5.0, 5.0, 5.0], 1.46, None),
    "bronzeFill": ([0.55, 0.38, 0.22], [5.0, 5.0, 5.0], 1.46, None),
}

if __name__ == "__main__":
    for name, (srgb, s, eta, given_a) in MATERIALS.items():
        if given_a is None:
            targets = [max(srgb_to_linear(c), 0.01) for c in srgb]
            a = [sig(solve_sigma_a(t, sc, eta)) for t, sc in zip(targets, s)]
        else:
            a = given_a
        albedo = [round(diffuse_albedo(ac, sc, eta), 4) for ac, sc in zip(a, s)]
        print(json.dumps({"name": name, "absorption_per_mm": a,
                          "reduced_scattering_per_mm": s, "refractive_index": eta,
                          "albedo": albedo}))
