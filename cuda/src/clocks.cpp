// The GPU's clocks (hsi/cuda/clocks.h). NVML's header is not part of every CUDA toolkit
// (it is not in the one this was written with), and linking the driver's library would
// stop the program from starting where there is no driver: the five NVML entry points
// used are declared here, with their documented C signatures, and loaded by dlopen.
#include "hsi/cuda/clocks.h"

#include <dlfcn.h>

#include <cstdio>

#include "device.h"

namespace hsi::cuda {

namespace {

// NVML's types as nvml.h declares them: nvmlReturn_t is an enum (0 = NVML_SUCCESS),
// nvmlDevice_t an opaque pointer, nvmlClockType_t an enum.
using NvmlReturn = int;
using NvmlDevice = struct NvmlDeviceOpaque*;
constexpr int kNvmlClockSm = 1, kNvmlClockMem = 2;

struct Nvml {
  NvmlReturn (*init)() = nullptr;
  NvmlReturn (*shutdown)() = nullptr;
  NvmlReturn (*by_pci)(const char*, NvmlDevice*) = nullptr;
  NvmlReturn (*clock)(NvmlDevice, int, unsigned*) = nullptr;
  NvmlReturn (*max_clock)(NvmlDevice, int, unsigned*) = nullptr;
  std::string error;  // empty: loaded
};

template <class F>
void load(void* lib, const char* name, F& f, std::string& error) {
  f = reinterpret_cast<F>(dlsym(lib, name));
  if (!f && error.empty()) error = std::string("libnvidia-ml.so.1 has no ") + name;
}

const Nvml& nvml() {
  static const Nvml n = [] {
    Nvml r;
    void* lib = dlopen("libnvidia-ml.so.1", RTLD_NOW | RTLD_LOCAL);  // kept open for the process
    if (!lib) {
      const char* e = dlerror();
      r.error = std::string("NVML not loaded: ") + (e ? e : "libnvidia-ml.so.1 not found");
      return r;
    }
    load(lib, "nvmlInit_v2", r.init, r.error);
    load(lib, "nvmlShutdown", r.shutdown, r.error);
    load(lib, "nvmlDeviceGetHandleByPciBusId_v2", r.by_pci, r.error);
    load(lib, "nvmlDeviceGetClockInfo", r.clock, r.error);
    load(lib, "nvmlDeviceGetMaxClockInfo", r.max_clock, r.error);
    return r;
  }();
  return n;
}

}  // namespace

std::string Clocks::describe() const {
  char buf[512];
  if (nvml)
    std::snprintf(buf, sizeof buf, "%s: SM %d MHz (max %d MHz), memory %d MHz (current clocks, read by NVML)", device.c_str(),
                  sm_mhz, sm_max_mhz, memory_mhz);
  else
    std::snprintf(buf, sizeof buf,
                  "%s: peak SM clock %d MHz, peak memory clock %d MHz (cudaDevAttrClockRate and cudaDevAttrMemoryClockRate: the "
                  "device's peak clocks, not the current ones; %s)",
                  device.c_str(), sm_max_mhz, memory_mhz, why_not_nvml.c_str());
  return buf;
}

Clocks clocks() {
  Clocks c;
  const int dev = current_device();
  cudaDeviceProp prop{};
  HSI_CUDA_CHECK(cudaGetDeviceProperties(&prop, dev));
  c.device = prop.name;
  int khz = 0;
  HSI_CUDA_CHECK(cudaDeviceGetAttribute(&khz, cudaDevAttrClockRate, dev));
  c.sm_max_mhz = khz / 1000;
  HSI_CUDA_CHECK(cudaDeviceGetAttribute(&khz, cudaDevAttrMemoryClockRate, dev));
  c.memory_mhz = khz / 1000;

  const Nvml& n = nvml();
  if (!n.error.empty()) {
    c.why_not_nvml = n.error;
    return c;
  }
  char pci[32] = {};
  HSI_CUDA_CHECK(cudaDeviceGetPCIBusId(pci, sizeof pci, dev));
  if (const NvmlReturn e = n.init(); e != 0) {
    c.why_not_nvml = "nvmlInit_v2 returned " + std::to_string(e);
    return c;
  }
  NvmlDevice h = nullptr;
  unsigned sm = 0, sm_max = 0, mem = 0;
  NvmlReturn e = n.by_pci(pci, &h);
  if (e == 0) e = n.clock(h, kNvmlClockSm, &sm);
  if (e == 0) e = n.max_clock(h, kNvmlClockSm, &sm_max);
  if (e == 0) e = n.clock(h, kNvmlClockMem, &mem);
  n.shutdown();
  if (e != 0) {
    c.why_not_nvml = "an NVML clock query for " + std::string(pci) + " returned " + std::to_string(e);
    return c;
  }
  c.nvml = true;
  c.sm_mhz = static_cast<int>(sm);
  c.sm_max_mhz = static_cast<int>(sm_max);
  c.memory_mhz = static_cast<int>(mem);
  return c;
}

}  // namespace hsi::cuda
