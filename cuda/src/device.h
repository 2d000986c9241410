// Checked CUDA calls and RAII owners of device resources (memory, pinned memory,
// streams, events, cuBLAS handles): the building blocks of the CUDA backend, defined
// once here. Private to cuda/ (its benchmark reaches it through hsi_cuda_internals).
// Host code only; needs the CUDA toolkit's headers.
#pragma once

#include <cublas_v2.h>
#include <cusolverDn.h>
#include <cuda_runtime.h>

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <optional>
#include <set>
#include <shared_mutex>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hsi/cuda/newton_core.h"

namespace hsi::cuda {

[[noreturn]] inline void fail_call(const char* call, const std::string& what, const char* file, int line) {
  throw Error(std::string(call) + " failed: " + what + " (" + file + ":" + std::to_string(line) + ")");
}
inline void check_call(cudaError_t e, const char* call, const char* file, int line) {
  if (e != cudaSuccess) fail_call(call, std::string(cudaGetErrorName(e)) + ": " + cudaGetErrorString(e), file, line);
}
inline void check_call(cublasStatus_t s, const char* call, const char* file, int line) {
  if (s != CUBLAS_STATUS_SUCCESS) fail_call(call, std::string(cublasGetStatusName(s)) + ": " + cublasGetStatusString(s), file, line);
}
inline void check_call(cusolverStatus_t s, const char* call, const char* file, int line) {
  if (s != CUSOLVER_STATUS_SUCCESS) fail_call(call, "cuSOLVER status " + std::to_string(static_cast<int>(s)), file, line);
}

}  // namespace hsi::cuda

// Throws hsi::cuda::Error naming the call, the error and the place.
#define HSI_CUDA_CHECK(call) ::hsi::cuda::check_call((call), #call, __FILE__, __LINE__)

namespace hsi::cuda {

// Stream captures and the calls that break them, across threads. A capture in flight
// on one thread (GraphCache) is invalidated by calls on any other thread that
// synchronise the whole device (cudaFree, cudaFreeHost, a handle's destruction) or that
// the capture cannot be ordered against; with many cores on many threads (bench_stress
// --jobs 16, bench_batch's 16 workers) such calls came while others captured, captures
// failed (cudaErrorStreamCaptureInvalidated, cuBLAS launch failures inside the capture)
// and the process crashed. Every such call of this backend (the RAII owners below:
// memory, pinned memory, streams, events, library handles, graphs) holds this lock
// exclusively; every capture, from its beginning to its end, holds it shared, so
// captures on several threads run side by side and never beside those calls.
inline std::shared_mutex& capture_guard() {
  static std::shared_mutex m;
  return m;
}
// Captures that failed in this process (GraphCache: the work then ran directly); tests
// and benchmarks read it.
inline std::atomic<long>& capture_failures() {
  static std::atomic<long> n{0};
  return n;
}
// Graphs launched by GraphCache in this process and the nodes they held (kernels,
// copies, memsets; a library call captured as a child graph counts once): benchmarks
// read them (issue #23: under load a frame costs about its count of small launches).
struct GraphCounts {
  std::atomic<long> launches{0}, nodes{0};
};
inline GraphCounts& graph_counts() {
  static GraphCounts c;
  return c;
}
// What this thread holds of capture_guard: nothing, the lock exclusively (an
// OutsideCaptures further up its stack, e.g. a graph key's first run, which may make
// buffers), or shared (it is capturing).
enum class GuardHeld : unsigned char { None, Exclusive, Shared };
inline GuardHeld& guard_held() {
  thread_local GuardHeld held = GuardHeld::None;
  return held;
}
// Held around a call that must not run while another thread captures. Nested in one
// already held by this thread it locks nothing (shared_mutex is not recursive: it would
// wait for itself); inside this thread's own capture it locks nothing either (the call
// fails that capture, and GraphCache runs the work directly).
class OutsideCaptures {
 public:
  OutsideCaptures() {
    if (guard_held() != GuardHeld::None) return;
    lock_ = std::unique_lock<std::shared_mutex>(capture_guard());
    guard_held() = GuardHeld::Exclusive;
  }
  ~OutsideCaptures() {
    if (lock_.owns_lock()) guard_held() = GuardHeld::None;
  }
  OutsideCaptures(const OutsideCaptures&) = delete;
  OutsideCaptures& operator=(const OutsideCaptures&) = delete;

 private:
  std::unique_lock<std::shared_mutex> lock_;
};

// Device memory for `count` values of T (uninitialised).
template <class T>
class DeviceArray {
 public:
  DeviceArray() = default;
  explicit DeviceArray(size_t count) : count_(count) {
    if (!count) return;
    OutsideCaptures guard;
    HSI_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&p_), count * sizeof(T)));
  }
  ~DeviceArray() {
    if (!p_) return;
    OutsideCaptures guard;
    cudaFree(p_);
  }
  DeviceArray(DeviceArray&& o) noexcept : p_(std::exchange(o.p_, nullptr)), count_(std::exchange(o.count_, 0)) {}
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(count_, o.count_);
    return *this;
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  T* get() const { return p_; }
  size_t size() const { return count_; }
  size_t bytes() const { return count_ * sizeof(T); }

 private:
  T* p_ = nullptr;
  size_t count_ = 0;
};

// Page-locked host memory (fast, truly asynchronous copies), zero-filled when made:
// cudaMallocHost does not clear what it hands out, and a slot nobody has written yet (the
// batch stepper's [x; 0] staging, issue #23) must not read what pinned memory freed
// earlier in the process held.
template <class T>
class PinnedArray {
  static_assert(std::is_trivially_copyable_v<T>, "PinnedArray holds plain values");

 public:
  PinnedArray() = default;
  explicit PinnedArray(size_t count) : count_(count) {
    if (!count) return;
    OutsideCaptures guard;
    HSI_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&p_), count * sizeof(T)));
    std::memset(static_cast<void*>(p_), 0, count * sizeof(T));
  }
  ~PinnedArray() {
    if (!p_) return;
    OutsideCaptures guard;
    cudaFreeHost(p_);
  }
  PinnedArray(PinnedArray&& o) noexcept : p_(std::exchange(o.p_, nullptr)), count_(std::exchange(o.count_, 0)) {}
  PinnedArray& operator=(PinnedArray&& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(count_, o.count_);
    return *this;
  }
  PinnedArray(const PinnedArray&) = delete;
  PinnedArray& operator=(const PinnedArray&) = delete;
  T* get() const { return p_; }
  T& operator[](size_t i) const { return p_[i]; }
  size_t size() const { return count_; }

 private:
  T* p_ = nullptr;
  size_t count_ = 0;
};

// A non-blocking stream (no implicit ordering with the legacy default stream).
class Stream {
 public:
  Stream() {
    OutsideCaptures guard;
    HSI_CUDA_CHECK(cudaStreamCreateWithFlags(&s_, cudaStreamNonBlocking));
  }
  ~Stream() {
    OutsideCaptures guard;
    cudaStreamDestroy(s_);
  }
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;
  operator cudaStream_t() const { return s_; }

 private:
  cudaStream_t s_ = nullptr;
};

class Event {
 public:
  explicit Event(bool timing = false) {
    OutsideCaptures guard;
    HSI_CUDA_CHECK(cudaEventCreateWithFlags(&e_, timing ? cudaEventDefault : cudaEventDisableTiming));
  }
  ~Event() {
    OutsideCaptures guard;
    cudaEventDestroy(e_);
  }
  Event(const Event&) = delete;
  Event& operator=(const Event&) = delete;
  operator cudaEvent_t() const { return e_; }

 private:
  cudaEvent_t e_ = nullptr;
};

// Pinned staging for host → device copies, refilled only once the device has read its
// previous contents (the event marks the end of the last copy out of it).
template <class T>
class Upload {
 public:
  explicit Upload(size_t count) : buf_(count) {}
  T* begin_fill() {
    if (pending_) HSI_CUDA_CHECK(cudaEventSynchronize(done_));
    pending_ = false;
    return buf_.get();
  }
  void send(T* dst, size_t count, cudaStream_t stream) {
    if (count > buf_.size()) throw Error("hsi::cuda: upload larger than its staging buffer");
    HSI_CUDA_CHECK(cudaMemcpyAsync(dst, buf_.get(), count * sizeof(T), cudaMemcpyHostToDevice, stream));
    HSI_CUDA_CHECK(cudaEventRecord(done_, stream));
    pending_ = true;
  }

 private:
  PinnedArray<T> buf_;
  Event done_;
  bool pending_ = false;
};

// A cuBLAS handle bound to a stream, scalars passed from the host, with a workspace of
// its own (cuBLAS's size for Hopper), so that calls captured into CUDA graphs allocate
// nothing.
class BlasHandle {
 public:
  static constexpr size_t kWorkspaceBytes = size_t{32} << 20;
  explicit BlasHandle(cudaStream_t stream) : workspace_(kWorkspaceBytes) {
    OutsideCaptures guard;
    HSI_CUDA_CHECK(cublasCreate(&h_));
    try {
      HSI_CUDA_CHECK(cublasSetStream(h_, stream));
      HSI_CUDA_CHECK(cublasSetPointerMode(h_, CUBLAS_POINTER_MODE_HOST));
      HSI_CUDA_CHECK(cublasSetWorkspace(h_, workspace_.get(), workspace_.bytes()));
    } catch (...) {
      cublasDestroy(h_);
      throw;
    }
  }
  ~BlasHandle() {
    OutsideCaptures guard;
    cublasDestroy(h_);
  }
  BlasHandle(const BlasHandle&) = delete;
  BlasHandle& operator=(const BlasHandle&) = delete;
  operator cublasHandle_t() const { return h_; }

 private:
  DeviceArray<unsigned char> workspace_;  // outlives the handle (declared first)
  cublasHandle_t h_ = nullptr;
};

// A cuSOLVER dense handle bound to a stream.
class SolverHandle {
 public:
  explicit SolverHandle(cudaStream_t stream) {
    OutsideCaptures guard;
    HSI_CUDA_CHECK(cusolverDnCreate(&h_));
    if (const cusolverStatus_t st = cusolverDnSetStream(h_, stream); st != CUSOLVER_STATUS_SUCCESS) {
      cusolverDnDestroy(h_);
      HSI_CUDA_CHECK(st);
    }
  }
  ~SolverHandle() {
    OutsideCaptures guard;
    cusolverDnDestroy(h_);
  }
  SolverHandle(const SolverHandle&) = delete;
  SolverHandle& operator=(const SolverHandle&) = delete;
  operator cusolverDnHandle_t() const { return h_; }

 private:
  cusolverDnHandle_t h_ = nullptr;
};

// An instantiated CUDA graph (owns the executable; the graph itself is freed once
// instantiated).
class GraphExec {
 public:
  explicit GraphExec(cudaGraph_t graph) {
    OutsideCaptures guard;
    const cudaError_t e = cudaGraphInstantiate(&g_, graph, 0);
    cudaGraphDestroy(graph);
    HSI_CUDA_CHECK(e);
  }
  ~GraphExec() {
    if (!g_) return;
    OutsideCaptures guard;
    cudaGraphExecDestroy(g_);
  }
  GraphExec(GraphExec&& o) noexcept : g_(std::exchange(o.g_, nullptr)) {}
  GraphExec& operator=(GraphExec&& o) noexcept {
    std::swap(g_, o.g_);
    return *this;
  }
  GraphExec(const GraphExec&) = delete;
  GraphExec& operator=(const GraphExec&) = delete;
  operator cudaGraphExec_t() const { return g_; }

 private:
  cudaGraphExec_t g_ = nullptr;
};

// A stream's recurring call sequences as CUDA graphs, one per key: the first run of a
// key runs `enqueue` directly, the second captures what it puts on the stream and
// instantiates it, every later run launches it (one launch instead of tens: the Newton stepper's calls are launch-bound, issue
// #23). `enqueue` must be capturable and replayable: asynchronous work on the stream
// only (no synchronisation, allocation or host reads of device data), and everything it
// passes by value the same on every run of its key; values that change between runs go
// through device memory (or pinned host memory the graph copies from). Disabled, run()
// just calls `enqueue` (the default: graphs_enabled()).
class GraphCache {
 public:
  explicit GraphCache(bool enabled) : enabled_(enabled) {}
  bool enabled() const { return enabled_; }
  // What decides which kernels a key's work launches besides the key (the device and the
  // problem's sizes): a key's first run with a signature some cache of this process has
  // already run loaded every module it uses then, so it needs no exclusion from other
  // threads' captures (a batch's workers make cores of the same shapes side by side).
  // Empty, the default: every first run is excluded.
  using Signature = std::vector<long long>;
  void set_signature(Signature signature) { signature_ = std::move(signature); }

  template <class Enqueue>
  void run(std::uint64_t key, cudaStream_t stream, Enqueue&& enqueue) {
    if (!enabled_) {
      enqueue();
      return;
    }
    auto it = graphs_.find(key);
    if (it == graphs_.end()) {
      // The first run of a key runs directly: every kernel and library routine it uses
      // is loaded then (CUDA loads modules lazily), not inside the capture.
      auto [f, first] = failures_.try_emplace(key, -1);
      int& failures = f->second;
      if (first || failures >= kMaxCaptureFailures) {
        if (first) failures = 0;
        // The first run loads modules (lazily, at its first launches): outside any
        // other thread's capture too, unless the same work has run before in this process.
        const bool loaded = first && !signature_.empty() && first_runs().has(signature_, key);
        std::optional<OutsideCaptures> guard;
        if (first && !loaded) guard.emplace();
        enqueue();
        if (first && !loaded && !signature_.empty()) first_runs().add(signature_, key);
        return;
      }
      // A capture that fails (invalidated, or a call refused while capturing) runs the
      // same work directly instead, and is tried again next time, up to a limit.
      // Relaxed: a library routine may load its kernel lazily inside the capture (cuBLAS
      // can pick other kernels while capturing than in the direct run); in the stricter
      // modes that load failed the capture whenever other threads' cores were busy
      // (bench_stress, 16 workers on the H100).
      std::string why;
      cudaGraph_t graph = nullptr;
      cudaError_t ended = cudaSuccess;
      {
        std::shared_lock<std::shared_mutex> capturing(capture_guard());  // no device-wide call meanwhile
        HSI_CUDA_CHECK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeRelaxed));
        guard_held() = GuardHeld::Shared;
        try {
          enqueue();
        } catch (const Error& e) {
          why = e.what();
        }
        guard_held() = GuardHeld::None;
        ended = cudaStreamEndCapture(stream, &graph);
      }
      if (why.empty() && ended != cudaSuccess) why = std::string("cudaStreamEndCapture: ") + cudaGetErrorName(ended);
      if (!why.empty() || !graph) {
        if (graph) cudaGraphDestroy(graph);
        (void)cudaGetLastError();
        if (last_failure_.empty())  // once per cache: a performance fallback, not an error
          std::fprintf(stderr, "hsi cuda: a CUDA graph capture failed, the call runs without one: %s\n", why.c_str());
        ++failures;
        capture_failures().fetch_add(1);
        last_failure_ = why;
        enqueue();
        return;
      }
      size_t nodes = 0;
      if (cudaGraphGetNodes(graph, nullptr, &nodes) != cudaSuccess) nodes = 0;
      it = graphs_.emplace(key, Captured{GraphExec(graph), static_cast<long>(nodes)}).first;
    }
    HSI_CUDA_CHECK(cudaGraphLaunch(it->second.exec, stream));
    graph_counts().launches.fetch_add(1, std::memory_order_relaxed);
    graph_counts().nodes.fetch_add(it->second.nodes, std::memory_order_relaxed);
  }
  size_t size() const { return graphs_.size(); }
  // Why the last failed capture failed (empty if none has).
  const std::string& last_failure() const { return last_failure_; }

 private:
  // The (signature, key) pairs whose first run has happened in this process.
  class FirstRuns {
   public:
    bool has(const Signature& signature, std::uint64_t key) {
      std::lock_guard<std::mutex> lock(m_);
      return done_.count({signature, key}) != 0;
    }
    void add(const Signature& signature, std::uint64_t key) {
      std::lock_guard<std::mutex> lock(m_);
      done_.emplace(signature, key);
    }

   private:
    std::mutex m_;
    std::set<std::pair<Signature, std::uint64_t>> done_;
  };
  static FirstRuns& first_runs() {
    static FirstRuns runs;
    return runs;
  }

  static constexpr int kMaxCaptureFailures = 3;
  struct Captured {
    GraphExec exec;
    long nodes = 0;  // its top-level nodes (graph_counts)
  };
  Signature signature_;
  bool enabled_;
  std::unordered_map<std::uint64_t, Captured> graphs_;
  std::unordered_map<std::uint64_t, int> failures_;
  std::string last_failure_;
};

// The calling thread's current device ordinal (throws on a CUDA error).
inline int current_device() {
  int device = 0;
  HSI_CUDA_CHECK(cudaGetDevice(&device));
  return device;
}

// The key of this device's copy of some setup data (ShapeSetup::shared_backend_data).
inline std::string device_key(const char* what) {
  return std::string("cuda:") + std::to_string(current_device()) + ":" + what;
}

// Whether the CUDA backend replays its recurring call sequences as graphs: yes, unless
// HSI_CUDA_GRAPHS=0 (then the same work is launched directly, what GraphCache::run does
// when disabled). Captures on many threads are safe beside each other and beside the
// backend's allocations and frees (capture_guard).
inline bool graphs_enabled() {
  const char* v = std::getenv("HSI_CUDA_GRAPHS");
  return !(v && std::string(v) == "0");
}

// Whether the Newton system is factored by the backend's own dense Cholesky
// (dense_cholesky.h) rather than cuSOLVER: only with HSI_CUDA_CHOLESKY=own, until it is
// faster (bench_dense on the H100: 0.8-1.0x cuSOLVER's potrf at our orders).
inline bool own_cholesky_enabled() {
  const char* v = std::getenv("HSI_CUDA_CHOLESKY");
  return v && std::string(v) == "own";
}

// Whether the Newton system's triangular solves (after cuSOLVER's potrf, and with a kept
// factor) are cuSOLVER's potrs rather than dense_cholesky.h's cholesky_solve: only with
// HSI_CUDA_SOLVE=cusolver (the reference). cholesky_solve is one cluster kernel up to
// kCholeskySolveClusterMaxOrder; above it potrs is used either way.
inline bool cusolver_solve_forced() {
  const char* v = std::getenv("HSI_CUDA_SOLVE");
  return v && std::string(v) == "cusolver";
}

// Whether the exact system's solve is split (NewtonStepper::decrement: the factor and the
// forward substitution first, the back substitution and the direction only where the
// decrement does not stop the solve): on by default; HSI_CUDA_SPLIT_SOLVE=0 solves
// whole every time (the reference the split is measured against, bench_cuda and
// bench_batch in one binary).
inline bool split_solve_enabled() {
  const char* v = std::getenv("HSI_CUDA_SPLIT_SOLVE");
  return !(v && std::string(v) == "0");
}

}  // namespace hsi::cuda
