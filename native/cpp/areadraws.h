// Next-event estimation's light samples of the area lamps (nextevent.cpp), drawn for a chunk of
// points before its point-by-point loop: the points that picked an area lamp without spread
// (area_lanes_apply) are drawn and weighted kLampLanes at a time (arealanes.h), in the float32
// operations of sample_lamp and nee_scale, so with the same bits.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nextevent.h"

namespace dacrt {

// A light sample of one point, weighted (nee_scale): direction, distance, value and whether
// it can contribute.
struct Drawn {
    float wi[3], dist, value[3];
    bool ok;
};

// The entries the chunk's cnt points (i0..) pick and their selection probabilities (pick_entry,
// nextevent.h), for the whole chunk before its draws.
void pick_entries(const LightChoice& L, const VertexPoints& p, size_t i0, size_t cnt, uint32_t* entry, float* p_sel);

// Draws the samples of the chunk's points (i0.., words wa, wb; entries and p_sel from
// pick_entries) that picked an area lamp, lamp by lamp, kLampLanes at a time, into out[j];
// drawn[j] says which. A chunk that reaches more than four such lamps leaves the points of the
// others to sample_lamp, one at a time.
void draw_chunk(const LightChoice& L, const VertexPoints& p, size_t i0, size_t cnt, const uint32_t* entry,
                const float* p_sel, const uint32_t* wa, const uint32_t* wb, Drawn* out, uint8_t* drawn);

}  // namespace dacrt
