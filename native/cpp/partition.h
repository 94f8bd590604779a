// Object partitioning (Afra 2012): reorder the triangle id array in place into two disjoint
// halves, quicksort-like, reading the precomputed triangle boxes; each child's box and centroid
// box are accumulated during the same sweep, so no extra pass over the triangles is needed.
// Two split choices: spatial median of the centroid bounds (fast) and binned SAH (better
// splits, one extra binning pass). Scalar code, identical on every ISA.
// Included inside an ISA namespace.
#pragma once

inline void nb_empty(NodeBounds& b) {
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = b.clo[a] = INFINITY;
        b.hi[a] = b.chi[a] = -INFINITY;
    }
}

inline void nb_grow(NodeBounds& b, const Box& t) {
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = std::min(b.lo[a], t.lo[a]);
        b.hi[a] = std::max(b.hi[a], t.hi[a]);
        const float c = centre(t.lo[a], t.hi[a]);
        b.clo[a] = std::min(b.clo[a], c);
        b.chi[a] = std::max(b.chi[a], c);
    }
}

// Hoare partition by pred; every id is classified exactly once and grows its side's bounds.
template <class Pred>
size_t partition_ids(uint32_t* ids, size_t n, const Box* boxes, Pred pred, NodeBounds& L, NodeBounds& R) {
    nb_empty(L);
    nb_empty(R);
    size_t i = 0, j = n;
    for (;;) {
        while (i < j && pred(ids[i])) nb_grow(L, boxes[ids[i++]]);
        while (i < j && !pred(ids[j - 1])) nb_grow(R, boxes[ids[--j]]);
        if (i >= j) break;
        std::swap(ids[i], ids[j - 1]);
        nb_grow(L, boxes[ids[i++]]);
        nb_grow(R, boxes[ids[--j]]);
    }
    return i;
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
    nb_empty(L);
    nb_empty(R);
    for (size_t i = 0; i < k; ++i) nb_grow(L, boxes[ids[i]]);
    for (size_t i = k; i < n; ++i) nb_grow(R, boxes[ids[i]]);
    return k;
}

// Spatial median: split the centroid bounds at the middle of their widest axis.
inline size_t split_median(uint32_t* ids, size_t n, const Box* boxes, const NodeBounds& nb,
                           NodeBounds& L, NodeBounds& R, int& axis_out) {
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (nb.chi[a] - nb.clo[a] > nb.chi[axis] - nb.clo[axis]) axis = a;
    axis_out = axis;
    const float mid = centre(nb.clo[axis], nb.chi[axis]);
    if (!(nb.chi[axis] > nb.clo[axis])) return 0;  // all centres coincide
    return partition_ids(ids, n, boxes, [&](uint32_t t) {
        return centre(boxes[t].lo[axis], boxes[t].hi[axis]) < mid;
    }, L, R);
}

// Binned SAH over the three axes (16 bins, centroid binning as in Wald 2007). Areas in double:
// coordinates near 1e19 would overflow float products.
inline size_t split_sah(uint32_t* ids, size_t n, const Box* boxes, const NodeBounds& nb,
                        NodeBounds& L, NodeBounds& R, int& axis_out) {
    constexpr int B = 16;
    struct Bin { float lo[3], hi[3]; uint32_t count; };
    Bin bins[3][B];
    float scale[3];
    for (int a = 0; a < 3; ++a) {
        const float ext = nb.chi[a] - nb.clo[a];
        scale[a] = ext > 0.0f ? float(B) * (1.0f - 0x1p-20f) / ext : 0.0f;
        if (!std::isfinite(scale[a])) scale[a] = 0.0f;
        for (int b = 0; b < B; ++b) {
            for (int k = 0; k < 3; ++k) { bins[a][b].lo[k] = INFINITY; bins[a][b].hi[k] = -INFINITY; }
            bins[a][b].count = 0;
        }
    }
    auto bin_of = [&](const Box& t, int a) {
        int b = int((centre(t.lo[a], t.hi[a]) - nb.clo[a]) * scale[a]);
        return b < 0 ? 0 : (b >= B ? B - 1 : b);
    };
    for (size_t i = 0; i < n; ++i) {
        const Box& t = boxes[ids[i]];
        for (int a = 0; a < 3; ++a) {
            Bin& bn = bins[a][bin_of(t, a)];
            ++bn.count;
            for (int k = 0; k < 3; ++k) {
                bn.lo[k] = std::min(bn.lo[k], t.lo[k]);
                bn.hi[k] = std::max(bn.hi[k], t.hi[k]);
            }
        }
    }
    auto half_area = [](const float lo[3], const float hi[3]) {
        const double x = double(hi[0]) - lo[0], y = double(hi[1]) - lo[1], z = double(hi[2]) - lo[2];
        return x * y + y * z + z * x;
    };
    double best = INFINITY;
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3; ++a) {
        if (scale[a] == 0.0f) continue;
        double right_cost[B];
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        uint32_t cnt = 0;
        for (int b = B - 1; b > 0; --b) {
            for (int k = 0; k < 3; ++k) { lo[k] = std::min(lo[k], bins[a][b].lo[k]); hi[k] = std::max(hi[k], bins[a][b].hi[k]); }
            cnt += bins[a][b].count;
            right_cost[b] = cnt ? half_area(lo, hi) * cnt : 0.0;
        }
        for (int k = 0; k < 3; ++k) { lo[k] = INFINITY; hi[k] = -INFINITY; }
        cnt = 0;
        for (int b = 0; b < B - 1; ++b) {  // split between bin b and b + 1
            for (int k = 0; k < 3; ++k) { lo[k] = std::min(lo[k], bins[a][b].lo[k]); hi[k] = std::max(hi[k], bins[a][b].hi[k]); }
            cnt += bins[a][b].count;
            if (cnt == 0 || cnt == n) continue;
            const double cost = half_area(lo, hi) * cnt + right_cost[b + 1];
            if (cost < best) { best = cost; best_axis = a; best_bin = b; }
        }
    }
    axis_out = best_axis;
    if (best_axis < 0) return 0;
    return partition_ids(ids, n, boxes, [&](uint32_t t) { return bin_of(boxes[t], best_axis) <= best_bin; }, L, R);
}
