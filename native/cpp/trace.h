// The divide-and-conquer recursion (Afra 2012): filter the rays against the triangle set's box,
// stop at a leaf when rays or triangles fall under the threshold, otherwise partition the
// triangles and recurse into both halves with the same (filtered) rays, nearer half first so
// closest-hit rays shorten tfar before the farther half filters them.
// The top levels are partitioned once per call and shared by all threads (see SharedTop).
// Memory: nothing per ray; a triangle id array per thread plus the shared one. The stack holds
// O(depth) frames; depth is bounded by switching to object-median splits deep down.
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

// Largest shared node that a few-ray visit (<= leaf_rays) leaves unsplit: bigger ones are split
// for the kept top. A leaf met by 1-3 rays costs a SIMD step per triangle, each triangle's
// records fetched from scattered memory, while a split is made once per frame and serves every
// later batch: with 256 a 4-spp dragon frame's batches of 700-10K rays ran 39-181 triangle
// tests a ray, with 32 20-59, and the frame's trace CPU time fell 0.84-0.93x (README, "Where the
// time goes"; 16-64 within noise of each other on one thread, 32 best on two).
constexpr size_t kPrivateFewRaysTris = 32;

template <int W, Query Q>
struct Tracer {
    const Box* boxes;
    const CompactTri* tris;
    const uint32_t* prims;
    Hit* hits;
    uint8_t* occluded;
    const int32_t* skip;
    const uint8_t* mask;
    uint8_t visible;
    size_t num_ids;
    Config cfg;
    float origin_abs_max;
    int filter_kind;  // FilterKind (filter.h): odd direction components, far origins
    SharedTop* top;
    uint32_t* priv;  // this thread's id scratch
    Stats st;
    Interrupt* interrupt;  // null: runs to the end
    StealBoard* steal = nullptr;    // null: no work stealing
    const uint32_t* map = nullptr;  // a stolen task's local id -> the caller's id (null: ids are the caller's)
    Ray* chunk = nullptr;           // the caller's records that hold this tracer's rays (its chunk's)
    size_t chunk_n = 0;

    // A farther child still to be visited, which an idle thread may take (StealBoard).
    struct Pending {
        Ray* rays;
        size_t na;
        uint32_t* ids;
        size_t nt;
        NodeBounds nb;
        uint64_t depth;
        uint32_t h;
        bool shared, given;
    };
    std::vector<Pending> pending;

    // Records the farther child before the nearer one is visited; returns its slot (or ~0).
    size_t defer(Ray* rays, size_t na, uint32_t* ids, size_t nt, const NodeBounds& nb, uint64_t depth, uint32_t h,
                 bool shared) {
        if (!steal) return ~size_t(0);
        pending.push_back(Pending{rays, na, ids, nt, nb, depth, h, shared, false});
        return pending.size() - 1;
    }
    // Whether the deferred child is still this thread's to visit.
    bool resume(size_t slot) {
        if (slot == ~size_t(0)) return true;
        const bool given = pending[slot].given;
        pending.pop_back();
        return !given;
    }

    // Hands the shallowest deferred child of a node of kMinRays..kMaxRays rays to an idle thread.
    void offer() {
        Pending* f = nullptr;
        for (Pending& p : pending)
            if (!p.given && p.na >= StealBoard::kMinRays && p.na <= StealBoard::kMaxRays &&
                p.nt > size_t(cfg.leaf_size)) {
                f = &p;
                break;
            }
        if (!f || !steal->reserve()) return;
        std::unique_ptr<StolenTask> t;
        {
            try {
                t.reset(new StolenTask());
                const size_t m = f->na;
                t->rays.assign(f->rays, f->rays + m);
                t->map.resize(m);
                if (skip) t->skip.resize(m);
                for (size_t k = 0; k < m; ++k) {
                    const uint32_t id = t->rays[k].id;
                    const bool in = id < num_ids;  // see TraceJob::num_ids
                    t->map[k] = !in ? ~0u : map ? map[id] : id;
                    if (skip) t->skip[k] = in ? skip[id] : -1;
                    t->rays[k].id = uint32_t(k);
                }
                if (Q == Query::Any) t->occluded.assign(m, 0);
                else t->hits.assign(m, Hit{INFINITY, -1, 0.0f, 0.0f});
                if (f->shared) {
                    t->ids = f->ids;
                } else {  // this thread's scratch is reused once it leaves the node
                    t->own_ids.assign(f->ids, f->ids + f->nt);
                    t->ids = t->own_ids.data();
                }
                t->nt = f->nt;
                t->nb = f->nb;
                t->depth = f->depth;
                t->h = f->h;
                t->shared = f->shared;
                t->origin_abs_max = origin_abs_max;
                t->filter_kind = filter_kind;
                t->fix = chunk;
                t->fix_n = chunk_n;
            } catch (...) {  // out of memory: keep the work
                t.reset();
            }
        }
        if (!t) {
            steal->withdraw();
            return;
        }
        f->given = true;
        ++st.steals;
        steal->publish(std::move(t));
    }

    // At every node entry: an idle thread waits for work.
    void maybe_offer() {
        if (steal && steal->want.load(std::memory_order_relaxed) > 0) offer();
    }

    // A node of na active rays and nt triangles is a leaf: all of them tested brute force.
    bool is_leaf(size_t na, size_t nt) const {
        return nt <= size_t(cfg.leaf_size) || na <= size_t(cfg.leaf_rays);
    }

    // Filtering a node whose box most rays hit is not worth its cost (Nabata et al. 2013 skip
    // such filters, judged on sampled rays): with a share p of the n rays kept, a filter tests
    // n rays so that the two children test 2pn instead of 2n, a saving only for p < 1/2. So
    // at a node of many rays (not a leaf: a leaf would test the extra rays against every
    // triangle) 32 evenly spaced rays are tested first, and if at least kSampledKept of them
    // hit the box all n rays stay active; the children's filters cull the rest. Only which
    // rays reach a leaf changes, never a hit (leaves decide exactly). Measured on the tracer
    // benchmark's San Francisco rays (1M, 1 and 2 threads): box tests per ray -8%, trace
    // time -5 to -7% on diffuse, camera and shadow rays, for thresholds of 18-22 of 32.
    static constexpr size_t kSampledRays = 1024;
    static constexpr int kSampledKept = 20;
    template <int Kind>
    static bool most_inside(const Ray* rays, size_t n, const float lo[3], const float hi[3]) {
        alignas(64) Ray s[32];
        for (size_t k = 0; k < 32; ++k) std::memcpy(&s[k], rays + (k * n) / 32, sizeof(Ray));
        int kept = 0;
        for (int b = 0; b < 32; b += W) kept += __builtin_popcount(block_active<W, Kind>(s + b, lo, hi));
        return kept >= kSampledKept;
    }

    // Filter against nb's (padded) box; returns the active count (n when the filter is skipped).
    size_t filter(Ray* rays, size_t n, const NodeBounds& nb, uint64_t depth, size_t nt) {
        if (depth > st.max_depth) st.max_depth = depth;
        float lo[3], hi[3];
#ifndef DACRT_NONROBUST
        // Conservative box: the watertight test may accept a ray a few ulps of |v - o| outside
        // the exact triangle; the box must never cull such a ray or closed meshes could leak.
        // A leaf keeps a hit only where [0, t] meets its triangle's box padded by half this
        // (leaf.h), so every node on the way keeps the ray while its tfar >= t.
        float abs_max = 0.0f;
        for (int a = 0; a < 3; ++a) abs_max = std::max(abs_max, std::max(std::fabs(nb.lo[a]), std::fabs(nb.hi[a])));
        const float pad = 32.0f * 0x1p-24f * (abs_max + origin_abs_max);
#else
        const float pad = 0.0f;
#endif
        for (int a = 0; a < 3; ++a) { lo[a] = nb.lo[a] - pad; hi[a] = nb.hi[a] + pad; }
        return filter_kind == kFast ? filter_box<kFast>(rays, n, nt, lo, hi)
               : filter_kind == kOdd ? filter_box<kOdd>(rays, n, nt, lo, hi)
                                     : filter_box<kPrecise>(rays, n, nt, lo, hi);
    }

    // filter() with the box test of FilterKind Kind (filter.h).
    template <int Kind>
    size_t filter_box(Ray* rays, size_t n, size_t nt, const float lo[3], const float hi[3]) {
        if (n >= kSampledRays && !is_leaf(n, nt) && most_inside<Kind>(rays, n, lo, hi)) {
            ++st.filter_skips;
            return n;
        }
        const size_t na = filter_rays<W, Kind>(rays, n, lo, hi, st);
        st.box_hits += na;
        return na;
    }

    // Scratch of partition_ids_stable, kept by the thread across calls (4 bytes a triangle of
    // the largest scene split); null when it cannot grow (the split is then made in place).
    static uint32_t* split_scratch(size_t nt) {
        thread_local std::vector<uint32_t> v;
        try {
            if (v.size() < nt) v.resize(nt);
        } catch (...) {  // out of memory while holding a shared node's lock: never throw there
            return nullptr;
        }
        return v.data();
    }

    size_t split(uint32_t* ids, size_t nt, const NodeBounds& nb, float rays, uint64_t depth,
                 NodeBounds& L, NodeBounds& R, int& axis, bool shared = false) {
        ++st.partition_steps;
        size_t k = 0;
        const bool sah = cfg.partition == Partition::Sah ||
                         (cfg.partition == Partition::Adaptive && rays > cfg.sah_ratio * float(nt));
        uint32_t* tmp = shared ? split_scratch(nt) : nullptr;
        if (depth < 64) {
            if (sah) { ++st.sah_steps; k = split_sah(ids, nt, boxes, nb, L, R, axis, tmp); }
            else { ++st.median_steps; k = split_median(ids, nt, boxes, nb, L, R, axis, tmp); }
        }
        if (k == 0 || k == nt) k = split_object_median(ids, nt, boxes, nb, L, R, axis);
        return k;
    }

    // Phase timers: a node of at least kTimedRays rays reads the clock 3 times (~27 ns, lost in
    // its work). At a node of a few rays those reads were a third of its cost (the small late
    // batches of a frame: a 1K-ray dragon batch 1.57 -> 1.10 us a ray without them), so a
    // subtree entered with fewer rays is timed as a whole (2 reads) and only its split between
    // the phases is sampled, on one node in kTimedEvery (the first included). Scaling each
    // sampled node's ticks by kTimedEvery instead made one preempted node count 16 times (a
    // 15 ms call reported 458 ms of leaf time) and a call of under 16 small nodes none at all.
    static constexpr size_t kTimedRays = 256;
    static constexpr uint32_t kTimedEvery = 16;
    enum Phase { kFilter, kPartition, kLeaf };
    uint32_t small_nodes = 0;
    bool in_small = false;         // inside a subtree entered with < kTimedRays rays
    uint64_t small_ticks = 0;      // those subtrees' ticks, measured
    uint64_t sampled[3] = {};      // their sampled nodes' ticks by phase
    // The node's timing: 1 (timed), 2 (sampled in a small subtree) or 0 (not timed).
    uint64_t timing(size_t n) {
        if (n >= kTimedRays) return 1;
        return (small_nodes++ & (kTimedEvery - 1)) == 0 ? 2 : 0;
    }
    static uint64_t clock(uint64_t w) { return w ? phase_clock() : 0; }
    void count(Phase p, uint64_t w, uint64_t ticks) {
        if (w == 1) (p == kFilter ? st.filter_ticks : p == kPartition ? st.partition_ticks : st.leaf_ticks) += ticks;
        else if (w == 2) sampled[p] += ticks;
    }
    // Times the subtree of a node of n rays as a whole if it is the first of < kTimedRays.
    struct SmallScope {
        Tracer& t;
        const bool root;
        uint64_t c0 = 0;
        SmallScope(Tracer& tr, size_t n) : t(tr), root(!tr.in_small && n < kTimedRays) {
            if (root) { t.in_small = true; c0 = phase_clock(); }
        }
        ~SmallScope() {
            if (root) { t.small_ticks += phase_clock() - c0; t.in_small = false; }
        }
    };
    // The small subtrees' ticks into the phases, in the sampled nodes' proportions.
    void settle_timing() {
        const double s = double(sampled[0]) + double(sampled[1]) + double(sampled[2]);
        if (small_ticks == 0) return;
        if (!(s > 0.0)) {  // no sampled node took a tick: the clock did not move
            st.leaf_ticks += small_ticks;
            return;
        }
        const uint64_t f = std::min(small_ticks, uint64_t(double(small_ticks) * (double(sampled[0]) / s)));
        const uint64_t p = std::min(small_ticks - f, uint64_t(double(small_ticks) * (double(sampled[1]) / s)));
        st.filter_ticks += f;
        st.partition_ticks += p;
        st.leaf_ticks += small_ticks - f - p;
    }

    // filter() timed: sets the node's timing weight w and the clock after filtering c1.
    size_t timed_filter(Ray* rays, size_t n, const NodeBounds& nb, uint64_t depth, size_t nt, uint64_t& w, uint64_t& c1) {
        w = timing(n);
        const uint64_t c0 = clock(w);
        const size_t na = filter(rays, n, nb, depth, nt);
        c1 = clock(w);
        count(kFilter, w, c1 - c0);
        return na;
    }

    // Whether the caller stopped the call: checked on entering a node, never inside one, so a
    // shared split is always completed and the kept top stays valid for the next call.
    bool stopped() { return interrupt && interrupt->stop(); }

    void node(Ray* rays, size_t n, uint32_t* ids, size_t nt, const NodeBounds& nb, uint64_t depth) {
        if (stopped()) return;
        const SmallScope scope(*this, n);
        maybe_offer();
        uint64_t w, c1;
        const size_t na = timed_filter(rays, n, nb, depth, nt, w, c1);
        if (na == 0) return;
        node_split(rays, na, ids, nt, nb, depth, c1, w);
    }

    // A node whose rays[0, na) are filtered: leaf, or split and recurse (c1: clock at entry,
    // w: the node's timing weight).
    void node_split(Ray* rays, size_t na, uint32_t* ids, size_t nt, const NodeBounds& nb, uint64_t depth,
                    uint64_t c1, uint64_t w) {
        if (is_leaf(na, nt)) {
            intersect_leaf<W, Q>(rays, na, ids, nt, boxes, tris, prims, hits, occluded, skip, num_ids, mask, visible, st);
            count(kLeaf, w, clock(w) - c1);
            return;
        }
        NodeBounds L, R;
        int axis = 0;
        const size_t k = split(ids, nt, nb, float(na), depth, L, R, axis);
        count(kPartition, w, clock(w) - c1);
        if (majority_positive(rays, na, axis)) {
            const size_t slot = defer(rays, na, ids + k, nt - k, R, depth + 1, 0, false);
            node(rays, na, ids, k, L, depth + 1);
            if (resume(slot)) node(rays, na, ids + k, nt - k, R, depth + 1);
        } else {
            const size_t slot = defer(rays, na, ids, k, L, depth + 1, 0, false);
            node(rays, na, ids + k, nt - k, R, depth + 1);
            if (resume(slot)) node(rays, na, ids, k, L, depth + 1);
        }
    }

    // A node of the shared top: its split is made once, by whichever thread arrives first.
    void shared_node(Ray* rays, size_t n, uint32_t* ids, size_t nt, const NodeBounds& nb, uint64_t depth, uint32_t h) {
        if (stopped()) return;
        const SmallScope scope(*this, n);
        maybe_offer();
        uint64_t w, c1;
        const size_t na = timed_filter(rays, n, nb, depth, nt, w, c1);
        if (na == 0) return;
        if (nt <= size_t(cfg.leaf_size)) {  // never split, so its ids never move
            intersect_leaf<W, Q>(rays, na, ids, nt, boxes, tris, prims, hits, occluded, skip, num_ids, mask, visible, st);
            count(kLeaf, w, clock(w) - c1);
            return;
        }
        SharedNode& sn = top->pool->at(h);
        // Few rays at a small unsplit node: as in a private node, a brute-force leaf costs less
        // than a split, so they go on privately (a copy of the ids taken under the node's lock,
        // so no split can reorder them meanwhile) and leave the split to a batch that needs it.
        const bool few = na <= size_t(cfg.leaf_rays) && nt <= kPrivateFewRaysTris;
        for (int s = sn.state.load(std::memory_order_acquire); s != 2; s = sn.state.load(std::memory_order_acquire)) {
            int expected = 0;
            if (s == 0 && sn.state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) {
                if (few) {
                    std::memcpy(priv, ids, nt * sizeof(uint32_t));
                    sn.state.store(0, std::memory_order_release);
                    const uint64_t c2 = clock(w);
                    count(kPartition, w, c2 - c1);
                    node_split(rays, na, priv, nt, nb, depth, c2, w);
                    return;
                }
                sn.k = uint32_t(split(ids, nt, nb, float(na) * top->ray_scale, depth, sn.L, sn.R, sn.axis, true));
                sn.child = top->pool->alloc2();
                sn.state.store(2, std::memory_order_release);
                break;
            }
            std::this_thread::yield();  // another thread splits it (or copies its ids)
        }
        count(kPartition, w, clock(w) - c1);  // includes waiting for another thread's split
        const size_t k = sn.k;
        const uint32_t c = sn.child;
        bool lower_first = majority_positive(rays, na, sn.axis);
        // Threads tracing their chunks walk the shared top in step, so one waits while the
        // other splits each large node. If the nearer child is being split right now, the
        // farther one goes first (and gets split meanwhile): order changes work, never hits.
        const uint32_t nearer = lower_first ? c : (c ? c + 1 : 0);
        if (nearer && top->pool->at(nearer).state.load(std::memory_order_relaxed) == 1) lower_first = !lower_first;
        if (lower_first) {
            const size_t slot = defer(rays, na, ids + k, nt - k, sn.R, depth + 1, c ? c + 1 : 0, true);
            child(rays, na, ids, k, sn.L, depth + 1, c);
            if (resume(slot)) child(rays, na, ids + k, nt - k, sn.R, depth + 1, c ? c + 1 : 0);
        } else {
            const size_t slot = defer(rays, na, ids, k, sn.L, depth + 1, c, true);
            child(rays, na, ids + k, nt - k, sn.R, depth + 1, c ? c + 1 : 0);
            if (resume(slot)) child(rays, na, ids, k, sn.L, depth + 1, c);
        }
    }

    // h: the node's pool index (0: no shared node, the pool was full; trace privately).
    void child(Ray* rays, size_t n, uint32_t* ids, size_t nt, const NodeBounds& nb, uint64_t depth, uint32_t h) {
        if (h != 0 && depth < uint64_t(top->max_depth) && nt > top->min_tris) {
            shared_node(rays, n, ids, nt, nb, depth, h);
        } else {  // leave the shared top: continue on a private copy of the ids
            std::memcpy(priv, ids, nt * sizeof(uint32_t));
            node(rays, n, priv, nt, nb, depth);
        }
    }
};

template <int W, Query Q>
void run_chunk(const TraceJob& job, Ray* rays, size_t n, uint32_t* ids, Stats& st) {
    const TriangleSet& ts = *job.ts;
    Tracer<W, Q> tr{ts.boxes.data(), ts.tris.data(), ts.prim.data(), job.hits, job.occluded, job.skip, job.mask, job.visible,
                    job.num_ids, job.cfg, job.batch.origin_abs_max,
                    job.batch.far_origins ? kPrecise : job.batch.odd_dirs ? kOdd : kFast,
                    job.top, ids, Stats{}, job.interrupt, job.steal, nullptr, rays, n};
    NodeBounds root;
    for (int a = 0; a < 3; ++a) {
        root.lo[a] = ts.bounds.lo[a]; root.hi[a] = ts.bounds.hi[a];
        root.clo[a] = ts.centroid_bounds.lo[a]; root.chi[a] = ts.centroid_bounds.hi[a];
    }
    tr.child(rays, n, job.top->ids, ts.valid_ids.size(), root, 0, 1);
    tr.settle_timing();
    st.add(tr.st);
}

// A stolen child (StolenTask): its copied rays against its subtree, hits of its own.
template <int W, Query Q>
void run_task(const TraceJob& job, StolenTask& t, uint32_t* ids, Stats& st) {
    const TriangleSet& ts = *job.ts;
    Tracer<W, Q> tr{ts.boxes.data(), ts.tris.data(), ts.prim.data(), t.hits.data(), t.occluded.data(),
                    t.skip.empty() ? nullptr : t.skip.data(), job.mask, job.visible, t.rays.size(), job.cfg,
                    t.origin_abs_max, t.filter_kind, job.top, ids, Stats{}, job.interrupt, job.steal, t.map.data(),
                    t.fix, t.fix_n};
    if (t.shared) tr.child(t.rays.data(), t.rays.size(), t.ids, t.nt, t.nb, t.depth, t.h);
    else tr.node(t.rays.data(), t.rays.size(), t.ids, t.nt, t.nb, t.depth);
    tr.settle_timing();
    st.add(tr.st);
}

template <int W>
void trace_chunk_w(const TraceJob& job, Ray* rays, size_t n, uint32_t* ids, Stats& st) {
    if (job.query == Query::Any) run_chunk<W, Query::Any>(job, rays, n, ids, st);
    else run_chunk<W, Query::Closest>(job, rays, n, ids, st);
}

template <int W>
void trace_task_w(const TraceJob& job, StolenTask& t, uint32_t* ids, Stats& st) {
    if (job.query == Query::Any) run_task<W, Query::Any>(job, t, ids, st);
    else run_task<W, Query::Closest>(job, t, ids, st);
}
