#!/usr/bin/env python3
"""Writes bent_bar.json: a bar [0, 7] x [-0.2, 0.2] and two keyframes given as
coefficients over a user cage: the bar rolled up by g_a(z) = exp((0.05 + 0.8 i) z)
through 5.6 rad < 2 pi (no overlap), then by the holomorphic
g(z) = exp((0.05 + i) z), which turns it through 7 rad > 2 pi, so its
far end lies over its near end (radius e^(0.05 x - y) grows along the bar: the two
layers' outlines cross properly). g' != 0 and psi = 0 (f_zbar = 0): locally
injective, certified, but not globally injective: the global-overlap test scene
of issue #20. Cauchy coordinates with phi_j = g(z_j) reproduce g up to the
cage's discretisation."""
import cmath
import json
import os


def rect_loop(x0, y0, x1, y1, step):
    def edge(a, b):
        n = max(1, round(abs(b - a) / step))
        return [a + (b - a) * k / n for k in range(n)]
    c = [complex(x0, y0), complex(x1, y0), complex(x1, y1), complex(x0, y1)]
    pts = []
    for i in range(4):
        pts += edge(c[i], c[(i + 1) % 4])
    return pts


def xy(pts):
    return [[p.real, p.imag] for p in pts]


shape = rect_loop(0.0, -0.2, 7.0, 0.2, 0.1)
cage = rect_loop(-0.15, -0.35, 7.15, 0.35, 0.1)
g = lambda z: cmath.exp(complex(0.05, 1.0) * z)
g_a = lambda z: cmath.exp(complex(0.05, 0.8) * z)
scene = {
    "hsi_scene": 1,
    "name": "bent_bar",
    "samples": 2000,
    "hessian_ratio": 0.2,
    "shape": {"outer": xy(shape), "holes": []},
    "cage": {"loops": [xy(cage)], "hole_points": []},
    "handles": [],
    "keyframes": [
        {"time": 0.0, "phi": xy([g_a(z) for z in cage]), "psi": [[0.0, 0.0]] * len(cage)},
        {"time": 1.0, "phi": xy([g(z) for z in cage]), "psi": [[0.0, 0.0]] * len(cage)},
    ],
}
with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "bent_bar.json"), "w") as f:
    json.dump(scene, f, indent=1)
    f.write("\n")
