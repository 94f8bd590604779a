// Triangles in one plane (see coplanar.h): quads merged, repeated keys found, in threaded passes
// over the triangles that write only a 4-byte tag each. Most meshes repeat no plane (a curved
// surface) or one huge plane (a flat grid, left out), so bitmaps of hash slots seen once and
// twice (in cache) leave few triangles to look up exactly, and the result is small. A sort of
// the keys or a hash partition of all of them had cost 20-60 ms per 1M triangles; the keys
// come from triangle_table's pass (computed here from the table's rows, a second read of 24
// bytes a triangle, they had cost ~8 ms more per 1M).
#include "coplanar.h"

#include <algorithm>
#include <utility>

#include "parallel.h"

namespace dacrt {

namespace {

inline uint64_t mixed(uint64_t k) { return k * 0x9E3779B97F4A7C15ull; }

// Triangles i and i + 1 (of one key) sharing an edge by index run in opposite directions, facing
// one way: a quad's (or a fan's neighbouring) two triangles, on either side of the edge.
inline bool quad_pair(const float* geo, size_t M, const int32_t* tri, size_t i) {
    const int32_t* a = tri + 3 * i;
    const int32_t* b = a + 3;
    bool shared = false;
    for (int k = 0; k < 3; ++k)
        for (int m = 0; m < 3; ++m) shared |= a[k] == b[(m + 1) % 3] && a[(k + 1) % 3] == b[m];
    if (!shared) return false;
    const float dot = geo[9 * M + i] * geo[9 * M + i + 1] + geo[10 * M + i] * geo[10 * M + i + 1] +
                      geo[11 * M + i] * geo[11 * M + i + 1];
    return dot > 0.0f;
}

// A thread's candidates: its keys' groups (count of listed triangles, and of all with the mates)
// in an open-addressing table that grows, and its rows, kept while a group is small enough.
struct LocalGroups {
    struct Group {
        uint64_t key;
        uint32_t listed, all;
    };
    std::vector<uint64_t> slot;
    std::vector<uint32_t> id;
    std::vector<Group> groups;
    std::vector<std::pair<uint32_t, uint32_t>> rows;  // (group, row | a mate follows << 31)
    int log = 0;                                      // slot.size() == 1 << log

    // (the product's top bits: they depend on every bit of the key)
    size_t home(uint64_t k) const { return size_t(mixed(k) >> (64 - log)); }

    size_t find(uint64_t k) const {
        size_t h = home(k);
        while (slot[h] != 0 && slot[h] != k) h = (h + 1) & (slot.size() - 1);
        return h;
    }

    void add(uint64_t k, uint32_t row, bool mate, size_t max_group) {
        const uint32_t at = group_of(k);
        Group& g = groups[at];
        ++g.listed;
        g.all += mate ? 2 : 1;
        if (g.all <= max_group) rows.emplace_back(at, row | (mate ? 0x80000000u : 0u));
    }

    uint32_t group_of(uint64_t k) {
        if (2 * (groups.size() + 1) > slot.size()) grow();
        const size_t h = find(k);
        if (slot[h] == 0) {
            slot[h] = k;
            id[h] = uint32_t(groups.size());
            groups.push_back({k, 0, 0});
        }
        return id[h];
    }

    void grow() {
        log = std::max(6, log + 1);
        const size_t cap = size_t(1) << log;
        slot.assign(cap, 0);
        id.assign(cap, 0);
        for (uint32_t g = 0; g < groups.size(); ++g) {
            size_t h = home(groups[g].key);
            while (slot[h] != 0) h = (h + 1) & (cap - 1);
            slot[h] = groups[g].key;
            id[h] = g;
        }
    }
};

}  // namespace

// 1: each thread reads its triangles' keys (the next one's kept for the quad test), tags the
// listed ones with their hash slot and marks the slot in its bitmaps of slots seen once and
// seen twice; 2: the bitmaps merged (a slot seen twice by all threads together); 3: each thread
// puts only its triangles in a slot seen twice (the repeats, and ~1/16 of the rest that share a
// slot) into a table of its own; 4: the threads' groups summed, those repeated and small
// enough kept. Nothing of size M but the tags is written.
void coplanar_groups(const uint64_t* keys, const float* geo, size_t M, const int32_t* tri, const uint8_t* candidates,
                     size_t max_group, std::vector<int64_t>& rows, std::vector<int64_t>& start) {
    rows.clear();
    start.assign(1, 0);
    if (M < 2) return;
    const int threads = threads_for(M, size_t(1) << 15);
    const size_t step = (M + size_t(threads) - 1) / size_t(threads);
    int bits = 10;
    while (bits < 23 && (size_t(1) << bits) < 16 * M) ++bits;
    const size_t words = (size_t(1) << bits) / 64;
    // A key's two slots, as in a Bloom filter: the first from its hash's top bits, the second
    // from those and the 7 bits below them. A key is a candidate where both slots were seen
    // twice: ~12% of 1M unique keys share one slot of 8M, ~1.5% both (the rest are keyed once)
    auto tag_of = [&](uint64_t k) { return uint32_t(mixed(k) >> (64 - bits - 7)); };   // slot << 7 | 7 bits
    auto second = [&](uint32_t t) { return uint32_t((uint64_t(t) * 0xC2B2AE3D27D4EB4Full) >> (64 - bits)); };
    constexpr uint32_t kListed = 0x80000000u, kMate = 0x40000000u, kHash = 0x3FFFFFFFu;
    std::vector<uint32_t> tag(M);  // 0: not listed; else listed | a mate follows | slot << 7 | 7 bits
    // per thread its bitmaps of slots seen once and twice, interleaved word by word (one cache
    // line for both), one pair per slot function; the keys of a block are computed first and
    // their words prefetched, so the random accesses overlap instead of stalling one by one
    std::vector<std::vector<uint64_t>> seen(static_cast<size_t>(threads)), seen2(static_cast<size_t>(threads));
    run_workers(threads, [&](int w) {
        const size_t b = std::min(M, size_t(w) * step), e = std::min(M, b + step);
        auto& bm = seen[size_t(w)];
        auto& bm2 = seen2[size_t(w)];
        bm.assign(2 * words, 0);
        bm2.assign(2 * words, 0);
        if (b >= e) return;
        auto plain_key = [&](size_t i) { return candidates[i] ? keys[i] : uint64_t(0); };
        auto pair = [&](size_t i, uint64_t k, uint64_t next) {
            return k != 0 && k == next && quad_pair(geo, M, tri, i);
        };
        bool q_prev = false, head_prev = false;
        if (b >= 1) {
            const uint64_t k1 = plain_key(b - 1), k0 = plain_key(b);
            q_prev = pair(b - 1, k1, k0);
            head_prev = q_prev && !(b >= 2 && pair(b - 2, plain_key(b - 2), k1));
        }
        constexpr size_t kBlock = 64;
        uint64_t kb[kBlock + 1];
        uint32_t hb[kBlock], sb[kBlock];
        uint64_t first = plain_key(b);
        for (size_t i0 = b; i0 < e; i0 += kBlock) {
            const size_t n = std::min(kBlock, e - i0);
            kb[0] = first;
            // keys i0 + 1 .. i0 + n (the last one the next block's first), 0 past M - 1
            const size_t m = std::min(n, M - 1 - i0);
            for (size_t j = 1; j <= m; ++j)
                kb[j] = keys[i0 + j] & (uint64_t(0) - uint64_t(candidates[i0 + j] != 0));
            for (size_t j = m + 1; j <= n; ++j) kb[j] = 0;
            for (size_t j = 0; j < n; ++j) {
                hb[j] = tag_of(kb[j]);
                sb[j] = second(hb[j]);
                __builtin_prefetch(&bm[2 * ((hb[j] >> 7) >> 6)], 1);
                __builtin_prefetch(&bm2[2 * (sb[j] >> 6)], 1);
            }
            for (size_t j = 0; j < n; ++j) {
                const size_t i = i0 + j;
                const bool q = i + 1 < M && pair(i, kb[j], kb[j + 1]);
                const bool head = q && !q_prev;
                if (kb[j] != 0 && !head_prev) {
                    const uint32_t s = hb[j] >> 7, s2 = sb[j];
                    uint64_t* word = &bm[2 * (s >> 6)];
                    word[1] |= word[0] & (uint64_t(1) << (s & 63));
                    word[0] |= uint64_t(1) << (s & 63);
                    uint64_t* word2 = &bm2[2 * (s2 >> 6)];
                    word2[1] |= word2[0] & (uint64_t(1) << (s2 & 63));
                    word2[0] |= uint64_t(1) << (s2 & 63);
                    tag[i] = kListed | (head ? kMate : 0u) | hb[j];
                } else {
                    tag[i] = 0;
                }
                q_prev = q;
                head_prev = head;
            }
            first = kb[n];
        }
    });
    // 2: seen twice by one thread, or once by two
    std::vector<uint64_t> twice(words), twice2(words);
    parallel_for(words, [&](size_t w0, size_t w1) {
        for (size_t j = w0; j < w1; ++j) {
            uint64_t o = seen[0][2 * j], t = seen[0][2 * j + 1], o2 = seen2[0][2 * j], t2 = seen2[0][2 * j + 1];
            for (int w = 1; w < threads; ++w) {
                t |= seen[size_t(w)][2 * j + 1] | (o & seen[size_t(w)][2 * j]);
                o |= seen[size_t(w)][2 * j];
                t2 |= seen2[size_t(w)][2 * j + 1] | (o2 & seen2[size_t(w)][2 * j]);
                o2 |= seen2[size_t(w)][2 * j];
            }
            twice[j] = t;
            twice2[j] = t2;
        }
    }, size_t(1) << 14);
    // 3: the triangles in slots seen twice looked up (their words prefetched ahead)
    std::vector<LocalGroups> local(static_cast<size_t>(threads));
    run_workers(threads, [&](int w) {
        const size_t b = std::min(M, size_t(w) * step), e = std::min(M, b + step);
        LocalGroups& g = local[size_t(w)];
        constexpr size_t kAhead = 32;
        for (size_t i = b; i < e; ++i) {
            if (i + kAhead < e && tag[i + kAhead] & kListed) {
                const uint32_t h = tag[i + kAhead] & kHash;
                __builtin_prefetch(&twice[(h >> 7) >> 6]);
                __builtin_prefetch(&twice2[second(h) >> 6]);
            }
            const uint32_t t = tag[i];
            if (!(t & kListed)) continue;
            const uint32_t s = (t & kHash) >> 7, s2 = second(t & kHash);
            if (!(twice[s >> 6] >> (s & 63) & 1) || !(twice2[s2 >> 6] >> (s2 & 63) & 1)) continue;
            g.add(keys[i], uint32_t(i), t & kMate, max_group);
        }
    });
    // 4: the groups summed over threads (few: the repeats and the slots they share)
    LocalGroups all;
    for (const auto& g : local)
        for (const auto& x : g.groups) {
            auto& sum = all.groups[all.group_of(x.key)];
            sum.listed += x.listed;
            sum.all += x.all;
        }
    std::vector<std::pair<uint64_t, int64_t>> kept;
    for (const auto& g : local)
        for (const auto& [gid, r] : g.rows) {
            const uint64_t key = g.groups[gid].key;
            const auto& sum = all.groups[all.id[all.find(key)]];
            if (sum.listed < 2 || sum.all > max_group) continue;
            const int64_t row = int64_t(r & 0x7FFFFFFFu);
            kept.emplace_back(key, row);
            if (r & 0x80000000u) kept.emplace_back(key, row + 1);
        }
    std::sort(kept.begin(), kept.end());
    start.clear();
    for (size_t j = 0; j < kept.size(); ++j) {
        if (j == 0 || kept[j].first != kept[j - 1].first) start.push_back(int64_t(rows.size()));
        rows.push_back(kept[j].second);
    }
    start.push_back(int64_t(rows.size()));
}

}  // namespace dacrt
