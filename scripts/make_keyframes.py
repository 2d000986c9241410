#!/usr/bin/python3
"""Poses hsi's bundled assets: gives every scene in assets/ handles and keyframes.

Run from anywhere, after the assets exist (scripts/make_assets.py, and for the
sprite scripts/make_sprite.py + hsi import-png) and hsi is built:

    cmake -S . -B build -G Ninja && cmake --build build --target hsi
    /usr/bin/python3 scripts/make_keyframes.py --hsi build/bin/hsi --png /tmp/keyframes

For each asset the script reads assets/NAME.json, sets its `handles` and its
`keyframes` (time and one target per handle; any old coefficients `phi`/`psi` and
the user cage `loops`/`hole_points` are dropped, the cage options are kept), writes
the scene back and then runs

    hsi keyframes assets/NAME.json --in-place --png PNGDIR/NAME

which solves each keyframe (certified, locally injective), stores the automatic
cage as a user cage and writes the coefficients into the scene. `--only NAME`
(repeatable) restricts it to some assets; `--no-solve` only writes the targets.

The poses are made the way an animator would pose them: a few handles on the
shape's skeleton (on the medial line of limbs and rings, never in holes, at least
3% of the bounding-box diagonal from the boundary), and each keyframe's targets are
the handles moved by one analytic deformation of the plane (bending the shape onto
a curve, rotating parts about a pivot with a smooth falloff, squash and stretch),
so the targets of a keyframe are consistent with each other. Keyframe 0 is the rest
pose; the others are large deformations that a harmonic map reaches without folding.

Deterministic: the same assets and hsi give the same files. Needs only
/usr/bin/python3 with python3-numpy (Debian 12) and the standard library.
"""

import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASSETS = os.path.join(ROOT, "assets")
MARGIN = 0.03  # handles keep this fraction of the bounding-box diagonal from the boundary


# --------------------------------------------------------------------------- geometry

def load_scene(name):
    with open(os.path.join(ASSETS, name + ".json")) as f:
        scene = json.load(f)
    outer = np.array(scene["shape"]["outer"], dtype=np.float64)
    holes = [np.array(h, dtype=np.float64) for h in scene["shape"].get("holes", [])]
    return scene, outer, holes


def point_in_loop(loop, p):
    x, y = loop[:, 0], loop[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    crosses = (y > p[1]) != (yn > p[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = x + (p[1] - y) * (xn - x) / (yn - y)
    return bool(np.count_nonzero(crosses & (p[0] < xi)) % 2)


def loop_distance(loop, p):
    a = loop
    b = np.roll(loop, -1, axis=0)
    d = b - a
    t = np.clip(((p - a) * d).sum(1) / np.maximum((d * d).sum(1), 1e-300), 0.0, 1.0)
    q = a + t[:, None] * d
    return float(np.sqrt(((q - p) ** 2).sum(1)).min())


def check_handles(name, outer, holes, handles):
    """Every handle on the shape (inside the outer loop, outside the holes) and at
    least MARGIN × the bounding-box diagonal from every loop."""
    diag = float(np.linalg.norm(outer.max(0) - outer.min(0)))
    for k, h in enumerate(handles):
        p = np.array([h.real, h.imag])
        assert point_in_loop(outer, p), f"{name}: handle {k} {p} is outside the shape"
        for j, hole in enumerate(holes):
            assert not point_in_loop(hole, p), f"{name}: handle {k} {p} is in hole {j + 1}"
        gap = min(loop_distance(l, p) for l in [outer] + holes)
        assert gap >= MARGIN * diag, (f"{name}: handle {k} {p} is only {gap:.4f} from the boundary, "
                                      f"need {MARGIN} × diagonal = {MARGIN * diag:.4f}")


def ray_to_boundary(outer, c, angle):
    """Distance from c (complex, inside) along the direction `angle` to the outer loop."""
    d = np.array([math.cos(angle), math.sin(angle)])
    a = outer
    e = np.roll(outer, -1, axis=0) - a
    w = a - np.array([c.real, c.imag])
    den = d[0] * e[:, 1] - d[1] * e[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / den
        u = (w[:, 0] * d[1] - w[:, 1] * d[0]) / den
    ok = (np.abs(den) > 1e-15) & (t > 0) & (u >= 0) & (u <= 1)
    return float(t[ok].min())


def ring(c, r, degrees):
    return [c + r * complex(math.cos(math.radians(a)), math.sin(math.radians(a))) for a in degrees]


# --------------------------------------------------------------------------- deformations
# Each maps a numpy array of complex points to their images.

def smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def rotate(p, center, degrees):
    return center + (p - center) * np.exp(1j * math.radians(degrees))


def twist(p, center, degrees, r_in, r_out):
    """The harmonic twist about center: w ↦ (w + i·k·w/|w|²)/(1 + i·k/r_out²) with
    w = p − center, which keeps the circle of radius r_out in place and turns the
    circle of radius r_in by `degrees` against it (points in between turn less, as
    1/|w|²). It is the only rotationally symmetric harmonic map that twists, so a
    harmonic map cannot twist a hole much more than this: turning the circle r_in
    by θ takes k = r_in² tan θ', and the map folds where |w|² ≤ k."""
    lo, hi = 0.0, r_in * r_in
    for _ in range(100):  # bisection for k: the turn grows with k up to k = r_in²
        k = 0.5 * (lo + hi)
        turn = math.degrees(math.atan(k / r_in ** 2) - math.atan(k / r_out ** 2))
        lo, hi = (k, hi) if turn < abs(degrees) else (lo, k)
    assert abs(turn - abs(degrees)) < 1e-6, f"a harmonic twist cannot turn r = {r_in} by {degrees}°"
    k = math.copysign(k, degrees)
    w = p - center
    return center + (w + 1j * k * w / np.abs(w) ** 2) / (1 + 1j * k / r_out ** 2)


def bend(p, origin, direction, bends, blur=0.1, s_range=(-10.0, 10.0), samples=40001):
    """Bends the plane along a line, like a strip bent onto a curve. The line goes
    through origin in the direction `direction` (unit complex); s is the arc length
    along it and t the signed offset from it. The centre line is bent: its turning
    angle grows by `degrees` over each bend (s0, s1, degrees) at constant curvature,
    the curvature profile blurred by a Gaussian of width `blur` so it changes
    smoothly; s = 0 stays fixed. A point goes to c(s) + n(s)·(1 − exp(−κ(s) t))/κ(s)
    (c the bent centre line, n its normal, κ its curvature): where κ is constant
    this is the conformal bend z ↦ (exp(iκz) − 1)/(iκ), a harmonic map that never
    folds (the inner side shrinks by exp(−κt) instead of 1 − κt), so the targets of
    a keyframe agree with each other and a harmonic map can reach them."""
    s = np.linspace(s_range[0], s_range[1], samples)
    ds = s[1] - s[0]
    kappa = np.zeros_like(s)
    for s0, s1, deg in bends:
        lo, hi = min(s0, s1), max(s0, s1)
        kappa += np.where((s >= lo) & (s <= hi), math.radians(deg) / (hi - lo), 0.0)
    if blur > 0:
        x = np.arange(-int(4 * blur / ds), int(4 * blur / ds) + 1) * ds
        kernel = np.exp(-0.5 * (x / blur) ** 2)
        kappa = np.convolve(kappa, kernel / kernel.sum(), mode="same")
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * ds)])
    i0 = int(np.argmin(np.abs(s)))
    theta -= theta[i0]
    tangent = np.exp(1j * theta)
    pos = np.concatenate([[0j], np.cumsum(0.5 * (tangent[1:] + tangent[:-1]) * ds)])
    pos -= pos[i0]
    local = (p - origin) / direction
    sp, tp = local.real, local.imag
    assert sp.min() >= s_range[0] and sp.max() <= s_range[1]
    th = np.interp(sp, s, theta)
    k = np.interp(sp, s, kappa)
    c = np.interp(sp, s, pos.real) + 1j * np.interp(sp, s, pos.imag)
    small = np.abs(k) < 1e-9
    offset = np.where(small, tp, -np.expm1(-k * tp) / np.where(small, 1.0, k))
    return origin + direction * (c + 1j * offset * np.exp(1j * th))


def hinge(p, pivot, direction, s0, s1, deg0, deg1):
    """Rotates about pivot by deg0 where the coordinate s along direction (unit
    complex, measured from pivot) is below s0 and by deg1 above s1, blending
    smoothly in between: two parts turning about a joint."""
    s = ((p - pivot) / direction).real
    a = deg0 + (deg1 - deg0) * smoothstep((s - s0) / (s1 - s0))
    return pivot + (p - pivot) * np.exp(1j * np.radians(a))


def scale(p, center, sx, sy, degrees=0.0):
    """Scales by sx, sy along the axes rotated by `degrees` about center."""
    r = np.exp(1j * math.radians(degrees))
    q = (p - center) / r
    return center + (sx * q.real + 1j * sy * q.imag) * r


def compose(*fns):
    def f(p):
        for fn in fns:
            p = fn(p)
        return p
    return f


# --------------------------------------------------------------------------- poses
# Each asset: handles (complex) and a list of keyframes (description, deformation).
# Keyframe k is at time k.

REST = ("rest pose", lambda p: p)


def pose_annulus(outer, holes):
    hc = complex(0.07, 0.04)  # the hole's centre; its radius is 0.45
    handles = ring(0j, 0.86, range(0, 360, 60)) + ring(hc, 0.56, range(30, 390, 60))
    floor = complex(0.0, -0.98)
    return handles, [
        REST,
        ("squashed onto the floor (0.65 × as tall, 1.45 × as wide), the hole twisted 20° "
         "counter-clockwise against the rim",
         lambda p: scale(twist(p, hc, 20.0, 0.45, 0.92), floor, 1.45, 0.65)),
        ("stretched up (1.35 × as tall, 0.75 × as wide) and leaning 35° right in a smooth bend, "
         "the hole twisted 20° clockwise",
         lambda p: bend(scale(twist(p, hc, -20.0, 0.45, 0.92), floor, 0.75, 1.35), floor, 1j,
                        [(0.0, 2.6, -35.0)])),
    ]


def pose_bar_holes(outer, holes):
    xs = [-1.55, -0.755, 0.02, 0.72, 1.55]
    handles = [complex(x, 0) for x in xs] + [complex(-1.14, 0.47), complex(-1.14, -0.47),
                                             complex(1.14, 0.47), complex(1.14, -0.47)]
    return handles, [
        REST,
        ("bent into a U: both ends curled up, 180° in all",
         lambda p: bend(p, 0j, 1 + 0j, [(-1.6, 1.6, 180.0)])),
        ("bent into an S: left half curled down by 90°, right half up by 90°",
         lambda p: bend(p, 0j, 1 + 0j, [(-1.6, 0.0, -90.0), (0.0, 1.6, 90.0)])),
    ]


def pose_arm(outer, holes):
    axis = complex(3.75, 0.55)
    d = axis / abs(axis)  # the limb's direction from the body's centre
    hc = complex(-0.2, 0.0)
    handles = ring(hc, 0.62, [90, 180, 270]) + [complex(0.5, 0.0)] + [s * d for s in (1.5, 2.2, 2.9, 3.6)]
    shoulder = (0.9, 1.7)
    elbow = (2.1, 2.9)
    return handles, [
        REST,
        ("limb swung up by 100° about the shoulder, body still",
         lambda p: bend(p, 0j, d, [(*shoulder, 100.0)])),
        ("limb lowered to 30° with the forearm bent up by 70° (a wave)",
         lambda p: bend(p, 0j, d, [(*shoulder, 30.0), (*elbow, 70.0)])),
        ("limb swung down by 80° below the rest pose, forearm bent back by 30°",
         lambda p: bend(p, 0j, d, [(*shoulder, -80.0), (*elbow, 30.0)])),
    ]


def pose_blob(outer, holes):
    c = complex(0.0, -0.05)
    angles = range(15, 360, 60)
    handles = [c] + [c + 0.62 * ray_to_boundary(outer, c, math.radians(a)) *
                     complex(math.cos(math.radians(a)), math.sin(math.radians(a))) for a in angles]
    floor = complex(0.0, -0.95)
    return handles, [
        REST,
        ("squashed onto the floor: 0.6 × as tall, 1.5 × as wide",
         lambda p: scale(p, floor, 1.5, 0.6)),
        ("leaning right in a smooth 40° bend and stretched up (1.35 × as tall, 0.75 × as wide)",
         lambda p: scale(bend(p, floor, 1j, [(0.0, 1.9, -40.0)]), floor, 0.75, 1.35)),
        ("swinging back: leaning left in a 35° bend, 1.2 × as tall",
         lambda p: scale(bend(p, floor, 1j, [(0.0, 1.9, 35.0)]), floor, 0.85, 1.2)),
    ]


def pose_two_holes(outer, holes):
    big = complex(-0.28, 0.02)  # radius 0.42
    small = complex(0.58, 0.12)
    handles = ring(big, 0.55, [90, 180, 270]) + [complex(0.33, 0.0)] + ring(small, 0.33, [90, 0, 270])
    return handles, [
        REST,
        ("bent into a crescent: the sides curled up, 100° in all",
         lambda p: bend(p, 0j, 1 + 0j, [(-1.1, 1.1, 100.0)])),
        ("stretched 1.4 × along a diagonal and squeezed across it, the large hole twisted 20°",
         lambda p: scale(twist(p, big, 20.0, 0.42, 0.8), 0j, 1.4, 0.72, 35.0)),
    ]


def pose_links(outer, holes):
    lc, rc = complex(-0.95, 0.0), complex(0.95, 0.0)
    handles = ring(lc, 0.75, [90, 180, 270]) + [0j] + ring(rc, 0.75, [90, 0, 270])
    return handles, [
        REST,
        ("folded up at the joint by 80° (each link turned 40°)",
         lambda p: hinge(p, complex(0.0, 0.35), 1 + 0j, -0.7, 0.7, -40.0, 40.0)),
        ("folded down at the joint by 70°",
         lambda p: hinge(p, complex(0.0, -0.35), 1 + 0j, -0.7, 0.7, 35.0, -35.0)),
    ]


def stride(p):
    """Spreads the A's legs: points below the crossbar move outwards, more at the feet."""
    w = smoothstep((0.45 - p.imag) / 0.45)
    return p + 0.12 * w * np.sign(p.real - 0.458)


def pose_glyph_A(outer, holes):
    handles = [complex(0.093, 0.06), complex(0.823, 0.06), complex(0.19, 0.31), complex(0.726, 0.31),
               complex(0.30, 0.60), complex(0.616, 0.60), complex(0.458, 0.93), complex(0.458, 0.31)]
    base = complex(0.458, 0.0)
    return handles, [
        REST,
        ("leaning right: bent over by 40° above the planted feet",
         lambda p: bend(p, base, 1j, [(0.05, 1.0, -40.0)])),
        ("leaning left by 35° with the legs spread into a stride",
         lambda p: bend(stride(p), base, 1j, [(0.05, 1.0, 35.0)])),
    ]


def pose_glyph_B(outer, holes):
    handles = [complex(0.068, 0.08), complex(0.068, 0.5), complex(0.068, 0.92), complex(0.30, 0.945),
               complex(0.60, 0.74), complex(0.30, 0.532), complex(0.638, 0.29), complex(0.30, 0.055)]
    base = complex(0.35, 0.0)
    return handles, [
        REST,
        ("bowing forward: bent over to the right by 40°",
         lambda p: bend(p, base, 1j, [(0.05, 1.0, -40.0)])),
        ("waving: an S, the bottom half bent left by 35° and the top half back right by 35°",
         lambda p: bend(p, base, 1j, [(0.0, 0.5, 35.0), (0.5, 1.0, -35.0)])),
    ]


def pose_glyph_8(outer, holes):
    top, bottom = complex(0.33, 0.74), complex(0.33, 0.29)  # the loops' centres
    handles = [complex(0.33, 0.948), complex(0.098, 0.74), complex(0.573, 0.74),
               complex(0.33, 0.53),
               complex(0.066, 0.29), complex(0.596, 0.29), complex(0.33, 0.052)]

    def loops(deg, lift=0.05):
        """The top loop turns by deg about its centre, the bottom one by −deg about its
        own, the turn blending smoothly through the waist (no turn at y = 0.53); the
        loops also move apart by 2 × lift, so the notch at the waist that the twist
        closes stays open."""
        def f(p):
            w = smoothstep((p.imag - 0.25) / 0.56)
            a = np.radians(deg) * (2 * w - 1)
            c = np.where(p.imag > 0.53, top, bottom)
            return c + (p - c) * np.exp(1j * a) + 1j * lift * (2 * w - 1)
        return f

    return handles, [
        REST,
        ("loops twisted in opposite directions (top 25° counter-clockwise, bottom 25° clockwise) "
         "and pulled apart a little",
         loops(25.0)),
        ("loops twisted the other way and the whole 8 leaning 20° right",
         lambda p: rotate(loops(-25.0)(p), complex(0.33, 0.0), -20.0)),
    ]


def pose_sprite_pretzel(outer, holes):
    def px(x, y):  # make_sprite.py's pixel coordinates (256 × 256, y down)
        return complex(x / 256, 1 - y / 256)

    handles = [px(36, 90), px(220, 90), px(56, 60), px(200, 60), px(128, 212), px(128, 132),
               px(66, 176), px(190, 176)]
    mid = px(128, 132)  # where the rope crosses itself
    return handles, [
        REST,
        ("bent into an arch: the lobes drooping, 70° in all",
         lambda p: bend(p, mid, 1 + 0j, [(-0.42, 0.42, -70.0)])),
        ("bent the other way: the lobes raised like wings, 70° in all",
         lambda p: bend(p, mid, 1 + 0j, [(-0.42, 0.42, 70.0)])),
    ]


POSES = {
    "annulus": pose_annulus,
    "arm": pose_arm,
    "bar_holes": pose_bar_holes,
    "blob": pose_blob,
    "glyph_8": pose_glyph_8,
    "glyph_A": pose_glyph_A,
    "glyph_B": pose_glyph_B,
    "links": pose_links,
    "two_holes": pose_two_holes,
    "sprite_pretzel": pose_sprite_pretzel,
}


def poses(name):
    """(handles as a complex array, [(time, description, targets)]) for an asset."""
    _, outer, holes = load_scene(name)
    handles, keys = POSES[name](outer, holes)
    handles = np.array(handles, dtype=np.complex128)
    check_handles(name, outer, holes, handles)
    out = []
    for k, (desc, fn) in enumerate(keys):
        targets = np.asarray(fn(handles.copy()), dtype=np.complex128)
        assert targets.shape == handles.shape and np.all(np.isfinite(targets)), f"{name}: keyframe {k}"
        out.append((float(k), desc, targets))
    return handles, out


def describe():
    """Markdown lines for assets/README.md: each asset's handles and poses."""
    lines = []
    for name in POSES:
        if not os.path.exists(os.path.join(ASSETS, name + ".json")):
            continue
        handles, keys = poses(name)
        lines.append(f"* `{name}`, {len(handles)} handles:")
        lines += [f"  * t = {t:g}: {d}" for t, d, _ in keys]
    return lines


def pt(z):
    return [round(float(z.real), 6) + 0.0, round(float(z.imag), 6) + 0.0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hsi", default=os.path.join("build", "bin", "hsi"), help="the hsi tool; default: build/bin/hsi")
    ap.add_argument("--png", default=os.path.join("/tmp", "hsi_keyframes"),
                    help="draw each keyframe to PNG/NAME/keyframe_K.png (default: /tmp/hsi_keyframes)")
    ap.add_argument("--only", action="append", choices=sorted(POSES), help="pose only this asset (repeatable)")
    ap.add_argument("--no-solve", action="store_true", help="write the handles and targets, do not run hsi")
    args = ap.parse_args()
    hsi = os.path.abspath(args.hsi)
    png = os.path.abspath(args.png)
    os.chdir(ROOT)
    if not args.no_solve and not os.path.exists(hsi):
        sys.exit(f"make_keyframes: {args.hsi} not found; build it (cmake --build build --target hsi) or pass --hsi")
    failed = []
    for name in args.only or POSES:
        path = os.path.join("assets", name + ".json")
        scene, _, _ = load_scene(name)
        handles, keys = poses(name)
        scene["handles"] = [pt(h) for h in handles]
        scene["keyframes"] = [{"time": t, "targets": [pt(q) for q in targets]} for t, _, targets in keys]
        cage = scene.get("cage")
        if isinstance(cage, dict):
            cage.pop("loops", None)
            cage.pop("hole_points", None)
        with open(path, "w") as f:
            f.write(json.dumps(scene, indent=1) + "\n")
        print(f"== {name}: {len(handles)} handles, {len(keys)} keyframes", flush=True)
        for t, d, _ in keys:
            print(f"   t = {t:g}: {d}", flush=True)
        if args.no_solve:
            continue
        cmd = [hsi, "keyframes", path, "--in-place", "--png", os.path.join(png, name)]
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        sys.stdout.write(r.stdout)
        sys.stdout.flush()
        solved = [l for l in r.stdout.splitlines() if l.startswith("keyframe ")]
        if r.returncode != 0 or len(solved) != len(keys) or not all(
                "reached all targets" in l and "certified" in l for l in solved):
            failed.append(name)
    if failed:
        sys.exit("make_keyframes: not every keyframe reached its targets certified: " + ", ".join(failed))


if __name__ == "__main__":
    main()
