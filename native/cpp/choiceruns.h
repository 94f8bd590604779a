// The light choice's cdf by runs (LightChoice::run_cdf): std::upper_bound(cdf, u) always lands
// on the first entry of a run of equal cdf values (the entry before it has a smaller value, or
// there is none), so a search over each run's value, the run's first entry kept beside it,
// lands on the same entry. With a light tree all members but the first have no mass of their
// own: many_lights' 373 entries are 3 runs, a search of 2 steps instead of 9 per point.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dacrt {

struct ChoiceRuns {
    std::vector<double> cdf;       // each run's value, strictly increasing
    std::vector<uint32_t> entry;   // each run's first entry
};

// The runs of cdf[0..n) into r; left empty (the whole cdf searched) unless cdf is
// non-decreasing and free of NaN, the order whose search is its partition point.
inline void choice_runs(const double* cdf, size_t n, ChoiceRuns& r) {
    r.cdf.clear();
    r.entry.clear();
    if (n >= (size_t(1) << 32)) return;
    for (size_t e = 0; e < n; ++e) {
        if (cdf[e] != cdf[e]) return r.cdf.clear(), r.entry.clear();
        if (e && cdf[e] < cdf[e - 1]) return r.cdf.clear(), r.entry.clear();
        if (e && cdf[e] == cdf[e - 1]) continue;
        r.cdf.push_back(cdf[e]);
        r.entry.push_back(uint32_t(e));
    }
}

}  // namespace dacrt
