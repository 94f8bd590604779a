// Instruction-set selection at run time and the multithreaded driver of a trace call.
#pragma once
#include <string>
#include <vector>

#include "kernel.h"

namespace dacrt {

enum class Isa { Portable, Avx2, Avx512 };

std::vector<std::string> supported_isas();
std::string isa_name(Isa isa);
// "" -> best the CPU runs; otherwise that name, which must be supported (throws otherwise).
Isa resolve_isa(const std::string& requested);
int hardware_threads();
FieldsFn fields_fn(Isa isa);  // the ISA's SIMD check of ray fields

struct TraceResult {
    Stats stats;
    int threads = 1;
    double seconds = 0.0;
};

// Validates nothing (see ray.h validate_rays); traces rays[0, n) with `threads` threads
// (0 = all cores). Independent ray chunks per thread, as in the paper, with dynamic hand-out.
TraceResult trace(const TriangleSet& ts, Ray* rays, size_t n, const TraceJob& job, int threads, Isa isa);

}  // namespace dacrt
