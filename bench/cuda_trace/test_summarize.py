#!/usr/bin/python3
"""summarize.py's arithmetic on a made-up trace (CTest: cuda_trace_summary)."""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summarize  # noqa: E402

# Two threads, each with a range; thread 7's holds two kernels that overlap on two
# streams, a copy after a 3 µs gap, a 4 µs gap the host spends half in a sync call.
recs = [
    ("r", 1000, 1000, 7, 0, 0, 1, "sequence cuda"),
    ("r", 1500, 1500, 8, 0, 0, 2, "other"),
    ("k", 2000, 5000, 13, 1, 1, 40, "kernA"),
    ("k", 4000, 9000, 14, 1, 2, 40, "kernB"),
    ("c", 12000, 13000, 13, 0, 0, 8, "memcpy kind 2"),
    ("a", 13000, 15000, 7, 0, 0, 3, "cudaStreamSynchronize_v3020"),
    ("a", 13500, 13600, 7, 0, 0, 4, "cudaGraphLaunch_v10000"),
    ("k", 17000, 18000, 13, 1, 3, 1, "kernA"),
    ("e", 20000, 20000, 7, 0, 0, 1, ""),
    ("e", 30000, 30000, 8, 0, 0, 2, ""),
]
ranges = summarize.ranges_of(recs)
assert [r[0] for r in ranges] == ["sequence cuda", "other"], ranges
name, t0, t1 = ranges[0]
assert (t0, t1) == (1000, 20000)
st = summarize.analyze(t0, t1, recs)
close = lambda a, b: abs(a - b) < 1e-9
assert close(st["wall"], 19.0)
assert close(st["busy"], 7.0 + 1.0 + 1.0), st["busy"]          # [2, 9] ∪ [12, 13] ∪ [17, 18]
assert close(st["kernels"], 3.0 + 5.0 + 1.0)
assert close(st["copies"], 1.0)
assert close(st["idle"], 19.0 - 9.0)
assert close(st["idle_waiting"], 2.0), st["idle_waiting"]       # [13, 15] inside the idle [13, 17]
assert sorted(st["gaps"]) == [3.0, 4.0], st["gaps"]             # [9, 12] and [13, 17]; the range's ends are not gaps
assert st["calls"]["cudaStreamSynchronize_v3020"] == 1 and st["calls"]["cudaGraphLaunch_v10000"] == 1
assert st["by_name"]["kernA"] == [2, 4.0]
# A record that only starts inside the range is not counted in it.
assert summarize.analyze(4500, 20000, recs)["kernels"] == 1.0
# A file that is not a trace: an error naming the file and line, not a silent skip.
with tempfile.NamedTemporaryFile("w", suffix=".tsv", delete=False) as f:
    f.write("# hsi_cuda_trace\nk\t1\t2\t3\t0\t0\t1\tkern\nk\t1\tnot-a-number\t3\t0\t0\t1\tkern\n")
try:
    summarize.load(f.name)
    raise AssertionError("a malformed record was accepted")
except ValueError as e:
    assert "line 3" in str(e) and f.name in str(e), e
finally:
    os.unlink(f.name)
print("summarize.py: ok")
