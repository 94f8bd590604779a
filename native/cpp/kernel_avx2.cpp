// The DACRT kernel compiled for the avx2 instruction set (8 rays per SIMD step).
#include <immintrin.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <thread>
#include <utility>

#include "kernel.h"

namespace dacrt {
namespace avx2 {
#include "simd/avx2.h"
#include "rayblock.h"
#include "filter.h"
#include "partition.h"
#include "leaf.h"
#include "trace.h"
#include "validate.h"

void trace_chunk(const TraceJob& job, Ray* rays, size_t n, uint32_t* ids, Stats& st) {
    trace_chunk_w<8>(job, rays, n, ids, st);
}

void trace_task(const TraceJob& job, StolenTask& t, uint32_t* ids, Stats& st) {
    trace_task_w<8>(job, t, ids, st);
}

bool fields_valid(const Ray* rays, size_t n, BatchInfo& info) {
    return fields_valid_w<8>(rays, n, info);
}
}  // namespace avx2
}  // namespace dacrt
