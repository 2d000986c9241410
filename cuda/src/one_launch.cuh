// One-launch reductions (newton_kernels.h, certify_kernels.h): every block writes its
// partial results, and the block that counts last on a device counter finishes them in
// a fixed order, so a reduction is one launch instead of a partials pass and a
// finishing pass, and its result does not depend on which block came last.
#pragma once

namespace hsi::cuda::kernels {

// Called by every thread of a block after its thread 0 wrote the block's partial
// results: true, in every thread, in the block that counted last, whose threads may
// then read every block's partials; that block also sets the counter back to 0 for the
// next launch (every block has counted by then). One launch instead of a partials pass
// and a finishing pass: the partials are summed by one block in a fixed order, so the
// result does not depend on which block came last. Partials are read with __ldcg (from
// L2, where the other blocks' writes are, never a stale L1 line).
__device__ inline bool last_block_done(unsigned* __restrict__ done) {
  __shared__ bool last;
  if (threadIdx.x == 0) {
    __threadfence();  // this block's partials are visible device-wide before it counts
    last = atomicAdd(done, 1u) == gridDim.x - 1;
    if (last) {
      *done = 0;
      __threadfence();  // the other blocks' partials, counted before, are read after this
    }
  }
  __syncthreads();
  return last;
}

}  // namespace hsi::cuda::kernels
