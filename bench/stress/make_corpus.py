#!/usr/bin/python3
"""Writes hsi's Newton stress corpus (issue #20): bench/stress/corpus.json and the
shapes it poses.

    cmake -S . -B build -G Ninja && cmake --build build --target hsi
    /usr/bin/python3 bench/stress/make_corpus.py --hsi build/bin/hsi

Deterministic: a fixed seed (--seed, default 20) and the same hsi give byte-identical
files. Needs only /usr/bin/python3 with python3-numpy (Debian 12). What it writes:

* shapes/: new shapes with long thin parts and holes. comb, fork, chain (thin rings
  joined by thin bridges) and letter_b (a thin-stroked B) are drawn here as
  anti-aliased RGBA masks (signed distance fields of strokes and rings) and traced by
  `hsi import-png`, like a sprite; grid_K (K = 2, 3, 6) is the issue's grid, written
  as polygons: a square of side 2K with a K x K grid of round holes (radius 0.45,
  centres 2 apart, 24-gons).
* sprites/*.json: scenes traced by `hsi import-png` from the real sprites in
  sprites/ (copied from Debian game-data packages; see README.md there), scaled to a
  size of about 2.
* corpus.json: the sequences. Each names a shape (a scene file relative to this
  folder; the bundled assets/*.json included, their keyframes ignored), |G|, the
  handles and 2 or 3 keyframes as targets, i.e. exactly what an animator gives:
  `solve_scene_keyframes` makes the keyframes (the authoring path) and the
  interpolator the frames between. bench_stress and the test slice read it.

Handles are points inside the shape (at least 1% of the bounding-box diagonal from
the boundary, spread by farthest-point sampling over a fine grid of the shape).
Targets are the handles moved by analytic deformations of the plane (the bend,
hinge and scale of scripts/make_keyframes.py, rigid turns, smooth random drags,
turns about a hole), composed, with parameters drawn from a seeded generator:
keyframe 0 is mostly NOT the rest pose, parts turn up to 180° and beyond (several
keyframes stepping there), scales change, |G| runs from 2,000 to 40,000. Some drags
cannot be reached without folding; the authoring solver then returns the closest
certified map, and bench_stress counts those keyframes.
"""

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import zlib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from make_keyframes import bend, hinge, scale, point_in_loop, loop_distance  # noqa: E402

BUNDLED = ["annulus", "arm", "bar_holes", "blob", "glyph_8", "glyph_A", "glyph_B", "links", "sprite_pretzel",
           "two_holes"]

# Sprites copied from Debian game-data packages (sprites/README.md): file, name.
SPRITES = [
    ("ceferino_title.png", "ceferino_title"),     # ceferino-data ima/tit_2.png: "Ceferino", script letters
    ("ceferino_title3.png", "ceferino_title3"),   # ceferino-data ima/tit_3.png
    ("ceferino_title1.png", "ceferino_title1"),   # ceferino-data ima/tit_1.png
    ("ceferino_gaucho.png", "ceferino_gaucho"),   # ceferino-data ima/gaucho.png (sheet: the largest figure)
    ("ceferino_levels.png", "ceferino_levels"),   # ceferino-data ima/niveles.png (tiles: ladder, branches)
    ("gnujump_run.png", "gnujump_run"),           # gnujump-data skins/auri/heroanim1/run.2.png
    ("gnujump_stand.png", "gnujump_stand"),       # gnujump-data skins/auri/heroanim1/stand.0.png
    ("chromium_enemy01.png", "chromium_enemy01"), # chromium-bsu-data png/enemy01.png (a ring)
    ("chromium_superbomb.png", "chromium_superbomb"),  # chromium-bsu-data png/superBomb.png
]

SAMPLES = [2000, 5000, 10000, 20000, 40000]


# --------------------------------------------------------------------------- PNG masks

def write_png(path, rgba):
    h, w, _ = rgba.shape
    raw = b"".join(b"\x00" + rgba[y].tobytes() for y in range(h))

    def chunk(tag, data):
        c = tag + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def seg_dist(px, py, a, b):
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    t = np.clip(((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy), 0, 1)
    return np.hypot(px - ax - t * dx, py - ay - t * dy)


def ring_dist(px, py, c, r):
    return np.abs(np.hypot(px - c[0], py - c[1]) - r)


def arc_dist(px, py, c, r, a0, a1):
    """Distance to the arc of circle (c, r) from angle a0 to a1 (radians, a0 < a1)."""
    ang = np.arctan2(py - c[1], px - c[0])
    mid = 0.5 * (a0 + a1)
    rel = (ang - mid + np.pi) % (2 * np.pi) - np.pi
    on = np.abs(rel) <= 0.5 * (a1 - a0)
    d_on = np.abs(np.hypot(px - c[0], py - c[1]) - r)
    e0 = (c[0] + r * math.cos(a0), c[1] + r * math.sin(a0))
    e1 = (c[0] + r * math.cos(a1), c[1] + r * math.sin(a1))
    d_end = np.minimum(np.hypot(px - e0[0], py - e0[1]), np.hypot(px - e1[0], py - e1[1]))
    return np.where(on, d_on, d_end)


def mask_png(path, sdf_fn, box, ppu):
    """Draws {sdf < 0} over box = (x0, y0, x1, y1) at ppu pixels per unit, anti-aliased,
    with a two-colour gradient as texture. Pixel (0, 0) is the top-left corner."""
    x0, y0, x1, y1 = box
    w, h = int(round((x1 - x0) * ppu)), int(round((y1 - y0) * ppu))
    xs = x0 + (np.arange(w) + 0.5) / ppu
    ys = y1 - (np.arange(h) + 0.5) / ppu
    px, py = np.meshgrid(xs, ys)
    d = sdf_fn(px, py)
    alpha = np.clip(0.5 - d * ppu, 0, 1)
    g = (px - x0) / (x1 - x0)
    stripes = 0.85 + 0.15 * (np.floor((px + py) * 4) % 2)
    rgba = np.zeros((h, w, 4), np.uint8)
    rgba[..., 0] = np.clip((60 + 170 * g) * stripes, 0, 255)
    rgba[..., 1] = np.clip((120 + 60 * (1 - g)) * stripes, 0, 255)
    rgba[..., 2] = np.clip((200 - 140 * g) * stripes, 0, 255)
    rgba[..., 3] = np.round(alpha * 255)
    write_png(path, rgba)


def comb_sdf(px, py):
    # A bar 4.4 x 0.5 with three round holes, nine teeth 1.6 long and 0.13 wide below it.
    d = np.maximum(np.abs(px) - 2.2, np.abs(py - 0.25) - 0.25) - 0.0
    d = np.maximum(d, -np.minimum.reduce([np.hypot(px - x, py - 0.25) - 0.12 for x in (-1.5, 0.0, 1.5)]))
    for k in range(9):
        x = -2.0 + 0.5 * k
        d = np.minimum(d, seg_dist(px, py, (x, 0.1), (x, -1.5)) - 0.065)
    return d


def fork_sdf(px, py):
    # A long handle (2.6 x 0.22) ending in a ring (a hanging loop), a head and four tines.
    d = seg_dist(px, py, (-2.4, 0), (0.3, 0)) - 0.11
    d = np.minimum(d, ring_dist(px, py, (-2.55, 0), 0.22) - 0.07)
    d = np.minimum(d, np.maximum(np.abs(px - 0.45) - 0.25, np.abs(py) - 0.42))
    d = np.maximum(d, -(np.hypot(px - 0.45, py) - 0.1))
    for y in (-0.33, -0.11, 0.11, 0.33):
        d = np.minimum(d, seg_dist(px, py, (0.6, y), (1.9, y)) - 0.05)
    return d


def chain_sdf(px, py):
    # Four thin rings (radius 0.6, 0.12 wide) joined by thin bridges.
    cs = [(-2.1 + 1.4 * k, 0.0) for k in range(4)]
    d = np.minimum.reduce([ring_dist(px, py, c, 0.6) - 0.06 for c in cs])
    for a, b in zip(cs, cs[1:]):
        d = np.minimum(d, seg_dist(px, py, (a[0] + 0.6, 0), (b[0] - 0.6, 0)) - 0.05)
    return d


def letter_b_sdf(px, py):
    # A thin-stroked B (height 2, stroke 0.12): a stem and two bowls, two holes.
    w = 0.06
    d = seg_dist(px, py, (0, -1), (0, 1)) - w
    for (yc, r) in ((0.5, 0.5), (-0.45, 0.55)):
        d = np.minimum(d, seg_dist(px, py, (0, yc + r), (0.3, yc + r)) - w)
        d = np.minimum(d, seg_dist(px, py, (0, yc - r), (0.3, yc - r)) - w)
        d = np.minimum(d, arc_dist(px, py, (0.3, yc), r, -math.pi / 2, math.pi / 2) - w)
    return d


GENERATED = [
    ("comb", comb_sdf, (-2.4, -1.7, 2.4, 0.7)),
    ("fork", fork_sdf, (-2.95, -0.6, 2.1, 0.6)),
    ("chain", chain_sdf, (-2.9, -0.8, 2.9, 0.8)),
    ("letter_b", letter_b_sdf, (-0.2, -1.2, 1.05, 1.2)),
]
PPU = 80


def import_png(hsi, png, out, name, pixel_size, tolerance=0.5, max_edge=6):
    # --filter linear: the scenes were first written before import-png chose nearest
    # filtering for small sprites; the filter does not change a solve, and keeping the
    # files' bytes keeps bench_stress's keyframe cache (keyed by them) valid.
    subprocess.run([hsi, "import-png", png, "-o", out, "--name", name, "--pixel-size", repr(pixel_size),
                    "--tolerance", repr(tolerance), "--max-edge", repr(max_edge), "--filter", "linear"], check=True,
                   stdout=subprocess.DEVNULL)


def extent(scene_path):
    with open(scene_path) as f:
        o = np.array(json.load(f)["shape"]["outer"])
    return float(max(np.ptp(o[:, 0]), np.ptp(o[:, 1])))


def circle(c, r, n, clockwise=False):
    a = 2 * np.pi * np.arange(n) / n
    if clockwise:
        a = -a
    return [[round(c[0] + r * math.cos(t), 9), round(c[1] + r * math.sin(t), 9)] for t in a]


def grid_scene(k):
    side = 2.0 * k
    per = 4 * k  # outer vertices per side: 0.5 apart
    outer = []
    for (x0, y0, dx, dy) in ((0, 0, 1, 0), (side, 0, 0, 1), (side, side, -1, 0), (0, side, 0, -1)):
        for i in range(per):
            t = side * i / per
            outer.append([x0 + dx * t, y0 + dy * t])
    holes = [circle((1 + 2 * i, 1 + 2 * j), 0.45, 24, clockwise=True) for j in range(k) for i in range(k)]
    return {"hsi_scene": 1, "name": f"grid_{k}", "shape": {"outer": outer, "holes": holes}}


# --------------------------------------------------------------------------- handles

def load_shape(path):
    with open(path) as f:
        s = json.load(f)
    outer = np.array(s["shape"]["outer"], dtype=np.float64)
    holes = [np.array(h, dtype=np.float64) for h in s["shape"].get("holes", [])]
    return outer, holes


def interior_points(outer, holes, margin_frac=0.01, n=140):
    lo, hi = outer.min(0), outer.max(0)
    diag = float(np.linalg.norm(hi - lo))
    step = diag / n
    margin = margin_frac * diag
    xs = np.arange(lo[0] + step / 2, hi[0], step)
    ys = np.arange(lo[1] + step / 2, hi[1], step)
    pts = []
    for y in ys:
        for x in xs:
            p = np.array([x, y])
            if not point_in_loop(outer, p) or any(point_in_loop(h, p) for h in holes):
                continue
            if min(loop_distance(l, p) for l in [outer] + holes) < margin:
                continue
            pts.append(complex(x, y))
    return np.array(pts), diag


def farthest(points, k, first):
    chosen = [first]
    d = np.abs(points - points[first])
    for _ in range(k - 1):
        i = int(np.argmax(d))
        chosen.append(i)
        d = np.minimum(d, np.abs(points - points[i]))
    return points[chosen]


class Frame:
    """The shape's centre (of its interior points), long axis e and extent along it."""

    def __init__(self, pts, diag):
        self.c = complex(pts.mean())
        q = np.stack([(pts - self.c).real, (pts - self.c).imag])
        w, v = np.linalg.eigh(q @ q.T)
        self.e = complex(v[0, 1], v[1, 1])
        if self.e.real < 0:
            self.e = -self.e
        u = ((pts - self.c) / self.e).real
        self.umin, self.umax = float(u.min()), float(u.max())
        self.diag = diag
        self.pts = pts

    def at(self, u):
        return self.c + self.e * u

    def u(self, frac):
        return self.umin + frac * (self.umax - self.umin)


# --------------------------------------------------------------------------- deformations

def rigid(c, degrees, s=1.0, t=0j):
    return lambda p: c + t + s * np.exp(1j * math.radians(degrees)) * (p - c)


def compose(*fns):
    def f(p):
        for fn in fns:
            p = fn(p)
        return p
    return f


def part_turn(F, frac, degrees):
    """Turns the part beyond frac of the long axis by `degrees` about the axis there,
    the rest still, blending over 10% of the length (a hinge)."""
    w = 0.05 * (F.umax - F.umin)
    return lambda p: hinge(p, F.at(F.u(frac)), F.e, -w, w, 0.0, degrees)


def bend_part(F, frac0, frac1, degrees):
    # bend() measures s from its origin; the centre of the frame is s = 0.
    return lambda p: bend(p, F.c, F.e, [(F.u(frac0), F.u(frac1), degrees)], blur=0.02 * (F.umax - F.umin),
                          s_range=(F.umin - F.diag, F.umax + F.diag))


def u_or_s(F, degrees, s_shape):
    half = degrees / 2
    return lambda p: bend(p, F.c, F.e, [(F.u(0.0), F.u(0.5), -half if s_shape else half), (F.u(0.5), F.u(1.0), half)],
                          blur=0.02 * (F.umax - F.umin), s_range=(F.umin - F.diag, F.umax + F.diag))


def stretch(F, sx, sy):
    return lambda p: scale(p, F.c, sx, sy, math.degrees(math.atan2(F.e.imag, F.e.real)))


def random_drag(F, rng, amplitude):
    """A smooth drag: three Gaussian bumps of displacement, each |d| = amplitude × diagonal."""
    bumps = []
    for _ in range(3):
        centre = F.pts[rng.integers(len(F.pts))]
        d = amplitude * F.diag * np.exp(2j * np.pi * rng.random())
        bumps.append((centre, d, 0.35 * F.diag))
    return lambda p: p + sum(d * np.exp(-np.abs(p - c) ** 2 / (2 * w * w)) for c, d, w in bumps)


def hole_turn(hole, degrees, reach):
    """Turns the points within `reach` of the hole's centroid by `degrees` about it,
    fading to nothing at 2 × reach."""
    c = complex(*hole.mean(0))

    def f(p):
        r = np.abs(p - c)
        a = degrees * (1 - np.clip((r - reach) / reach, 0, 1))
        return c + (p - c) * np.exp(1j * np.radians(a))
    return f


def U(rng, a, b):
    return float(a + (b - a) * rng.random())


def sign(rng):
    return 1.0 if rng.random() < 0.5 else -1.0


def sequences_for(name, F, holes, rng):
    """[(kind, description, [deformation per keyframe], extra handle fn)] for one shape."""
    out = []
    c = F.c
    th = U(rng, 60, 150) * sign(rng)
    a = U(rng, 0.3, 0.7)
    out.append(("hinge", f"rest, then the part beyond {a:.2f} of the long axis turned {th:.0f} deg",
                [lambda p: p, part_turn(F, a, th)]))
    rot, s = U(rng, -180, 180), U(rng, 0.7, 1.4)
    t0 = U(rng, -40, 40)
    t1 = t0 + U(rng, 90, 150) * sign(rng)
    a = U(rng, 0.3, 0.7)
    out.append(("hinge_posed", f"turned {rot:.0f} deg, scaled {s:.2f}, part beyond {a:.2f} turned {t0:.0f} then {t1:.0f} deg",
                [compose(part_turn(F, a, t0), rigid(c, rot, s)), compose(part_turn(F, a, t1), rigid(c, rot, s))]))
    rot = U(rng, -90, 90)
    a = U(rng, 0.35, 0.65)
    sg = sign(rng)
    out.append(("hinge_steps", f"turned {rot:.0f} deg; part beyond {a:.2f} turned 0, {sg * 100:.0f}, {sg * 200:.0f} deg",
                [rigid(c, rot), compose(part_turn(F, a, sg * 100), rigid(c, rot)),
                 compose(part_turn(F, a, sg * 200), rigid(c, rot))]))
    th = U(rng, 120, 200) * sign(rng)
    a = U(rng, 0.2, 0.5)
    out.append(("bend", f"rest, then bent by {th:.0f} deg from {a:.2f} of the long axis on",
                [lambda p: p, bend_part(F, a, 1.0, th)]))
    th = U(rng, 240, 300) * sign(rng)
    out.append(("bend_steps", f"bent along the whole axis by {th / 3:.0f}, {2 * th / 3:.0f}, {th:.0f} deg",
                [bend_part(F, 0.0, 1.0, th / 3), bend_part(F, 0.0, 1.0, 2 * th / 3), bend_part(F, 0.0, 1.0, th)]))
    th = U(rng, 90, 180)
    out.append(("u_to_s", f"a U of {th:.0f} deg, then an S", [u_or_s(F, th, False), u_or_s(F, th, True)]))
    rot0, rot1 = U(rng, -180, 180), 0.0
    rot1 = rot0 + U(rng, 90, 270) * sign(rng)
    s0, s1 = U(rng, 0.5, 0.8), U(rng, 1.3, 1.8)
    out.append(("scale", f"scaled {s0:.2f} and turned {rot0:.0f} deg, then scaled {s1:.2f} and turned {rot1:.0f} deg",
                [rigid(c, rot0, s0), rigid(c, rot1, s1)]))
    k1, k2 = U(rng, 1.3, 1.7), U(rng, 1.2, 1.5)
    out.append(("squash_stretch", f"stretched {k1:.2f} along the axis, then {k2:.2f} across it, then back to 1.3 x 1",
                [stretch(F, k1, 1 / math.sqrt(k1)), stretch(F, 1 / math.sqrt(k2), k2), stretch(F, 1.3, 1.0)]))
    rot0 = U(rng, -180, 180)
    spin = U(rng, 180, 360) * sign(rng)
    th = U(rng, 30, 70) * sign(rng)
    out.append(("spin", f"turned {rot0:.0f} deg, then {spin:.0f} deg further and bent {th:.0f} deg",
                [rigid(c, rot0), compose(bend_part(F, 0.0, 1.0, th), rigid(c, rot0 + spin))]))
    amps = [U(rng, 0.05, 0.15) for _ in range(3)]
    drags = [random_drag(F, rng, A) for A in amps]
    out.append(("drag", "three smooth random drags ({})".format(", ".join(f"{A:.2f}" for A in amps)), drags))
    if holes:
        big = sorted(range(len(holes)), key=lambda i: -np.ptp(holes[i][:, 0]) * np.ptp(holes[i][:, 1]))[:2]
        fns = []
        for sgn in (1, -1):
            def f(p, sgn=sgn):
                for j, i in enumerate(big):
                    r = 0.5 * max(np.ptp(holes[i][:, 0]), np.ptp(holes[i][:, 1]))
                    p = hole_turn(holes[i], sgn * (20 if j == 0 else -15), 1.3 * r)(p)
                return p
            fns.append(f)
        rot = U(rng, -60, 60)
        out.append(("hole_turn", f"turned {rot:.0f} deg; around the largest holes the shape turned +20/-15 deg, then the other way",
                    [compose(fns[0], rigid(c, rot)), compose(fns[1], rigid(c, rot))]))
    else:
        th = U(rng, 60, 120) * sign(rng)
        out.append(("ends_turn", f"both ends turned {th:.0f} deg the same way about their thirds",
                    [lambda p: p, compose(part_turn(F, 0.67, th), lambda p: hinge(p, F.at(F.u(0.33)), F.e, -0.05 * (F.umax - F.umin),
                                                                                     0.05 * (F.umax - F.umin), th, 0.0))]))
    A = U(rng, 0.05, 0.12)
    a = U(rng, 0.35, 0.65)
    th1, th2 = U(rng, 90, 150) * sign(rng), U(rng, 100, 180) * sign(rng)
    out.append(("mixed", f"a random drag ({A:.2f}) scaled 0.8, then part beyond {a:.2f} turned {th1:.0f} deg, then bent {th2:.0f} deg",
                [compose(random_drag(F, rng, A), rigid(c, 0, 0.8)), part_turn(F, a, th1), bend_part(F, 0.0, 1.0, th2)]))
    out.append(("halves_180", "the two halves turned -90 and +90 deg about the middle (180 deg between them)",
                [lambda p: p, lambda p: hinge(p, c, F.e, -0.05 * (F.umax - F.umin), 0.05 * (F.umax - F.umin), -90, 90)]))
    return out


def pt(z):
    return [round(float(z.real), 6), round(float(z.imag), 6)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hsi", required=True, help="the hsi command-line tool (for import-png)")
    ap.add_argument("--seed", type=int, default=20)
    args = ap.parse_args()
    hsi = os.path.abspath(args.hsi)
    os.makedirs(os.path.join(HERE, "shapes"), exist_ok=True)

    shapes = []  # (name, scene path relative to HERE, family)
    for b in BUNDLED:
        shapes.append((b, f"../../assets/{b}.json", "bundled"))
    for name, sdf, box in GENERATED:
        png = os.path.join(HERE, "shapes", name + ".png")
        js = os.path.join(HERE, "shapes", name + ".json")
        mask_png(png, sdf, box, PPU)
        import_png(hsi, png, js, name, 1.0 / PPU, tolerance=0.5, max_edge=8)
        shapes.append((name, f"shapes/{name}.json", "thin"))
    for k in (2, 3, 6):
        with open(os.path.join(HERE, "shapes", f"grid_{k}.json"), "w") as f:
            json.dump(grid_scene(k), f, separators=(",", ":"))
            f.write("\n")
        shapes.append((f"grid_{k}", f"shapes/grid_{k}.json", "grid"))
    for png, name in SPRITES:
        src = os.path.join(HERE, "sprites", png)
        js = os.path.join(HERE, "sprites", name + ".json")
        import_png(hsi, src, js, name, 1.0)
        px = 2.0 / extent(js)
        import_png(hsi, src, js, name, px, tolerance=0.5, max_edge=4)
        shapes.append((name, f"sprites/{name}.json", "sprite"))

    seqs = []
    for si, (name, rel, family) in enumerate(shapes):
        outer, holes = load_shape(os.path.join(HERE, rel))
        pts, diag = interior_points(outer, holes)
        F = Frame(pts, diag)
        rng = np.random.default_rng([args.seed, zlib.crc32(name.encode())])
        first = int(np.argmin(((pts - F.c) / F.e).real))
        cands = sequences_for(name, F, holes, rng)
        if family == "grid":
            k = int(name.split("_")[1])
            side = 2.0 * k
            hs = np.array([0.25 + 0.25j, side - 0.25 + 0.25j, side - 0.25 + (side - 0.25) * 1j,
                           0.25 + (side - 0.25) * 1j, k + 0.25j])
            piv = complex(0, k)
            right = np.array([False, True, True, False, False])
            kf1 = np.where(right, piv + (hs - piv) * np.exp(0.6j), hs)
            seqs.append({"id": f"{name}/issue", "shape": name, "kind": "issue",
                         "description": "the issue's grid: rest, then the right-hand handles turned 0.6 rad about the middle of the left side",
                         "samples": 10000, "handles": [pt(z) for z in hs],
                         "keyframes": [{"time": 0, "targets": [pt(z) for z in hs]},
                                       {"time": 1, "targets": [pt(z) for z in kf1]}]})
        for qi, (kind, desc, fns) in enumerate(cands):
            K = (6, 8, 10)[(si + qi) % 3]
            hs = farthest(pts, K, first)
            samples = SAMPLES[(si + qi) % len(SAMPLES)]
            kfs = [{"time": t, "targets": [pt(z) for z in fn(hs.copy())]} for t, fn in enumerate(fns)]
            seqs.append({"id": f"{name}/{kind}", "shape": name, "kind": kind, "description": desc, "samples": samples,
                         "handles": [pt(z) for z in hs], "keyframes": kfs})

    corpus = {
        "hsi_stress_corpus": 1,
        "generator": "bench/stress/make_corpus.py",
        "seed": args.seed,
        "shapes": [{"name": n, "scene": r, "family": f} for n, r, f in shapes],
        "sequences": seqs,
    }
    # One shape and one sequence per line: readable diffs when the generator changes.
    with open(os.path.join(HERE, "corpus.json"), "w") as f:
        head = {k: v for k, v in corpus.items() if k not in ("shapes", "sequences")}
        f.write(json.dumps(head, separators=(",", ":"))[:-1] + ',\n"shapes":[\n')
        f.write(",\n".join(json.dumps(s, separators=(",", ":")) for s in corpus["shapes"]) + '\n],\n"sequences":[\n')
        f.write(",\n".join(json.dumps(s, separators=(",", ":")) for s in corpus["sequences"]) + "\n]}\n")
    pairs = sum(len(s["keyframes"]) == 2 for s in seqs)
    print(f"{len(shapes)} shapes, {len(seqs)} sequences ({pairs} pairs, {len(seqs) - pairs} triples)")


if __name__ == "__main__":
    main()
