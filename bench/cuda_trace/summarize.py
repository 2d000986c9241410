#!/usr/bin/python3
"""Where the GPU's time goes inside each NVTX range of a trace from libhsi_cuda_trace.so.

    python3 bench/cuda_trace/summarize.py trace.tsv [--range SUBSTRING] [--per N] [--top K]

Per range (bench_cuda: "sequence cuda", ...; bench_batch: "batch W=16 ..."): wall time; the
GPU's busy time (the union of kernels, copies and sets on every stream) and idle time; the
idle time split by what the host threads did meanwhile (waiting in a Synchronize call:
the GPU had nothing queued that the host had released yet, i.e. a round trip; not
waiting: the host was deciding or launching); the kernels' summed time over the busy
time (how many ran side by side on average); the gaps between GPU activity by length;
the runtime calls; and the kernels by summed time. With --per N every time is also
divided by N (a sequence's solved frames).
"""
import argparse
import bisect
import collections
import sys


def load(path):
    recs = []
    header = ""
    with open(path) as f:
        for number, line in enumerate(f, 1):
            if line.startswith("#"):
                header = line.strip()
                continue
            p = line.rstrip("\n").split("\t", 7)
            try:
                if len(p) != 8 or p[0] not in "kcsare" or len(p[0]) != 1:
                    raise ValueError("expected 8 tab-separated fields, the first one of k c s a r e")
                recs.append((p[0], int(p[1]), int(p[2]), int(p[3]), int(p[4]), int(p[5]), int(p[6]), p[7]))
            except ValueError as e:
                raise ValueError(f"{path}, line {number}: not a libhsi_cuda_trace.so record ({e})") from None
    return header, recs


def ranges_of(recs):
    """NVTX push/pop pairs (a start and an end share CUPTI's range id), by start time."""
    open_ = collections.defaultdict(list)
    out = []
    for kind, start, _end, _thread, _g, _n, rid, name in sorted((r for r in recs if r[0] in "re"), key=lambda r: r[1]):
        if kind == "r":
            open_[rid].append((start, name))
        elif open_[rid]:
            s, n = open_[rid].pop()
            out.append((n, s, start))
    return sorted(out, key=lambda r: r[1])


def union(intervals):
    merged = []
    for s, e in sorted(intervals):
        if merged and s <= merged[-1][1]:
            if e > merged[-1][1]:
                merged[-1][1] = e
        else:
            merged.append([s, e])
    return merged


def overlap_with(intervals_sorted, starts, s, e):
    """Length of [s, e) covered by a sorted, disjoint interval list."""
    total = 0
    i = max(bisect.bisect_right(starts, s) - 1, 0)
    while i < len(intervals_sorted) and intervals_sorted[i][0] < e:
        a, b = intervals_sorted[i]
        total += max(0, min(b, e) - max(a, s))
        i += 1
    return total


def analyze(t0, t1, recs):
    """The numbers of one range [t0, t1] (ns): times in µs."""
    inside = [r for r in recs if r[1] >= t0 and r[2] <= t1]
    gpu = [r for r in inside if r[0] in "kcs"]
    api = [r for r in inside if r[0] == "a"]
    busy_iv = union([(r[1], r[2]) for r in gpu])
    # Idle stretches inside the range, and how much of each a host thread spent waiting.
    waits = union([(r[1], r[2]) for r in api if "Synchronize" in r[7]])
    wait_starts = [w[0] for w in waits]
    idle = []
    prev = t0
    for s, e in busy_iv:
        if s > prev:
            idle.append((prev, s))
        prev = max(prev, e)
    if t1 > prev:
        idle.append((prev, t1))
    st = {
        "wall": (t1 - t0) / 1e3,
        "busy": sum(e - s for s, e in busy_iv) / 1e3,
        "kernels": sum(r[2] - r[1] for r in gpu if r[0] == "k") / 1e3,
        "copies": sum(r[2] - r[1] for r in gpu if r[0] in "cs") / 1e3,
        "idle": sum(e - s for s, e in idle) / 1e3,
        "idle_waiting": sum(overlap_with(waits, wait_starts, s, e) for s, e in idle) / 1e3,
        # gaps between two stretches of GPU work (not the range's ends)
        "gaps": [(e - s) / 1e3 for s, e in idle if s != t0 and e != t1],
        "gpu_records": len(gpu),
        "calls": collections.Counter(r[7] for r in api),
        "call_time": collections.Counter(),
        "by_name": collections.defaultdict(lambda: [0, 0.0]),
    }
    for r in api:
        st["call_time"][r[7]] += (r[2] - r[1]) / 1e3
    for r in gpu:
        st["by_name"][r[7]][0] += 1
        st["by_name"][r[7]][1] += (r[2] - r[1]) / 1e3
    return st


def report(name, st, per, top):
    wall, busy = st["wall"], st["busy"]
    f = (lambda x: x / per) if per else (lambda x: x)
    unit = "per unit (÷ %g)" % per if per else "total"
    print(f"\n## {name}\n")
    print(f"wall {wall / 1e3:.3f} ms; {st['gpu_records']} GPU records, {sum(st['calls'].values())} runtime calls; figures in µs, {unit}\n")
    print("| what | µs | share of wall |")
    print("|---|---:|---:|")
    for label, v in [("wall", wall), ("GPU busy (union of every stream)", busy), ("GPU idle", st["idle"]),
                     ("  of it a host thread waiting in a Synchronize call", st["idle_waiting"]),
                     ("  of it no host thread waiting (host deciding / launching)", st["idle"] - st["idle_waiting"]),
                     ("kernels, summed", st["kernels"]), ("copies and sets, summed", st["copies"])]:
        print(f"| {label} | {f(v):.1f} | {100 * v / wall if wall else 0:.1f}% |")
    if busy > 0:
        print(f"\nGPU work side by side on average while busy: {(st['kernels'] + st['copies']) / busy:.2f}")
    print("\n| gap between GPU activity (µs) | count | summed µs |")
    print("|---|---:|---:|")
    for lo, hi in [(0, 2), (2, 5), (5, 10), (10, 20), (20, 50), (50, float("inf"))]:
        sel = [g for g in st["gaps"] if lo <= g < hi]
        label = f"{lo}–{hi}" if hi != float("inf") else f"≥ {lo}"
        print(f"| {label} | {f(len(sel)):.2f} | {f(sum(sel)):.1f} |")
    print("\n| runtime call | count | host µs in it |")
    print("|---|---:|---:|")
    for c, n in st["calls"].most_common():
        print(f"| {c} | {f(n):.2f} | {f(st['call_time'][c]):.1f} |")
    print(f"\n| kernel / copy (top {top}) | count | summed µs | mean µs | share of busy |")
    print("|---|---:|---:|---:|---:|")
    for k, (n, t) in sorted(st["by_name"].items(), key=lambda kv: -kv[1][1])[:top]:
        print(f"| {k[:90]} | {f(n):.2f} | {f(t):.1f} | {t / n:.2f} | {100 * t / busy if busy else 0:.1f}% |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("trace")
    ap.add_argument("--range", default="", help="only ranges whose name contains this")
    ap.add_argument("--per", type=float, default=0, help="also divide by this (e.g. the solved frames)")
    ap.add_argument("--top", type=int, default=25)
    a = ap.parse_args()
    try:
        header, recs = load(a.trace)
    except (OSError, ValueError) as e:
        print(f"summarize.py: {e}", file=sys.stderr)
        return 2
    print(f"trace {a.trace}: {len(recs)} records; {header}")
    rs = [r for r in ranges_of(recs) if a.range in r[0]]
    if not rs:
        print("no NVTX ranges matched (was NVTX_INJECTION64_PATH set to CUPTI's library?)", file=sys.stderr)
        return 1
    for name, t0, t1 in rs:
        report(name, analyze(t0, t1, recs), a.per, a.top)
    return 0


if __name__ == "__main__":
    sys.exit(main())
