// The kernel of the CUDA mesh evaluator (mesh_evaluator.cpp) behind a plain launch
// function, as newton_kernels.h: complex values are double2, matrices column-major.
#pragma once

#include <cuda_runtime.h>

namespace hsi::cuda::kernels {

// Per point p of P, with the rows C (and D, may be null) P × M and the coefficients
// coef = [φ | ψ] (2M): f_p = Σ_j C_pj φ_j + conj(Σ_j C_pj ψ_j), and where D is given
// f_z,p = Σ_j D_pj φ_j and conj f_zbar,p = Σ_j D_pj ψ_j (harmonic_map.h). out holds
// f, then (with D) f_z, then conj f_zbar: P values each. One thread per point: the
// rows are read once, coalesced, and every thread reads the same coefficient.
cudaError_t mesh_values(long long P, int M, const double2* C, const double2* D, const double2* coef, double2* out,
                        cudaStream_t stream);

}  // namespace hsi::cuda::kernels
