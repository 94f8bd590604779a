// Entry points of the per-ISA kernels. Each is the same template code (filter, partition, leaf,
// trace) compiled in its own translation unit with its own instruction set and namespace.
#pragma once
#include <cstddef>
#include <cstdint>

#include "ray.h"
#include "triangles.h"

namespace dacrt {

struct TraceJob {
    const TriangleSet* ts;
    Config cfg;
    Query query;
    Hit* hits;            // Closest: output by ray id
    uint8_t* occluded;    // Any: output by ray id
    float origin_abs_max; // largest |origin coordinate| over the batch (box padding)
};

// Trace rays[0, n) against all valid triangles; ids: a scratch copy of ts.valid_ids.
using ChunkFn = void (*)(const TraceJob&, Ray*, size_t, uint32_t*, Stats&);
namespace portable { void trace_chunk(const TraceJob&, Ray*, size_t, uint32_t*, Stats&); }
namespace avx2 { void trace_chunk(const TraceJob&, Ray*, size_t, uint32_t*, Stats&); }
namespace avx512 { void trace_chunk(const TraceJob&, Ray*, size_t, uint32_t*, Stats&); }

}  // namespace dacrt
