// Object partitioning (Afra 2012): reorder the triangle id array in place into two disjoint
// halves, quicksort-like, reading the precomputed triangle boxes; each child's box and centroid
// box are accumulated during the same sweep, so no extra pass over the triangles is needed.
// Two split choices: spatial median of the centroid bounds (fast) and binned SAH (better
// splits, one extra binning pass). Scalar code, identical on every ISA.
// Included inside an ISA namespace.
#pragma once

// Four-lane float vectors via the compiler's vector extension: SSE on x86, NEON elsewhere, the
// same IEEE min/max/add/mul per lane everywhere. Lane 3 is padding.
typedef float v4f __attribute__((vector_size(16)));
typedef int32_t v4i __attribute__((vector_size(16)));

inline v4f v4_load(const float* p) { v4f r; std::memcpy(&r, p, sizeof(r)); return r; }
inline v4f v4_min(v4f a, v4f b) { return a < b ? a : b; }
inline v4f v4_max(v4f a, v4f b) { return a > b ? a : b; }

// Box and centroid box of a triangle set, accumulated in registers during a sweep.
struct Grow {
    v4f lo, hi, clo, chi;
    Grow() : lo(v4f{} + INFINITY), hi(v4f{} - INFINITY), clo(v4f{} + INFINITY), chi(v4f{} - INFINITY) {}
    void add(const Box& t) {
        const v4f l = v4_load(t.lo), h = v4_load(t.hi);
        lo = v4_min(lo, l);
        hi = v4_max(hi, h);
        const v4f c = l * 0.5f + h * 0.5f;  // centre(), lane-wise
        clo = v4_min(clo, c);
        chi = v4_max(chi, c);
    }
    void store(NodeBounds& b) const {
        for (int a = 0; a < 3; ++a) { b.lo[a] = lo[a]; b.hi[a] = hi[a]; b.clo[a] = clo[a]; b.chi[a] = chi[a]; }
    }
};

inline void nb_empty(NodeBounds& b) { Grow().store(b); }

// The sweeps read boxes[ids[i]] in id order, which the scene's order may scatter over a few MB
// (San Francisco: 268K boxes, 8.6 MB): each read missed L2 and the branchy loop had few of them
// in flight. Prefetching the box 16 ids ahead on both ends: partition phase -5..-9% (min over
// runs 20.4 -> 19.3 ms a call), trace +2% (median of 6 alternating runs, 1 thread, San Francisco
// diffuse rays; 32 ahead the same). Ids and splits are unchanged.
constexpr size_t kPartitionPrefetch = 16;

// Hoare partition by pred; every id is classified exactly once and grows its side's bounds.
template <class Pred>
size_t partition_ids(uint32_t* ids, size_t n, const Box* boxes, Pred pred, NodeBounds& L, NodeBounds& R) {
    Grow gl, gr;
    size_t i = 0, j = n;
    constexpr size_t D = kPartitionPrefetch;
    for (;;) {
        while (i < j && pred(ids[i])) {
            if (i + D < n) __builtin_prefetch(boxes + ids[i + D]);
            gl.add(boxes[ids[i++]]);
        }
        while (i < j && !pred(ids[j - 1])) {
            if (j > D) __builtin_prefetch(boxes + ids[j - 1 - D]);
            gr.add(boxes[ids[--j]]);
        }
        if (i >= j) break;
        std::swap(ids[i], ids[j - 1]);
        gl.add(boxes[ids[i++]]);
        gr.add(boxes[ids[--j]]);
    }
    gl.store(L);
    gr.store(R);
    return i;
}

// partition_ids, stable: ids that pass pred keep their order at the front, the rest theirs
// behind (through tmp, n ids). For the shared top, which splits every id of the scene once per
// level (San Francisco: ~13 levels of 268K ids, ~12% of a call's CPU time without a kept top):
// Hoare's swaps turn the ascending root order into runs read up and down, kept ascending a
// node's box reads go one way through memory. Measured (San Francisco 1M rays, 2 threads,
// process CPU time, alternating processes, load 16-20): diffuse 0.93-0.97x, shadow 0.97x,
// dragon diffuse 0.99x; stable private splits as well 1.03x (small nodes, in cache, where
// Hoare's predictable branches win), stable from 16 ids instead of 1024 1.05x. Splits and
// hits do not depend on the order (a split is a function of the set, ties broken by id).
template <class Pred>
size_t partition_ids_stable(uint32_t* ids, size_t n, const Box* boxes, Pred pred, NodeBounds& L, NodeBounds& R,
                            uint32_t* tmp) {
    Grow gl, gr;
    size_t w = 0, r = 0;
    constexpr size_t D = kPartitionPrefetch;
    for (size_t i = 0; i < n; ++i) {
        if (i + D < n) __builtin_prefetch(boxes + ids[i + D]);
        const uint32_t id = ids[i];
        const bool left = pred(id);
        ids[w] = id;  // w <= i: never ahead of the read
        tmp[r] = id;
        w += left;
        r += !left;
        if (left) gl.add(boxes[id]);
        else gr.add(boxes[id]);
    }
    std::memcpy(ids + w, tmp, r * sizeof(uint32_t));
    gl.store(L);
    gr.store(R);
    return w;
}

// Nodes of at least this many ids are partitioned stably when the caller gives scratch.
constexpr size_t kStablePartitionIds = 1024;

template <class Pred>
size_t partition_ids_by(uint32_t* ids, size_t n, const Box* boxes, Pred pred, NodeBounds& L, NodeBounds& R,
                        uint32_t* tmp) {
    if (tmp && n >= kStablePartitionIds) return partition_ids_stable(ids, n, boxes, pred, L, R, tmp);
    return partition_ids(ids, n, boxes, pred, L, R);
}

// Fallback that always halves: object median by centre along the widest centroid axis.
inline size_t split_object_median(uint32_t* ids, size_t n, const Box* boxes, const NodeBounds& nb,
                                  NodeBounds& L, NodeBounds& R, int& axis_out) {
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (nb.chi[a] - nb.clo[a] > nb.chi[axis] - nb.clo[axis]) axis = a;
    axis_out = axis;
    const size_t k = n / 2;
    std::nth_element(ids, ids + k, ids + n, [&](uint32_t x, uint32_t y) {
        const float cx = centre(boxes[x].lo[axis], boxes[x].hi[axis]);
        const float cy = centre(boxes[y].lo[axis], boxes[y].hi[axis]);
        return cx < cy || (cx == cy && x < y);
    });
    Grow gl, gr;
    for (size_t i = 0; i < k; ++i) gl.add(boxes[ids[i]]);
    for (size_t i = k; i < n; ++i) gr.add(boxes[ids[i]]);
    gl.store(L);
    gr.store(R);
    return k;
}

// Spatial median: split the centroid bounds at the middle of their widest axis.
inline size_t split_median(uint32_t* ids, size_t n, const Box* boxes, const NodeBounds& nb,
                           NodeBounds& L, NodeBounds& R, int& axis_out, uint32_t* tmp = nullptr) {
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (nb.chi[a] - nb.clo[a] > nb.chi[axis] - nb.clo[axis]) axis = a;
    axis_out = axis;
    const float mid = centre(nb.clo[axis], nb.chi[axis]);
    if (!(nb.chi[axis] > nb.clo[axis])) return 0;  // all centres coincide
    return partition_ids_by(ids, n, boxes, [&](uint32_t t) {
        return centre(boxes[t].lo[axis], boxes[t].hi[axis]) < mid;
    }, L, R, tmp);
}

// Binned SAH over the three axes (16 bins, centroid binning as in Wald 2007), all three axes
// binned in one vectorised pass. Areas in double: coordinates near 1e19 would overflow floats.
inline size_t split_sah(uint32_t* ids, size_t n, const Box* boxes, const NodeBounds& nb,
                        NodeBounds& L, NodeBounds& R, int& axis_out, uint32_t* tmp = nullptr) {
    constexpr int B = 16;
    struct Bin { v4f lo, hi; };
    Bin bins[3][B];
    uint32_t count[3][B] = {};
    float scale_s[4] = {0, 0, 0, 0}, clo_s[4] = {0, 0, 0, 0};
    for (int a = 0; a < 3; ++a) {
        const float ext = nb.chi[a] - nb.clo[a];
        float sc = ext > 0.0f ? float(B) * (1.0f - 0x1p-20f) / ext : 0.0f;
        scale_s[a] = std::isfinite(sc) ? sc : 0.0f;
        clo_s[a] = nb.clo[a];
        for (int b = 0; b < B; ++b) { bins[a][b].lo = v4f{} + INFINITY; bins[a][b].hi = v4f{} - INFINITY; }
    }
    const v4f scale = v4_load(scale_s), clo = v4_load(clo_s);
    const v4f top = v4f{} + float(B - 1);
    auto bin_index = [&](const Box& t) {
        const v4f l = v4_load(t.lo), h = v4_load(t.hi);
        v4f f = (l * 0.5f + h * 0.5f - clo) * scale;
        f = v4_max(v4_min(f, top), v4f{});
        return __builtin_convertvector(f, v4i);
    };
    for (size_t i = 0; i < n; ++i) {
        const Box& t = boxes[ids[i]];
        const v4f l = v4_load(t.lo), h = v4_load(t.hi);
        const v4i b = bin_index(t);
        for (int a = 0; a < 3; ++a) {
            Bin& bn = bins[a][b[a]];
            bn.lo = v4_min(bn.lo, l);
            bn.hi = v4_max(bn.hi, h);
            ++count[a][b[a]];
        }
    }
    auto half_area = [](v4f lo, v4f hi) {
        const double x = double(hi[0]) - lo[0], y = double(hi[1]) - lo[1], z = double(hi[2]) - lo[2];
        return x * y + y * z + z * x;
    };
    double best = INFINITY;
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3; ++a) {
        if (scale_s[a] == 0.0f) continue;
        double right_cost[B];
        v4f lo = v4f{} + INFINITY, hi = v4f{} - INFINITY;
        uint32_t cnt = 0;
        for (int b = B - 1; b > 0; --b) {
            lo = v4_min(lo, bins[a][b].lo);
            hi = v4_max(hi, bins[a][b].hi);
            cnt += count[a][b];
            right_cost[b] = cnt ? half_area(lo, hi) * cnt : 0.0;
        }
        lo = v4f{} + INFINITY;
        hi = v4f{} - INFINITY;
        cnt = 0;
        for (int b = 0; b < B - 1; ++b) {  // split between bin b and b + 1
            lo = v4_min(lo, bins[a][b].lo);
            hi = v4_max(hi, bins[a][b].hi);
            cnt += count[a][b];
            if (cnt == 0 || cnt == n) continue;
            const double cost = half_area(lo, hi) * cnt + right_cost[b + 1];
            if (cost < best) { best = cost; best_axis = a; best_bin = b; }
        }
    }
    axis_out = best_axis;
    if (best_axis < 0) return 0;
    return partition_ids_by(ids, n, boxes, [&](uint32_t t) { return bin_index(boxes[t])[best_axis] <= best_bin; }, L, R,
                            tmp);
}
