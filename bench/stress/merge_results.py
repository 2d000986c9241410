#!/usr/bin/env python3
"""Merge bench_stress JSON files (later files win for the same sequence, frames and projection)
into whole-corpus tables: per frames/interval and projection, and PartProj against Delete per shape."""
import json, sys, collections
runs = {}
corpus_ids = set()
for path in sys.argv[1:]:
    d = json.load(open(path))
    for r in d["runs"]:
        if r.get("failed_runs", 0) and not r.get("frames"):
            continue
        runs[(r["id"], r["frames_per_interval"], r["projection"])] = (r, path)
tab = collections.defaultdict(lambda: dict(seq=0, frames=0, it=0.0, cap=0, nc=0, cert=0, maxit=0, unconv=[]))
shape = collections.defaultdict(lambda: [0, 0.0])
for (sid, F, proj), (r, path) in runs.items():
    t = tab[(F, proj)]
    t["seq"] += 1; t["frames"] += r["frames"]; t["it"] += r["mean_iterations"] * r["frames"]
    t["cap"] += r["at_cap"]; t["nc"] += r.get("not_converged", 0); t["cert"] += r["certified"]
    t["maxit"] = max(t["maxit"], r["max_iterations"])
    for u in r.get("unconverged_frames", []):
        t["unconv"].append(f'{sid} t={u["t"]:.3f} {u["stop"]} {u["iterations"]} it')
    s = shape[(r["shape"], F, proj)]; s[0] += r["frames"]; s[1] += r["mean_iterations"] * r["frames"]
print("| frames/interval | projection | sequences | frames | mean it | max it | at cap | not converged | certified |")
print("|---:|---|---:|---:|---:|---:|---:|---:|---:|")
for (F, proj) in sorted(tab):
    t = tab[(F, proj)]
    print(f'| {F} | {proj} | {t["seq"]} | {t["frames"]} | {t["it"]/t["frames"]:.2f} | {t["maxit"]} | {t["cap"]} | {t["nc"]} | {t["cert"]} |')
print()
for (F, proj) in sorted(tab):
    for u in tab[(F, proj)]["unconv"]:
        print(f"- {F} {proj}: {u}")
print()
for F in sorted({k[1] for k in shape}):
    worse = []
    names = sorted({k[0] for k in shape if k[1] == F})
    for n in names:
        p, d = shape.get((n, F, "partproj")), shape.get((n, F, "delete"))
        if p and d and p[0] and d[0]:
            mp, md = p[1] / p[0], d[1] / d[0]
            if mp > md: worse.append(f"{n} {mp:.2f}/{md:.2f}")
    print(f"PartProj > Delete at {F}: {len(worse)} of {len(names)} shapes: " + ", ".join(worse))
