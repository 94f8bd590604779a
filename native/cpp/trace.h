// The divide-and-conquer recursion (Afra 2012): filter the rays against the triangle set's box,
// stop at a leaf when rays or triangles fall under the threshold, otherwise partition the
// triangles and recurse into both halves with the same (filtered) rays, nearer half first so
// closest-hit rays shorten tfar before the farther half filters them.
// Memory: nothing per ray; the caller provides the triangle id array it reorders. The stack
// holds O(depth) frames; the depth is bounded by switching to object-median splits deep down.
// Included inside an ISA namespace.
#pragma once

// Whether most active rays travel towards +axis (then the lower child is nearer), judged on up
// to 32 evenly spaced rays: counting all of them in the filter cost more than it saved.
inline bool majority_positive(const Ray* rays, size_t na, int axis) {
    const size_t samples = std::min<size_t>(na, 32);
    int vote = 0;
    for (size_t s = 0; s < samples; ++s) {
        const float d = rays[s * na / samples].dir[axis];
        vote += (d > 0.0f) - (d < 0.0f);
    }
    return vote >= 0;
}

template <int W, Query Q>
struct Tracer {
    const Box* boxes;
    const CompactTri* tris;
    Hit* hits;
    uint8_t* occluded;
    Config cfg;
    float origin_abs_max;
    Stats st;

    void node(Ray* rays, size_t n, uint32_t* ids, size_t nt, const NodeBounds& nb, uint64_t depth) {
        if (depth > st.max_depth) st.max_depth = depth;
        float lo[3], hi[3];
#ifndef DACRT_NONROBUST
        // Conservative box: the watertight test may accept a ray a few ulps of |v - o| outside
        // the exact triangle; the box must never cull such a ray or closed meshes could leak.
        float abs_max = 0.0f;
        for (int a = 0; a < 3; ++a) abs_max = std::max(abs_max, std::max(std::fabs(nb.lo[a]), std::fabs(nb.hi[a])));
        const float pad = 32.0f * 0x1p-24f * (abs_max + origin_abs_max);
#else
        const float pad = 0.0f;
#endif
        for (int a = 0; a < 3; ++a) { lo[a] = nb.lo[a] - pad; hi[a] = nb.hi[a] + pad; }
        const size_t na = filter_rays<W>(rays, n, lo, hi, st);
        if (na == 0) return;
        const size_t leaf = size_t(cfg.leaf_size);
        if (nt <= leaf || na <= leaf) {
            intersect_leaf<W, Q>(rays, na, ids, nt, boxes, tris, hits, occluded, st);
            return;
        }
        NodeBounds L, R;
        int axis = 0;
        size_t k = 0;
        ++st.partition_steps;
        const bool sah = cfg.partition == Partition::Sah ||
                         (cfg.partition == Partition::Adaptive && float(na) > cfg.sah_ratio * float(nt));
        if (depth < 64) {
            if (sah) { ++st.sah_steps; k = split_sah(ids, nt, boxes, nb, L, R, axis); }
            else { ++st.median_steps; k = split_median(ids, nt, boxes, nb, L, R, axis); }
        }
        if (k == 0 || k == nt) k = split_object_median(ids, nt, boxes, nb, L, R, axis);
        if (majority_positive(rays, na, axis)) {
            node(rays, na, ids, k, L, depth + 1);
            node(rays, na, ids + k, nt - k, R, depth + 1);
        } else {
            node(rays, na, ids + k, nt - k, R, depth + 1);
            node(rays, na, ids, k, L, depth + 1);
        }
    }
};

template <int W, Query Q>
void run_chunk(const TraceJob& job, Ray* rays, size_t n, uint32_t* ids, Stats& st) {
    const TriangleSet& ts = *job.ts;
    Tracer<W, Q> tr{ts.boxes.data(), ts.tris.data(), job.hits, job.occluded, job.cfg, job.origin_abs_max, Stats{}};
    NodeBounds root;
    for (int a = 0; a < 3; ++a) {
        root.lo[a] = ts.bounds.lo[a]; root.hi[a] = ts.bounds.hi[a];
        root.clo[a] = ts.centroid_bounds.lo[a]; root.chi[a] = ts.centroid_bounds.hi[a];
    }
    tr.node(rays, n, ids, ts.valid_ids.size(), root, 0);
    st.add(tr.st);
}

template <int W>
void trace_chunk_w(const TraceJob& job, Ray* rays, size_t n, uint32_t* ids, Stats& st) {
    if (job.query == Query::Any) run_chunk<W, Query::Any>(job, rays, n, ids, st);
    else run_chunk<W, Query::Closest>(job, rays, n, ids, st);
}
