// Filling frame buffers with streaming stores (core/stream-inl.h), dispatched at run time to the
// machine's instruction set.
#pragma once
#include <cstddef>
#include <cstdint>

namespace hsr {

/// dst[i] = value for i < n, the cache lines covered whole written with streaming stores; fenced
/// before it returns (other threads may read dst once they know the call returned).
void streamFill(uint32_t* dst, uint32_t value, size_t n);

}  // namespace hsr
