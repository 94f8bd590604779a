// The light choice's cdf by runs (LightChoice::run_cdf): std::upper_bound(cdf, u) always lands
// on the first entry of a run of equal cdf values (the entry before it has a smaller value, or
// there is none), so a search over each run's value, the run's first entry kept beside it,
// lands on the same entry. With a light tree all members but the first have no mass of their
// own: many_lights' 373 entries are 3 runs, a search of 2 steps instead of 9 per point.
// Building them reads every entry (a million emissive triangles in a tree: ~1M doubles), so a
// frame builds them once with its light choice (dacrt.shading.LightChoice) and each kernel call
// only checks them (choice_runs_error, O(runs)).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
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

// Empty when run_cdf, run_entry (r runs) can be cdf[0..n)'s runs, else what is wrong: each
// run starts where the cdf steps up to its value and holds it until the next run (or the end).
// O(runs): the entries inside a run are not read, so runs of another cdf equal at the runs'
// bounds pass; they are meant to come from choice_runs of the same cdf. No runs always pass
// (the whole cdf is searched).
inline std::string choice_runs_error(const double* cdf, size_t n, const double* run_cdf, const uint32_t* run_entry,
                                     size_t r) {
    if (r == 0) return {};
    if (r > n) return std::to_string(r) + " runs for " + std::to_string(n) + " entries";
    if (run_entry[0] != 0) return "the first run starts at entry " + std::to_string(run_entry[0]) + ", not 0";
    for (size_t k = 0; k < r; ++k) {
        const size_t e = run_entry[k];
        const char* wrong = nullptr;
        if (e >= n || (k && e <= run_entry[k - 1])) wrong = "the runs' entries must increase, each below the entries";
        else if (!(run_cdf[k] == cdf[e])) wrong = "its value is not the cdf's there";
        else if (k && !(run_cdf[k - 1] < run_cdf[k] && cdf[e - 1] == run_cdf[k - 1]))
            wrong = "the previous run does not end just before it";
        if (wrong) return "run " + std::to_string(k) + " (entry " + std::to_string(e) + "): " + wrong;
    }
    if (!(cdf[n - 1] == run_cdf[r - 1])) return "the last run does not reach the last entry";
    return {};
}

}  // namespace dacrt
