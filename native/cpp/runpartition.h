// The filter's in-place partition of ray records (filter.h; the chunk cuts, chunkorder.cpp, use
// its run size and record swap for their forward sweep): Hoare-style on runs of 64 records from both ends, each run classified
// at once into a mask word (one bit per record, set: the record goes to the front), so only
// misplaced records move (about p(1-p)n swaps for a front share p, against pn for a one-sided
// sweep) and the branches are per run, not per record. Included inside a namespace of its
// user (an ISA namespace for the filter), so every instruction set gets its own copy.
#pragma once

constexpr size_t kRunRays = 64;

// Exchanges two records; a == b is allowed (each copy goes through a temporary).
inline void swap_records(Ray* a, Ray* b) {
    Ray ta, tb;
    std::memcpy(&ta, a, sizeof(Ray));
    std::memcpy(&tb, b, sizeof(Ray));
    std::memcpy(a, &tb, sizeof(Ray));
    std::memcpy(b, &ta, sizeof(Ray));
}

// Moves the records of rays[0, n) that run(p) marks (bit k: record p + k, for the kRunRays
// records from p) to the front, runs from both ends, until fewer than a run's worth remain
// between them. Returns the range [b, e) left unsettled (under 3 runs): [0, b) holds only
// marked records, [e, n) only unmarked ones; the caller partitions [b, e) by its own rule.
template <class Run>
__attribute__((always_inline)) inline void partition_runs(Ray* rays, size_t n, Run run, size_t& b, size_t& e) {
    size_t i = 0, j = n;    // [0, i) settled marked (but a pending left run), [j, n) unmarked
    size_t li = 0, rj = 0;  // pending runs
    uint64_t ml = 0, mr = 0;  // unmarked records of the left run, marked records of the right run
    // The masks of the next unclaimed run on each side, taken before a swap loop (at pl, pr;
    // SIZE_MAX: none), so the box tests overlap the swaps' dependency chain instead of waiting
    // for the loop's mispredicted exit. A mask is used only while its run is still the next
    // one on its side and unclaimed (j - i >= kRunRays): the swaps touch claimed runs only,
    // and a claim by the other side overlapping it leaves j - i < kRunRays.
    size_t pl = SIZE_MAX, pr = SIZE_MAX;
    uint64_t mpl = 0, mpr = 0;
    for (;;) {
        while (ml == 0 && j - i >= kRunRays) {
            ml = ~(pl == i ? mpl : run(rays + i));
            li = i;
            i += kRunRays;
        }
        while (mr == 0 && j - i >= kRunRays) {
            j -= kRunRays;
            mr = pr == j ? mpr : run(rays + j);
            rj = j;
        }
        if (ml == 0 || mr == 0) break;
        if (j - i >= kRunRays) {
            if (pl != i) {
                mpl = run(rays + i);
                pl = i;
            }
            if (pr != j - kRunRays) {
                mpr = run(rays + j - kRunRays);
                pr = j - kRunRays;
            }
        }
        do {
            swap_records(rays + li + __builtin_ctzll(ml), rays + rj + __builtin_ctzll(mr));
            ml &= ml - 1;
            mr &= mr - 1;
        } while (ml && mr);
    }
    b = ml ? li : i;
    e = mr ? rj + kRunRays : j;
}
