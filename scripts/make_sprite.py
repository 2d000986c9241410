#!/usr/bin/python3
"""Draws assets/sprite_pretzel.png: an original, procedurally generated 256x256 RGBA
sprite of a stylised pretzel (one rope, three holes) with an anti-aliased alpha mask,
coloured with a baked-crust gradient, a bevel, diagonal stripes and salt grains, so
that a deformation of the texture is easy to see.

Needs only /usr/bin/python3 with python3-numpy; the PNG is written with zlib+struct.
Deterministic: the same file comes out every time.

Regenerate the sprite and its scene from the repository root:

    /usr/bin/python3 scripts/make_sprite.py
    build/bin/hsi import-png assets/sprite_pretzel.png -o assets/sprite_pretzel.json \
        --tolerance 0.5 --max-edge 6 --pixel-size 0.00390625

(--pixel-size 1/256 makes the image one unit square, like the other assets' order-1
coordinates; --max-edge 6 splits long simplified edges so the outline bends smoothly
when deformed. The scene is named after the file: sprite_pretzel.)
"""
import os
import struct
import sys
import zlib

import numpy as np

SIZE = 256
SUPERSAMPLE = 4  # alpha is the rope's coverage, from 4x4 samples per pixel
ROPE = 13.5      # rope radius in pixels


def catmull_rom(points, samples=24):
    """Open Catmull-Rom spline through the points (ends repeated)."""
    p = np.asarray(points, dtype=float)
    p = np.vstack([p[0], p, p[-1]])
    out = []
    for i in range(1, len(p) - 2):
        p0, p1, p2, p3 = p[i - 1], p[i], p[i + 1], p[i + 2]
        for t in np.linspace(0, 1, samples, endpoint=False):
            t2, t3 = t * t, t * t * t
            out.append(0.5 * ((2 * p1) + (-p0 + p2) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t2
                              + (-p0 + 3 * p1 - 3 * p2 + p3) * t3))
    out.append(p[-2])
    return np.array(out)


def pretzel_path():
    """The rope's centre line (pixel coordinates, y down): from the left end on the
    bottom arc, up through the twist, round the right lobe, along the bottom, round
    the left lobe, back through the twist and down to the right end."""
    pts = [(92, 190), (110, 160), (128, 132), (148, 104), (168, 70), (200, 60),
           (220, 90), (214, 136), (190, 176), (158, 204), (128, 212), (98, 204),
           (66, 176), (42, 136), (36, 90), (56, 60), (88, 70), (108, 104),
           (128, 132), (146, 160), (164, 190)]
    return catmull_rom(pts)


def distance_to_polyline(px, py, path):
    """Distance from every point (px, py) to the polyline, and the arc length
    parameter of the nearest point (for the stripes along the rope)."""
    best = np.full(px.shape, np.inf)
    arc = np.zeros(px.shape)
    s0 = 0.0
    for a, b in zip(path[:-1], path[1:]):
        d = b - a
        length2 = float(d @ d)
        t = np.clip(((px - a[0]) * d[0] + (py - a[1]) * d[1]) / length2, 0.0, 1.0)
        dist = np.hypot(px - (a[0] + t * d[0]), py - (a[1] + t * d[1]))
        closer = dist < best
        best = np.where(closer, dist, best)
        arc = np.where(closer, s0 + t * np.sqrt(length2), arc)
        s0 += np.sqrt(length2)
    return best, arc


def render():
    path = pretzel_path()
    # Alpha: coverage of the rope, supersampled.
    n = SIZE * SUPERSAMPLE
    sub = (np.arange(n) + 0.5) / SUPERSAMPLE
    sx, sy = np.meshgrid(sub, sub)
    dist_sub, _ = distance_to_polyline(sx, sy, path)
    alpha = (dist_sub < ROPE).reshape(SIZE, SUPERSAMPLE, SIZE, SUPERSAMPLE).mean(axis=(1, 3))

    # Colour at pixel centres.
    c = np.arange(SIZE) + 0.5
    x, y = np.meshgrid(c, c)
    dist, arc = distance_to_polyline(x, y, path)
    h = np.clip(dist / ROPE, 0.0, 1.0)
    bevel = np.sqrt(1.0 - 0.92 * h * h)                      # round rope, lit from the front
    light = np.clip(0.55 + 0.45 * bevel - 0.12 * (x - y) / SIZE, 0.0, 1.0)
    # Baked crust: a diagonal gradient from golden to dark brown.
    g = np.clip((x + 1.3 * y) / (2.3 * SIZE), 0.0, 1.0)[..., None]
    golden = np.array([0.93, 0.66, 0.30])
    brown = np.array([0.55, 0.27, 0.10])
    rgb = golden * (1 - g) + brown * g
    # Twisted-rope stripes: bands across the rope, slanting with the distance.
    stripes = 0.5 + 0.5 * np.sin(arc / 5.0 + 2.2 * dist / ROPE)
    rgb = rgb * (0.66 + 0.34 * stripes)[..., None]
    # A faint checker in screen space, so that any deformation shows.
    checker = ((np.floor(x / 16) + np.floor(y / 16)) % 2)[..., None]
    rgb = rgb * (0.9 + 0.1 * checker)
    rgb = rgb * light[..., None]
    # Salt grains: small bright ellipses at fixed pseudo-random places on the rope.
    rng = np.random.default_rng(20221003)
    for _ in range(45):
        k = rng.integers(0, len(path))
        ox, oy = rng.normal(0, ROPE * 0.4, 2)
        gx, gy = path[k][0] + ox, path[k][1] + oy
        r = rng.uniform(1.0, 1.9)
        grain = np.clip(1.5 - np.hypot((x - gx) / 1.4, y - gy) / r, 0.0, 1.0)[..., None]
        rgb = rgb * (1 - grain) + np.array([0.98, 0.97, 0.93]) * grain

    rgba = np.dstack([np.clip(rgb, 0, 1), alpha])
    # Transparent pixels get the colour of the rope nearby (no dark fringes when the
    # texture is filtered): simply keep the computed colour, which is defined everywhere.
    return np.round(rgba * 255).astype(np.uint8)


def write_png(path, rgba):
    """8-bit RGBA PNG, each row filtered with Paeth/Sub/Up/None, whichever is smallest."""
    h, w, _ = rgba.shape
    data = rgba.astype(np.int16)
    rows = []
    prev = np.zeros((w * 4,), dtype=np.int16)
    for j in range(h):
        cur = data[j].reshape(-1)
        left = np.concatenate([np.zeros(4, dtype=np.int16), cur[:-4]])
        upleft = np.concatenate([np.zeros(4, dtype=np.int16), prev[:-4]])
        p = left + prev - upleft
        pa, pb, pc = np.abs(p - left), np.abs(p - prev), np.abs(p - upleft)
        paeth = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, prev, upleft))
        candidates = {0: cur, 1: cur - left, 2: cur - prev, 4: cur - paeth}
        ftype, filtered = min(candidates.items(),
                              key=lambda kv: int(np.abs(((kv[1] + 128) % 256) - 128).sum()))
        rows.append(bytes([ftype]) + (filtered % 256).astype(np.uint8).tobytes())
        prev = cur
    raw = b"".join(rows)

    def chunk(tag, body):
        return (struct.pack(">I", len(body)) + tag + body
                + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF))

    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9))
           + chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(png)
    return len(png)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "assets", "sprite_pretzel.png")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    size = write_png(out, render())
    print(f"wrote {out}: {SIZE}x{SIZE} RGBA, {size} bytes")


if __name__ == "__main__":
    main()
