// Which rays missed everything, as lamp_gather and environment_gather read it for the lamps at
// infinity: the caller's flags, or the tracer's hit records read in place (prim < 0). Flags made
// from the records had cost the calling thread a pass over them at every path vertex (numpy's
// `prim >= 0`, then `~hit`) on the world-lit scenes, whose gathers alone read them.
#pragma once

#include <cstddef>
#include <cstdint>

#include "ray.h"

namespace dacrt {

struct Missed {
    const uint8_t* flags = nullptr;  // flags[i] != 0: ray i missed; or, with flags null,
    const Hit* hits = nullptr;       // hits[i].prim < 0 (null both: not given, never read)
    bool operator()(size_t i) const { return flags ? flags[i] != 0 : hits[i].prim < 0; }
};

}  // namespace dacrt
