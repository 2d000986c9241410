#!/usr/bin/python3
"""Generates hsi's bundled assets (assets/*.json, assets/*.png, assets/README.md).

Regenerate everything, from the repository root:

    cmake -S . -B build -G Ninja && cmake --build build --target hsi
    /usr/bin/python3 scripts/make_assets.py --hsi build/bin/hsi

The script writes the procedural scenes (annulus, bar_holes, two_holes, links, arm,
blob) itself, every texture, and then imports the glyph scenes with these commands
(run from the repository root; the script runs them for you):

    build/bin/hsi import-glyph B -o assets/glyph_B.json --height 1 --flatness 0.0005 --max-edge 0.02 --texture assets/glyph_B.png --name glyph_B
    build/bin/hsi import-glyph 8 -o assets/glyph_8.json --height 1 --flatness 0.0005 --max-edge 0.02 --texture assets/glyph_8.png --name glyph_8
    build/bin/hsi import-glyph A -o assets/glyph_A.json --height 1 --flatness 0.0005 --max-edge 0.02 --texture assets/glyph_A.png --name glyph_A

Everything is deterministic: the same inputs give byte-identical files. Needs only
/usr/bin/python3 with python3-numpy (Debian 12) and the standard library; PNGs are
written with zlib + struct. Other assets in the folder (sprite_* scenes) are left alone.

The scenes come out without handles and keyframes: pose them afterwards with
scripts/make_keyframes.py (the README's "Keyframes" section lists the poses).
"""

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import zlib

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASSETS = os.path.join(ROOT, "assets")

TEX_SIZE = 512          # textures are TEX_SIZE × TEX_SIZE RGB
TEX_MARGIN = 0.05       # texture_rect = bounding box expanded by 5% on every side
MIN_CLEARANCE = 0.08    # holes at least this fraction of the bbox diagonal from other loops
MAX_PNG_BYTES = 300_000

GLYPHS = ["B", "8", "A"]
GLYPH_ARGS = ["--height", "1", "--flatness", "0.0005", "--max-edge", "0.02"]


# --------------------------------------------------------------------------- geometry

def resample(poly, n):
    """n points evenly spaced by arc length along the closed polyline poly (m × 2)."""
    closed = np.vstack([poly, poly[:1]])
    seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.arange(n) * (s[-1] / n)
    x = np.interp(t, s, closed[:, 0])
    y = np.interp(t, s, closed[:, 1])
    return np.stack([x, y], axis=1)


def circle(cx, cy, r, n):
    t = 2 * np.pi * np.arange(n) / n
    return np.stack([cx + r * np.cos(t), cy + r * np.sin(t)], axis=1)


def rounded_rect(cx, cy, w, h, r, n, angle=0.0):
    """A w × h rectangle with corner radius r, centred at (cx, cy), rotated by angle."""
    hx, hy = w / 2 - r, h / 2 - r
    pts = []
    for k, (sx, sy) in enumerate([(1, 1), (-1, 1), (-1, -1), (1, -1)]):
        a = np.linspace(k * np.pi / 2, (k + 1) * np.pi / 2, 256)
        pts.append(np.stack([sx * hx + r * np.cos(a), sy * hy + r * np.sin(a)], axis=1))
    dense = resample(np.vstack(pts), 4096)
    c, s = math.cos(angle), math.sin(angle)
    rot = dense @ np.array([[c, s], [-s, c]])
    return resample(rot + [cx, cy], n)


def polar(rfun, n, dense=8192):
    t = 2 * np.pi * np.arange(dense) / dense
    r = rfun(t)
    assert np.all(r > 0)
    return resample(np.stack([r * np.cos(t), r * np.sin(t)], axis=1), n)


def star_outline(sdf, center, n, rmax, rays=16384, steps=4000):
    """The boundary of {sdf < 0}, star-shaped about center: on each ray, the first
    crossing by marching then bisection; resampled evenly to n points."""
    t = 2 * np.pi * np.arange(rays) / rays
    d = np.stack([np.cos(t), np.sin(t)], axis=1)
    r = np.linspace(0, rmax, steps)
    inside = np.empty((rays, steps), dtype=bool)
    for j in range(steps):
        p = center + r[j] * d
        inside[:, j] = sdf(p[:, 0], p[:, 1]) < 0
    assert inside[:, 0].all() and not inside[:, -1].any()
    first_out = np.argmin(inside, axis=1)
    # Star-shaped: no ray re-enters the set after leaving it.
    idx = np.arange(steps)[None, :]
    assert not (inside & (idx > first_out[:, None])).any(), "shape is not star-shaped about its centre"
    lo, hi = r[first_out - 1], r[first_out]
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        p = center + mid[:, None] * d
        ins = sdf(p[:, 0], p[:, 1]) < 0
        lo = np.where(ins, mid, lo)
        hi = np.where(ins, hi, mid)
    pts = center + (0.5 * (lo + hi))[:, None] * d
    return resample(pts, n)


def smin(a, b, k):
    """Polynomial smooth minimum (smooth union of two distance fields)."""
    h = np.maximum(k - np.abs(a - b), 0.0) / k
    return np.minimum(a, b) - h * h * k / 4


def sd_disc(x, y, cx, cy, r):
    return np.hypot(x - cx, y - cy) - r


def sd_capsule(x, y, ax, ay, bx, by, r):
    px, py, ex, ey = x - ax, y - ay, bx - ax, by - ay
    h = np.clip((px * ex + py * ey) / (ex * ex + ey * ey), 0, 1)
    return np.hypot(px - h * ex, py - h * ey) - r


def signed_area(loop):
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def orient(loop, ccw):
    return loop if (signed_area(loop) > 0) == ccw else loop[::-1].copy()


def point_in_loop(loop, p):
    x, y = loop[:, 0], loop[:, 1]
    x2, y2 = np.roll(x, -1), np.roll(y, -1)
    cond = (y > p[1]) != (y2 > p[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = x + (p[1] - y) * (x2 - x) / (y2 - y)
    return bool(np.sum(cond & (p[0] < xi)) % 2)


def point_segment_distances(pts, loop):
    """Distance from each point to the closed polyline loop."""
    a = loop[None, :, :]
    b = np.roll(loop, -1, axis=0)[None, :, :]
    p = pts[:, None, :]
    ab = b - a
    t = np.clip(np.sum((p - a) * ab, axis=2) / np.sum(ab * ab, axis=2), 0, 1)
    q = a + t[:, :, None] * ab
    return np.min(np.linalg.norm(p - q, axis=2), axis=1)


def loop_distance(l1, l2):
    return float(min(point_segment_distances(l1, l2).min(), point_segment_distances(l2, l1).min()))


def assert_simple(loop, what):
    """No two non-adjacent edges of the loop intersect (proper or touching)."""
    a = loop
    b = np.roll(loop, -1, axis=0)
    n = len(loop)

    def cross(o, p, q):
        return (p[..., 0] - o[..., 0]) * (q[..., 1] - o[..., 1]) - (p[..., 1] - o[..., 1]) * (q[..., 0] - o[..., 0])

    A, B = a[:, None, :], b[:, None, :]
    C, D = a[None, :, :], b[None, :, :]
    d1, d2 = cross(A, B, C), cross(A, B, D)
    d3, d4 = cross(C, D, A), cross(C, D, B)
    tol = 1e-12 * max(1.0, float(np.abs(loop).max())) ** 2

    def on_segment(p, q, r, d):
        """r lies on the segment [p, q], given d = cross(p, q, r) (collinearity)."""
        return ((np.abs(d) <= tol)
                & (np.minimum(p[..., 0], q[..., 0]) <= r[..., 0]) & (r[..., 0] <= np.maximum(p[..., 0], q[..., 0]))
                & (np.minimum(p[..., 1], q[..., 1]) <= r[..., 1]) & (r[..., 1] <= np.maximum(p[..., 1], q[..., 1])))

    proper = (((d1 > tol) & (d2 < -tol)) | ((d1 < -tol) & (d2 > tol))) & \
             (((d3 > tol) & (d4 < -tol)) | ((d3 < -tol) & (d4 > tol)))
    touch = on_segment(A, B, C, d1) | on_segment(A, B, D, d2) | on_segment(C, D, A, d3) | on_segment(C, D, B, d4)
    hit = proper | touch
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    adjacent = (i == j) | ((i + 1) % n == j) | ((j + 1) % n == i)
    bad = hit & ~adjacent
    assert not bad.any(), f"{what} intersects itself"
    seg = np.linalg.norm(b - a, axis=1)
    assert seg.min() > 1e-9, f"{what} has a zero-length edge"


def check_shape(name, outer, holes, enforce_clearance=True):
    """Simplicity, containment and clearance (MIN_CLEARANCE of the bbox diagonal);
    returns the smallest gap between two loops relative to the diagonal."""
    lo, hi = outer.min(axis=0), outer.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    loops = [outer] + holes
    for k, loop in enumerate(loops):
        assert_simple(loop, f"{name} loop {k}")
    for k, h in enumerate(holes):
        assert point_in_loop(outer, h[0]), f"{name}: hole {k + 1} is outside the outer loop"
    clearance = math.inf
    for a in range(len(loops)):
        for b in range(a + 1, len(loops)):
            clearance = min(clearance, loop_distance(loops[a], loops[b]))
    if holes and enforce_clearance:
        assert clearance >= MIN_CLEARANCE * diag, (
            f"{name}: loops only {clearance:.4f} apart, need {MIN_CLEARANCE} × diagonal = {MIN_CLEARANCE * diag:.4f}")
    return clearance / diag if holes else None


# --------------------------------------------------------------------------- shapes

def shape_annulus():
    outer = polar(lambda t: 1.0 + 0.035 * np.cos(2 * t + 0.4) + 0.015 * np.sin(3 * t), 192)
    holes = [circle(0.07, 0.04, 0.45, 96)]
    return "A disc with one round, slightly off-centre hole.", outer, holes


def shape_bar_holes():
    outer = rounded_rect(0.0, 0.0, 3.4, 1.3, 0.45, 256)
    holes = [
        circle(-1.14, 0.0, 0.21, 56),
        rounded_rect(-0.38, 0.0, 0.40, 0.60, 0.10, 64),
        circle(0.38, 0.03, 0.16, 48),
        rounded_rect(1.14, 0.0, 0.44, 0.36, 0.12, 64, angle=0.25),
    ]
    return "A long rounded bar (3.4 × 1.3) with two round and two rounded-rectangle holes.", outer, holes


def shape_two_holes():
    outer = polar(lambda t: 1.0 + 0.12 * np.cos(2 * t) + 0.06 * np.sin(3 * t) + 0.03 * np.cos(5 * t + 0.7), 224)
    holes = [circle(-0.28, 0.02, 0.42, 128), circle(0.58, 0.12, 0.06, 32)]
    return "An organic blob with one large hole and one very small hole (radius ratio 7).", outer, holes


def shape_links():
    def sdf(x, y):
        return smin(sd_disc(x, y, -0.95, 0.0, 1.0), sd_disc(x, y, 0.95, 0.0, 1.0), 0.6)

    outer = star_outline(sdf, np.array([0.0, 0.0]), 288, rmax=2.5)
    holes = [circle(-0.97, 0.0, 0.5, 112), circle(0.97, 0.0, 0.5, 112)]
    return "A figure-eight: two fused rings, one connected outline with two holes.", outer, holes


def shape_arm():
    tip = np.array([3.75, 0.55])

    def sdf(x, y):
        body = sd_disc(x, y, 0.0, 0.0, 1.0)
        limb = sd_capsule(x, y, 0.0, 0.0, tip[0], tip[1], 0.2)
        return smin(body, limb, 0.3)

    outer = star_outline(sdf, np.array([0.0, 0.0]), 320, rmax=4.5)
    holes = [circle(-0.2, 0.0, 0.33, 80)]
    length = float(np.linalg.norm(tip)) + 0.2 - 1.0  # from the body's rim to the tip
    return (f"A round body with one hole and a long thin limb (about {length:.1f} long, 0.4 wide: "
            f"aspect ratio {length / 0.4:.1f}).", outer, holes)


def shape_blob():
    outer = polar(lambda t: 1.0 + 0.22 * np.cos(2 * t + 0.4) + 0.14 * np.sin(3 * t) + 0.07 * np.cos(5 * t + 1.0)
                  + 0.03 * np.sin(7 * t + 2.0), 256)
    return "A simply connected organic shape (no holes).", outer, []


SHAPES = {
    "annulus": shape_annulus,
    "bar_holes": shape_bar_holes,
    "two_holes": shape_two_holes,
    "links": shape_links,
    "arm": shape_arm,
    "blob": shape_blob,
}


# --------------------------------------------------------------------------- textures

def write_png(path, img):
    """8-bit RGB or RGBA PNG; per row the filter (None, Sub, Up, Average) with the
    smallest sum of absolute values, zlib level 9."""
    img = np.ascontiguousarray(img, dtype=np.uint8)
    h, w, c = img.shape
    color_type = {3: 2, 4: 6}[c]
    rows = img.reshape(h, w * c).astype(np.int16)
    prev = np.zeros(w * c, dtype=np.int16)
    out = bytearray()
    for y in range(h):
        row = rows[y]
        left = np.concatenate([np.zeros(c, dtype=np.int16), row[:-c]])
        cands = [
            row,
            row - left,
            row - prev,
            row - ((left + prev) // 2),
        ]
        costs = [int(np.abs(((f + 128) % 256) - 128).sum()) for f in cands]
        best = int(np.argmin(costs))
        out.append(best)
        out += (cands[best] % 256).astype(np.uint8).tobytes()
        prev = row

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, color_type, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(bytes(out), 9))
    png += chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)
    return len(png)


def lerp_colors(t, stops):
    """Piecewise-linear colour ramp; t in [0, 1] (any shape), stops: list of RGB 0..255."""
    stops = np.asarray(stops, dtype=np.float64)
    k = len(stops) - 1
    x = np.clip(t, 0, 1) * k
    i = np.minimum(np.floor(x).astype(int), k - 1)
    f = (x - i)[..., None]
    return stops[i] * (1 - f) + stops[i + 1] * f


def hsv(h, s, v):
    """HSV → RGB in 0..1, arrays."""
    h = (h % 1.0) * 6
    i = np.floor(h).astype(int) % 6
    f = h - np.floor(h)
    p, q, t = v * (1 - s), v * (1 - s * f), v * (1 - s * (1 - f))
    r = np.choose(i, [v, q, p, p, t, v])
    g = np.choose(i, [t, v, v, q, p, p])
    b = np.choose(i, [p, p, t, v, v, q])
    return np.stack([r, g, b], axis=-1)


def edge(d, px):
    """Anti-aliased step: 1 where d > 0, 0 where d < 0, ramp one pixel (px) wide."""
    return np.clip(0.5 + d / px, 0, 1)


def texture_coords(aspect):
    """World-proportional coordinates over the texture: u in [0, aspect'], v in [0, 1']
    scaled so that one unit is the same length in x and y (square pattern cells on
    the shape, whatever its aspect ratio), plus the size of one pixel in those units."""
    n = TEX_SIZE
    x = (np.arange(n) + 0.5) / n
    y = 1 - (np.arange(n) + 0.5) / n    # row 0 is the top of the texture rectangle
    sx, sy = (aspect, 1.0) if aspect >= 1 else (1.0, 1.0 / aspect)
    u, v = np.meshgrid(x * sx, y * sy)
    return u, v, max(sx, sy) / n


def checker(u, v, cell, px):
    """1 on half the cells, 0 on the others, anti-aliased."""
    a = np.sin(np.pi * u / cell) * np.sin(np.pi * v / cell)
    # Distance-like quantity: the product changes sign at cell borders.
    return edge(a / (np.pi / cell), px)


def stripes(s, period, px, duty=0.5):
    f = (s / period) % 1.0
    d = np.minimum(f - 0, duty - f) * period     # > 0 inside the stripe
    d = np.where(f < duty, d, -np.minimum(f - duty, 1 - f) * period)
    return edge(d, px)


def dots(u, v, spacing, radius, px, hexagonal=False):
    if hexagonal:
        row = np.floor(v / (spacing * 0.866))
        uu = u + 0.5 * spacing * (row % 2)
        cy = (row + 0.5) * spacing * 0.866
        cx = (np.floor(uu / spacing) + 0.5) * spacing
        d = radius - np.hypot(uu - cx, v - cy)
    else:
        cx = (np.floor(u / spacing) + 0.5) * spacing
        cy = (np.floor(v / spacing) + 0.5) * spacing
        d = radius - np.hypot(u - cx, v - cy)
    return edge(d, px)


def grid_lines(u, v, spacing, width, px):
    du = np.abs(((u / spacing + 0.5) % 1.0) - 0.5) * spacing
    dv = np.abs(((v / spacing + 0.5) % 1.0) - 0.5) * spacing
    return edge(width / 2 - np.minimum(du, dv), px)


def mix(a, b, t):
    return a * (1 - t[..., None]) + b * t[..., None]


def tex_annulus(aspect):
    u, v, px = texture_coords(aspect)
    ang = np.arctan2(v - 0.5 * v.max(), u - 0.5 * u.max()) / (2 * np.pi)
    base = hsv(ang, 0.55, 0.95) * 255        # hue wheel around the centre
    c = checker(u, v, 1 / 12, px)
    return mix(base, base * 0.45, c)


def tex_bar_holes(aspect):
    u, v, px = texture_coords(aspect)
    base = lerp_colors(u / u.max(), [(40, 90, 200), (90, 200, 170), (250, 220, 80)])
    s = stripes(u + v, 0.09, px * 1.4, duty=0.45)
    img = mix(base, np.full(3, 250.0), 0.65 * s)
    g = grid_lines(u, v, 0.25, 0.012, px)
    return mix(img, np.full(3, 30.0), g)


def tex_two_holes(aspect):
    u, v, px = texture_coords(aspect)
    base = lerp_colors(v / v.max(), [(230, 80, 60), (245, 170, 60), (250, 240, 200)])
    d = dots(u, v, 1 / 14, 0.022, px)
    return mix(base, np.array([40.0, 60.0, 140.0]), d)


def tex_links(aspect):
    u, v, px = texture_coords(aspect)
    t = (u / u.max() + v / v.max()) / 2
    light = lerp_colors(t, [(255, 120, 130), (170, 140, 255), (110, 220, 255)])
    c = checker(u, v, 1 / 10, px)
    img = mix(light, light * 0.35, c)
    g = grid_lines(u, v, 1 / 10, 0.006, px)
    return mix(img, np.full(3, 255.0), 0.8 * g)


def tex_arm(aspect):
    u, v, px = texture_coords(aspect)
    base = lerp_colors(u / u.max(), [(60, 160, 80), (230, 230, 90), (230, 110, 50)])
    across = stripes(u, 0.08, px, duty=0.5)           # bands across the limb: bending shows
    along = stripes(v, 0.08, px, duty=0.18)
    img = mix(base, base * 0.55, across)
    return mix(img, np.full(3, 35.0), 0.75 * along)


def tex_blob(aspect):
    u, v, px = texture_coords(aspect)
    r = np.hypot(u - 0.5 * u.max(), v - 0.5 * v.max()) / (0.5 * max(u.max(), v.max()))
    base = lerp_colors(r, [(255, 245, 210), (120, 210, 200), (40, 90, 150)])
    d = dots(u, v, 1 / 11, 0.03, px, hexagonal=True)
    img = mix(base, np.array([200.0, 40.0, 110.0]), d)
    g = grid_lines(u, v, 1 / 5.5, 0.006, px)
    return mix(img, np.full(3, 60.0), 0.6 * g)


def tex_glyph_B(aspect):
    u, v, px = texture_coords(aspect)
    base = lerp_colors(v / v.max(), [(30, 60, 160), (250, 150, 40)])
    c = checker(u, v, 1 / 16, px)
    return mix(base, np.full(3, 245.0), 0.75 * c)


def tex_glyph_8(aspect):
    u, v, px = texture_coords(aspect)
    base = lerp_colors(u / u.max(), [(150, 40, 160), (40, 180, 200)])
    s = stripes(v, 1 / 18, px)
    img = mix(base, base * 0.5 + 120, s)
    d = dots(u, v, 1 / 9, 0.014, px)
    return mix(img, np.full(3, 255.0), d)


def tex_glyph_A(aspect):
    u, v, px = texture_coords(aspect)
    t = np.clip(0.5 + 0.5 * (u - v), 0, 1)
    base = lerp_colors(t, [(250, 230, 90), (220, 70, 70), (70, 50, 130)])
    g = grid_lines(u, v, 1 / 12, 0.007, px)
    s = stripes(u - v, 1 / 6, px, duty=0.5)
    img = mix(base, base * 0.8, s)
    return mix(img, np.full(3, 20.0), g)


TEXTURES = {
    "annulus": (tex_annulus, "hue wheel about the centre + checkerboard"),
    "bar_holes": (tex_bar_holes, "blue-green-yellow gradient + diagonal stripes + grid"),
    "two_holes": (tex_two_holes, "red-orange vertical gradient + square grid of dots"),
    "links": (tex_links, "pink-violet-cyan diagonal gradient + checkerboard + grid"),
    "arm": (tex_arm, "green-yellow-orange gradient + bands across and lines along the limb"),
    "blob": (tex_blob, "radial gradient + hexagonal dots + grid"),
    "glyph_B": (tex_glyph_B, "blue-orange vertical gradient + fine checkerboard"),
    "glyph_8": (tex_glyph_8, "purple-cyan gradient + horizontal stripes + dots"),
    "glyph_A": (tex_glyph_A, "yellow-red-violet diagonal gradient + diagonal bands + grid"),
}


def make_texture(name, aspect):
    fn = TEXTURES[name][0]
    img = np.clip(np.rint(fn(aspect)), 0, 255).astype(np.uint8)
    path = os.path.join(ASSETS, name + ".png")
    size = write_png(path, img)
    assert size < MAX_PNG_BYTES, f"{path}: {size} bytes, over {MAX_PNG_BYTES}"
    return size


# --------------------------------------------------------------------------- scenes

def fmt(v):
    s = f"{v:.6f}"
    return "0.000000" if s == "-0.000000" else s


def fmt_loop(loop, indent):
    pts = [f"[{fmt(x)}, {fmt(y)}]" for x, y in loop]
    lines = [", ".join(pts[i:i + 4]) for i in range(0, len(pts), 4)]
    pad = " " * indent
    return "[\n" + ",\n".join(pad + "  " + l for l in lines) + "\n" + pad + "]"


def expanded_rect(lo, hi):
    m = TEX_MARGIN * (hi - lo)
    return [float(lo[0] - m[0]), float(lo[1] - m[1]), float(hi[0] + m[0]), float(hi[1] + m[1])]


def write_scene(name, outer, holes):
    outer = orient(np.round(outer, 6), True)
    holes = [orient(np.round(h, 6), False) for h in holes]
    lo, hi = outer.min(axis=0), outer.max(axis=0)
    rect = expanded_rect(lo, hi)
    text = "{\n"
    text += '  "hsi_scene": 1,\n'
    text += f'  "name": {json.dumps(name)},\n'
    text += '  "shape": {\n'
    text += '    "outer": ' + fmt_loop(outer, 4) + ",\n"
    if holes:
        text += '    "holes": [\n' + ",\n".join("      " + fmt_loop(h, 6) for h in holes) + "\n    ]\n"
    else:
        text += '    "holes": []\n'
    text += "  },\n"
    text += f'  "texture": "{name}.png",\n'
    text += '  "texture_rect": [' + ", ".join(fmt(v) for v in rect) + "]\n"
    text += "}\n"
    json.loads(text)  # well-formed
    with open(os.path.join(ASSETS, name + ".json"), "w") as f:
        f.write(text)
    return outer, holes, rect


def glyph_command(hsi, ch, with_texture=True, output=None):
    name = f"glyph_{ch}"
    out = output or os.path.join("assets", name + ".json")
    cmd = [hsi, "import-glyph", ch, "-o", out] + GLYPH_ARGS
    if with_texture:
        cmd += ["--texture", os.path.join("assets", name + ".png")]
    cmd += ["--name", name]
    return cmd


def load_loops(path):
    with open(path) as f:
        j = json.load(f)
    outer = np.array(j["shape"]["outer"], dtype=np.float64)
    holes = [np.array(h, dtype=np.float64) for h in j["shape"].get("holes", [])]
    return j, outer, holes


# --------------------------------------------------------------------------- README

README_HEAD = """\
# Bundled assets

Scenes (hsi scene format, version 1: see `engine/include/hsi/scene_io.h`) with their
textures, for the tests, the examples and the viewer. Everything here except the
`sprite_*` scenes is generated by `scripts/make_assets.py`; do not edit the files by
hand, change the script and regenerate:

```sh
cmake -S . -B build -G Ninja && cmake --build build --target hsi
/usr/bin/python3 scripts/make_assets.py --hsi build/bin/hsi
```

The script writes the procedural scenes and every texture itself, then imports the
glyph scenes with (run from the repository root):

```sh
{glyph_commands}
```

The output is deterministic (the same script and font give byte-identical files).

## Provenance and licence

* The procedural shapes and all textures are our own, made by the script from
  formulas (polar Fourier curves, smooth unions of discs and capsules, rounded
  rectangles; gradients with checkerboards, stripes, dots and grids). They are part
  of hsi and under its licence.
* The `glyph_*` outlines are the letter and digit outlines of **DejaVu Sans**
  (`/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf`, Debian package
  `fonts-dejavu-core`), flattened to polygons by `hsi import-glyph`. DejaVu is
  derived from Bitstream Vera (Copyright (c) 2003 by Bitstream, Inc.; the DejaVu
  changes are in the public domain); its licence permits using, copying, modifying
  and redistributing the font software. These files are polygon shape data made
  from three outlines, not a font; see `/usr/share/doc/fonts-dejavu-core/copyright`
  for the full licence. Their textures are our own.
* No other third-party artwork is included.

## Conventions

* Coordinates are of order 1, y up. Outer loops are counter-clockwise and holes
  clockwise (the loader normalizes the orientation anyway).
* Holes keep a clearance of at least {clearance:.0%} of the shape's bounding-box diagonal
  from the outer loop and from each other (procedural shapes; checked by the script),
  so that a cage fits between the loops.
* `texture_rect` is the shape's bounding box expanded by {margin:.0%} of its width and
  height on every side. Textures are {tex}×{tex} RGB PNGs; their patterns are drawn
  in world proportions over that rectangle (checker cells are square on the shape).

## Assets

| scene | loops | outer vertices | hole vertices | size (w × h) | min. loop gap / diagonal | texture | description |
|---|---|---|---|---|---|---|---|
"""

SPRITE_NOTE = """
Scenes named `sprite_*` are not made by this script. `sprite_pretzel` is an original
procedural sprite: `scripts/make_sprite.py` draws `sprite_pretzel.png` (256×256 RGBA,
anti-aliased alpha) and `hsi import-png` traces its alpha into the scene (see the
header of `scripts/make_sprite.py`):

```sh
/usr/bin/python3 scripts/make_sprite.py
build/bin/hsi import-png assets/sprite_pretzel.png -o assets/sprite_pretzel.json \\
    --tolerance 0.5 --max-edge 6 --pixel-size 0.00390625
```
"""

KEYFRAMES_HEAD = """
## Keyframes

Every scene has handles and keyframes (t = 0, 1, …), posed by
`scripts/make_keyframes.py` and solved by `hsi keyframes` (certified locally
injective; the automatic cage is stored as the scene's user cage and each keyframe's
coefficients `phi`/`psi` are written into the scene). This script writes the scenes
without keyframes, so run it after this one (and after importing the sprite):

```sh
/usr/bin/python3 scripts/make_keyframes.py --hsi build/bin/hsi --png /tmp/keyframes
```

Keyframe 0 is the rest pose (targets = handles); the targets of the others are the
handles moved by one analytic deformation each (a conformal bend onto a curve, a
hinge about a joint, squash and stretch, the harmonic twist of a hole), drawn
to `/tmp/keyframes/NAME/keyframe_K.png`. A harmonic map cannot twist a hole far
against the rim around it without wrecking the shape: the only rotationally
symmetric harmonic twist, w ↦ w + i·k·w/|w|², turns the annulus' hole by at most
about 30° before it folds. So the holes turn 20°, and the large motions are bends,
hinges, squash and stretch.

"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hsi", default=os.path.join(ROOT, "build", "bin", "hsi"),
                    help="the hsi tool (for the glyph scenes); default: build/bin/hsi")
    ap.add_argument("--skip-glyphs", action="store_true", help="do not (re)import the glyph scenes")
    args = ap.parse_args()
    os.makedirs(ASSETS, exist_ok=True)
    os.chdir(ROOT)

    rows = []
    for name, fn in SHAPES.items():
        desc, outer, holes = fn()
        outer, holes, rect = write_scene(name, outer, holes)
        gap = check_shape(name, outer, holes)
        aspect = (rect[2] - rect[0]) / (rect[3] - rect[1])
        size = make_texture(name, aspect)
        rows.append((name, outer, holes, gap, size, desc))
        print(f"{name}: outer {len(outer)}, holes {[len(h) for h in holes]}, texture {size} bytes")

    glyph_descs = {"B": "The capital letter B of DejaVu Sans: two holes.",
                   "8": "The digit 8 of DejaVu Sans: two holes.",
                   "A": "The capital letter A of DejaVu Sans: one (triangular) hole."}
    if not args.skip_glyphs:
        hsi = os.path.relpath(args.hsi, ROOT) if os.path.isabs(args.hsi) else args.hsi
        if not os.path.exists(hsi):
            sys.exit(f"make_assets: {hsi} not found; build it (cmake --build build --target hsi) or pass --hsi")
        tmpdir = tempfile.mkdtemp(prefix="hsi_assets_")
        tmp = os.path.join(tmpdir, "glyph_probe.json")
        for ch in GLYPHS:
            name = f"glyph_{ch}"
            # First pass without a texture: the glyph's proportions set the texture's.
            subprocess.run(glyph_command(hsi, ch, with_texture=False, output=tmp), check=True,
                           stdout=subprocess.DEVNULL)
            _, outer, _ = load_loops(tmp)
            os.remove(tmp)
            lo, hi = outer.min(axis=0), outer.max(axis=0)
            rect = expanded_rect(lo, hi)
            size = make_texture(name, (rect[2] - rect[0]) / (rect[3] - rect[1]))
            cmd = glyph_command(hsi, ch)
            print("$ " + " ".join(cmd))
            subprocess.run(cmd, check=True)
        os.rmdir(tmpdir)
    for ch in GLYPHS:
        name = f"glyph_{ch}"
        path = os.path.join(ASSETS, name + ".json")
        if not os.path.exists(path):
            continue
        _, outer, holes = load_loops(path)
        # Glyph clearances are what the font gives: reported, not enforced.
        gap = check_shape(name, outer, holes, enforce_clearance=False)
        rows.append((name, outer, holes, gap, os.path.getsize(os.path.join(ASSETS, name + ".png")),
                     glyph_descs[ch]))

    cmds = "\n".join(" ".join(["build/bin/hsi"] + glyph_command("hsi", ch)[1:]) for ch in GLYPHS)
    text = (README_HEAD.replace("{glyph_commands}", cmds)
            .replace("{clearance:.0%}", f"{MIN_CLEARANCE:.0%}")
            .replace("{margin:.0%}", f"{TEX_MARGIN:.0%}")
            .replace("{tex}", str(TEX_SIZE)))
    for name, outer, holes, gap, size, desc in rows:
        lo, hi = outer.min(axis=0), outer.max(axis=0)
        hv = ", ".join(str(len(h)) for h in holes) if holes else "–"
        g = f"{gap:.3f}" if gap is not None else "–"
        text += (f"| `{name}.json` | {1 + len(holes)} (outer + {len(holes)} hole{'' if len(holes) == 1 else 's'}) "
                 f"| {len(outer)} | {hv} | {hi[0] - lo[0]:.2f} × {hi[1] - lo[1]:.2f} | {g} "
                 f"| `{name}.png` ({size // 1024} KB): {TEXTURES[name][1]} | {desc} |\n")
    sprite = os.path.join(ASSETS, "sprite_pretzel.json")
    if os.path.exists(sprite):
        # Not made here (scripts/make_sprite.py + hsi import-png): described, not written.
        _, outer, holes = load_loops(sprite)
        gap = check_shape("sprite_pretzel", outer, holes, enforce_clearance=False)
        lo, hi = outer.min(axis=0), outer.max(axis=0)
        size = os.path.getsize(os.path.join(ASSETS, "sprite_pretzel.png"))
        text += (f"| `sprite_pretzel.json` | {1 + len(holes)} (outer + {len(holes)} holes) | {len(outer)} "
                 f"| {', '.join(str(len(h)) for h in holes)} | {hi[0] - lo[0]:.2f} × {hi[1] - lo[1]:.2f} "
                 f"| {gap:.3f} | `sprite_pretzel.png` ({size // 1024} KB): 256×256 RGBA sprite, baked-crust "
                 f"gradient + bevel + diagonal stripes + salt grains | A stylised pretzel (one rope crossing "
                 f"itself, three holes), traced from the sprite's alpha by `hsi import-png`. |\n")
    text += SPRITE_NOTE
    text += KEYFRAMES_HEAD
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import make_keyframes  # the poses are defined there; this only describes them
    text += "\n".join(make_keyframes.describe()) + "\n"
    with open(os.path.join(ASSETS, "README.md"), "w") as f:
        f.write(text)
    print("wrote assets/README.md")


if __name__ == "__main__":
    main()
