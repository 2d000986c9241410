// A GPU timeline of any CUDA program, without changing it: a CUPTI injection library.
//
//   CUDA_INJECTION64_PATH=build/lib/libhsi_cuda_trace.so \
//   NVTX_INJECTION64_PATH=<libcupti.so>  (optional: the programs' NVTX ranges too) \
//   HSI_TRACE_OUT=trace.tsv build/bin/bench_cuda ...
//   python3 bench/cuda_trace/summarize.py trace.tsv
//
// The driver loads it at cuInit and calls InitializeInjection(); CUPTI's activity API then
// records, with the device's timestamps (ns, one clock for host and device records):
//   kernel   every kernel, also those inside CUDA graphs and cuBLAS / cuSOLVER calls
//            (start, end, stream, graph id, graph node id, grid, name)
//   memcpy / memset
//   api      the runtime calls that wait for the GPU or hand it work (names with
//            Synchronize, GraphLaunch, LaunchKernel, Memcpy), with the calling thread
//   range    NVTX push/pop ranges (with NVTX_INJECTION64_PATH set to CUPTI's library)
// and writes them at exit as tab-separated lines (HSI_TRACE_OUT, default hsi_trace.tsv).
// HSI_TRACE_MAX_RECORDS (default 4,000,000) bounds what is kept; the summary says when
// records were dropped. The device machine has no Nsight Systems (README, Speed
// section): this is our view of where a frame's time goes between kernels.
#include <cupti.h>
#include <cxxabi.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace {

constexpr size_t kBufferBytes = 8u << 20;

struct Record {
  char kind;  // k kernel, c memcpy, s memset, a api, r range start, e range end
  std::uint64_t start, end;
  std::uint32_t stream_or_thread;
  std::uint32_t graph;
  std::uint64_t node;
  std::uint64_t extra;  // kernel: grid blocks; memcpy/memset: bytes; range: id
  std::string name;
};

struct Trace {
  std::mutex mutex;
  std::vector<Record> records;
  std::unordered_map<std::string, std::string> demangled;
  size_t max_records = 4000000;
  std::uint64_t dropped = 0;  // records past max_records (under mutex, as all of this)
  std::string out = "hsi_trace.tsv";
  bool written = false;
};

Trace& trace() {
  static Trace* t = new Trace;  // never destroyed: CUPTI may call back during exit
  return *t;
}

const std::string& demangle(Trace& t, const char* name) {
  auto it = t.demangled.find(name);
  if (it != t.demangled.end()) return it->second;
  int status = 0;
  char* d = abi::__cxa_demangle(name, nullptr, nullptr, &status);
  std::string s = status == 0 && d ? d : name;
  std::free(d);
  // Keep the function's qualified name: drop the parameter list (the last top-level
  // parentheses, not "(anonymous namespace)"), template arguments, the anonymous
  // namespace and a template's return type.
  if (!s.empty() && s.back() == ')') {
    int depth = 0;
    for (size_t q = s.size(); q-- > 0;) {
      if (s[q] == ')') ++depth;
      if (s[q] == '(' && --depth == 0) {
        s.erase(q);
        break;
      }
    }
  }
  for (auto p = s.find('<'); p != std::string::npos; p = s.find('<')) {
    int depth = 0;
    size_t q = p;
    for (; q < s.size(); ++q) {
      if (s[q] == '<') ++depth;
      if (s[q] == '>' && --depth == 0) break;
    }
    s.erase(p, q - p + 1);
  }
  constexpr std::string_view anon = "(anonymous namespace)::";
  for (auto p = s.find(anon); p != std::string::npos; p = s.find(anon)) s.erase(p, anon.size());
  if (auto p = s.rfind(' '); p != std::string::npos) s.erase(0, p + 1);  // a template's return type: "void f" -> "f"
  for (char& c : s)
    if (c == '\t' || c == '\n') c = ' ';
  return t.demangled.emplace(name, s).first->second;
}

void CUPTIAPI buffer_requested(std::uint8_t** buffer, size_t* size, size_t* max_records) {
  *buffer = static_cast<std::uint8_t*>(std::aligned_alloc(8, kBufferBytes));
  *size = kBufferBytes;
  *max_records = 0;
}

bool api_wanted(const char* name) {
  return std::strstr(name, "Synchronize") || std::strstr(name, "GraphLaunch") || std::strstr(name, "LaunchKernel") ||
         std::strstr(name, "Memcpy");
}

void CUPTIAPI buffer_completed(CUcontext, std::uint32_t, std::uint8_t* buffer, size_t, size_t valid) {
  Trace& t = trace();
  std::lock_guard<std::mutex> lock(t.mutex);
  CUpti_Activity* a = nullptr;
  while (cuptiActivityGetNextRecord(buffer, valid, &a) == CUPTI_SUCCESS) {
    if (t.records.size() >= t.max_records) {
      ++t.dropped;
      continue;
    }
    Record r{};
    switch (a->kind) {
      case CUPTI_ACTIVITY_KIND_CONCURRENT_KERNEL:
      case CUPTI_ACTIVITY_KIND_KERNEL: {
        const auto* k = reinterpret_cast<const CUpti_ActivityKernel10*>(a);
        r = {'k', k->start, k->end, k->streamId, k->graphId, k->graphNodeId,
             static_cast<std::uint64_t>(k->gridX) * static_cast<std::uint64_t>(k->gridY) * static_cast<std::uint64_t>(k->gridZ),
             demangle(t, k->name)};
        break;
      }
      case CUPTI_ACTIVITY_KIND_MEMCPY: {
        const auto* m = reinterpret_cast<const CUpti_ActivityMemcpy6*>(a);
        r = {'c', m->start, m->end, m->streamId, m->graphId, m->graphNodeId, m->bytes,
             "memcpy kind " + std::to_string(static_cast<int>(m->copyKind))};
        break;
      }
      case CUPTI_ACTIVITY_KIND_MEMSET: {
        const auto* m = reinterpret_cast<const CUpti_ActivityMemset4*>(a);
        r = {'s', m->start, m->end, m->streamId, m->graphId, m->graphNodeId, m->bytes, "memset"};
        break;
      }
      case CUPTI_ACTIVITY_KIND_RUNTIME: {
        const auto* api = reinterpret_cast<const CUpti_ActivityAPI*>(a);
        const char* name = nullptr;
        if (cuptiGetCallbackName(CUPTI_CB_DOMAIN_RUNTIME_API, api->cbid, &name) != CUPTI_SUCCESS || !name) continue;
        if (!api_wanted(name)) continue;
        r = {'a', api->start, api->end, api->threadId, 0, 0, api->correlationId, name};
        break;
      }
      case CUPTI_ACTIVITY_KIND_MARKER: {
        const auto* m = reinterpret_cast<const CUpti_ActivityMarker2*>(a);
        const bool start = (m->flags & CUPTI_ACTIVITY_FLAG_MARKER_START) != 0;
        const bool end = (m->flags & CUPTI_ACTIVITY_FLAG_MARKER_END) != 0;
        if (!start && !end) continue;
        r = {start ? 'r' : 'e', m->timestamp, m->timestamp, m->objectId.pt.threadId, 0, 0, m->id, m->name ? m->name : ""};
        break;
      }
      default:
        continue;
    }
    t.records.push_back(std::move(r));
  }
  std::free(buffer);
}

void write_trace() {
  Trace& t = trace();
  cuptiActivityFlushAll(CUPTI_ACTIVITY_FLAG_FLUSH_FORCED);
  std::lock_guard<std::mutex> lock(t.mutex);
  if (t.written) return;
  t.written = true;
  // Range ends carry no name: take the start's (same id).
  std::unordered_map<std::uint64_t, std::string> range_names;
  for (const Record& r : t.records)
    if (r.kind == 'r') range_names[r.extra] = r.name;
  FILE* f = std::fopen(t.out.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "hsi_cuda_trace: cannot write %s\n", t.out.c_str());
    return;
  }
  std::fprintf(f, "# hsi_cuda_trace: kind start_ns end_ns stream_or_thread graph node extra name; dropped %llu\n",
               static_cast<unsigned long long>(t.dropped));
  for (const Record& r : t.records) {
    const std::string& name = r.kind == 'e' ? range_names[r.extra] : r.name;
    std::fprintf(f, "%c\t%llu\t%llu\t%u\t%u\t%llu\t%llu\t%s\n", r.kind, static_cast<unsigned long long>(r.start),
                 static_cast<unsigned long long>(r.end), r.stream_or_thread, r.graph, static_cast<unsigned long long>(r.node),
                 static_cast<unsigned long long>(r.extra), name.c_str());
  }
  std::fclose(f);
  std::fprintf(stderr, "hsi_cuda_trace: %zu records (%llu dropped) in %s\n", t.records.size(),
               static_cast<unsigned long long>(t.dropped), t.out.c_str());
}

bool check(CUptiResult r, const char* what) {
  if (r == CUPTI_SUCCESS) return true;
  const char* msg = nullptr;
  cuptiGetResultString(r, &msg);
  std::fprintf(stderr, "hsi_cuda_trace: %s failed: %s\n", what, msg ? msg : "?");
  return false;
}

}  // namespace

extern "C" int InitializeInjection(void) {
  Trace& t = trace();
  if (const char* out = std::getenv("HSI_TRACE_OUT")) t.out = out;
  if (const char* max = std::getenv("HSI_TRACE_MAX_RECORDS")) t.max_records = std::strtoull(max, nullptr, 10);
  t.records.reserve(std::min<size_t>(t.max_records, 1u << 20));
  if (!check(cuptiActivityRegisterCallbacks(buffer_requested, buffer_completed), "cuptiActivityRegisterCallbacks")) return 0;
  bool ok = check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_CONCURRENT_KERNEL), "enable kernels");
  ok = check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_MEMCPY), "enable memcpy") && ok;
  ok = check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_MEMSET), "enable memset") && ok;
  ok = check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_RUNTIME), "enable runtime API") && ok;
  check(cuptiActivityEnable(CUPTI_ACTIVITY_KIND_MARKER), "enable NVTX markers");  // optional
  std::atexit(write_trace);
  return ok ? 1 : 0;
}
