#!/usr/bin/env python3
"""The web player in a real browser (ctest web_player, web/test_web_player.cmake).

Serves SITE over HTTP on 127.0.0.1 (python's http.server, an ephemeral port), loads
player.html in headless Chromium (WebGL2 on SwiftShader, no GPU needed) at the times
of the given frames of SITE/seq.hsib, takes a screenshot each, and compares it with
`hsi render`'s PNG of the same frame (RENDER/frame_NNNN.png, same size and view).

Tolerance (stated in the README): the shape's coverage (pixels that differ from the
white background by more than 24/255 in some channel) agrees with IoU >= 0.98, and
over the pixels both cover, the mean absolute difference per channel is <= 4/255
(measured: IoU 0.998, 0.7/255; a neighbouring frame instead gives IoU 0.57, 52/255).
Both draw the same triangulation with the same texture; they differ in antialiasing
and texture filtering only.

With --distortion LO,HI the player colours the shape by sigma1/sigma2 at the vertices
(&distortion=LO,HI): the coverage must still match hsi render's plain picture (IoU >=
0.98), and every pixel both cover must be that picture's colour under the colour map
at the player's opacity, 0.15 * render + 0.85 * viridis(t) for some t (the map's
coefficients read from SITE/render_shade.glsl, the one source of it), to a mean of
<= 8/255; and the colours must not be the plain texture (mean difference > 20/255).
This checks that the WebGL2 path draws the distortion through the map; the values of
sigma themselves are checked against the C runtime by the [hsib_gpu] tests.

usage: web_player_check.py CHROMIUM SITE RENDER WIDTH HEIGHT [--distortion LO,HI] FRAME [FRAME ...]
"""
import re
import functools
import http.server
import os
import struct
import subprocess
import sys
import tempfile
import threading
import zlib


def read_png(path):
    """RGB(A) 8-bit non-interlaced PNG -> (width, height, rows of RGB tuples)."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", chunk)
            assert depth == 8 and ctype in (2, 6) and interlace == 0, f"{path}: unsupported PNG ({depth} bit, type {ctype})"
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else (b if pb <= pc else c))) & 255
        prev = line
        px = []
        for x in range(w):
            r, g, bl = line[x * bpp:x * bpp + 3]
            if bpp == 4:  # over white, as the page's background
                al = line[x * bpp + 3] / 255.0
                r, g, bl = (round(v * al + 255 * (1 - al)) for v in (r, g, bl))
            px.append((r, g, bl))
        rows.append(px)
    return w, h, rows


def frame_times(path):
    b = open(path, "rb").read()
    header, frames, record = struct.unpack_from("<I", b, 8)[0], struct.unpack_from("<I", b, 40)[0], struct.unpack_from("<I", b, 44)[0]
    static = struct.unpack_from("<Q", b, 80)[0]
    start = header + static
    return [struct.unpack_from("<d", b, start + f * record)[0] for f in range(frames)]


def compare(a, b):
    (wa, ha, A), (wb, hb, B) = a, b
    assert (wa, ha) == (wb, hb), f"sizes differ: {wa}x{ha} and {wb}x{hb}"
    inter = union = 0
    diff_sum = diff_n = 0
    for y in range(ha):
        for x in range(wa):
            pa, pb = A[y][x], B[y][x]
            ca = max(255 - v for v in pa) > 24
            cb = max(255 - v for v in pb) > 24
            union += ca or cb
            inter += ca and cb
            if ca and cb:
                diff_sum += sum(abs(u - v) for u, v in zip(pa, pb))
                diff_n += 3
    return inter / max(union, 1), diff_sum / max(diff_n, 1), union


def viridis_samples(site, n=64):
    """The colour map of shaders/render_shade.glsl (staged as SITE/render_shade.glsl), n samples in 0..255."""
    text = open(os.path.join(site, "render_shade.glsl")).read()
    c = [tuple(float(v) for v in m.split(",")) for m in re.findall(r"const vec3 c\d = vec3\(([^)]*)\);", text)]
    assert len(c) == 7, "render_shade.glsl: the colour map's seven coefficients were not found"
    out = []
    for i in range(n):
        t = i / (n - 1)
        rgb = []
        for k in range(3):
            v = 0.0
            for j in reversed(range(7)):
                v = v * t + c[j][k]
            rgb.append(255 * min(max(v, 0.0), 1.0))
        out.append(tuple(rgb))
    return out


def colour_map_distance(shot, plain, samples):
    """Mean over pixels both cover of min_t |shot - (0.15 plain + 0.85 viridis(t))| per channel."""
    (w, h, A), (_, _, B) = shot, plain
    total = n = 0
    for y in range(h):
        for x in range(w):
            pa, pb = A[y][x], B[y][x]
            if max(255 - v for v in pa) > 24 and max(255 - v for v in pb) > 24:
                total += min(sum(abs(pa[k] - (0.15 * pb[k] + 0.85 * s[k])) for k in range(3)) for s in samples) / 3
                n += 1
    return total / max(n, 1)


def main():
    chromium, site, render, width, height = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
    rest = sys.argv[6:]
    distortion = None
    if rest and rest[0] == "--distortion":
        distortion, rest = rest[1], rest[2:]
    frames = [int(f) for f in rest]
    samples = viridis_samples(site) if distortion else None
    times = frame_times(os.path.join(site, "seq.hsib"))
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

    handler = functools.partial(Quiet, directory=site)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    port = server.server_address[1]
    failed = False
    try:
        for f in frames:
            shot = os.path.join(site, f"browser_{'distortion_' if distortion else ''}{f:04d}.png")
            url = (f"http://127.0.0.1:{port}/player.html?hsib=seq.hsib&texture=texture.png&w={width}&h={height}"
                   f"&t={times[f]!r}&view_frames={','.join(map(str, frames))}" + (f"&distortion={distortion}" if distortion else ""))
            with tempfile.TemporaryDirectory() as profile:
                cmd = [chromium, "--headless=new", "--no-sandbox", "--no-first-run", f"--user-data-dir={profile}",
                       "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--hide-scrollbars",
                       "--force-device-scale-factor=1", f"--window-size={width},{height}", "--virtual-time-budget=30000",
                       f"--screenshot={shot}", url]
                r = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
            if r.returncode != 0 or not os.path.exists(shot):
                print(f"frame {f}: chromium failed ({r.returncode}):\n{r.stderr[-3000:]}")
                failed = True
                continue
            want = os.path.join(render, f"frame_{f:04d}.png")
            got, plain = read_png(shot), read_png(want)
            iou, mad, covered = compare(got, plain)
            if distortion:
                off_map = colour_map_distance(got, plain, samples)
                ok = iou >= 0.98 and off_map <= 8 and mad > 20 and covered > 0.05 * width * height
                print(f"frame {f} (t = {times[f]:.4f}), distortion {distortion}: coverage IoU {iou:.4f} (>= 0.98), off the colour "
                      f"map by {off_map:.2f}/255 (<= 8), {mad:.1f}/255 from the plain texture (> 20), {covered} pixels covered: "
                      f"{'ok' if ok else 'FAILED'}  [{shot} vs {want}]")
            else:
                ok = iou >= 0.98 and mad <= 4 and covered > 0.05 * width * height
                print(f"frame {f} (t = {times[f]:.4f}): coverage IoU {iou:.4f} (>= 0.98), mean abs difference {mad:.2f}/255 (<= 4), "
                      f"{covered} pixels covered: {'ok' if ok else 'FAILED'}  [{shot} vs {want}]")
            failed = failed or not ok
    finally:
        server.shutdown()
    print("web player: FAILED" if failed else f"web player ok: {len(frames)} frames match hsi render")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
