// Path compaction between bounces (see shading.h): the columns idx of several per-path arrays
// gathered in one threaded pass, instead of one single-threaded np.take per array.
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

}  // namespace dacrt
