// Validation of a ray batch before tracing.
#pragma once
#include <string>

#include "kernel.h"

namespace dacrt {

// Return "" when the batch is valid, else a message naming the first bad ray and field. The
// output array (indexed by ray id) doubles as the mark array that finds repeated ids, so
// validation allocates nothing; on success it holds all misses / all unoccluded.
// info receives what the trace needs to know of the batch (kernel.h BatchInfo).
// fields: the ISA's SIMD field check (dispatch.h fields_fn). threads: at most this many
// threads (0 = all cores), as the trace call that follows.
std::string validate_rays(const Ray* rays, size_t n, Hit* hits, FieldsFn fields, BatchInfo& info, int threads);
std::string validate_rays(const Ray* rays, size_t n, uint8_t* occluded, FieldsFn fields, BatchInfo& info,
                          int threads);

}  // namespace dacrt
