// Path compaction between bounces (see shading.h): the columns idx of several per-path arrays
// gathered in one threaded pass, instead of one single-threaded np.take per array; or a few
// columns dropped in place (drop_columns).
#include <cstring>
#include <utility>
#include <vector>

#include "parallel.h"
#include "shading.h"

namespace dacrt {

namespace {

template <class T>
void gather_rows(const Columns& c, const int64_t* idx, size_t k, size_t b, size_t e) {
    const T* src = static_cast<const T*>(c.src);
    T* dst = static_cast<T*>(c.dst);
    for (size_t r = 0; r < c.rows; ++r) {
        const T* s = src + r * c.n;
        T* d = dst + r * k;
        for (size_t j = b; j < e; ++j) d[j] = s[index_at(idx, j, c.n)];
    }
}

}  // namespace

void take_columns(const Columns* arrays, size_t count, const int64_t* idx, size_t k) {
    parallel_for(k, [arrays, count, idx, k](size_t b, size_t e) {
        for (size_t a = 0; a < count; ++a) {
            const Columns& c = arrays[a];
            switch (c.itemsize) {
                case 1: gather_rows<uint8_t>(c, idx, k, b, e); break;
                case 2: gather_rows<uint16_t>(c, idx, k, b, e); break;
                case 4: gather_rows<uint32_t>(c, idx, k, b, e); break;
                default: gather_rows<uint64_t>(c, idx, k, b, e); break;
            }
        }
    }, size_t(1) << 15);
}

size_t drop_columns(const uint8_t* keep, size_t n, const Columns* arrays, size_t count, Ray* rays) {
    std::vector<std::pair<size_t, size_t>> runs;  // the kept runs (start, length) past the first drop
    size_t first = 0;
    while (first < n && keep[first]) ++first;
    if (first == n) return n;
    for (size_t j = first; j < n;) {
        while (j < n && !keep[j]) ++j;
        const size_t b = j;
        while (j < n && keep[j]) ++j;
        if (j > b) runs.emplace_back(b, j - b);
    }
    size_t m = first;
    for (const auto& r : runs) m += r.second;
    // every destination lies at or before its source and before every later source (m <= n),
    // so rows and runs move forward in order; a run overlapping its own destination: memmove
    auto move = [&](char* base, size_t rows, size_t size) {
        for (size_t r = 0; r < rows; ++r) {
            if (r) std::memmove(base + r * m * size, base + r * n * size, first * size);
            size_t w = r * m + first;
            for (const auto& run : runs) {
                std::memmove(base + w * size, base + (r * n + run.first) * size, run.second * size);
                w += run.second;
            }
        }
    };
    for (size_t a = 0; a < count; ++a) move(static_cast<char*>(arrays[a].dst), arrays[a].rows, arrays[a].itemsize);
    if (rays) {
        move(reinterpret_cast<char*>(rays), 1, sizeof(Ray));
        for (size_t j = first; j < m; ++j) rays[j].id = uint32_t(j);
    }
    return m;
}

}  // namespace dacrt
