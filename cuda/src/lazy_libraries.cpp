// cuBLAS and cuSOLVER opened on first use instead of linked: loading them costs about
// 250 MB of memory (cuBLASLt's relocations and initialisers alone about 100 MB of
// private pages) in every process that links them, so every hsi command paid it,
// import-png of a 30 x 38 sprite included. Each entry point the backend calls is
// defined here with the header's own signature (a mismatch does not compile) and
// forwards to the library's symbol; a library that cannot be opened throws
// hsi::cuda::Error naming it, which the backend factory reports as its fallback reason.
#include <cublas_v2.h>
#include <cusolverDn.h>
#include <dlfcn.h>

#include <string>

#include "hsi/cuda/newton_core.h"

namespace {

struct Library {
  const char* soname;  // found through the program's run path, like a linked library
  const char* path;    // the build's copy, where the run path does not reach
};
constexpr Library kCublas{HSI_CUBLAS_SONAME, HSI_CUBLAS_PATH};
constexpr Library kCusolver{HSI_CUSOLVER_SONAME, HSI_CUSOLVER_PATH};

void* open_library(const Library& lib) {
  void* h = dlopen(lib.soname, RTLD_NOW | RTLD_LOCAL);
  if (!h) h = dlopen(lib.path, RTLD_NOW | RTLD_LOCAL);
  if (!h) {
    const char* why = dlerror();
    throw hsi::cuda::Error(std::string("cannot load ") + lib.soname + " (needed by the CUDA backend): " + (why ? why : "unknown reason"));
  }
  return h;
}

// Each library is opened once (thread-safe static initialisation).
void* handle_of(const Library& lib) {
  if (&lib == &kCublas) {
    static void* const h = open_library(kCublas);
    return h;
  }
  static void* const h = open_library(kCusolver);
  return h;
}

void* symbol(const Library& lib, const char* name) {
  void* const handle = handle_of(lib);
  void* const p = dlsym(handle, name);
  if (!p) throw hsi::cuda::Error(std::string(lib.soname) + " has no symbol " + name + " (another CUDA version than the build's?)");
  return p;
}

}  // namespace

// R name PARAMS forwards ARGS to the library's `name`, resolved once.
#define HSI_LAZY(lib, R, name, params, args)                                   \
  extern "C" R name params {                                                   \
    static const auto fn = reinterpret_cast<R(*) params>(symbol(lib, #name)); \
    return fn args;                                                            \
  }

HSI_LAZY(kCublas, cublasStatus_t, cublasCreate_v2, (cublasHandle_t * handle), (handle))
HSI_LAZY(kCublas, cublasStatus_t, cublasDestroy_v2, (cublasHandle_t handle), (handle))
HSI_LAZY(kCublas, cublasStatus_t, cublasSetStream_v2, (cublasHandle_t handle, cudaStream_t stream), (handle, stream))
HSI_LAZY(kCublas, cublasStatus_t, cublasSetPointerMode_v2, (cublasHandle_t handle, cublasPointerMode_t mode), (handle, mode))
HSI_LAZY(kCublas, cublasStatus_t, cublasSetWorkspace_v2, (cublasHandle_t handle, void* workspace, size_t bytes),
         (handle, workspace, bytes))
HSI_LAZY(kCublas, const char*, cublasGetStatusName, (cublasStatus_t status), (status))
HSI_LAZY(kCublas, const char*, cublasGetStatusString, (cublasStatus_t status), (status))
HSI_LAZY(kCublas, cublasStatus_t, cublasZgemm_v2,
         (cublasHandle_t h, cublasOperation_t ta, cublasOperation_t tb, int m, int n, int k, const cuDoubleComplex* alpha,
          const cuDoubleComplex* A, int lda, const cuDoubleComplex* B, int ldb, const cuDoubleComplex* beta, cuDoubleComplex* C,
          int ldc),
         (h, ta, tb, m, n, k, alpha, A, lda, B, ldb, beta, C, ldc))
HSI_LAZY(kCublas, cublasStatus_t, cublasDgemm_v2,
         (cublasHandle_t h, cublasOperation_t ta, cublasOperation_t tb, int m, int n, int k, const double* alpha, const double* A,
          int lda, const double* B, int ldb, const double* beta, double* C, int ldc),
         (h, ta, tb, m, n, k, alpha, A, lda, B, ldb, beta, C, ldc))
HSI_LAZY(kCublas, cublasStatus_t, cublasDgemmStridedBatched,
         (cublasHandle_t h, cublasOperation_t ta, cublasOperation_t tb, int m, int n, int k, const double* alpha, const double* A,
          int lda, long long int sa, const double* B, int ldb, long long int sb, const double* beta, double* C, int ldc,
          long long int sc, int batch),
         (h, ta, tb, m, n, k, alpha, A, lda, sa, B, ldb, sb, beta, C, ldc, sc, batch))
HSI_LAZY(kCublas, cublasStatus_t, cublasDgeam,
         (cublasHandle_t h, cublasOperation_t ta, cublasOperation_t tb, int m, int n, const double* alpha, const double* A, int lda,
          const double* beta, const double* B, int ldb, double* C, int ldc),
         (h, ta, tb, m, n, alpha, A, lda, beta, B, ldb, C, ldc))
HSI_LAZY(kCublas, cublasStatus_t, cublasDgemv_v2,
         (cublasHandle_t h, cublasOperation_t t, int m, int n, const double* alpha, const double* A, int lda, const double* x,
          int incx, const double* beta, double* y, int incy),
         (h, t, m, n, alpha, A, lda, x, incx, beta, y, incy))
HSI_LAZY(kCublas, cublasStatus_t, cublasDaxpy_v2,
         (cublasHandle_t h, int n, const double* alpha, const double* x, int incx, double* y, int incy),
         (h, n, alpha, x, incx, y, incy))
HSI_LAZY(kCublas, cublasStatus_t, cublasDscal_v2, (cublasHandle_t h, int n, const double* alpha, double* x, int incx),
         (h, n, alpha, x, incx))

HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnCreate, (cusolverDnHandle_t * handle), (handle))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnDestroy, (cusolverDnHandle_t handle), (handle))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnSetStream, (cusolverDnHandle_t handle, cudaStream_t stream), (handle, stream))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnDpotrf,
         (cusolverDnHandle_t h, cublasFillMode_t uplo, int n, double* A, int lda, double* work, int lwork, int* info),
         (h, uplo, n, A, lda, work, lwork, info))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnDpotrf_bufferSize,
         (cusolverDnHandle_t h, cublasFillMode_t uplo, int n, double* A, int lda, int* lwork), (h, uplo, n, A, lda, lwork))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnDpotrs,
         (cusolverDnHandle_t h, cublasFillMode_t uplo, int n, int nrhs, const double* A, int lda, double* B, int ldb, int* info),
         (h, uplo, n, nrhs, A, lda, B, ldb, info))
// cuSOLVER's other Cholesky entry points, timed against ours in bench_dense (issue #23).
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnCreateParams, (cusolverDnParams_t * params), (params))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnDestroyParams, (cusolverDnParams_t params), (params))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnXpotrf_bufferSize,
         (cusolverDnHandle_t h, cusolverDnParams_t params, cublasFillMode_t uplo, int64_t n, cudaDataType type_a, const void* A,
          int64_t lda, cudaDataType compute_type, size_t* device_bytes, size_t* host_bytes),
         (h, params, uplo, n, type_a, A, lda, compute_type, device_bytes, host_bytes))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnXpotrf,
         (cusolverDnHandle_t h, cusolverDnParams_t params, cublasFillMode_t uplo, int64_t n, cudaDataType type_a, void* A,
          int64_t lda, cudaDataType compute_type, void* device_buffer, size_t device_bytes, void* host_buffer, size_t host_bytes,
          int* info),
         (h, params, uplo, n, type_a, A, lda, compute_type, device_buffer, device_bytes, host_buffer, host_bytes, info))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnXpotrs,
         (cusolverDnHandle_t h, cusolverDnParams_t params, cublasFillMode_t uplo, int64_t n, int64_t nrhs, cudaDataType type_a,
          const void* A, int64_t lda, cudaDataType type_b, void* B, int64_t ldb, int* info),
         (h, params, uplo, n, nrhs, type_a, A, lda, type_b, B, ldb, info))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnDpotrfBatched,
         (cusolverDnHandle_t h, cublasFillMode_t uplo, int n, double* A_array[], int lda, int* info_array, int batch),
         (h, uplo, n, A_array, lda, info_array, batch))
HSI_LAZY(kCusolver, cusolverStatus_t, cusolverDnDpotrsBatched,
         (cusolverDnHandle_t h, cublasFillMode_t uplo, int n, int nrhs, double* A_array[], int lda, double* B_array[], int ldb,
          int* info, int batch),
         (h, uplo, n, nrhs, A_array, lda, B_array, ldb, info, batch))
